//! GPU tests (run on lavapipe in CI). Without an adapter they fail with instructions, unless
//! RADIOSITY_GPU=skip is set.

use crate::common;

use common::gpu::{gpu, max_row_relative_diff, sliver_scene};
use radiosity::gpu::{self, Precision, math};
use radiosity::pipeline::Backend;

#[test]
fn f32_math_library_is_within_3_ulp_for_normal_numbers() {
    let Some(ctx) = gpu() else { return };
    for r in math::measure(ctx, Precision::F32, 100_000).unwrap() {
        assert!(r.worst_ulp <= 3.0, "{:?}: {} ulp at {:?}", r.function, r.worst_ulp, r.worst_at);
    }
}

#[test]
fn f64_math_library_is_within_2_ulp_on_200_000_samples() {
    let Some(ctx) = gpu() else { return };
    assert!(ctx.adapter.f64, "adapter {} lacks SHADER_F64", ctx.adapter.name);
    for r in math::measure(ctx, Precision::F64, 200_000).unwrap() {
        println!("{:?}: worst {:.3} ulp at {:?}", r.function, r.worst_ulp, r.worst_at);
        assert!(r.worst_ulp <= 2.0, "{:?}: {} ulp at {:?}", r.function, r.worst_ulp, r.worst_at);
    }
}

use radiosity::assembly::{AssemblyOptions, Problem, assemble};
use radiosity::discretization::{Discretization, Method};
use radiosity::mesh::{Mesh, MeshKind, S5Diagonals, paper_discontinuity_cuts};
use radiosity::scene::{BuiltinScene, SurfaceParameters};

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
            MeshKind::Discontinuity(
                paper_discontinuity_cuts(&scene, &p, S5Diagonals::Paper).unwrap(),
            )
        } else {
            MeshKind::Uniform
        };
        let mesh = Mesh::new(&scene, &kind, refine).unwrap();
        let disc = Discretization::new(&scene, &mesh, method).unwrap();
        let problem = Problem::new(scene.clone(), mesh.clone(), disc.clone());
        let opts = AssemblyOptions::default();
        let cpu = assemble(&problem, &opts, &radiosity::progress::Silent).unwrap();
        let assembler = gpu::GpuAssembler::new(ctx, Precision::F64, method).unwrap();
        let gpu = assembler.assemble(&problem, &opts, &radiosity::progress::Silent).unwrap();
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

#[test]
fn f32_kernels_are_within_single_precision_error_of_the_f64_cpu_matrix() {
    let Some(ctx) = gpu() else { return };
    let p = SurfaceParameters::default();
    for method in [Method::Centroid, Method::linear(1.0 / 6.0).unwrap()] {
        let scene = BuiltinScene::FivePiece.build(p).unwrap();
        let mesh = Mesh::new(&scene, &MeshKind::Uniform, 2).unwrap();
        let disc = Discretization::new(&scene, &mesh, method).unwrap();
        let problem = Problem::new(scene.clone(), mesh.clone(), disc.clone());
        let opts = AssemblyOptions::default();
        let cpu = assemble(&problem, &opts, &radiosity::progress::Silent).unwrap();
        let assembler = gpu::GpuAssembler::new(ctx, Precision::F32, method).unwrap();
        let f32 = assembler.assemble(&problem, &opts, &radiosity::progress::Silent).unwrap();
        let (d, i, j) = max_row_relative_diff(&cpu.matrix, &f32.matrix);
        println!("{method}: f32 max row-relative diff {d:.2e}");
        // f32 rounding is 6e-8; near the node the closed forms amplify it where their edge terms
        // cancel (measured: 3.5e-6 centroid, 8.7e-5 linear, where the moments carry logs and the
        // IMT sums); far from it the f32 far-field rule keeps it at rounding level.
        let bound = if method == Method::Centroid { 2e-5 } else { 3e-4 };
        assert!(
            d < bound,
            "{method}: ({i}, {j}): cpu {} f32 {}",
            cpu.matrix.get(i, j),
            f32.matrix.get(i, j)
        );
        assert!(d > 1e-9, "f32 kernels that agree to {d:e} are not running in f32");
    }
}

#[test]
fn the_gpu_column_of_table_4_1_agrees_with_the_exact_cpu_column() {
    let Some(_) = gpu() else { return };
    use radiosity::study::{StudyOptions, run_study};
    let options = StudyOptions {
        max_n: Some(160),
        backend: Some(Backend::Gpu(Precision::F64)),
        progress: Default::default(),
    };
    let result = run_study("table-4.1", &options).unwrap();
    let gpu_rows: Vec<_> = result.rows.iter().filter(|r| r.label.backend == "gpu").collect();
    assert_eq!(gpu_rows.len(), 3, "n = 10, 40, 160");
    for r in gpu_rows {
        assert_eq!(r.label.quadrature.name(), "exact");
        let difference = r.integration_error.expect("compared with the exact CPU run");
        assert!(difference < 1e-13, "n = {}: {difference:e}", r.label.n);
    }
}

#[test]
fn studies_on_the_gpu_print_the_cpu_errors() {
    let Some(_) = gpu() else { return };
    use radiosity::study::{StudyOptions, run_study};
    let options =
        |backend| StudyOptions { max_n: Some(160), backend, progress: Default::default() };
    for id in ["table-3.1", "table-3.4"] {
        let cpu = run_study(id, &options(Some(Backend::Cpu))).unwrap();
        let gpu = run_study(id, &options(Some(Backend::Gpu(Precision::F64)))).unwrap();
        assert_eq!(cpu.rows.len(), gpu.rows.len());
        for (c, g) in cpu.rows.iter().zip(&gpu.rows) {
            assert_eq!(g.label.backend, "gpu");
            assert!(
                (c.error - g.error).abs() <= 1e-10 * c.error,
                "{id} n = {}: {} vs {}",
                c.label.n,
                c.error,
                g.error
            );
        }
    }
}

#[test]
fn tiles_and_a_full_near_list_give_the_same_matrix() {
    // The tile size follows the device's binding limit and the near list its capacity: force
    // several tiles and a near list too small for the tile's pairs.
    let Some(ctx) = gpu() else { return };
    let p = SurfaceParameters::default();
    let scene = BuiltinScene::BaffledBox.build(p).unwrap();
    let mesh = Mesh::new(&scene, &MeshKind::Uniform, 3).unwrap();
    let method = Method::linear(1.0 / 6.0).unwrap();
    let disc = Discretization::new(&scene, &mesh, method).unwrap();
    let problem = Problem::new(scene.clone(), mesh.clone(), disc.clone());
    let opts = AssemblyOptions::default();
    let assembler = gpu::GpuAssembler::new(ctx, Precision::F64, method).unwrap();
    let limits = gpu::TileLimits { rows: 97, near_pairs: 100, ..Default::default() };
    let gpu = assembler
        .assemble_with_limits(&problem, &opts, limits, &radiosity::progress::Silent)
        .unwrap();
    assert!(assembler.last_timings().tiles > 1);
    let cpu = assemble(&problem, &opts, &radiosity::progress::Silent).unwrap();
    let (d, _, _) = max_row_relative_diff(&cpu.matrix, &gpu.matrix);
    assert!(d <= 1e-12, "{d:e}");
    // Closed box: rows of K/rho sum to 1.
    for (i, node) in disc.nodes().enumerate() {
        let s: f64 = gpu.matrix.row(i).iter().sum::<f64>() / node.rho;
        assert!((s - 1.0).abs() < 1e-11, "row {i}: {s}");
    }
}

#[test]
fn tiles_are_sized_by_the_views_of_a_scene_of_many_faces() {
    // A city has many faces and few elements per face: a tile's views of every face outweigh
    // its output rows. With a 64 KiB binding (as a device of 128 MiB would see a scene of 10 000
    // faces) tiles sized by their output alone held 256 KiB of views and were refused.
    let Some(ctx) = gpu() else { return };
    let scene = radiosity::scene::city(3, 3).unwrap();
    let mesh = Mesh::new(&scene, &MeshKind::Uniform, 0).unwrap();
    let disc = Discretization::new(&scene, &mesh, Method::Centroid).unwrap();
    let problem = Problem::new(scene.clone(), mesh.clone(), disc.clone());
    let opts = AssemblyOptions::default();
    let assembler = gpu::GpuAssembler::new(ctx, Precision::F64, Method::Centroid).unwrap();
    let limits = gpu::TileLimits { binding_bytes: 64 << 10, ..Default::default() };
    let gpu = assembler
        .assemble_with_limits(&problem, &opts, limits, &radiosity::progress::Silent)
        .unwrap();
    assert!(assembler.last_timings().tiles > 10, "{} tiles", assembler.last_timings().tiles);
    let cpu = assemble(&problem, &opts, &radiosity::progress::Silent).unwrap();
    let (d, _, _) = max_row_relative_diff(&cpu.matrix, &gpu.matrix);
    assert!(d <= 1e-12, "{d:e}");
}

#[test]
fn tiles_whose_visible_pieces_outgrow_a_binding_are_split() {
    // The occluded box has many partly visible pairs: the visible pieces of a tile (the f32
    // kernels take the host's) are known only once it is planned, and with a 12 KiB binding
    // several tiles sized by their output rows hold more pieces than that. They are split and
    // planned again instead of refused.
    let Some(ctx) = gpu() else { return };
    let scene = radiosity::scene::load(std::path::Path::new("examples/occluded-box.toml")).unwrap();
    let mesh = Mesh::new(&scene, &MeshKind::Uniform, 2).unwrap();
    let disc = Discretization::new(&scene, &mesh, Method::Centroid).unwrap();
    let problem = Problem::new(scene.clone(), mesh.clone(), disc.clone());
    let opts = AssemblyOptions::default();
    let assembler = gpu::GpuAssembler::new(ctx, Precision::F32, Method::Centroid).unwrap();
    let binding: u64 = 12 << 10;
    let limits = gpu::TileLimits { binding_bytes: binding, ..Default::default() };
    let gpu = assembler
        .assemble_with_limits(&problem, &opts, limits, &radiosity::progress::Silent)
        .unwrap();
    // Tiles sized by their output alone: 5 rows of 576 entries each.
    let by_output = disc.dof().div_ceil((binding / (4 * disc.dof() as u64)) as usize);
    let tiles = assembler.last_timings().tiles;
    assert!(tiles > by_output, "{tiles} tiles, as many as the output alone needs ({by_output})");
    let whole = assembler.assemble(&problem, &opts, &radiosity::progress::Silent).unwrap();
    let (d, _, _) = max_row_relative_diff(&whole.matrix, &gpu.matrix);
    assert_eq!(d, 0.0, "split tiles give other values than whole ones");
    assert!(assembler.last_timings().pairs_clipped_on_host > 0);
}

/// `radiosity bench` of `scene` at refine `refine`, one repetition, with `extra` options, as JSON.
fn bench_json(scene: &str, method: &str, refine: &str, extra: &[&str]) -> serde_json::Value {
    let mut args =
        vec!["bench", "--scene", scene, "--method", method, "--refine", refine, "--repeats", "1"];
    args.extend_from_slice(extra);
    args.extend_from_slice(&["--json", "-"]);
    common::json(&args)
}

/// `radiosity bench` of `scene` at refine 1, one repetition, as JSON.
fn bench_once(scene: &str, method: &str) -> serde_json::Value {
    bench_json(scene, method, "1", &[])
}

#[test]
fn bench_prints_per_backend_timings_and_differences_as_json() {
    let Some(_) = gpu() else { return };
    let v = bench_once("five-piece", "linear");
    for backend in ["cpu", "gpu"] {
        for key in ["setup_seconds", "pairs_per_second"] {
            assert!(v[backend][key].as_f64().unwrap() > 0.0, "{backend}.{key}: {v}");
        }
    }
    assert!(v["device"].as_str().unwrap().contains('('), "{v}");
    assert!(v["speedup"].as_f64().unwrap() > 0.0);
    // The host's share: the GPU path's planning over the CPU's whole setup.
    let planning = v["gpu"]["breakdown"]["planning_seconds"].as_f64().unwrap();
    let share = v["host_share"].as_f64().unwrap();
    assert!(
        (share - planning / v["cpu"]["setup_seconds"].as_f64().unwrap()).abs() <= 1e-12 * share
    );
    assert!(v["max_rel_diff"].as_f64().unwrap() <= 1e-12, "{v}");
    assert!(v["max_abs_diff"].as_f64().unwrap() <= 1e-12, "{v}");
}

#[test]
fn the_stability_study_passes_its_bounds_on_the_gpu_in_f64_and_f32() {
    let Some(_) = gpu() else { return };
    let result =
        radiosity::study::stability::run_stability(Some(Backend::Gpu(Precision::F64))).unwrap();
    for precision in ["f64", "f32"] {
        let rows: Vec<_> =
            result.rows.iter().filter(|r| r.backend == "gpu" && r.precision == precision).collect();
        assert!(rows.len() >= 20, "{precision}: {} rows", rows.len());
        for r in rows {
            assert!(
                r.passed,
                "{} ({}, gpu {precision}): {} > {}",
                r.case, r.method, r.relative_error, r.bound
            );
        }
    }
    assert_eq!(result.failed, 0);
}

#[test]
fn a_scene_file_with_occluders_assembles_on_the_gpu_as_on_the_cpu() {
    let Some(_) = gpu() else { return };
    for method in ["centroid", "linear"] {
        let v = bench_once("examples/furnished-room.toml", method);
        assert!(v["max_rel_diff"].as_f64().unwrap() <= 1e-12, "{method}: {v}");
    }
}

#[test]
fn a_scene_far_from_the_origin_assembles_on_the_gpu_within_the_usual_tolerance() {
    let Some(_) = gpu() else { return };
    let dir = std::env::temp_dir().join(format!("radiosity-gpu-far-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let scene = common::translated_scene("examples/occluded-box.toml", [-3e7, 0.0, 2e3], &dir);
    // The f32 bound is the one of the paper's surfaces at the origin (centroid method).
    for (precision, bound) in [("f64", 1e-12), ("f32", 2e-5)] {
        let v = common::json(&[
            "bench",
            "--scene",
            scene.to_str().unwrap(),
            "--refine",
            "1",
            "--repeats",
            "1",
            "--precision",
            precision,
            "--json",
            "-",
        ]);
        assert!(v["max_rel_diff"].as_f64().unwrap() <= bound, "{precision}: {v}");
    }
}

/// `bench` times the matrix `solve` uses: on the GPU, the columns of thin elements (where the
/// closed forms cancel) are recomputed on the CPU in both. Before, `bench` skipped that step and
/// its GPU matrix differed from the CPU's by 5.4e-11 here (linear method).
#[test]
fn bench_assembles_what_solve_assembles_also_on_thin_elements() {
    let Some(_) = gpu() else { return };
    let scene = sliver_scene("thin");
    let v = bench_once(scene.to_str().unwrap(), "linear");
    assert!(v["max_rel_diff"].as_f64().unwrap() <= 1e-13, "{v}");
    assert!(v["gpu"]["preparation_seconds"].as_f64().unwrap() > 0.0, "{v}");
}

#[test]
fn gpu_check_runs_more_samples_than_one_dispatch_holds() {
    let Some(_) = gpu() else { return };
    // 65 535 workgroups of 64 invocations hold 4 194 240 samples: more need several dispatches.
    let v = common::json(&["gpu-check", "--samples", "4500000", "--json", "-"]);
    let functions = v["functions"].as_array().unwrap();
    assert_eq!(functions.len(), 7);
    for f in functions {
        assert_eq!(f["samples"], 4_500_000, "{f}");
        assert!(f["worst_ulp"].as_f64().unwrap() <= 3.0, "{f}");
    }
}

/// `bench --operator compressed --backends cpu,gpu` of `scene`, one repetition, as JSON.
fn bench_compressed(scene: &str, method: &str, refine: &str, tolerance: &str) -> serde_json::Value {
    let extra = ["--operator", "compressed", "--compression-tolerance", tolerance];
    bench_json(scene, method, refine, &[&extra[..], &["--backends", "cpu,gpu"]].concat())
}

/// The compressed operator built by the GPU's pair kernel (exact blocks in batches, cross
/// approximations in lockstep) against the one built on the CPU: their products agree to 1e-10
/// relative, and both are within 10 x the tolerance of the dense matrix; on the paper's surface,
/// with occluders (partly visible pairs with their pieces), for both methods, and on thin
/// elements (recomputed on the CPU, as in the dense GPU path).
#[test]
fn the_compressed_operator_built_on_the_gpu_matches_the_one_built_on_the_cpu() {
    let Some(_) = gpu() else { return };
    let sliver = sliver_scene("compressed");
    let cases = [
        ("five-piece", "centroid", "3", 1e-6, true),
        ("five-piece", "centroid", "3", 1e-12, true),
        // Before pivots were chosen among near-ties by index, the two differed here by 1.4e-7:
        // entries equal by symmetry, rounded differently, chose different pivots.
        ("five-piece", "linear", "4", 1e-6, true),
        ("baffled-box", "centroid", "3", 1e-6, true),
        ("examples/occluded-box.toml", "centroid", "2", 1e-6, false),
        (sliver.to_str().unwrap(), "linear", "2", 1e-6, false),
    ];
    for (scene, method, refine, tolerance, far) in cases {
        let v = bench_compressed(scene, method, refine, &tolerance.to_string());
        let what = format!("{scene} {method} refine {refine} tolerance {tolerance:e}");
        assert_eq!(v["backend"], "cpu", "{what}: {v}");
        let gpu = &v["gpu"];
        assert!(gpu["device"].as_str().unwrap().contains('('), "{what}: {v}");
        let diff = gpu["max_product_rel_diff"].as_f64().unwrap();
        assert!(diff <= 1e-10, "{what}: gpu and cpu differ by {diff:e}: {v}");
        let dense = v["max_product_rel_diff"].as_f64().unwrap();
        assert!(dense <= 10.0 * tolerance, "{what}: {dense:e} from the dense matrix: {v}");
        if far {
            assert!(v["far_blocks"].as_u64().unwrap() > 0, "{what}: no low-rank block: {v}");
        }
        // The cross approximations advance together, a round of every block's next rows or
        // columns per submission: fewer submissions than two per approximated block.
        let approximated = ["far_blocks", "incompressible_blocks"].map(|k| v[k].as_u64().unwrap());
        let submissions = gpu["gpu_submissions"].as_u64().unwrap();
        assert!(submissions > 0, "{what}: {v}");
        if approximated.iter().sum::<u64>() > 20 {
            let most = 2 * approximated.iter().sum::<u64>();
            assert!(submissions < most, "{what}: {submissions} submissions: {v}");
        }
    }
}

/// The scenes of the device-resident checks: the paper's surface (both methods), a room with
/// furniture, a box with baffles, a room lit by a black lamp (rho = 0: rows of zeros), and a
/// sliver shelf (thin elements, whose columns come from the host).
fn resident_cases() -> Vec<(&'static str, Problem)> {
    let sliver = sliver_scene("resident");
    let scene = |name: &str| match name.strip_prefix("examples/") {
        Some(_) => radiosity::scene::load(std::path::Path::new(name)).unwrap(),
        None => {
            let builtin = BuiltinScene::ALL.iter().find(|b| b.name() == name).unwrap();
            builtin.build(SurfaceParameters::default()).unwrap()
        }
    };
    let problem = |name: &'static str, method: Method, refine: u32| {
        let scene = match name {
            "sliver" => radiosity::scene::load(&sliver).unwrap(),
            _ => scene(name),
        };
        let mesh = Mesh::new(&scene, &MeshKind::Uniform, refine).unwrap();
        let disc = Discretization::new(&scene, &mesh, method).unwrap();
        (name, Problem::new(scene, mesh, disc))
    };
    vec![
        problem("five-piece", Method::Centroid, 3),
        problem("five-piece", Method::linear(Method::PAPER_ALPHA).unwrap(), 2),
        problem("examples/furnished-room.toml", Method::Centroid, 1),
        problem("baffled-box", Method::Centroid, 2),
        problem("examples/louvre-room.toml", Method::Centroid, 1),
        problem("sliver", Method::linear(Method::PAPER_ALPHA).unwrap(), 1),
    ]
}

#[test]
fn gmres_on_the_device_resident_matrix_equals_gmres_on_the_host() {
    // The same GPU-built matrix, read back and solved by the host's GMRES, or kept on the
    // device with GMRES's products there (thin columns from the host): u to 1e-12.
    use radiosity::solve::{self, SolverChoice, SolverOptions};
    let Some(ctx) = gpu() else { return };
    let options = AssemblyOptions::default();
    let silent = &radiosity::progress::Silent;
    for (name, problem) in resident_cases() {
        let method = problem.disc.method;
        let assembler = gpu::GpuAssembler::new(ctx, Precision::F64, method).unwrap();
        let mut host = assembler.assemble(&problem, &options, silent).unwrap();
        radiosity::assembly::recompute_thin_columns(&mut host, &problem, &options);
        let device =
            gpu::DeviceOperator::assemble(&assembler, &problem, &options, Precision::F64, silent)
                .unwrap();
        assert_eq!(host.stats, device.stats, "{name}");
        let thin = radiosity::assembly::ThinColumns::new(&problem, &options);
        assert_eq!(thin.is_some(), name == "sliver", "{name}: thin columns");
        let e: Vec<f64> = (0..problem.disc.dof()).map(|i| 1.0 + (i as f64 * 0.37).sin()).collect();
        let iterative = SolverOptions::with(SolverChoice::Iterative);
        let on_host = solve::solve_many(&host.matrix, &[&e], iterative).unwrap().pop().unwrap();
        let rho: Vec<f64> = problem.disc.nodes().map(|n| n.rho).collect();
        let on_device =
            solve::solve_by_products(&device, &e, (&rho, &rho), iterative, 0.0).unwrap();
        let scale = on_host.u.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        let d = on_host.u.iter().zip(&on_device.u).fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
        assert!(d <= 1e-12 * scale, "{name} ({method}): u differs by {:.2e}", d / scale);
        // The product itself, against the host's matrix.
        let kx = device.apply_many(&[&e]).unwrap().pop().unwrap();
        let want = host.matrix.apply(&e);
        let scale = want.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        let d = kx.iter().zip(&want).fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
        assert!(d <= 1e-14 * scale, "{name} ({method}): K x differs by {:.2e}", d / scale);
    }
}

#[test]
fn k_stored_in_f32_on_the_device_reports_the_error_it_adds() {
    // The error the f32 storage reports is the one the f64 matrix's entries take when rounded
    // (computed here on the host from the same kernels' matrix), and the solution moves from
    // the f64 one by no more than the reported bound.
    use radiosity::solve::{self, SolverChoice, SolverOptions};
    let Some(ctx) = gpu() else { return };
    let (options, silent) = (AssemblyOptions::default(), &radiosity::progress::Silent);
    for (name, problem) in resident_cases().into_iter().filter(|(n, _)| *n != "sliver") {
        let assembler = gpu::GpuAssembler::new(ctx, Precision::F64, problem.disc.method).unwrap();
        let host = assembler.assemble(&problem, &options, silent).unwrap();
        let f32 = Precision::F32;
        let device = gpu::DeviceOperator::assemble(&assembler, &problem, &options, f32, silent);
        let device = device.unwrap();
        let dof = problem.disc.dof();
        let (mut k, mut d) = (0.0f64, 0.0f64);
        for i in 0..dof {
            let row = host.matrix.row(i);
            k = k.max(row.iter().map(|v| v.abs()).sum());
            d = d.max(row.iter().map(|&v| (v - v as f32 as f64).abs()).sum());
        }
        let s = device.storage;
        assert_eq!(s.storage, f32, "{name}");
        assert!(d > 0.0 && (s.matrix - d / k).abs() <= 1e-12 * (d / k), "{name}: {s:?}");
        assert!(s.matrix < 1e-7, "{name}: {s:?}");
        let bound = s.solution_bound.expect("||K|| < 1 in these scenes");
        let e: Vec<f64> = (0..dof).map(|i| 1.0 + (i as f64 * 0.37).sin()).collect();
        let rho: Vec<f64> = problem.disc.nodes().map(|n| n.rho).collect();
        let solver =
            SolverOptions { tolerance: 1e-13, ..SolverOptions::with(SolverChoice::Iterative) };
        let wide = solve::solve_many(&host.matrix, &[&e], solver).unwrap().pop().unwrap();
        let narrow = solve::solve_by_products(&device, &e, (&rho, &rho), solver, 0.0).unwrap();
        let scale = narrow.u.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        let moved = wide.u.iter().zip(&narrow.u).fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
        assert!(moved > 0.0, "{name}: f32 storage changed nothing");
        assert!(
            moved <= bound * scale + 1e-11 * scale,
            "{name}: {:.2e} > {bound:.2e}",
            moved / scale
        );
    }
}

#[test]
fn f32_storage_is_reported_and_refused_where_k_is_not_kept_on_the_device() {
    if gpu().is_none() {
        return;
    }
    let args = ["solve", "--scene", "five-piece", "--refine", "2", "--storage", "f32"];
    let json = common::json(
        &[&args[..], &["--backend", "gpu", "--solver", "iterative", "--json", "-"]].concat(),
    );
    assert_eq!(json["operator_location"], "device", "{json}");
    assert_eq!(json["storage"], "f32", "{json}");
    let error = json["storage_error"].as_f64().unwrap();
    assert!(error > 0.0 && error < 1e-7, "{json}");
    assert!(json["storage_solution_bound"].as_f64().unwrap() >= error, "{json}");
    for refused in [&["--backend", "cpu"][..], &["--backend", "gpu", "--solver", "lu"]] {
        let (ok, _, err) = common::radiosity(&[&args[..], refused].concat());
        assert!(!ok);
        assert!(err.contains("storage") && err.contains("--solver iterative"), "{err}");
    }
}

#[test]
fn a_device_resident_solve_reads_back_vectors_not_the_matrix() {
    // five-piece refine 4 (2 560 unknowns): the matrix is 52 MB, 12.8 times what the vectors
    // of 200 products would be; what comes back is one vector per product.
    if gpu().is_none() {
        return;
    }
    let args = ["solve", "--scene", "five-piece", "--refine", "4", "--solver", "iterative"];
    let json = common::json(&[&args[..], &["--backend", "gpu", "--json", "-"]].concat());
    let dof = json["dof"].as_u64().unwrap();
    assert_eq!(json["operator_location"], "device", "{json}");
    let read_back = json["bytes_read_back"].as_u64().unwrap();
    assert!(read_back > 0 && read_back <= 200 * dof * 8, "read back {read_back} bytes: {json}");
    assert!(json["bytes_uploaded"].as_u64().unwrap() > 0);
    assert!(json["gpu_submissions"].as_u64().unwrap() > json["iterations"].as_u64().unwrap());
    let idle = json["device_idle_fraction"].as_f64().unwrap();
    assert!((0.0..=1.0).contains(&idle), "{json}");
    // E_n as the CPU's matrix gives it (0.5114, Table 3.1 at n = 2 560).
    let cpu = common::json(&[&args[..], &["--json", "-"]].concat());
    let (error, expected) = (json["error"].as_f64().unwrap(), cpu["error"].as_f64().unwrap());
    assert!((error - expected).abs() <= 1e-9 * expected, "E_n {error} against {expected}");
    assert_eq!(format!("{error:.4}"), "0.5114");
    // Read back, the matrix itself comes over (at refine 3).
    let small = ["solve", "--scene", "five-piece", "--refine", "3", "--backend", "gpu"];
    let host = common::json(&[&small[..], &["--solver", "lu", "--json", "-"]].concat());
    assert_eq!(host["operator_location"], "host");
    assert_eq!(host["bytes_read_back"].as_u64().unwrap(), 640 * 640 * 8);
}

#[test]
fn the_compressed_operator_on_the_device_gives_the_host_product() {
    // Exact blocks (dense and sparse rows) and low-rank factors uploaded once; the device's
    // product equals the host's to 1e-13 (relative max) on the resident checks' scenes.
    use radiosity::operator::packed::{self, DESCRIPTOR};
    use radiosity::operator::{CompressedOperator, CompressionOptions};
    if gpu().is_none() {
        return;
    }
    let (options, silent) = (AssemblyOptions::default(), &radiosity::progress::Silent);
    let compression = CompressionOptions { tolerance: 1e-8, ..Default::default() };
    let (mut kinds, mut most_parts) = ([0usize; 3], 0);
    for (name, problem) in resident_cases() {
        let op = CompressedOperator::build(&problem, &options, &compression, None, silent).unwrap();
        let p = op.packed().unwrap();
        for d in p.indices[..p.blocks * DESCRIPTOR].chunks_exact(DESCRIPTOR) {
            kinds[d[packed::field::KIND] as usize] += 1;
        }
        let device = radiosity::pipeline::compressed_on_device(&op, None).unwrap();
        assert_eq!(device.parts(), 1, "{name}");
        let d = op.max_product_difference(&|x| device.apply_many(&[x]).unwrap().pop().unwrap());
        assert!(d <= 1e-13, "{name}: products differ by {d:.2e}");
        // Split over bindings of a quarter of the values (or the least that holds each block),
        // as an operator larger than the device's binding limit is.
        let mut limit = 2 * p.values.len() as u64;
        while op.packed_parts(limit).is_none() {
            limit *= 2;
        }
        let split = radiosity::pipeline::compressed_on_device(&op, Some(limit)).unwrap();
        most_parts = most_parts.max(split.parts());
        let d = op.max_product_difference(&|x| split.apply_many(&[x]).unwrap().pop().unwrap());
        assert!(d <= 1e-13, "{name} in {} parts: products differ by {d:.2e}", split.parts());
    }
    assert!(kinds.iter().all(|&k| k > 0), "dense, sparse and low-rank blocks met: {kinds:?}");
    assert!(most_parts >= 3, "operators split in at most {most_parts} parts");
}

#[test]
fn generated_scenes_assemble_on_the_gpu_as_on_the_cpu() {
    // Closed rooms with floating boxes, louvres, cities of rotated buildings far from the origin
    // and slivers touching walls (tests/common/generated.rs), both methods.
    use radiosity::scene::generated::{city, louvre, room_with_boxes, slivers_touching_walls};
    let Some(ctx) = gpu() else { return };
    let scenes = [room_with_boxes(0), louvre(1), city(0), slivers_touching_walls(2)];
    for scene in scenes {
        for (method, refine) in [(Method::Centroid, 2), (Method::linear(1.0 / 6.0).unwrap(), 1)] {
            let mesh = Mesh::new(&scene, &MeshKind::Uniform, refine).unwrap();
            let disc = Discretization::new(&scene, &mesh, method).unwrap();
            let problem = Problem::new(scene.clone(), mesh, disc);
            let opts = AssemblyOptions::default();
            let cpu = assemble(&problem, &opts, &radiosity::progress::Silent).unwrap();
            let assembler = gpu::GpuAssembler::new(ctx, Precision::F64, method).unwrap();
            let gpu = assembler.assemble(&problem, &opts, &radiosity::progress::Silent).unwrap();
            let (d, i, j) = max_row_relative_diff(&cpu.matrix, &gpu.matrix);
            assert!(
                d <= 1e-12,
                "{} {method}: entry ({i}, {j}): cpu {} gpu {} (row-relative diff {d:e})",
                scene.name,
                cpu.matrix.get(i, j),
                gpu.matrix.get(i, j)
            );
        }
    }
}
