//! What every stage after the scene works on, each part built once: the scene, its mesh, the
//! discretization and the pair planner. Assembly, the GPU, the compressed operator and the
//! error measurements take it whole instead of its parts.

use std::time::Instant;

use crate::discretization::Discretization;
use crate::mesh::Mesh;
use crate::scene::Scene;
use crate::visibility::PairPlanner;

/// A discretized scene with its pair planner.
#[derive(Clone, Debug)]
pub struct Problem {
    /// The scene.
    pub scene: Scene,
    /// Its mesh.
    pub mesh: Mesh,
    /// Nodes, elements and method.
    pub disc: Discretization,
    /// The scene's occluders and their index, for every pair plan.
    pub planner: PairPlanner,
    /// Time to build the planner: part of the setup time, as the assembly is.
    pub plan_seconds: f64,
}

impl Problem {
    /// The problem of `scene`, `mesh` and `disc`, with the planner built here.
    pub fn new(scene: Scene, mesh: Mesh, disc: Discretization) -> Self {
        let (planner, plan_seconds) = Self::plan(&scene);
        Self::with_planner(scene, mesh, disc, planner, plan_seconds)
    }

    /// The pair planner of `scene`, and the seconds it took to build.
    pub fn plan(scene: &Scene) -> (PairPlanner, f64) {
        let started = Instant::now();
        let planner = PairPlanner::new(scene);
        (planner, started.elapsed().as_secs_f64())
    }

    /// The problem with a planner built already (in `plan_seconds`).
    pub fn with_planner(
        scene: Scene,
        mesh: Mesh,
        disc: Discretization,
        planner: PairPlanner,
        plan_seconds: f64,
    ) -> Self {
        Self { scene, mesh, disc, planner, plan_seconds }
    }
}
