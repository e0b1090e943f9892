//! `study estimates`: whether the view factors' error estimate keeps its promise on scenes nobody
//! tuned for. Each scene of the generated families ([`crate::scene::generated`]: slivers touching
//! walls, rooms with boxes, louvres, cities of rotated buildings, two triangles touching in each
//! way two triangles can, seeds 0, 1, ...) and of the
//! scenes asked for (the command line adds the generated city:4x4) is run at each tolerance, each pair once and each
//! direction, and checked against a run at [`REFERENCE_TOLERANCE`]
//! ([`crate::viewfactors::ViewFactors::check_against`]): every entry within the two runs'
//! estimates, reciprocity within the areas times the estimate, no negative entry.

use std::time::Instant;

use serde::Serialize;

use crate::error::Result;
use crate::mesh::{Mesh, MeshKind};
use crate::pipeline::SceneSource;
use crate::progress::{Progress, Silent};
use crate::scene::generated::Contact;
use crate::scene::{Scene, SurfaceParameters, generated};
use crate::viewfactors::{ViewFactorOptions, ViewFactors, view_factors};
use crate::visibility::PairPlanner;

/// The tolerances checked by default.
pub const TOLERANCES: [f64; 3] = [1e-4, 1e-6, 1e-8];

/// The reference's tolerance: far below every tolerance checked, and above what f64 can meet on
/// these scenes.
pub const REFERENCE_TOLERANCE: f64 = 1e-11;

/// Seeds per family by default (the tests check the first few).
pub const DEFAULT_SEEDS: u64 = 8;

/// What the study runs.
#[derive(Clone, Debug)]
pub struct EstimateSeries {
    /// Seeds 0..`seeds` of each generated family.
    pub seeds: u64,
    /// Tolerances to check.
    pub tolerances: Vec<f64>,
    /// Further scenes (files, built-in scenes, cities), at refine 0.
    pub scenes: Vec<SceneSource>,
}

/// One scene at one tolerance, one way of integrating.
#[derive(Clone, Debug, Serialize)]
pub struct EstimateRow {
    /// The scene's name.
    pub scene: String,
    /// Elements (refine 0: the faces' triangles).
    pub n: usize,
    /// The tolerance asked for.
    pub tolerance: f64,
    /// Whether F_ij and F_ji were each integrated.
    pub each_direction: bool,
    /// The run's estimate of its largest error.
    pub error_estimate: f64,
    /// The largest difference from the reference.
    pub largest_error: f64,
    /// `largest_error` over the two runs' estimates: at most 1 where the promise holds.
    pub error_ratio: f64,
    /// The elements (i, j) of the entry where `error_ratio` is reached.
    pub worst_entry: (usize, usize),
    /// Reciprocity over what the estimate allows: at most 1 where it holds.
    pub reciprocity_ratio: f64,
    /// Entries below zero.
    pub negative: usize,
    /// Whether every promise held ([`crate::viewfactors::EstimateCheck::holds`]).
    pub holds: bool,
    /// Integrand evaluations.
    pub evaluations: u64,
    /// Time of the run.
    pub seconds: f64,
}

/// The study's result.
#[derive(Clone, Debug, Serialize)]
pub struct EstimateStudy {
    /// Study id.
    pub study: &'static str,
    /// The reference's tolerance.
    pub reference_tolerance: f64,
    /// Every run.
    pub rows: Vec<EstimateRow>,
    /// Runs whose promise failed.
    pub failed: usize,
    /// The largest error ratio per tolerance, over every scene and both ways.
    pub worst_ratio: Vec<(f64, f64)>,
}

/// The generated scenes of seeds 0..`seeds`, family by family.
fn generated_scenes(seeds: u64) -> Vec<Scene> {
    let families: [fn(u64) -> Scene; 4] = [
        generated::slivers_touching_walls,
        generated::room_with_boxes,
        generated::louvre,
        generated::city,
    ];
    let scenes = families.iter().flat_map(|family| (0..seeds).map(family));
    let contacts = Contact::ALL
        .into_iter()
        .flat_map(|kind| (0..seeds).map(move |seed| generated::contact(kind, seed)));
    scenes.chain(contacts).collect()
}

/// View factors of `scene` on `mesh` at `tolerance`.
fn compute(
    scene: &Scene,
    mesh: &Mesh,
    planner: &PairPlanner,
    tolerance: f64,
    each_direction: bool,
) -> Result<ViewFactors> {
    let options = ViewFactorOptions { tolerance, each_direction, ..Default::default() };
    view_factors(scene, mesh, planner, &options, &Silent)
}

/// Runs the study; `progress` counts the scenes.
pub fn run_estimates(series: &EstimateSeries, progress: &dyn Progress) -> Result<EstimateStudy> {
    for &t in &series.tolerances {
        ViewFactorOptions { tolerance: t, ..Default::default() }.validate()?;
    }
    let mut scenes = generated_scenes(series.seeds);
    for source in &series.scenes {
        scenes.push(source.build(SurfaceParameters::default())?);
    }
    progress.start("scenes", scenes.len());
    let mut rows = Vec::new();
    for scene in &scenes {
        let mesh = Mesh::new(scene, &MeshKind::Uniform, 0)?;
        let planner = PairPlanner::new(scene);
        let reference = compute(scene, &mesh, &planner, REFERENCE_TOLERANCE, false)?;
        for &tolerance in &series.tolerances {
            for each_direction in [false, true] {
                let started = Instant::now();
                let f = compute(scene, &mesh, &planner, tolerance, each_direction)?;
                let seconds = started.elapsed().as_secs_f64();
                let check = f.check_against(&reference);
                rows.push(EstimateRow {
                    scene: scene.name.clone(),
                    n: mesh.len(),
                    tolerance,
                    each_direction,
                    error_estimate: f.error_estimate,
                    largest_error: check.largest_error,
                    error_ratio: check.error_ratio,
                    worst_entry: check.worst_entry,
                    reciprocity_ratio: check.reciprocity_ratio,
                    negative: check.negative,
                    holds: check.holds(),
                    evaluations: f.evaluations,
                    seconds,
                });
            }
        }
        progress.advance(1);
    }
    progress.finish();
    let failed = rows.iter().filter(|r| !r.holds).count();
    let worst_ratio = series
        .tolerances
        .iter()
        .map(|&t| {
            let ratios = rows.iter().filter(|r| r.tolerance == t);
            (t, ratios.map(|r| r.error_ratio.max(r.reciprocity_ratio)).fold(0.0, f64::max))
        })
        .collect();
    Ok(EstimateStudy {
        study: "estimates",
        reference_tolerance: REFERENCE_TOLERANCE,
        rows,
        failed,
        worst_ratio,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_small_sweep_checks_every_scene_both_ways_and_keeps_its_promise() {
        let series = EstimateSeries { seeds: 1, tolerances: vec![1e-4], scenes: Vec::new() };
        let study = run_estimates(&series, &Silent).unwrap();
        // Four families and seven contacts of one seed; each pair once and each direction.
        assert_eq!(study.rows.len(), (4 + 7) * 2);
        assert!(study.rows.iter().all(|r| r.evaluations > 0 && r.error_estimate > 0.0));
        assert_eq!(study.failed, 0, "{:#?}", study.rows);
        assert_eq!(study.worst_ratio.len(), 1);
    }
}
