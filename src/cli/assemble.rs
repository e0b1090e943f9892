//! `radiosity assemble`: the matrix K as a NumPy file.

use radiosity::error::Result;
use radiosity::pipeline::{self};
use radiosity::visibility::PairPlanner;

use super::inspect::assemble_without_progress;
use super::*;

pub(crate) fn run_assemble(args: &AssembleArgs) -> Result<()> {
    let mut config = args.geometry.config()?;
    config.backend = backend(args.device.backend, args.device.precision);
    let (scene, mesh, disc) = pipeline::build(&config)?;
    let a = assemble_without_progress(&config, &scene, &mesh, &disc, &PairPlanner::new(&scene))?;
    radiosity::report::write_npy(&args.output, a.matrix.dof(), a.matrix.as_slice())?;
    eprintln!(
        "wrote K ({} x {}, float64, rho/pi included) to {}",
        a.matrix.dof(),
        a.matrix.dof(),
        args.output
    );
    Ok(())
}
