//! The operator a run solves with, as built ([`BuiltOperator`]): the dense matrix with its
//! timings, the matrix kept on the GPU, or the compressed operator; its products, solves and
//! summary.

use super::summary::{DeviceTransfers, OperatorSummary};
use super::{Problem, RunConfig};
use crate::assembly::{Assembly, peak_rss_bytes};
use crate::distributed::{DistributedReport, RankReport};
use crate::error::Result;
use crate::gpu::{self, DeviceBlocks, DeviceOperator, GpuTimings};
use crate::operator::{CompressedOperator, OperatorChoice};
use crate::solve;

/// An assembly with its timings.
pub struct TimedAssembly {
    pub(super) assembled: Assembly,
    pub(super) device: Option<String>,
    /// Where the GPU's (last) assembly spent its time and what it moved.
    pub(super) gpu: Option<GpuTimings>,
    /// The fastest assembly (pair plan included).
    pub(super) setup_seconds: f64,
    /// One-time preparation (GPU: compiling the kernels), not part of `setup_seconds`.
    pub(super) preparation_seconds: f64,
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
                operator: OperatorChoice::Dense.name(),
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
                operator: OperatorChoice::Dense.name(),
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
                    operator: OperatorChoice::Compressed.name(),
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
        peak_rss_bytes: peak_rss_bytes(),
        communication_seconds: traffic.seconds,
        communication_bytes: traffic.bytes,
        replicated_bytes: share.replicated_bytes,
    };
    Some(DistributedReport::gather(&*share.ranks, mine))
}
