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
    if cli::ranks::world().is_some() && !distributed {
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
        Command::Sun(args) => cli::sun::run_sun(&args),
        Command::BenchPlan { scene, nodes, json } => {
            cli::bench_plan::run(&scene, nodes, json.as_deref())
        }
        Command::GpuCheck { samples, precision, json } => {
            cli::gpu_check::gpu_check(samples, precision, json.as_deref())
        }
    }
}

fn main() -> ExitCode {
    quiet_vulkan_device_select();
    #[cfg(feature = "mpi")]
    let _mpi = start_mpi();
    let argv: Vec<String> = std::env::args().collect();
    if let Some(help) = cli::study::help_for_one_study(&argv) {
        print!("{help}");
        return ExitCode::SUCCESS;
    }
    match run(Cli::parse()) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => match cli::ranks::world() {
            // The other ranks may be waiting in a collective: stop them all.
            Some(w) => w.abort(&format!("error (rank {}): {e}", w.rank()), 1),
            None => {
                eprintln!("error: {e}");
                ExitCode::FAILURE
            }
        },
    }
}

/// Mesa's implicit Vulkan layer `VK_LAYER_MESA_device_select` orders the GPUs for a display
/// server: it connects to Wayland, and where there is none (a headless machine without
/// `XDG_RUNTIME_DIR`) libwayland prints "error: XDG_RUNTIME_DIR is invalid or not set in the
/// environment." on every adapter search, an error that is none. The adapter is chosen here by
/// kind and name (`gpu::GpuContext`), so the layer is switched off by its own variable, unless
/// the user set it.
fn quiet_vulkan_device_select() {
    const SWITCH: &str = "NODEVICE_SELECT";
    if std::env::var_os(SWITCH).is_none() {
        // SAFETY: the first thing `main` does, before any other thread exists to read the
        // environment.
        unsafe { std::env::set_var(SWITCH, "1") };
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
        cli::ranks::set_world(world.clone());
        let report = std::panic::take_hook();
        std::panic::set_hook(Box::new(move |info| {
            report(info);
            world.abort(&format!("rank {} panicked", world.rank()), 101);
        }));
    }
    Some(session)
}
