//! The pair plan of a generated city (occluders everywhere), as assembly uses it: building the
//! [`PairPlanner`], and the views from a sample of nodes to every face with the visible part of
//! each (by default the R*-tree searched with the view pyramid; the scan over every occluder for
//! comparison). `cargo bench --bench pair_plan`; `radiosity bench-plan` compares every way of
//! finding candidates in one run and checks that they agree.

use criterion::{Criterion, criterion_group, criterion_main};
use glam::DVec3;
use radiosity::geometry::signed_area;
use radiosity::scene::{Scene, city};
use radiosity::visibility::{Acceleration, FaceView, PairPlanner};
use std::hint::black_box;

/// Sampled nodes: the centres of `nodes` faces spread evenly over the scene, with their face.
fn sample(scene: &Scene, nodes: usize) -> Vec<(usize, DVec3, DVec3)> {
    let faces = scene.faces.len();
    (0..faces)
        .step_by((faces / nodes).max(1))
        .take(nodes)
        .map(|a| {
            let f = &scene.faces[a];
            let centre = f.vertices.iter().sum::<DVec3>() / f.vertices.len() as f64;
            (a, centre, f.frame.normal)
        })
        .collect()
}

/// The visible area of every face from every sampled node (what the views decide).
fn plan(planner: &PairPlanner, faces: usize, nodes: &[(usize, DVec3, DVec3)]) -> f64 {
    let mut visible = 0.0;
    for &(a, p, normal) in nodes {
        for b in 0..faces {
            let view = planner.face_view(p, normal, a, b);
            if let FaceView::Visible { .. } = view {
                visible += planner
                    .visible_part_of_face(&view, b)
                    .iter()
                    .map(|piece| signed_area(piece))
                    .sum::<f64>();
            }
        }
    }
    visible
}

fn pair_plan(c: &mut Criterion) {
    let scene = city(10, 10).unwrap();
    let faces = scene.faces.len();
    let nodes = sample(&scene, 10);
    let mut group = c.benchmark_group(format!("pair plan city 10x10 ({faces} faces)"));
    group.sample_size(10);
    group.bench_function("build planner", |b| b.iter(|| PairPlanner::new(black_box(&scene))));
    for (name, acceleration) in [("tree", Acceleration::Tree), ("scan", Acceleration::Scan)] {
        let planner = PairPlanner::with_acceleration(&scene, acceleration);
        group.bench_function(format!("views, {} nodes x every face ({name})", nodes.len()), |b| {
            b.iter(|| plan(&planner, faces, black_box(&nodes)))
        });
    }
    group.finish();
}

criterion_group!(benches, pair_plan);
criterion_main!(benches);
