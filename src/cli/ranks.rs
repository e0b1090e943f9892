//! The ranks of a distributed run: which process prints and writes.

use std::sync::OnceLock;

use radiosity::distributed::Ranks;

/// The ranks of this process's `mpirun`, where it started several.
static WORLD: OnceLock<Ranks> = OnceLock::new();

/// Makes the runs of this process distributed over `ranks`.
#[cfg_attr(not(feature = "mpi"), allow(dead_code))]
pub(crate) fn set_world(ranks: Ranks) {
    WORLD.set(ranks).expect("the world is set once, at the start");
}

/// The ranks the runs are spread over, or `None` for one process.
pub(crate) fn world() -> Option<Ranks> {
    WORLD.get().cloned()
}

/// Whether this process prints and writes: rank 0 of a distributed run, or a lone process.
pub(crate) fn is_root() -> bool {
    WORLD.get().is_none_or(|w| w.rank() == 0)
}
