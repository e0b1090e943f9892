//! Where the matrix is assembled and in which precision: `DeviceArgs` and its choices.

use clap::{Args, ValueEnum};

#[derive(Clone, Copy, PartialEq, Eq, ValueEnum)]
pub(crate) enum BackendArg {
    Cpu,
    Gpu,
}

#[derive(Clone, Copy, PartialEq, Eq, ValueEnum)]
pub(crate) enum PrecisionArg {
    F64,
    F32,
}

/// Where the matrix is assembled.
#[derive(Args)]
pub(crate) struct DeviceArgs {
    /// Where the collocation matrix is assembled
    #[arg(long, value_enum, default_value_t = BackendArg::Cpu)]
    pub(crate) backend: BackendArg,
    /// Precision of the GPU kernels
    #[arg(long, value_enum, default_value_t = PrecisionArg::F64)]
    pub(crate) precision: PrecisionArg,
}
