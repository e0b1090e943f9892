//! GPU tests (run on lavapipe in CI). Without an adapter they fail with instructions, unless
//! RADIOSITY_GPU=skip is set.

use radiosity::gpu::{self, GpuContext, INSTALL_HINT, Precision, math};

fn gpu() -> Option<&'static GpuContext> {
    if std::env::var("RADIOSITY_GPU").as_deref() == Ok("skip") {
        eprintln!("RADIOSITY_GPU=skip: GPU test skipped");
        return None;
    }
    match gpu::shared_context() {
        Ok(ctx) => Some(ctx),
        Err(e) => panic!("no usable GPU adapter: {e}\nGPU tests need one: {INSTALL_HINT}"),
    }
}

#[test]
fn f64_math_library_is_within_2_ulp_everywhere() {
    let Some(ctx) = gpu() else { return };
    assert!(ctx.adapter.f64, "adapter {} lacks SHADER_F64", ctx.adapter.name);
    for r in math::measure(ctx, Precision::F64, 200_000).unwrap() {
        println!("{:?}: worst {:.3} ulp at {:?}", r.function, r.worst_ulp, r.worst_at);
        assert!(r.worst_ulp <= 2.0, "{:?}: {} ulp at {:?}", r.function, r.worst_ulp, r.worst_at);
    }
}

use radiosity::assembly::{AssemblyOptions, CollocationMatrix, assemble};
use radiosity::discretization::{Discretization, Method};
use radiosity::mesh::{Mesh, MeshKind, paper_discontinuity_cuts};
use radiosity::scene::{BuiltinScene, SurfaceParameters};
use radiosity::visibility::PairPlanner;

/// Largest difference between two matrices relative to the largest entry of each row.
fn max_row_relative_diff(a: &CollocationMatrix, b: &CollocationMatrix) -> (f64, usize, usize) {
    let mut worst = (0.0, 0, 0);
    for i in 0..a.dof() {
        let scale = a.row(i).iter().fold(0.0f64, |m, v| m.max(v.abs())).max(f64::MIN_POSITIVE);
        for (j, (x, y)) in a.row(i).iter().zip(b.row(i)).enumerate() {
            let d = (x - y).abs() / scale;
            if d > worst.0 {
                worst = (d, i, j);
            }
        }
    }
    worst
}

#[test]
fn gpu_and_cpu_matrices_agree_to_1e_12_in_f64() {
    let Some(ctx) = gpu() else { return };
    let p = SurfaceParameters::default();
    let linear = Method::linear(1.0 / 6.0).unwrap();
    let cases = [
        (BuiltinScene::FourPiece, false, Method::Centroid, 2),
        (BuiltinScene::FivePiece, false, Method::Centroid, 2),
        (BuiltinScene::FivePiece, true, Method::Centroid, 1),
        (BuiltinScene::FourPiece, true, linear, 1),
        (BuiltinScene::FivePiece, false, linear, 1),
        (BuiltinScene::FivePiece, true, linear, 1),
        (BuiltinScene::BaffledBox, false, Method::Centroid, 2),
        (BuiltinScene::BaffledBox, false, linear, 1),
    ];
    for (which, discontinuity, method, refine) in cases {
        let scene = which.build(p).unwrap();
        let kind = if discontinuity {
            MeshKind::Discontinuity(paper_discontinuity_cuts(&scene, &p).unwrap())
        } else {
            MeshKind::Uniform
        };
        let mesh = Mesh::new(&scene, &kind, refine).unwrap();
        let disc = Discretization::new(&scene, &mesh, method).unwrap();
        let planner = PairPlanner::new(&scene);
        let opts = AssemblyOptions::default();
        let cpu = assemble(&mesh, &disc, &planner, &opts, &|_| {}).unwrap();
        let assembler = gpu::GpuAssembler::new(ctx, Precision::F64, method).unwrap();
        let gpu = assembler.assemble(&scene, &mesh, &disc, &planner, &opts, &|_| {}).unwrap();
        assert_eq!(cpu.stats, gpu.stats);
        let (d, i, j) = max_row_relative_diff(&cpu.matrix, &gpu.matrix);
        println!("{which} discontinuity={discontinuity} {method}: max row-relative diff {d:.2e}");
        assert!(
            d <= 1e-12,
            "{which} {method}: entry ({i}, {j}): cpu {} gpu {} (row-relative diff {d:e})",
            cpu.matrix.get(i, j),
            gpu.matrix.get(i, j)
        );
    }
}
