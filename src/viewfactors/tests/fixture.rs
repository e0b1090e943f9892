//! What the tests compute on: a scene at refine 0 with what a `Context` borrows ([`Fixture`]),
//! example scenes cut short, and whole matrices integrated in each direction.

use super::super::compute::view_factors;
use super::super::context::Context;
use super::super::matrix::ViewFactors;
use super::super::options::ViewFactorOptions;
use super::super::outer_rules::OuterRules;
use super::super::row::{Between, Tally};
use crate::assembly::{AssemblyOptions, PairIntegrator};
use crate::discretization::{Discretization, Method};
use crate::mesh::{Mesh, MeshKind};
use crate::scene::Scene;
use crate::visibility::PairPlanner;

/// The view factors of `scene` at `refine`, F_ij and F_ji each integrated, so that
/// reciprocity measures their accuracy.
pub(super) fn compute(scene: &Scene, refine: u32) -> (Mesh, ViewFactors) {
    let mesh = Mesh::new(scene, &MeshKind::Uniform, refine).unwrap();
    let planner = PairPlanner::new(scene);
    let options = ViewFactorOptions { each_direction: true, ..Default::default() };
    let f = view_factors(scene, &mesh, &planner, &options, &crate::progress::Silent);
    (mesh, f.unwrap())
}

/// The faces of `examples/FILE` up to the one named `name`, left out with those after it.
pub(super) fn example_before(file: &str, name: &str) -> Scene {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("examples").join(file);
    let text = std::fs::read_to_string(&path).unwrap();
    let end = text.find(&format!("[[faces]]\nname = \"{name}\"")).unwrap();
    crate::scene::parse_toml(&text[..end], &path).unwrap()
}

/// A scene at refine 0 and what a [`Context`] of its view factors borrows.
pub(in crate::viewfactors) struct Fixture {
    pub(in crate::viewfactors) scene: Scene,
    pub(in crate::viewfactors) mesh: Mesh,
    pub(in crate::viewfactors) planner: PairPlanner,
    pub(super) disc: Discretization,
    pub(super) integrator: PairIntegrator,
}

impl Fixture {
    pub(in crate::viewfactors) fn new(scene: Scene) -> Self {
        let mesh = Mesh::new(&scene, &MeshKind::Uniform, 0).unwrap();
        let planner = PairPlanner::new(&scene);
        let disc = Discretization::new(&scene, &mesh, Method::Centroid).unwrap();
        let integrator = PairIntegrator::new(Method::Centroid, &AssemblyOptions::default());
        Self { scene, mesh, planner, disc, integrator }
    }

    /// Every `step`-th pair `(i, j)` of the matrix, row by row, of elements on two faces between
    /// which at least two occluders may come, with those occluders.
    pub(in crate::viewfactors) fn pairs_among_occluders(
        &self,
        step: usize,
    ) -> Vec<(usize, usize, Vec<usize>)> {
        let elements = self.mesh.elements();
        let n = elements.len();
        (0..n * n)
            .step_by(step)
            .map(|k| (k / n, k % n))
            .filter(|&(i, j)| elements[i].face != elements[j].face)
            .map(|(i, j)| (i, j, self.planner.candidates(elements[i].face, elements[j].face)))
            .filter(|(_, _, occluders)| occluders.len() >= 2)
            .collect()
    }

    /// The scene `examples/FILE`.
    pub(super) fn example(file: &str) -> Self {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("examples").join(file);
        Self::new(crate::scene::load(&path).unwrap())
    }

    /// Every F_ij of the scene with `options`.
    pub(super) fn view_factors(&self, options: &ViewFactorOptions) -> ViewFactors {
        let silent = &crate::progress::Silent;
        view_factors(&self.scene, &self.mesh, &self.planner, options, silent).unwrap()
    }

    /// F_ij of the pair `(i, j)` at `tolerance`, among the occluders, and its estimated error.
    pub(super) fn pair_at(&self, (i, j): (usize, usize), tolerance: f64) -> (f64, f64) {
        let options = ViewFactorOptions { tolerance, ..Default::default() };
        let mut tally = Tally::default();
        let value = self.context(&options).pair(
            i,
            j,
            &mut Some(Between::Search),
            &OuterRules::new(&options),
            &mut tally,
        );
        (value, tally.error)
    }

    /// Asserts that at each of `tolerances` F_ij of `pair` is within it of `converged`, and
    /// within its own estimate.
    pub(super) fn assert_meets_each_tolerance(
        &self,
        pair: (usize, usize),
        converged: f64,
        tolerances: &[f64],
    ) {
        for &tolerance in tolerances {
            let (value, estimate) = self.pair_at(pair, tolerance);
            let off = (value - converged).abs();
            assert!(
                off <= tolerance && off <= estimate.max(1e-13),
                "{pair:?} at {tolerance}: {off} off, estimate {estimate}"
            );
        }
    }

    pub(super) fn context<'a>(&'a self, options: &'a ViewFactorOptions) -> Context<'a> {
        Context {
            scene: &self.scene,
            mesh: &self.mesh,
            disc: &self.disc,
            planner: &self.planner,
            integrator: &self.integrator,
            options,
        }
    }
}
