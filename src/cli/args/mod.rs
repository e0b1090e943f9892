//! The arguments (clap): groups of flags by what they configure, each command's own arguments,
//! and how they become the library's `RunConfig`.

mod colour;
mod commands;
mod device;
mod geometry;
mod import;
mod named;
mod operator;
mod outputs;
mod run_config;
mod values;

pub(crate) use commands::{
    AssembleArgs, BenchArgs, DEFAULT_FIGURES, SolveArgs, StudyArgs, SunArgs, ViewFactorArgs,
};
pub(crate) use named::named;
pub(crate) use outputs::OutputArgs;
pub(crate) use values::{parse_point, parse_size};
