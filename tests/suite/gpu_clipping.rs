//! The device's clipping of the elements of faces seen in part (shaders/clip.wgsl): in the row
//! tiles of the dense assembly, and for the listed pairs of the compressed operator's exact
//! blocks, each against the CPU's pieces and pair classes (run on lavapipe in CI).

use crate::common;

use common::gpu::{gpu, max_row_relative_diff, sliver_scene};
use radiosity::assembly::{AssemblyOptions, Problem, assemble};
use radiosity::discretization::{Discretization, Method};
use radiosity::gpu::{self, GpuContext, Precision};
use radiosity::mesh::{Mesh, MeshKind};
use radiosity::scene::{BuiltinScene, SurfaceParameters};

/// The scenes of the clipping checks at a refinement: occluders of every kind (slats, furniture,
/// baffles, stairs, houses, a box), the tangent plane cutting faces, shadows cutting elements.
fn occluded_cases(refine: u32) -> Vec<(String, radiosity::scene::Scene, u32)> {
    let file = |name: &str| radiosity::scene::load(std::path::Path::new(name)).unwrap();
    let p = SurfaceParameters::default();
    vec![
        ("louvre window".into(), file("examples/louvre-window.toml"), refine),
        ("furnished room".into(), file("examples/furnished-room.toml"), refine.saturating_sub(1)),
        ("baffled box".into(), BuiltinScene::BaffledBox.build(p).unwrap(), refine),
        ("staircase hall".into(), file("examples/staircase-hall.toml"), refine.saturating_sub(1)),
        (
            "city:4x4:lit".into(),
            radiosity::scene::lit_city(4, 4).unwrap(),
            refine.saturating_sub(1),
        ),
        ("occluded box".into(), file("examples/occluded-box.toml"), refine),
    ]
}

/// The GPU assembly of `problem` within `limits`, against the CPU's: the largest entry
/// difference relative to its row's largest entry, the pair classes, and the assembler's timings.
fn clipped_against_cpu(
    ctx: &GpuContext,
    problem: &Problem,
    limits: gpu::TileLimits,
) -> (f64, radiosity::visibility::PairStats, radiosity::visibility::PairStats, gpu::GpuTimings) {
    let opts = AssemblyOptions::default();
    let silent = &radiosity::progress::Silent;
    let cpu = assemble(problem, &opts, silent).unwrap();
    let assembler = gpu::GpuAssembler::new(ctx, Precision::F64, problem.disc.method).unwrap();
    let gpu = assembler.assemble_with_limits(problem, &opts, limits, silent).unwrap();
    let (d, _, _) = max_row_relative_diff(&cpu.matrix, &gpu.matrix);
    (d, cpu.stats, gpu.stats, assembler.last_timings())
}

#[test]
fn the_device_clips_elements_of_faces_seen_in_part_as_the_host_does() {
    // Host planning per (node, face): each element of a face seen in part is clipped and
    // integrated on the device (shaders/clip.wgsl). Same pair classes as the CPU, entries to
    // 1e-12 of their row's largest, and hardly a pair left to the host.
    let Some(ctx) = gpu() else { return };
    let linear = Method::linear(Method::PAPER_ALPHA).unwrap();
    for (method, refine) in [(Method::Centroid, 2), (linear, 2)] {
        for (name, scene, refine) in occluded_cases(refine) {
            let mesh = Mesh::new(&scene, &MeshKind::Uniform, refine).unwrap();
            let disc = Discretization::new(&scene, &mesh, method).unwrap();
            let problem = Problem::new(scene, mesh, disc);
            let (d, cpu, gpu, timings) =
                clipped_against_cpu(ctx, &problem, gpu::TileLimits::default());
            let what = format!("{name} refine {refine} {method}");
            println!(
                "{what}: {d:.2e}, {} pairs clipped on the device",
                timings.pairs_clipped_on_device
            );
            assert_eq!(cpu, gpu, "{what}");
            assert!(d <= 1e-12, "{what}: {d:e}");
            assert!(timings.pairs_clipped_on_device >= cpu.partial, "{what}: {timings:?}");
            // A pair whose pieces outgrow the kernel's stack is the host's: rare.
            let on_host = timings.pairs_clipped_on_host;
            assert!(on_host * 1000 <= timings.pairs_clipped_on_device, "{what}: {timings:?}");
        }
    }
}

#[test]
fn pairs_the_clipping_kernel_cannot_hold_are_clipped_on_the_host() {
    // A stack of one piece leaves every element that a shadow cuts in two to the host, a stack
    // of none every element that a shadow's box and sides may cut; a near list of a few pairs
    // holds fewer than are left, so the host clips all of the tile's (with a small binding, in
    // parts). The matrix and the pair classes stay the CPU's.
    let Some(ctx) = gpu() else { return };
    let linear = Method::linear(Method::PAPER_ALPHA).unwrap();
    let cases = [
        (Method::Centroid, 1, u64::MAX, u64::MAX),
        (Method::Centroid, 0, 8, 16 << 10),
        (linear, 1, 64, u64::MAX),
    ];
    for (method, pieces_on_device, near_pairs, binding_bytes) in cases {
        let scene =
            radiosity::scene::load(std::path::Path::new("examples/louvre-window.toml")).unwrap();
        let mesh = Mesh::new(&scene, &MeshKind::Uniform, 2).unwrap();
        let disc = Discretization::new(&scene, &mesh, method).unwrap();
        let problem = Problem::new(scene, mesh, disc);
        let limits = gpu::TileLimits { pieces_on_device, near_pairs, rows: 64, binding_bytes };
        let (d, cpu, gpu, timings) = clipped_against_cpu(ctx, &problem, limits);
        let what = format!("{method}, {pieces_on_device} pieces");
        assert_eq!(cpu, gpu, "{what}");
        assert!(d <= 1e-12, "{what}: {d:e}");
        assert!(timings.pairs_clipped_on_host > 0, "{what}: {timings:?}");
    }
}

/// The entries of `op`, row-major, column by column from its products with unit vectors.
fn operator_entries(op: &radiosity::operator::CompressedOperator) -> Vec<Vec<f64>> {
    let n = op.dof();
    let mut rows = vec![vec![0.0; n]; n];
    let mut unit = vec![0.0; n];
    for j in 0..n {
        unit[j] = 1.0;
        for (row, v) in rows.iter_mut().zip(op.apply(&unit)) {
            row[j] = v;
        }
        unit[j] = 0.0;
    }
    rows
}

/// The largest entry difference of two matrices (rows), relative to its row's largest entry.
fn max_entry_rel_diff(a: &[Vec<f64>], b: &[Vec<f64>]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(p, q)| {
            let largest = p.iter().fold(0.0f64, |m, v| m.max(v.abs())).max(f64::MIN_POSITIVE);
            p.iter().zip(q).fold(0.0f64, |m, (x, y)| m.max((x - y).abs())) / largest
        })
        .fold(0.0, f64::max)
}

/// The compressed operator of `problem` with every block exact (admissible only where a
/// cluster is a point), built on the CPU block by block and through the GPU's pair evaluator
/// within `limits`: the two operators, and what the evaluator clipped where.
fn exact_operators(
    ctx: &GpuContext,
    problem: &Problem,
    limits: gpu::TileLimits,
) -> (
    radiosity::operator::CompressedOperator,
    radiosity::operator::CompressedOperator,
    gpu::DeviceTraffic,
) {
    use radiosity::assembly::PairEvaluation;
    use radiosity::operator::{CompressedOperator, CompressionOptions};
    let (options, silent) = (AssemblyOptions::default(), &radiosity::progress::Silent);
    let compression = CompressionOptions { tolerance: 1e-12, eta: 1e-9, ..Default::default() };
    let cpu = CompressedOperator::build(problem, &options, &compression, None, silent).unwrap();
    let assembler = gpu::GpuAssembler::new(ctx, Precision::F64, problem.disc.method).unwrap();
    let evaluator = gpu::PairEvaluator::new(&assembler, &problem.scene, &problem.disc, &options)
        .unwrap()
        .limited(limits);
    let batches = Some(&evaluator as &dyn PairEvaluation);
    let gpu = CompressedOperator::build(problem, &options, &compression, batches, silent).unwrap();
    (cpu, gpu, evaluator.traffic())
}

#[test]
fn the_compressed_operators_exact_blocks_are_clipped_on_the_device_as_on_the_host() {
    // Each (node, face) of an exact block seen in part is handed to the device once, with the
    // box tree over the block's elements of the face; the device classifies and clips them as
    // the host's row walk does. Same pair classes as the CPU's build, entries to 1e-12 of their
    // row's largest, hardly a pair left to the host.
    let Some(ctx) = gpu() else { return };
    let linear = Method::linear(Method::PAPER_ALPHA).unwrap();
    for (method, refine) in [(Method::Centroid, 2), (linear, 1)] {
        for (name, scene, refine) in occluded_cases(refine) {
            let mesh = Mesh::new(&scene, &MeshKind::Uniform, refine).unwrap();
            let disc = Discretization::new(&scene, &mesh, method).unwrap();
            let problem = Problem::new(scene, mesh, disc);
            let (cpu, gpu, traffic) = exact_operators(ctx, &problem, gpu::TileLimits::default());
            let what = format!("{name} refine {refine} {method}");
            let d = max_entry_rel_diff(&operator_entries(&cpu), &operator_entries(&gpu));
            println!("{what}: {d:.2e}, {traffic:?}");
            assert_eq!(cpu.pairs, gpu.pairs, "{what}");
            assert!(d <= 1e-12, "{what}: {d:e}");
            assert!(traffic.pairs_clipped_on_device >= cpu.pairs.partial, "{what}: {traffic:?}");
            let on_host = traffic.pairs_clipped_on_host;
            assert!(on_host * 1000 <= traffic.pairs_clipped_on_device, "{what}: {traffic:?}");
        }
    }
}

#[test]
fn listed_pairs_the_clipping_kernel_cannot_hold_are_clipped_on_the_host() {
    // As for the row tiles: a stack of one piece, of none with a list of a few pairs (the host
    // takes every pair of a batch) in small bindings (many batches), and the linear method; then
    // a sliver shelf in a plate's shadow, whose thin elements' pairs are the host's. Classes and
    // entries stay the CPU's.
    let Some(ctx) = gpu() else { return };
    let linear = Method::linear(Method::PAPER_ALPHA).unwrap();
    let louvre = || radiosity::scene::load(std::path::Path::new("examples/louvre-window.toml"));
    // The sliver shelf, shadowed in part from the floor by a plate below it.
    let dir = std::env::temp_dir().join(format!("radiosity-gpu-listed-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let shelf = std::fs::read_to_string(sliver_scene("listed-cuts")).unwrap();
    let plate = "[[faces]]\nname = \"plate\"\n\
                 vertices = [[0.4, 0.3, 0.15], [0.4, 0.7, 0.15], [0.6, 0.7, 0.15], [0.6, 0.3, 0.15]]\n";
    std::fs::write(dir.join("shadowed.toml"), shelf + plate).unwrap();
    let sliver = radiosity::scene::load(&dir.join("shadowed.toml")).unwrap();
    let limits = |pieces_on_device, near_pairs, binding_bytes| gpu::TileLimits {
        pieces_on_device,
        near_pairs,
        binding_bytes,
        ..Default::default()
    };
    let cases = [
        ("louvre window", louvre().unwrap(), Method::Centroid, limits(1, u64::MAX, u64::MAX)),
        ("louvre window", louvre().unwrap(), Method::Centroid, limits(0, 8, 16 << 10)),
        ("louvre window", louvre().unwrap(), linear, limits(1, 64, u64::MAX)),
        ("shadowed sliver shelf", sliver, linear, gpu::TileLimits::default()),
    ];
    for (name, scene, method, limits) in cases {
        let mesh = Mesh::new(&scene, &MeshKind::Uniform, 1).unwrap();
        let disc = Discretization::new(&scene, &mesh, method).unwrap();
        let problem = Problem::new(scene, mesh, disc);
        let (cpu, gpu, traffic) = exact_operators(ctx, &problem, limits);
        let what = format!("{name} {method} {limits:?}");
        let d = max_entry_rel_diff(&operator_entries(&cpu), &operator_entries(&gpu));
        assert_eq!(cpu.pairs, gpu.pairs, "{what}");
        assert!(d <= 1e-12, "{what}: {d:e}");
        assert!(traffic.pairs_clipped_on_host > 0, "{what}: {traffic:?}");
    }
}
