//! [`Collective`] through MPI (rsmpi over the system's library).

use std::sync::Mutex;
use std::time::Instant;

use mpi::Threading;
use mpi::collective::SystemOperation;
use mpi::datatype::PartitionMut;
use mpi::environment::Universe;
use mpi::topology::{Communicator, SimpleCommunicator};
use mpi::traits::*;

use super::{Collective, Traffic};

/// Values summed over the ranks at once ([`Collective::sum`]): 512 KiB a piece.
const SUM_PIECE: usize = 1 << 16;

/// MPI for the life of the process: finalized when dropped, after the last collective.
pub struct MpiSession {
    _universe: Universe,
}

/// The world communicator of an `mpirun` (or a single process started without one).
pub struct MpiWorld {
    rank: usize,
    size: usize,
    /// Serializes the calls (MPI was initialized for serialized calls from any thread) and
    /// counts what they move.
    traffic: Mutex<Traffic>,
}

impl std::fmt::Debug for MpiWorld {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "MpiWorld {{ rank: {}, size: {} }}", self.rank, self.size)
    }
}

impl MpiWorld {
    /// Initializes MPI, or `None` where it was initialized already.
    pub fn init() -> Option<(MpiSession, Self)> {
        let (universe, _) = mpi::initialize_with_threading(Threading::Serialized)?;
        let world = universe.world();
        let me = Self {
            rank: world.rank() as usize,
            size: world.size() as usize,
            traffic: Mutex::new(Traffic::default()),
        };
        Some((MpiSession { _universe: universe }, me))
    }

    /// Runs `call` on the world communicator, one call at a time, counting `bytes` and its time.
    fn call<T>(&self, bytes: usize, call: impl FnOnce(&SimpleCommunicator) -> T) -> T {
        let mut traffic = self.traffic.lock().unwrap_or_else(|e| e.into_inner());
        let started = Instant::now();
        let out = call(&SimpleCommunicator::world());
        traffic.seconds += started.elapsed().as_secs_f64();
        traffic.bytes += bytes as u64;
        out
    }
}

impl Collective for MpiWorld {
    fn rank(&self) -> usize {
        self.rank
    }

    fn size(&self) -> usize {
        self.size
    }

    fn sum(&self, values: &mut [f64]) {
        // Reduced at the root in one order and broadcast: the same bits on every rank, so that
        // their solvers take the same steps (an all-reduce may sum in a different order on
        // each rank). In pieces: the root's sums of a whole vector, and the library's buffer
        // beside them, would be two more vectors of n on rank 0 alone.
        self.call(2 * 8 * values.len(), |world| {
            let root = world.process_at_rank(0);
            let mut total = vec![0.0; values.len().min(SUM_PIECE)];
            for piece in values.chunks_mut(SUM_PIECE) {
                if self.rank == 0 {
                    let total = &mut total[..piece.len()];
                    root.reduce_into_root(&*piece, total, SystemOperation::sum());
                    piece.copy_from_slice(total);
                } else {
                    root.reduce_into(&*piece, SystemOperation::sum());
                }
            }
            root.broadcast_into(values);
        });
    }

    fn gather(&self, values: &[u64]) -> Vec<Vec<u64>> {
        let size = self.size;
        self.call(8 * values.len() * (size + 1), |world| {
            let mut counts = vec![0u64; size];
            world.all_gather_into(&(values.len() as u64), &mut counts[..]);
            let counts: Vec<i32> = counts.iter().map(|&c| c as i32).collect();
            let displs: Vec<i32> = counts
                .iter()
                .scan(0, |at, &c| {
                    let d = *at;
                    *at += c;
                    Some(d)
                })
                .collect();
            let total = counts.iter().map(|&c| c as usize).sum();
            let mut all = vec![0u64; total];
            {
                let mut parts = PartitionMut::new(&mut all[..], &counts[..], &displs[..]);
                world.all_gather_varcount_into(values, &mut parts);
            }
            let mut out = Vec::with_capacity(size);
            let mut at = 0;
            for &c in &counts {
                out.push(all[at..at + c as usize].to_vec());
                at += c as usize;
            }
            out
        })
    }

    fn gather_f64(&self, values: &[f64]) -> Vec<Vec<f64>> {
        let size = self.size;
        self.call(8 * values.len() * (size + 1), |world| {
            let mut all = vec![0.0; values.len() * size];
            world.all_gather_into(values, &mut all[..]);
            all.chunks(values.len().max(1)).map(<[f64]>::to_vec).collect()
        })
    }

    fn abort(&self, message: &str, code: i32) -> ! {
        eprintln!("{message}");
        SimpleCommunicator::world().abort(code)
    }

    fn traffic(&self) -> Traffic {
        *self.traffic.lock().unwrap_or_else(|e| e.into_inner())
    }
}
