//! `radiosity`: command-line front end. Parses the arguments and hands each command to its module
//! in `cli/`, which calls the library and prints.

mod cli;

use std::process::ExitCode;

use clap::Parser;

use cli::{Cli, Command};
use radiosity::error::Result;

fn run(cli: Cli) -> Result<()> {
    match cli.command {
        Command::Study { id, max_n, backend, precision, figures, json, markdown } => {
            cli::study::run(&id, max_n, backend, precision, &figures, json.as_deref(), markdown)
        }
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
    match run(Cli::parse()) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::FAILURE
        }
    }
}
