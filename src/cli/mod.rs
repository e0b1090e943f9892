//! The command line: the arguments (clap), and one module per command with what it prints.
//!
//! This file holds the command tree (`Cli`, `Command`) that main.rs parses and dispatches; the
//! argument groups and their conversion into the library's `RunConfig` are in `args/`, the
//! ranks of a distributed run in `ranks`.

pub(crate) mod args;
pub(crate) mod assemble;
pub(crate) mod bench;
pub(crate) mod bench_plan;
pub(crate) mod gpu_check;
pub(crate) mod inspect;
pub(crate) mod output;
pub(crate) mod progress;
pub(crate) mod ranks;
pub(crate) mod solve;
pub(crate) mod study;
pub(crate) mod sun;
pub(crate) mod viewfactors;

use clap::{Parser, Subcommand};

use args::{AssembleArgs, BenchArgs, SolveArgs, StudyArgs, SunArgs, ViewFactorArgs, named};
use radiosity::gpu::Precision;

#[derive(Parser)]
#[command(
    name = "radiosity",
    version,
    about = "Collocation solver for the occluded radiosity equation (Atkinson, Chien & Seol 2000)"
)]
pub(crate) struct Cli {
    #[command(subcommand)]
    pub(crate) command: Command,
}

#[derive(Subcommand)]
pub(crate) enum Command {
    /// Reproduce a table or figure of the paper, or run a study (ids: table-3.1 .. table-3.5,
    /// table-4.1, table-4.2, figure-3.4 .. figure-3.7, error-vs-time, grading)
    Study(StudyArgs),
    /// Solve one problem and report its error and timings
    Solve(SolveArgs),
    /// Matrix statistics: row sums of K/rho and pair-class counts
    Inspect(SolveArgs),
    /// Assemble the same matrix on several backends: timings, pairs per second, differences
    Bench(BenchArgs),
    /// Assemble the collocation matrix K and write it as a NumPy .npy file
    Assemble(AssembleArgs),
    /// Element-to-element view factors F_ij, with reciprocity and closure checks
    Viewfactors(ViewFactorArgs),
    /// Shortwave light under the sun and an isotropic sky: each face's exactly sunlit part,
    /// direct, sky and reflected irradiance, absorbed and reflected flux
    Sun(SunArgs),
    /// Time the pair plan (views of sampled nodes against every face) with and without the
    /// occluder index (R*-tree), and check that both give the same views
    BenchPlan {
        /// Scene (e.g. city:35x36, about 10 000 faces)
        #[arg(long, default_value = "city:35x36")]
        scene: String,
        /// Nodes sampled (face centres spread over the scene)
        #[arg(long, default_value_t = 100)]
        nodes: usize,
        /// Write JSON to PATH (`-` for standard output) instead of text
        #[arg(long, value_name = "PATH")]
        json: Option<String>,
    },
    /// The GPU adapter, its f64 support, and the worst errors (ulp) of the WGSL math library
    GpuCheck {
        /// Samples per function
        #[arg(long, default_value_t = 1_000_000)]
        samples: usize,
        /// Precision of the math library to test
        #[arg(long, value_parser = named::<Precision>(), default_value_t = Precision::F64)]
        precision: Precision,
        /// Write JSON to PATH (`-` for standard output) instead of text
        #[arg(long, value_name = "PATH")]
        json: Option<String>,
    },
}
