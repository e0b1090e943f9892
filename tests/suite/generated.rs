//! The collocation operator's invariants on scenes generated from seeds (closed rooms with
//! floating boxes, louvres, small cities of rotated buildings far from the origin, slivers
//! touching walls): every row of K/rho sums to 1 in a closed scene (Lemma 2.1), both methods; the
//! compressed operator's products are within ten times its tolerance of the dense matrix's, with
//! and without shadowed blocks. (GPU = CPU on the same families: `tests/suite/gpu.rs`.)

use radiosity::assembly::{AssemblyOptions, CollocationMatrix, Problem, assemble};
use radiosity::discretization::{Discretization, Method};
use radiosity::mesh::{Mesh, MeshKind};
use radiosity::operator::{CompressedOperator, CompressionOptions};
use radiosity::progress::Silent;
use radiosity::scene::Scene;
use radiosity::scene::generated::{city, louvre, room_with_boxes, slivers_touching_walls};

fn problem(scene: &Scene, method: Method, refine: u32) -> Problem {
    let mesh = Mesh::new(scene, &MeshKind::Uniform, refine).unwrap();
    let disc = Discretization::new(scene, &mesh, method).unwrap();
    Problem::new(scene.clone(), mesh, disc)
}

fn dense(problem: &Problem) -> CollocationMatrix {
    assemble(problem, &AssemblyOptions::default(), &Silent).unwrap().matrix
}

#[test]
fn closed_rooms_with_random_boxes_have_rows_of_k_over_rho_summing_to_one() {
    for seed in 0..3 {
        let scene = room_with_boxes(seed);
        for (method, refine) in [(Method::Centroid, 2), (Method::linear(1.0 / 6.0).unwrap(), 1)] {
            let problem = problem(&scene, method, refine);
            let k = dense(&problem);
            let sums = k.apply(&vec![1.0; problem.disc.dof()]);
            for (node, sum) in problem.disc.nodes().zip(sums) {
                let off = (sum / node.rho - 1.0).abs();
                assert!(
                    off < 1e-9,
                    "{} {method} refine {refine}: a row sums to 1 + {off:.1e}",
                    scene.name
                );
            }
        }
    }
}

#[test]
fn generated_scenes_compress_to_within_ten_times_the_tolerance_of_their_dense_matrix() {
    let scenes: Vec<(Scene, u32)> = (0..2)
        .map(|seed| (room_with_boxes(seed), 3))
        .chain((0..2).map(|seed| (louvre(seed), 3)))
        .chain((0..2).map(|seed| (city(seed), 3)))
        .chain((0..2).map(|seed| (slivers_touching_walls(seed), 4)))
        .collect();
    for (scene, refine) in scenes {
        let problem = problem(&scene, Method::Centroid, refine);
        let k = dense(&problem);
        for (tolerance, shadowed_blocks) in [(1e-6, false), (1e-6, true), (1e-9, false)] {
            let options = CompressionOptions {
                tolerance,
                shadowed_blocks: shadowed_blocks.into(),
                ..Default::default()
            };
            let assembly = AssemblyOptions::default();
            let op =
                CompressedOperator::build(&problem, &assembly, &options, None, &Silent).unwrap();
            if tolerance == 1e-6 {
                assert!(op.stats.far_blocks > 0, "{}: nothing compressed", scene.name);
            }
            let d = op.max_product_difference(&|x| k.apply(x));
            assert!(
                d <= 10.0 * tolerance,
                "{} refine {refine} at {tolerance:e}, shadowed {shadowed_blocks}: products differ by {d:.2e}",
                scene.name
            );
        }
    }
}
