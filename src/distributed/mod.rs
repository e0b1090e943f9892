//! Runs spread over several processes (ranks), as `mpirun -np N radiosity solve ...` starts them
//! (docs/distributed.md).
//!
//! Every rank reads the scene and builds the mesh, the cluster trees and the pair planner
//! (cheap, and the same everywhere); the compressed operator's block plan is walked in parts,
//! one per rank, and gathered; each rank then builds only its share of the blocks, balanced by
//! their estimated cost (the compressed operator's `build_shared`). A product `K x` sums the ranks' parts, reduced
//! at rank 0 and broadcast, so that every rank holds the same bits and runs the same GMRES on
//! replicated vectors: only the products are distributed, and the Krylov vectors are a small
//! part of the memory next to the operator.
//!
//! [`Collective`] is what the library asks of the transport; [`MpiWorld`] (cargo feature `mpi`)
//! gives it through MPI.

#[cfg(feature = "mpi")]
mod mpi;

#[cfg(feature = "mpi")]
pub use mpi::{MpiSession, MpiWorld};

use std::sync::Arc;

use serde::Serialize;

/// The collective operations a distributed run needs. Every rank must make the same calls in
/// the same order (as MPI's collectives require); a rank that fails stops all of them
/// ([`Collective::abort`]) instead of leaving them waiting.
pub trait Collective: Send + Sync + std::fmt::Debug {
    /// This process's rank, 0 ≤ rank < size.
    fn rank(&self) -> usize;
    /// The number of ranks.
    fn size(&self) -> usize;
    /// Sums `values` over the ranks in place; every rank gets the same bits (reduced at rank 0
    /// in one order, then broadcast).
    fn sum(&self, values: &mut [f64]);
    /// Every rank's `values`, in rank order, on every rank.
    fn gather(&self, values: &[u64]) -> Vec<Vec<u64>>;
    /// Every rank's `values` of equal length, in rank order, on every rank.
    fn gather_f64(&self, values: &[f64]) -> Vec<Vec<f64>>;
    /// Stops every rank with `code` after this rank's `message` is printed.
    fn abort(&self, message: &str, code: i32) -> !;
    /// What the collectives have moved so far on this rank.
    fn traffic(&self) -> Traffic;
}

/// A rank's shared handle on the collectives of its run.
pub type Ranks = Arc<dyn Collective>;

/// Time spent in, and bytes sent and received by, the collectives of one rank.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct Traffic {
    /// Wall time inside collective calls (waiting for the other ranks included).
    pub seconds: f64,
    /// Bytes this rank sent and received.
    pub bytes: u64,
}

/// What one rank of a distributed run did.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct RankReport {
    /// The rank.
    pub rank: usize,
    /// Its time to build its share of the operator (the block plan's walk included), less the
    /// time it waited for the other ranks: what the load balance compares.
    pub setup_seconds: f64,
    /// Bytes of its blocks.
    pub operator_bytes: u64,
    /// What it holds whatever its share: the scene, mesh, discretization and occluder index,
    /// the cluster trees, the block plan and the orders (`RankShare::replicated_bytes`).
    pub replicated_bytes: u64,
    /// Its peak resident memory.
    pub peak_rss_bytes: Option<u64>,
    /// Time in collectives, waiting included.
    pub communication_seconds: f64,
    /// Bytes it sent and received.
    pub communication_bytes: u64,
}

/// The ranks of a distributed run as a report gives them.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct DistributedReport {
    /// Number of ranks.
    pub ranks: usize,
    /// Each rank's figures, in rank order.
    pub per_rank: Vec<RankReport>,
    /// Largest time in collectives over the ranks.
    pub communication_seconds: f64,
    /// Bytes sent and received by all ranks together.
    pub communication_bytes: u64,
    /// Largest setup time over the mean: 1 is a perfect balance.
    pub load_imbalance: f64,
}

impl DistributedReport {
    /// Gathers every rank's `mine` (a collective: every rank calls it) into the report.
    pub fn gather(ranks: &dyn Collective, mine: RankReport) -> Self {
        let fields = [
            mine.setup_seconds,
            mine.operator_bytes as f64,
            mine.peak_rss_bytes.map_or(-1.0, |b| b as f64),
            mine.communication_seconds,
            mine.communication_bytes as f64,
            mine.replicated_bytes as f64,
        ];
        let per_rank: Vec<RankReport> = ranks
            .gather_f64(&fields)
            .into_iter()
            .enumerate()
            .map(|(rank, f)| RankReport {
                rank,
                setup_seconds: f[0],
                operator_bytes: f[1] as u64,
                peak_rss_bytes: (f[2] >= 0.0).then_some(f[2] as u64),
                communication_seconds: f[3],
                communication_bytes: f[4] as u64,
                replicated_bytes: f[5] as u64,
            })
            .collect();
        let setups: Vec<f64> = per_rank.iter().map(|r| r.setup_seconds).collect();
        let mean = setups.iter().sum::<f64>() / setups.len().max(1) as f64;
        let max = setups.iter().copied().fold(0.0, f64::max);
        Self {
            ranks: per_rank.len(),
            communication_seconds: per_rank
                .iter()
                .map(|r| r.communication_seconds)
                .fold(0.0, f64::max),
            communication_bytes: per_rank.iter().map(|r| r.communication_bytes).sum(),
            load_imbalance: if mean > 0.0 { max / mean } else { 1.0 },
            per_rank,
        }
    }
}

/// Ranks as threads of one process, so that the distributed paths are tested without MPI.
#[cfg(test)]
pub(crate) mod threads {
    use std::sync::{Arc, Barrier, Mutex};

    use super::{Collective, Ranks, Traffic};

    /// What the threads exchange: each rank's contribution, read by all after a barrier.
    #[derive(Debug)]
    struct Shared {
        barrier: Barrier,
        f64s: Mutex<Vec<Vec<f64>>>,
        u64s: Mutex<Vec<Vec<u64>>>,
    }

    /// One rank of [`run`].
    #[derive(Debug)]
    struct ThreadRank {
        rank: usize,
        shared: Arc<Shared>,
    }

    /// Runs `f` on `size` ranks, one thread each, and returns their results in rank order.
    pub(crate) fn run<T: Send>(size: usize, f: impl Fn(Ranks) -> T + Sync) -> Vec<T> {
        let shared = Arc::new(Shared {
            barrier: Barrier::new(size),
            f64s: Mutex::new(vec![Vec::new(); size]),
            u64s: Mutex::new(vec![Vec::new(); size]),
        });
        std::thread::scope(|scope| {
            let handles: Vec<_> = (0..size)
                .map(|rank| {
                    let ranks: Ranks = Arc::new(ThreadRank { rank, shared: shared.clone() });
                    let f = &f;
                    scope.spawn(move || f(ranks))
                })
                .collect();
            handles.into_iter().map(|h| h.join().expect("a rank panicked")).collect()
        })
    }

    impl ThreadRank {
        /// Every rank's `values` from `slots`, after all have put theirs.
        fn exchange<V: Clone>(&self, slots: &Mutex<Vec<Vec<V>>>, values: &[V]) -> Vec<Vec<V>> {
            slots.lock().unwrap()[self.rank] = values.to_vec();
            self.shared.barrier.wait();
            let all = slots.lock().unwrap().clone();
            // No rank puts its next values before every rank has read these.
            self.shared.barrier.wait();
            all
        }
    }

    impl Collective for ThreadRank {
        fn rank(&self) -> usize {
            self.rank
        }

        fn size(&self) -> usize {
            self.shared.f64s.lock().unwrap().len()
        }

        fn sum(&self, values: &mut [f64]) {
            let all = self.exchange(&self.shared.f64s, values);
            for (k, v) in values.iter_mut().enumerate() {
                *v = all.iter().map(|part| part[k]).sum();
            }
        }

        fn gather(&self, values: &[u64]) -> Vec<Vec<u64>> {
            self.exchange(&self.shared.u64s, values)
        }

        fn gather_f64(&self, values: &[f64]) -> Vec<Vec<f64>> {
            self.exchange(&self.shared.f64s, values)
        }

        fn abort(&self, message: &str, _code: i32) -> ! {
            panic!("{message}")
        }

        fn traffic(&self) -> Traffic {
            Traffic::default()
        }
    }
}
