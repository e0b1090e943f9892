//! `radiosity assemble`: the matrix K as a NumPy file.

use radiosity::assembly::Assembly;
use radiosity::discretization::Discretization;
use radiosity::error::Result;
use radiosity::mesh::Mesh;
use radiosity::pipeline::{self, RunConfig};
use radiosity::scene::Scene;
use radiosity::visibility::PairPlanner;

use super::*;

pub(crate) fn run_assemble(args: &AssembleArgs) -> Result<()> {
    let mut config = args.geometry.config()?;
    config.backend = backend(args.device.backend, args.device.precision);
    let (scene, mesh, disc) = pipeline::build(&config)?;
    super::output::print_notes(&scene);
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

/// K for `config` on its backend.
pub(crate) fn assemble_without_progress(
    config: &RunConfig,
    scene: &Scene,
    mesh: &Mesh,
    disc: &Discretization,
    planner: &PairPlanner,
) -> Result<Assembly> {
    let (assembled, _) = pipeline::assemble_on(
        config.backend,
        scene,
        mesh,
        disc,
        planner,
        &config.assembly,
        &|_| {},
    )?;
    Ok(assembled)
}
