//! The backend that assembles K: the CPU's threads, or the GPU's kernels compiled once.

use super::{Backend, Problem};
use crate::assembly::{self, Assembly, AssemblyOptions, Quadrature};
use crate::discretization::Method;
use crate::error::{Error, Result};
use crate::gpu::{self, GpuAssembler, GpuTimings, Precision};
use crate::progress::Progress;

impl Backend {
    /// This backend if it can run here: the CPU always, the GPU where an adapter that runs
    /// kernels of its precision is found (why not, otherwise).
    pub fn found(self) -> Result<Self> {
        match self {
            Self::Cpu => Ok(self),
            Self::Gpu(precision) => gpu::context_for(precision).map(|_| self),
        }
    }
}

/// The backends a command runs on when none is named (`bench`, the studies): the CPU, plus the
/// GPU in each of `precisions` where an adapter is found; a note says why a GPU is left out.
/// The one place where "the GPU where found" is decided.
pub fn cpu_and_found_gpus(precisions: &[Precision], notes: &mut Vec<String>) -> Vec<Backend> {
    let mut backends = vec![Backend::Cpu];
    for &precision in precisions {
        match Backend::Gpu(precision).found() {
            Ok(gpu) => backends.push(gpu),
            Err(e) => notes.push(format!("the GPU in {} is left out: {e}", precision.name())),
        }
    }
    backends
}

/// A backend ready to assemble K: on the GPU, the kernels compiled once (the one-time cost that
/// timings of the assembly leave out). Every command that assembles goes through it, so `bench`
/// times the very matrix `solve` uses.
pub enum Assembler {
    /// Plain Rust on all cores.
    Cpu,
    /// The GPU's compiled kernels.
    Gpu(GpuAssembler<'static>),
}

impl Assembler {
    /// Prepares `backend` for `method` and `quadrature` (the GPU evaluates the exact method only).
    pub fn new(backend: Backend, method: Method, quadrature: Quadrature) -> Result<Self> {
        match backend {
            Backend::Cpu => Ok(Self::Cpu),
            Backend::Gpu(_) if quadrature != Quadrature::Exact => Err(Error::InvalidParameter {
                name: "quadrature",
                value: quadrature.name().into(),
                reason: "the GPU backend evaluates the exact method only; use the CPU backend"
                    .into(),
            }),
            Backend::Gpu(precision) => {
                let ctx = gpu::context_for(precision)?;
                Ok(Self::Gpu(GpuAssembler::new(ctx, precision, method)?))
            }
        }
    }

    /// The GPU adapter's name and backend, for reports.
    pub fn device(&self) -> Option<String> {
        match self {
            Self::Cpu => None,
            Self::Gpu(g) => {
                let a = &g.context().adapter;
                Some(format!("{} ({})", a.name, a.backend))
            }
        }
    }

    /// Where the GPU's last assembly spent its time.
    pub fn last_timings(&self) -> Option<GpuTimings> {
        match self {
            Self::Cpu => None,
            Self::Gpu(g) => Some(g.last_timings()),
        }
    }

    /// Assembles K for `problem`. On the GPU the columns of thin elements, where the closed
    /// forms cancel, are recomputed on the CPU ([`assembly::recompute_thin_columns`]).
    pub fn assemble(
        &self,
        problem: &Problem,
        options: &AssemblyOptions,
        progress: &dyn Progress,
    ) -> Result<Assembly> {
        match self {
            Self::Cpu => assembly::assemble(problem, options, progress),
            Self::Gpu(g) => {
                let mut a = g.assemble(problem, options, progress)?;
                assembly::recompute_thin_columns(&mut a, problem, options);
                Ok(a)
            }
        }
    }
}

/// Assembles K for `problem` on `backend` once (kernels compiled for it); returns the device's
/// name for the GPU.
pub fn assemble_on(
    backend: Backend,
    problem: &Problem,
    options: &AssemblyOptions,
    progress: &dyn Progress,
) -> Result<(Assembly, Option<String>)> {
    let assembler = Assembler::new(backend, problem.disc.method, options.quadrature)?;
    let a = assembler.assemble(problem, options, progress)?;
    Ok((a, assembler.device()))
}
