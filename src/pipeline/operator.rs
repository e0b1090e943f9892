//! The operator a run solves with: the dense matrix, timed over repeated assemblies, or the
//! compressed operator where the configuration asks for it at this size.

use std::time::Instant;

use serde::Serialize;

use super::{Assembler, Problem, REPEAT_BELOW_SECONDS, RunConfig};
use crate::assembly::{Assembly, PairEvaluation};
use crate::distributed::{DistributedReport, RankReport};
use crate::error::{Error, Result};
use crate::gpu::{self, DeviceBlocks, DeviceOperator, GpuTimings};
use crate::operator::{
    CompressedOperator, CompressionOptions, OperatorChoice, OperatorStats, ProblemShape,
};
use crate::solve;
use crate::visibility::PairStats;

/// Assembles K for `config` up to `config.setup_repeats` times (fewer once one assembly takes over
/// [`REPEAT_BELOW_SECONDS`]) with one prepared backend; the setup time is the pair planner's
/// plus the fastest assembly's.
fn assemble_timed(config: &RunConfig, problem: &Problem) -> Result<TimedAssembly> {
    let started = Instant::now();
    let assembler =
        Assembler::new(config.backend, problem.disc.method, config.assembly.quadrature)?;
    let preparation_seconds = started.elapsed().as_secs_f64();
    let progress = &*config.progress;
    let mut timed = None;
    let mut fastest = f64::INFINITY;
    for _ in 0..config.setup_repeats.max(1) {
        progress.start("assembly", problem.disc.dof());
        let started = Instant::now();
        let assembled = assembler.assemble(problem, &config.assembly, progress)?;
        let seconds = started.elapsed().as_secs_f64();
        fastest = fastest.min(seconds);
        timed = Some(assembled);
        progress.finish();
        if seconds > REPEAT_BELOW_SECONDS {
            break;
        }
    }
    let assembled = timed.expect("at least one assembly");
    let setup_seconds = problem.plan_seconds + fastest;
    let (device, gpu) = (assembler.device(), assembler.last_timings());
    Ok(TimedAssembly { assembled, device, gpu, setup_seconds, preparation_seconds })
}

/// An assembly with its timings.
pub struct TimedAssembly {
    pub(super) assembled: Assembly,
    device: Option<String>,
    /// Where the GPU's (last) assembly spent its time and what it moved.
    gpu: Option<GpuTimings>,
    /// The fastest assembly (pair plan included).
    setup_seconds: f64,
    /// One-time preparation (GPU: compiling the kernels), not part of `setup_seconds`.
    preparation_seconds: f64,
}

impl TimedAssembly {
    /// A matrix read from a file in `setup_seconds`.
    pub(super) fn loaded(assembled: Assembly, setup_seconds: f64) -> Self {
        Self { assembled, device: None, gpu: None, setup_seconds, preparation_seconds: 0.0 }
    }
}

/// The operator a run solves with: the dense matrix K (on the host, or kept on the GPU) or the
/// compressed operator.
pub enum BuiltOperator {
    /// K stored entry by entry, with its timings.
    Dense(TimedAssembly),
    /// K assembled on the GPU and kept in its memory: GMRES's products run there, and only
    /// vectors cross.
    Device {
        /// The operator.
        op: Box<DeviceOperator>,
        /// The GPU adapter.
        device: Option<String>,
        /// Its setup time (pair plan included).
        setup_seconds: f64,
        /// One-time preparation of the backend (compiling the kernels).
        preparation_seconds: f64,
    },
    /// K in exact and low-rank blocks.
    Compressed {
        /// The operator (boxed: the variants stay near one size).
        op: Box<CompressedOperator>,
        /// Its blocks in the GPU's memory, where the run is on the GPU: GMRES's products run
        /// there.
        on_device: Option<Box<DeviceBlocks>>,
        /// What crossed to the GPU and back while the GPU evaluated its entries.
        build_traffic: Option<gpu::DeviceTraffic>,
        /// Its setup time (pair plan included).
        setup_seconds: f64,
        /// One-time preparation of the backend.
        preparation_seconds: f64,
    },
}

/// What a report says of the operator (the keys of `solve --json` that concern it).
#[derive(Clone, Debug, Serialize)]
pub struct OperatorSummary {
    /// `dense` or `compressed`.
    pub operator: &'static str,
    /// The GPU adapter, when the GPU evaluated the entries.
    pub device: Option<String>,
    /// Time to plan and assemble (or build) the operator.
    pub setup_seconds: f64,
    /// One-time preparation of the backend.
    pub preparation_seconds: f64,
    /// Pair classes.
    pub pairs: PairStats,
    /// Relative tolerance of the low-rank blocks (compressed operator).
    pub compression_tolerance: Option<f64>,
    /// Memory of the stored operator, in bytes.
    pub operator_bytes: u64,
    /// What the compressed operator's build was estimated to hold at its peak before it began
    /// (none for the dense matrix, whose 8 n² bytes are known, or an operator read from a file).
    pub memory_estimate_bytes: Option<u64>,
    /// Block statistics of the compressed operator.
    #[serde(flatten)]
    pub blocks: Option<OperatorStats>,
    /// Where the dense matrix assembled on the GPU lives, and what crossed.
    #[serde(flatten)]
    pub transfers: Option<DeviceTransfers>,
}

/// Where a matrix assembled on the GPU is kept and what crossed between host and device
/// (`operator_location`, `bytes_uploaded`, `bytes_read_back`, `gpu_submissions`,
/// `device_idle_fraction` in reports).
#[derive(Clone, Copy, Debug, Serialize)]
pub struct DeviceTransfers {
    /// `device` (kept there, products there) or `host` (read back).
    pub operator_location: &'static str,
    /// Bytes written to the device.
    pub bytes_uploaded: u64,
    /// Bytes read back.
    pub bytes_read_back: u64,
    /// Command submissions.
    pub gpu_submissions: u64,
    /// At most this share of the setup and solve's wall time was the device idle: one less the
    /// host's waits for it over that time (the device was busy at least while the host
    /// waited; it may have been busy longer).
    pub device_idle_fraction: f64,
    /// Host time spent waiting for the device.
    #[serde(skip)]
    pub device_wait_seconds: f64,
    /// For an operator kept on the device, the precision of its entries there and what that
    /// did to it (`storage`, `storage_error`, `storage_solution_bound`).
    #[serde(flatten, skip_serializing_if = "Option::is_none")]
    pub storage: Option<gpu::StorageError>,
}

impl DeviceTransfers {
    /// After `traffic`, of an operator kept on the device in `storage`, or read back (`None`).
    fn new(traffic: gpu::DeviceTraffic, storage: Option<gpu::StorageError>) -> Self {
        Self {
            operator_location: if storage.is_some() { "device" } else { "host" },
            bytes_uploaded: traffic.bytes_uploaded,
            bytes_read_back: traffic.bytes_read_back,
            gpu_submissions: traffic.gpu_submissions,
            device_idle_fraction: 0.0,
            device_wait_seconds: traffic.device_wait_seconds,
            storage,
        }
    }

    /// With the idle share of `wall_seconds` (setup and solve) filled in.
    pub fn over(mut self, wall_seconds: f64) -> Self {
        self.device_idle_fraction = if wall_seconds > 0.0 {
            (1.0 - self.device_wait_seconds / wall_seconds).clamp(0.0, 1.0)
        } else {
            0.0
        };
        self
    }
}

impl BuiltOperator {
    /// Number of unknowns.
    pub fn dof(&self) -> usize {
        match self {
            Self::Dense(t) => t.assembled.matrix.dof(),
            Self::Device { op, .. } => op.dof(),
            Self::Compressed { op, .. } => op.dof(),
        }
    }

    /// The dense matrix, when this is it.
    pub fn matrix(&self) -> Option<&crate::assembly::CollocationMatrix> {
        match self {
            Self::Dense(t) => Some(&t.assembled.matrix),
            Self::Device { .. } | Self::Compressed { .. } => None,
        }
    }

    /// The product `K x`.
    pub fn apply(&self, x: &[f64]) -> Result<Vec<f64>> {
        match self {
            Self::Dense(t) => Ok(t.assembled.matrix.apply(x)),
            Self::Device { op, .. } => Ok(op.apply_many(&[x])?.pop().expect("one product")),
            Self::Compressed { op, .. } => Ok(op.apply(x)),
        }
    }

    /// Solves `(I - K) u = E` for each right-hand side in `rhs` with the solver of `config`: LU
    /// factors the dense matrix once for all of them; on the compressed operator the GMRES
    /// solves advance together, each round's products computed in one pass over the blocks.
    pub fn solve_many(
        &self,
        config: &RunConfig,
        problem: &Problem,
        rhs: &[&[f64]],
    ) -> Result<Vec<solve::SolveOutcome>> {
        match self {
            Self::Dense(t) => solve::solve_many(&t.assembled.matrix, rhs, config.solver),
            Self::Device { .. } | Self::Compressed { .. } => {
                let rho: Vec<f64> = problem.disc.nodes().map(|n| n.rho).collect();
                let rho = (rho.as_slice(), rho.as_slice());
                let (op, tolerance) = self.products(config).expect("known by products");
                solve::solve_by_products_many(op, rhs, rho, config.solver, tolerance)
            }
        }
    }

    /// The operator as known by its products, with the relative error of those products (the
    /// compression's tolerance; 0 on the device), or `None` for the matrix on the host.
    pub fn products(&self, config: &RunConfig) -> Option<(&dyn solve::Products, f64)> {
        match self {
            Self::Dense(_) => None,
            Self::Device { op, .. } => Some((&**op, 0.0)),
            Self::Compressed { on_device: Some(blocks), .. } => {
                Some((&**blocks, config.compression.tolerance))
            }
            Self::Compressed { op, .. } => Some((&**op, config.compression.tolerance)),
        }
    }

    /// In a distributed run, every rank's figures gathered (a collective: every rank calls it
    /// at the same point); `None` for one process.
    pub fn distributed_report(&self) -> Option<DistributedReport> {
        match self {
            Self::Compressed { op, setup_seconds, .. } => distributed_report(op, *setup_seconds),
            Self::Dense(_) | Self::Device { .. } => None,
        }
    }

    /// What a report says of this operator, built for `config`.
    pub fn summary(&self, config: &RunConfig) -> OperatorSummary {
        let dof = self.dof();
        match self {
            Self::Dense(t) => OperatorSummary {
                operator: "dense",
                device: t.device.clone(),
                setup_seconds: t.setup_seconds,
                preparation_seconds: t.preparation_seconds,
                pairs: t.assembled.stats,
                compression_tolerance: None,
                operator_bytes: 8 * (dof as u64) * (dof as u64),
                memory_estimate_bytes: None,
                blocks: None,
                transfers: t.gpu.map(|g| DeviceTransfers::new(g.traffic(), None)),
            },
            Self::Device { op, device, setup_seconds, preparation_seconds } => OperatorSummary {
                operator: "dense",
                device: device.clone(),
                setup_seconds: *setup_seconds,
                preparation_seconds: *preparation_seconds,
                pairs: op.stats,
                compression_tolerance: None,
                operator_bytes: op.device_bytes(),
                memory_estimate_bytes: None,
                blocks: None,
                transfers: Some(DeviceTransfers::new(op.traffic(), Some(op.storage))),
            },
            Self::Compressed {
                op,
                on_device,
                build_traffic,
                setup_seconds,
                preparation_seconds,
            } => {
                // The build's batches and the products' trips, where the GPU took part.
                let transfers = (on_device.is_some() || build_traffic.is_some()).then(|| {
                    let products = on_device.as_ref().map(|b| b.traffic()).unwrap_or_default();
                    let storage = on_device.as_ref().map(|_| gpu::StorageError::none());
                    DeviceTransfers::new(build_traffic.unwrap_or_default() + products, storage)
                });
                OperatorSummary {
                    operator: "compressed",
                    device: op.device.clone(),
                    setup_seconds: *setup_seconds,
                    preparation_seconds: *preparation_seconds,
                    pairs: op.pairs,
                    compression_tolerance: Some(config.compression.tolerance),
                    operator_bytes: op.stats.operator_bytes,
                    memory_estimate_bytes: op.memory_estimate.as_ref().map(|e| e.peak_bytes()),
                    blocks: Some(op.stats),
                    transfers,
                }
            }
        }
    }
}

/// In a distributed run, every rank's figures gathered, this rank's operator `op` built in
/// `setup_seconds` (a collective: every rank calls it at the same point); `None` for one
/// process.
pub fn distributed_report(
    op: &CompressedOperator,
    setup_seconds: f64,
) -> Option<DistributedReport> {
    let share = op.share.as_ref()?;
    let traffic = share.ranks.traffic();
    let mine = RankReport {
        rank: share.ranks.rank(),
        setup_seconds: setup_seconds - share.waited_seconds,
        operator_bytes: share.operator_bytes,
        peak_rss_bytes: super::peak_rss_bytes(),
        communication_seconds: traffic.seconds,
        communication_bytes: traffic.bytes,
        replicated_bytes: share.replicated_bytes,
    };
    Some(DistributedReport::gather(&*share.ranks, mine))
}

/// The compressed operator of `config` for `problem`, its entries evaluated by `assembler` (the
/// CPU, or the GPU's pair kernel in batches, with what crossed to the GPU and back and how many
/// batches were submitted); refused where the configuration needs the dense matrix (LU).
pub fn build_compressed(
    config: &RunConfig,
    assembler: &Assembler,
    problem: &Problem,
) -> Result<(CompressedOperator, Option<gpu::DeviceTraffic>)> {
    if config.solver.choice == solve::SolverChoice::Lu {
        return Err(Error::InvalidParameter {
            name: "solver",
            value: "lu".into(),
            reason: "LU needs the dense matrix; the compressed operator is solved by GMRES \
                     (the iterative solver), or choose the dense operator"
                .into(),
        });
    }
    if let Some(ranks) = &config.ranks {
        check_distributed(config, ranks.size())?;
    }
    let Problem { scene, disc, .. } = problem;
    let device = match assembler {
        Assembler::Cpu => None,
        Assembler::Gpu(g) => Some(gpu::PairEvaluator::new(g, scene, disc, &config.assembly)?),
    };
    let batches = device.as_ref().map(|d| d as &dyn PairEvaluation);
    // The mesh's level, for the advice of a refusal for memory.
    let compression = &CompressionOptions { refine: Some(config.refine), ..config.compression };
    let (assembly, progress) = (&config.assembly, &*config.progress);
    let mut op = match &config.ranks {
        Some(ranks) => CompressedOperator::build_shared(
            problem,
            assembly,
            compression,
            batches,
            progress,
            ranks,
        )?,
        None => CompressedOperator::build(problem, assembly, compression, batches, progress)?,
    };
    op.device = assembler.device();
    Ok((op, device.map(|d| d.traffic())))
}

/// The dense matrix (timed as [`assemble_timed`]) or, when `config.operator` asks for it at this
/// size, the compressed operator (built once; its setup time includes the pair planner's, as
/// the dense assembly's does).
pub fn build_operator(config: &RunConfig, problem: &Problem) -> Result<BuiltOperator> {
    if let Some(ranks) = &config.ranks {
        check_distributed(config, ranks.size())?;
    }
    if let Some(path) = &config.operator_file {
        check_storage(config, true)?;
        return super::load_operator(path, config, problem);
    }
    let disc = &problem.disc;
    let compressed = compresses(config, problem);
    check_storage(config, compressed)?;
    if !compressed {
        if stays_on_device(config) {
            match assemble_on_device(config, problem) {
                Ok(built) => return Ok(built),
                Err(e) => config.progress.note(&format!(
                    "the matrix is kept on the host in f64 ({e}); the products run there"
                )),
            }
        }
        return Ok(BuiltOperator::Dense(assemble_timed(config, problem)?));
    }
    let started = Instant::now();
    let assembler = Assembler::new(config.backend, disc.method, config.assembly.quadrature)?;
    let preparation_seconds = started.elapsed().as_secs_f64();
    let started = Instant::now();
    let (op, build_traffic) = build_compressed(config, &assembler, problem)?;
    let setup_seconds = problem.plan_seconds + started.elapsed().as_secs_f64();
    let on_device = blocks_on_device(config, &op);
    Ok(BuiltOperator::Compressed {
        op: Box::new(op),
        on_device,
        build_traffic,
        setup_seconds,
        preparation_seconds,
    })
}

/// The compressed operator's blocks uploaded to the GPU for GMRES's products, where the run is
/// on the GPU in f64 in one process; `None`, with a note saying why, where they cannot go there.
pub(super) fn blocks_on_device(
    config: &RunConfig,
    op: &CompressedOperator,
) -> Option<Box<DeviceBlocks>> {
    if config.backend != super::Backend::Gpu(gpu::Precision::F64) || config.ranks.is_some() {
        return None;
    }
    let uploaded = compressed_on_device(op, None).map_err(|e| e.to_string());
    match uploaded {
        Ok(blocks) => Some(Box::new(blocks)),
        Err(why) => {
            config.progress.note(&format!(
                "the compressed operator stays on the host ({why}); its products run there"
            ));
            None
        }
    }
}

/// The blocks of `op` uploaded to the GPU (f64) for its products there, in as many parts as
/// the device's largest binding asks for, or parts of at most `max_binding` bytes where given
/// (tests split small operators so).
pub fn compressed_on_device(
    op: &CompressedOperator,
    max_binding: Option<u64>,
) -> Result<DeviceBlocks> {
    let ctx = gpu::context_for(gpu::Precision::F64)?;
    let max_binding = max_binding.unwrap_or_else(|| ctx.max_binding());
    let parts = op.packed_parts(max_binding).ok_or_else(|| {
        Error::Gpu(format!(
            "the compressed operator is distributed, a block passes the binding limit of \
             {max_binding} bytes, or an offset passes u32"
        ))
    })?;
    let arrays: Vec<gpu::BlockArrays> = parts
        .iter()
        .map(|p| gpu::BlockArrays {
            blocks: p.blocks,
            low_rank: p.low_rank,
            values: &p.values,
            indices: &p.indices,
            low_rank_at: p.low_rank_at,
            row_starts_at: p.row_starts_at,
            contributions_at: p.contributions_at,
            scratch: p.scratch,
        })
        .collect();
    let orders = (op.per_element(), op.node_order(), op.element_order());
    DeviceBlocks::upload(ctx, op.dof(), orders, &arrays)
}

/// Whether the dense K of `config` is assembled into the GPU's memory and kept there: on the
/// GPU in f64 with the iterative solver (GMRES needs only products; LU and the other commands
/// need the matrix on the host).
fn stays_on_device(config: &RunConfig) -> bool {
    config.backend == super::Backend::Gpu(gpu::Precision::F64)
        && config.solver.choice == solve::SolverChoice::Iterative
}

/// Refuses `--storage f32` where no dense K is kept in the GPU's memory: the storage is of
/// that matrix (the CPU's matrix, LU's and the compressed operator's blocks are in f64).
fn check_storage(config: &RunConfig, compressed: bool) -> Result<()> {
    if config.storage == gpu::Precision::F64 || (!compressed && stays_on_device(config)) {
        return Ok(());
    }
    let why = if config.operator_file.is_some() {
        "a saved operator is applied in f64"
    } else if compressed {
        "the compressed operator is stored in f64; choose --operator dense"
    } else {
        "only a matrix kept on the GPU is stored in f32: it needs --backend gpu (f64 kernels) \
         and --solver iterative"
    };
    Err(Error::InvalidParameter { name: "storage", value: "f32".into(), reason: why.into() })
}

/// K assembled on the GPU and left in its memory.
fn assemble_on_device(config: &RunConfig, problem: &Problem) -> Result<BuiltOperator> {
    let started = Instant::now();
    let assembler =
        Assembler::new(config.backend, problem.disc.method, config.assembly.quadrature)?;
    let preparation_seconds = started.elapsed().as_secs_f64();
    let Assembler::Gpu(gpu) = &assembler else {
        unreachable!("a GPU backend gives the GPU's assembler")
    };
    let started = Instant::now();
    let (options, progress) = (&config.assembly, &*config.progress);
    let op = Box::new(DeviceOperator::assemble(gpu, problem, options, config.storage, progress)?);
    let setup_seconds = problem.plan_seconds + started.elapsed().as_secs_f64();
    Ok(BuiltOperator::Device { op, device: assembler.device(), setup_seconds, preparation_seconds })
}

/// Refuses what a run over `size` ranks cannot do: only the compressed operator is spread over
/// them, so the dense one, LU and a saved operator (which holds the whole of it) are for runs of
/// one process.
fn check_distributed(config: &RunConfig, size: usize) -> Result<()> {
    let why = if config.operator == OperatorChoice::Dense {
        Some(("operator", "dense", "the dense operator is not distributed"))
    } else if config.solver.choice == solve::SolverChoice::Lu {
        Some(("solver", "lu", "LU needs the dense matrix, which is not distributed"))
    } else if config.operator_file.is_some() {
        Some((
            "operator-file",
            "given",
            "a saved operator holds the whole of it, not a rank's part",
        ))
    } else {
        None
    };
    match why {
        Some((name, value, why)) => Err(Error::InvalidParameter {
            name,
            value: value.into(),
            reason: format!(
                "{why}: run it in one process, or use the compressed operator over the {size} \
                 ranks"
            ),
        }),
        None => Ok(()),
    }
}

/// Whether `config` stores the compressed operator for `problem`: when asked for, or as
/// [`OperatorChoice::decide`] says under [`OperatorChoice::Auto`] (its reason given as a note)
/// unless LU (which needs the dense matrix) is asked for. A distributed run always compresses.
pub fn compresses(config: &RunConfig, problem: &Problem) -> bool {
    if let Some(ranks) = &config.ranks {
        config.progress.note(&format!(
            "operator: compressed, spread over {} ranks (the dense operator is not distributed)",
            ranks.size()
        ));
        return true;
    }
    if config.operator == OperatorChoice::Auto && config.solver.choice == solve::SolverChoice::Lu {
        return false;
    }
    let (compressed, why) = config.operator.decide(ProblemShape::of(problem));
    if let Some(why) = why {
        config.progress.note(&why);
    }
    compressed
}
