//! `radiosity`: command-line front end. Parses the arguments and hands each command to its module
//! in `cli/`, which calls the library and prints.

mod cli;

use std::process::ExitCode;

use clap::Parser;

use cli::{Cli, Command};
use radiosity::error::Result;

fn run(cli: Cli) -> Result<()> {
    let distributed = match &cli.command {
        Command::Solve(_) | Command::Inspect(_) | Command::Bench(_) => true,
        Command::Study(args) => args.id == "compression",
        _ => false,
    };
    if cli::world().is_some() && !distributed {
        return Err(radiosity::error::Error::InvalidParameter {
            name: "command",
            value: "under mpirun with several ranks".into(),
            reason: "solve, inspect, bench and study compression run distributed; run the others \
                     in one process"
                .into(),
        });
    }
    match cli.command {
        Command::Study(args) => cli::study::run(&args),
        Command::Solve(args) => cli::solve::run(&args),
        Command::Inspect(args) => cli::inspect::inspect(&args),
        Command::Bench(args) => cli::bench::run_bench(&args),
        Command::Assemble(args) => cli::assemble::run_assemble(&args),
        Command::Viewfactors(args) => cli::viewfactors::run_viewfactors(&args),
        Command::BenchPlan { scene, nodes, json } => {
            cli::bench_plan::run(&scene, nodes, json.as_deref())
        }
        Command::GpuCheck { samples, precision, json } => {
            cli::gpu_check::gpu_check(samples, precision, json.as_deref())
        }
    }
}

fn main() -> ExitCode {
    #[cfg(feature = "mpi")]
    let _mpi = start_mpi();
    match run(Cli::parse()) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => match cli::world() {
            // The other ranks may be waiting in a collective: stop them all.
            Some(w) => w.abort(&format!("error (rank {}): {e}", w.rank()), 1),
            None => {
                eprintln!("error: {e}");
                ExitCode::FAILURE
            }
        },
    }
}

/// Initializes MPI; under `mpirun -np N` with N > 1 the runs are spread over the ranks, and a
/// rank that panics stops all of them. MPI is finalized when the returned session is dropped.
#[cfg(feature = "mpi")]
fn start_mpi() -> Option<radiosity::distributed::MpiSession> {
    use radiosity::distributed::Collective;
    use std::sync::Arc;
    let (session, world) = radiosity::distributed::MpiWorld::init()?;
    if world.size() > 1 {
        let world = Arc::new(world);
        cli::set_world(world.clone());
        let report = std::panic::take_hook();
        std::panic::set_hook(Box::new(move |info| {
            report(info);
            world.abort(&format!("rank {} panicked", world.rank()), 101);
        }));
    }
    Some(session)
}
