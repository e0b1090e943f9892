//! The pair plan with and without the occluder index, timed in one run on the same views
//! (`radiosity bench-plan`): the visible parts must agree, only the time may differ.

use std::time::Instant;

use rayon::prelude::*;
use serde::Serialize;

use crate::geometry::signed_area;
use crate::scene::Scene;
use crate::visibility::{Acceleration, FaceView, PairPlanner, SkipReason};

/// Timings of the pair plan for a sample of nodes against every face.
#[derive(Clone, Debug, Serialize)]
pub struct PlanBench {
    /// Scene name.
    pub scene: String,
    /// Faces.
    pub faces: usize,
    /// Convex occluder pieces.
    pub occluders: usize,
    /// Sampled nodes (face centres), each against every face.
    pub nodes: usize,
    /// (node, face) views computed per planner.
    pub views: u64,
    /// Views with at least one shadow, or hidden.
    pub shadowed_views: u64,
    /// Per way of finding candidates: building the planner and computing the views.
    pub timings: Vec<PlanTiming>,
    /// Views time of the core solver's rule (`box-scan`) over that of the tree.
    pub speedup: f64,
    /// Views time of the pyramid test over every occluder (`scan`) over that of the tree.
    pub speedup_over_scan: f64,
    /// Whether all planners found the same visible area of every face (to 1e-9 of its area).
    pub identical: bool,
    /// The core solver built, before any view, the candidate list of every ordered pair of faces
    /// by testing every occluder: the time of that step, measured on a sample of 4000 pairs and
    /// scaled to all faces².
    pub pair_lists_seconds_projected: f64,
    /// A complete plan with one node per face (faces x faces views), projected from the measured
    /// views: the core solver's (pair lists + views) over the tree's.
    pub complete_plan_speedup: f64,
}

/// One way of finding candidate occluders, timed.
#[derive(Clone, Debug, Serialize)]
pub struct PlanTiming {
    /// `tree`, `scan` or `box-scan` ([`Acceleration`]).
    pub acceleration: Acceleration,
    /// Building the planner.
    pub build_seconds: f64,
    /// Computing the views.
    pub plan_seconds: f64,
}

/// Views from the centres of `nodes` faces spread evenly over the scene to every face, with both
/// planners.
pub fn bench_plan(scene: &Scene, nodes: usize) -> PlanBench {
    let faces = scene.faces.len();
    let step = (faces / nodes.clamp(1, faces)).max(1);
    let sample: Vec<usize> = (0..faces).step_by(step).take(nodes).collect();
    let timed = |acceleration| {
        let started = Instant::now();
        let planner = PairPlanner::with_acceleration(scene, acceleration);
        let build = started.elapsed().as_secs_f64();
        let started = Instant::now();
        let views: Vec<Vec<FaceView>> = sample
            .par_iter()
            .map(|&a| {
                let f = &scene.faces[a];
                let centre = f.vertices.iter().sum::<glam::DVec3>() / f.vertices.len() as f64;
                (0..faces).map(|b| planner.face_view(centre, f.frame.normal, a, b)).collect()
            })
            .collect();
        let plan = started.elapsed().as_secs_f64();
        // What the views decide: the visible area of each face (the tree's hidden faces have no
        // shadow list, the core solver's plan lists every shadow).
        let areas: Vec<f64> = views
            .par_iter()
            .flat_map(|row| {
                row.iter()
                    .enumerate()
                    .map(|(b, v)| {
                        planner
                            .visible_part_of_face(v, b)
                            .iter()
                            .map(|p| signed_area(p))
                            .sum::<f64>()
                    })
                    .collect::<Vec<f64>>()
            })
            .collect();
        (build, plan, views, areas, planner.occluders().len())
    };
    let (build, plan, views, reference, occluders) = timed(Acceleration::Tree);
    let shadowed = views
        .iter()
        .flatten()
        .filter(|v| match v {
            FaceView::Visible { shadows, .. } => !shadows.is_empty(),
            FaceView::Skip(reason) => *reason == SkipReason::Hidden,
        })
        .count() as u64;
    let mut timings = vec![PlanTiming {
        acceleration: Acceleration::Tree,
        build_seconds: build,
        plan_seconds: plan,
    }];
    let mut identical = true;
    for acceleration in [Acceleration::Scan, Acceleration::BoxScan] {
        let (build_seconds, plan_seconds, _, areas, _) = timed(acceleration);
        identical &= areas
            .iter()
            .zip(&reference)
            .zip(sample.iter().flat_map(|_| scene.faces.iter()))
            .all(|((a, b), face)| (a - b).abs() <= 1e-9 * face.area());
        timings.push(PlanTiming { acceleration, build_seconds, plan_seconds });
    }
    let baseline = PairPlanner::with_acceleration(scene, Acceleration::BoxScan);
    let pairs: Vec<(usize, usize)> =
        (0..4000).map(|k| ((k * 7919) % faces, (k * 104_729 + 1) % faces)).collect();
    let started = Instant::now();
    let listed: usize = pairs.par_iter().map(|&(a, b)| baseline.candidates(a, b).len()).sum();
    let per_pair = started.elapsed().as_secs_f64() / pairs.len() as f64;
    std::hint::black_box(listed);
    let pair_lists = per_pair * (faces * faces) as f64;
    let per_node = |seconds: f64| seconds / sample.len() as f64 * faces as f64;
    let complete_plan_speedup = (pair_lists + per_node(timings[2].plan_seconds)) / per_node(plan);
    PlanBench {
        pair_lists_seconds_projected: pair_lists,
        complete_plan_speedup,
        scene: scene.name.clone(),
        faces,
        occluders,
        nodes: sample.len(),
        views: (sample.len() * faces) as u64,
        shadowed_views: shadowed,
        speedup: timings[2].plan_seconds / plan,
        speedup_over_scan: timings[1].plan_seconds / plan,
        timings,
        identical,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_tree_gives_the_same_views_as_testing_every_occluder() {
        // city(12, 12) has 1201 faces: beyond the pair table, the tree itself is searched.
        let scenes =
            [crate::scene::city(4, 3), crate::scene::baffled_box(), crate::scene::city(12, 12)];
        for scene in scenes.map(Result::unwrap) {
            let b = bench_plan(&scene, 20);
            assert!(b.identical, "{}", scene.name);
            assert!(b.shadowed_views > 0, "{}", scene.name);
        }
    }
}
