//! How a run stores its operator, decided in one place ([`operator_kind`]) for a
//! configuration and its problem: `solve`, `assemble`, `inspect` and Python through
//! [`super::build_operator`], `bench` directly. It also refuses the combinations that cannot
//! be run (LU or a dense operator over ranks, f32 storage where no matrix stays on a GPU).

use super::{Backend, Problem, RunConfig};
use crate::error::{Error, Result};
use crate::gpu::Precision;
use crate::operator::{OperatorChoice, ProblemShape};
use crate::solve::SolverChoice;

/// How a run's operator is stored.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum OperatorKind {
    /// The dense matrix on the host.
    Dense,
    /// The dense matrix assembled into the GPU's memory and kept there: GMRES's products run
    /// there (or on the host, with a note, where it cannot be kept).
    DenseOnDevice,
    /// Exact blocks near, low-rank blocks far.
    Compressed,
}

/// How `config` stores its operator for `problem`: compressed when asked for, over ranks, or
/// as [`OperatorChoice::decide`] says under [`OperatorChoice::Auto`] (its reason given as a
/// note) unless LU is asked for; a dense matrix stays on the GPU where the run is there in f64
/// with the iterative solver. Refuses what cannot be run that way.
pub fn operator_kind(config: &RunConfig, problem: &Problem) -> Result<OperatorKind> {
    if let Some(ranks) = &config.ranks {
        check_distributed(config, ranks.size())?;
    }
    let compressed = compresses(config, problem);
    check_storage(config, compressed)?;
    Ok(match compressed {
        true => OperatorKind::Compressed,
        false if stays_on_device(config) => OperatorKind::DenseOnDevice,
        false => OperatorKind::Dense,
    })
}

/// Refuses what a run from a saved operator cannot do: spread it over ranks, or store it in
/// f32.
pub(super) fn check_saved(config: &RunConfig) -> Result<()> {
    if let Some(ranks) = &config.ranks {
        check_distributed(config, ranks.size())?;
    }
    check_storage(config, true)
}

/// Whether `config` stores the compressed operator for `problem`: when asked for, or as
/// [`OperatorChoice::decide`] says under [`OperatorChoice::Auto`] (its reason given as a note)
/// unless LU (which needs the dense matrix) is asked for. A distributed run always compresses.
fn compresses(config: &RunConfig, problem: &Problem) -> bool {
    if let Some(ranks) = &config.ranks {
        config.progress.note(&format!(
            "operator: compressed, spread over {} ranks (the dense operator is not distributed)",
            ranks.size()
        ));
        return true;
    }
    if config.operator == OperatorChoice::Auto && config.solver.choice == SolverChoice::Lu {
        return false;
    }
    let (compressed, why) = config.operator.decide(ProblemShape::of(problem));
    if let Some(why) = why {
        config.progress.note(&why);
    }
    compressed
}

/// Whether the dense K of `config` is assembled into the GPU's memory and kept there: on the
/// GPU in f64 with the iterative solver (GMRES needs only products; LU and the other commands
/// need the matrix on the host).
fn stays_on_device(config: &RunConfig) -> bool {
    config.backend == Backend::Gpu(Precision::F64)
        && config.solver.choice == SolverChoice::Iterative
}

/// Refuses `--storage f32` where no dense K is kept in the GPU's memory: the storage is of
/// that matrix (the CPU's matrix, LU's and the compressed operator's blocks are in f64).
fn check_storage(config: &RunConfig, compressed: bool) -> Result<()> {
    if config.storage == Precision::F64 || (!compressed && stays_on_device(config)) {
        return Ok(());
    }
    let why = if config.operator_file.is_some() {
        "a saved operator is applied in f64"
    } else if compressed {
        "the compressed operator stores its values by its tolerance, not by --storage; choose \
         --operator dense"
    } else {
        "only a matrix kept on the GPU is stored in f32: it needs --backend gpu (f64 kernels) \
         and --solver iterative"
    };
    Err(Error::InvalidParameter {
        name: "storage",
        value: Precision::F32.name().into(),
        reason: why.into(),
    })
}

/// Refuses what a run over `size` ranks cannot do: only the compressed operator is spread over
/// them, so the dense one, LU and a saved operator (which holds the whole of it) are for runs of
/// one process.
pub(super) fn check_distributed(config: &RunConfig, size: usize) -> Result<()> {
    let why = if config.operator == OperatorChoice::Dense {
        Some(("operator", OperatorChoice::Dense.name(), "the dense operator is not distributed"))
    } else if config.solver.choice == SolverChoice::Lu {
        Some((
            "solver",
            SolverChoice::Lu.name(),
            "LU needs the dense matrix, which is not distributed",
        ))
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
