//! Whole runs timed in one process: `radiosity bench` (here) and `radiosity bench-plan` ([`plan`]).
//!
//! `radiosity bench`: the same matrix assembled on each backend, timed in one run, and compared
//! entry by entry. It is the matrix `solve` uses: the same [`Assembler`] (on the GPU, thin
//! elements' columns recomputed on the CPU). Timings exclude one-time costs (device creation, shader compilation), which are
//! reported apart, and are the best of several repetitions.

pub mod plan;

pub use plan::{PlanBench, PlanTiming, bench_plan};

use std::time::Instant;

use serde::Serialize;

use crate::assembly::{AssemblyOptions, CollocationMatrix};
use crate::error::Result;
use crate::gpu::GpuTimings;
use crate::pipeline::{self, Assembler, Backend, Problem, RunConfig};
use crate::progress::Silent;

/// One backend's figures.
#[derive(Clone, Debug, Serialize)]
pub struct BackendTiming {
    /// `f64` or `f32`.
    pub precision: &'static str,
    /// Best assembly time over the repetitions (plan, kernels, transfers).
    pub setup_seconds: f64,
    /// All (node, element) pairs divided by `setup_seconds`.
    pub pairs_per_second: f64,
    /// One-time cost before the first assembly (GPU: device and shader compilation).
    pub preparation_seconds: f64,
    /// GPU: where the best assembly's time went.
    pub breakdown: Option<GpuTimings>,
}

/// The bench result.
#[derive(Clone, Debug, Serialize)]
pub struct BenchReport {
    /// Scene.
    pub scene: String,
    /// Mesh kind.
    pub mesh: &'static str,
    /// Method.
    pub method: &'static str,
    /// Elements.
    pub n: usize,
    /// Unknowns.
    pub dof: usize,
    /// All (node, element) pairs.
    pub pairs: u64,
    /// Pairs that needed a collocation integral (fully or partly visible).
    pub pairs_evaluated: u64,
    /// The GPU adapter, when the GPU ran.
    pub device: Option<String>,
    /// The CPU backend's figures.
    pub cpu: Option<BackendTiming>,
    /// The GPU backend's figures.
    pub gpu: Option<BackendTiming>,
    /// CPU time / GPU time, when both ran.
    pub speedup: Option<f64>,
    /// The GPU path's host planning over the CPU's whole setup, when both ran: at 1 or more the
    /// host alone takes as long as the CPU's whole assembly, whatever the device's speed.
    pub host_share: Option<f64>,
    /// Largest |K_cpu - K_gpu|, when both ran.
    pub max_abs_diff: Option<f64>,
    /// Largest |K_cpu - K_gpu| relative to the largest |K_cpu| entry of its row, when both ran.
    pub max_rel_diff: Option<f64>,
    /// Largest `||K_cpu - K_gpu||_∞` of a row relative to `||K_cpu||_1` of that row (the bound on
    /// the relative change of `(K u)_i` for u of one sign), when both ran. Unlike
    /// `max_rel_diff` it does not grow with n: entries of size h² carry the closed forms'
    /// absolute rounding of O(1) terms on both backends (docs/gpu.md).
    pub max_row_norm_rel_diff: Option<f64>,
    /// Repetitions per backend.
    pub repeats: usize,
}

/// Differences between two matrices of one size.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct MatrixDifferences {
    /// Largest `|a_ij - b_ij|`.
    pub abs: f64,
    /// Largest `|a_ij - b_ij| / max_j |a_ij|`.
    pub row_max_relative: f64,
    /// Largest `|a_ij - b_ij| / sum_j |a_ij|`.
    pub row_norm_relative: f64,
}

/// Largest absolute and row-relative differences between two matrices of one size.
pub fn matrix_differences(a: &CollocationMatrix, b: &CollocationMatrix) -> MatrixDifferences {
    let mut diff = MatrixDifferences::default();
    for i in 0..a.dof() {
        let (max, sum) =
            a.row(i).iter().fold((0.0f64, 0.0), |(m, s), v| (m.max(v.abs()), s + v.abs()));
        let d = a.row(i).iter().zip(b.row(i)).fold(0.0f64, |m, (x, y)| m.max((x - y).abs()));
        diff.abs = diff.abs.max(d);
        if max > 0.0 {
            diff.row_max_relative = diff.row_max_relative.max(d / max);
            diff.row_norm_relative = diff.row_norm_relative.max(d / sum);
        }
    }
    diff
}

/// Assembles the matrix of `config` for `problem` on each of `backends`, `repeats` times each
/// (the pair planner built once, outside the timings).
pub fn run(
    config: &RunConfig,
    problem: &Problem,
    backends: &[Backend],
    repeats: usize,
) -> Result<BenchReport> {
    let Problem { scene, mesh, disc, .. } = problem;
    let options: &AssemblyOptions = &config.assembly;
    let repeats = repeats.max(1);
    let mut report = BenchReport {
        scene: scene.name.clone(),
        mesh: config.mesh.name(),
        method: config.method.name(),
        n: mesh.len(),
        dof: disc.dof(),
        pairs: (disc.dof() * mesh.len()) as u64,
        pairs_evaluated: 0,
        device: None,
        cpu: None,
        gpu: None,
        speedup: None,
        host_share: None,
        max_abs_diff: None,
        max_rel_diff: None,
        max_row_norm_rel_diff: None,
        repeats,
    };
    let mut matrices: Vec<CollocationMatrix> = Vec::new();
    for &backend in backends {
        let started = Instant::now();
        let assembler = Assembler::new(backend, disc.method, options.quadrature)?;
        let preparation_seconds = started.elapsed().as_secs_f64();
        if let Assembler::Gpu(g) = &assembler {
            let a = &g.context().adapter;
            report.device = Some(format!("{} ({}, {})", a.name, a.backend, a.device_type));
        }
        let mut best = f64::INFINITY;
        let mut breakdown = None;
        let mut last = None;
        for _ in 0..repeats {
            let started = Instant::now();
            let a = assembler.assemble(problem, options, &Silent)?;
            let elapsed = started.elapsed().as_secs_f64();
            if elapsed < best {
                best = elapsed;
                breakdown = assembler.last_timings();
            }
            last = Some(a);
        }
        let a = last.expect("at least one repetition");
        report.pairs_evaluated = a.stats.full + a.stats.partial;
        let timing = BackendTiming {
            precision: backend.precision().name(),
            setup_seconds: best,
            pairs_per_second: report.pairs as f64 / best,
            preparation_seconds,
            breakdown,
        };
        match backend {
            Backend::Cpu => report.cpu = Some(timing),
            Backend::Gpu(_) => report.gpu = Some(timing),
        }
        matrices.push(a.matrix);
    }
    if let (Some(c), Some(g)) = (&report.cpu, &report.gpu) {
        report.speedup = Some(c.setup_seconds / g.setup_seconds);
        report.host_share = g.breakdown.map(|b| b.planning_seconds / c.setup_seconds);
        let cpu_index = backends.iter().position(|b| *b == Backend::Cpu).expect("cpu ran");
        let gpu_index = 1 - cpu_index;
        let diff = matrix_differences(&matrices[cpu_index], &matrices[gpu_index]);
        report.max_abs_diff = Some(diff.abs);
        report.max_rel_diff = Some(diff.row_max_relative);
        report.max_row_norm_rel_diff = Some(diff.row_norm_relative);
    }
    Ok(report)
}

/// `bench --operator compressed`: the compressed operator's build timed (best of `repeats`)
/// against the dense assembly on the CPU where the dense matrix fits, and their products compared;
/// with a second backend (the GPU) its build timed against the first and their products compared.
#[derive(Clone, Debug, Serialize)]
pub struct CompressedBenchReport {
    /// Scene.
    pub scene: String,
    /// Backend of the build the main figures describe (`cpu`, or `gpu` when only it is named).
    pub backend: &'static str,
    /// Its GPU (name and backend), when the GPU built it.
    pub device: Option<String>,
    /// Method.
    pub method: &'static str,
    /// Elements.
    pub n: usize,
    /// Unknowns.
    pub dof: usize,
    /// Always `compressed`.
    pub operator: &'static str,
    /// Relative tolerance of the low-rank blocks.
    pub compression_tolerance: f64,
    /// Best build time of the compressed operator.
    pub setup_seconds: f64,
    /// Memory of the compressed operator.
    pub operator_bytes: u64,
    /// Its block statistics.
    #[serde(flatten)]
    pub blocks: crate::operator::OperatorStats,
    /// Best dense assembly time on the CPU, when the dense matrix fits (at most
    /// [`DENSE_BENCH_LIMIT`] unknowns).
    pub dense_setup_seconds: Option<f64>,
    /// Dense time / compressed time.
    pub speedup: Option<f64>,
    /// Largest `max_i |(K_c x - K x)_i| / max_i |(K x)_i|` over three vectors (ones, one of one
    /// sign, one of both signs), against the dense matrix.
    pub max_product_rel_diff: Option<f64>,
    /// The same operator built on the GPU, when both backends are benched.
    pub gpu: Option<CompressedGpuBench>,
    /// Peak resident memory of the process.
    pub peak_rss_bytes: Option<u64>,
    /// Repetitions.
    pub repeats: usize,
    /// The ranks of a distributed run (`ranks`, `per_rank`, ...; the dense reference is built
    /// by every rank).
    #[serde(flatten, skip_serializing_if = "Option::is_none")]
    pub distributed: Option<crate::distributed::DistributedReport>,
}

/// The compressed operator built on the GPU beside the CPU's.
#[derive(Clone, Debug, Serialize)]
pub struct CompressedGpuBench {
    /// The GPU (name and backend).
    pub device: Option<String>,
    /// Precision of its kernels.
    pub precision: &'static str,
    /// Best build time.
    pub setup_seconds: f64,
    /// CPU build time / GPU build time, measured in this run.
    pub speedup: f64,
    /// Largest relative difference of its products from the CPU-built operator's (three
    /// vectors, as `max_product_rel_diff`).
    pub max_product_rel_diff: f64,
    /// Batches of pairs submitted to the GPU in its last build (the cross approximations
    /// advance together: about 2k rounds for rank k, not per block).
    pub gpu_submissions: u64,
    /// Of its last build's time, the host's waits for the device (the rest is the host's own
    /// work: plans, cross approximations, the blocks built on the CPU).
    pub device_wait_seconds: f64,
    /// Pairs of the exact blocks' faces seen in part that the device clipped.
    pub pairs_clipped_on_device: u64,
    /// Those left to the host: past the clipping kernel's limits, or thin elements (with f32
    /// kernels the host clips every one, not counted here).
    pub pairs_clipped_on_host: u64,
    /// Whether the GPU-built operator has the CPU-built one's pair classes, exactly.
    pub same_pair_classes: bool,
}

/// The dense reference of [`run_compressed`] runs up to this many unknowns (1.2 GB).
pub const DENSE_BENCH_LIMIT: usize = 12_288;

/// Builds the compressed operator of `config` (built as `scene`, `mesh`, `disc`) on each of
/// `backends` (one or two: the CPU, then the GPU) `repeats` times (best time), and the dense
/// matrix on the CPU as reference where it fits; all with one pair planner, built outside the
/// timings. Over several ranks (`config.ranks`; every rank calls it) the compressed operator is
/// spread over them.
pub fn run_compressed(
    config: &RunConfig,
    problem: &Problem,
    backends: &[Backend],
    repeats: usize,
) -> Result<CompressedBenchReport> {
    let Problem { scene, mesh, disc, .. } = problem;
    let repeats = repeats.max(1);
    let mut builds = Vec::new();
    for &backend in backends {
        let assembler = Assembler::new(backend, disc.method, config.assembly.quadrature)?;
        let mut best = f64::INFINITY;
        let mut op = None;
        for _ in 0..repeats {
            let started = Instant::now();
            op = Some(pipeline::build_compressed(config, &assembler, problem)?);
            best = best.min(started.elapsed().as_secs_f64());
        }
        builds.push((backend, op.expect("at least one repetition"), best));
    }
    let mut builds = builds.into_iter();
    let (backend, (op, _), best) = builds.next().expect("at least one backend");
    let gpu = builds.next().map(|(other, (other_op, traffic), seconds)| CompressedGpuBench {
        device: other_op.device.clone(),
        precision: other.precision().name(),
        setup_seconds: seconds,
        speedup: best / seconds,
        max_product_rel_diff: other_op.max_product_difference(&|x| op.apply(x)),
        gpu_submissions: traffic.map_or(0, |t| t.gpu_submissions),
        device_wait_seconds: traffic.map_or(0.0, |t| t.device_wait_seconds),
        pairs_clipped_on_device: traffic.map_or(0, |t| t.pairs_clipped_on_device),
        pairs_clipped_on_host: traffic.map_or(0, |t| t.pairs_clipped_on_host),
        same_pair_classes: other_op.pairs == op.pairs,
    });
    let dof = disc.dof();
    let (dense_setup_seconds, max_product_rel_diff) = if dof <= DENSE_BENCH_LIMIT {
        let assembler = Assembler::new(Backend::Cpu, disc.method, config.assembly.quadrature)?;
        let mut dense_best = f64::INFINITY;
        let mut dense = None;
        for _ in 0..repeats {
            let started = Instant::now();
            let a = assembler.assemble(problem, &config.assembly, &Silent)?;
            dense_best = dense_best.min(started.elapsed().as_secs_f64());
            dense = Some(a.matrix);
        }
        let k = dense.expect("at least one repetition");
        let worst = op.max_product_difference(&|x| k.apply(x));
        (Some(dense_best), Some(worst))
    } else {
        (None, None)
    };
    Ok(CompressedBenchReport {
        scene: scene.name.clone(),
        method: config.method.name(),
        n: mesh.len(),
        dof,
        backend: backend.name(),
        device: op.device.clone(),
        operator: crate::operator::OperatorChoice::Compressed.name(),
        compression_tolerance: config.compression.tolerance,
        setup_seconds: best,
        operator_bytes: op.stats.operator_bytes,
        blocks: op.stats,
        dense_setup_seconds,
        speedup: dense_setup_seconds.map(|d| d / best),
        max_product_rel_diff,
        gpu,
        peak_rss_bytes: pipeline::peak_rss_bytes(),
        repeats,
        distributed: pipeline::distributed_report(&op, best),
    })
}
