//! `radiosity assemble`: the matrix K as a NumPy file.

use radiosity::assembly::Assembly;
use radiosity::error::Result;
use radiosity::pipeline::{self, Problem, RunConfig};
use radiosity::progress::Silent;

use super::*;

pub(crate) fn run_assemble(args: &AssembleArgs) -> Result<()> {
    let mut config = args.geometry.config()?;
    config.backend = backend(args.device.backend, args.device.precision);
    let problem = pipeline::build(&config)?;
    super::output::print_notes(&problem.scene);
    let a = assemble_without_progress(&config, &problem)?;
    radiosity::report::write_npy(&args.output, a.matrix.dof(), a.matrix.as_slice())?;
    eprintln!(
        "wrote K ({} x {}, float64, rho/pi included) to {}",
        a.matrix.dof(),
        a.matrix.dof(),
        args.output
    );
    Ok(())
}

/// K for `config` on its backend.
pub(crate) fn assemble_without_progress(config: &RunConfig, problem: &Problem) -> Result<Assembly> {
    let (assembled, _) = pipeline::assemble_on(config.backend, problem, &config.assembly, &Silent)?;
    Ok(assembled)
}
