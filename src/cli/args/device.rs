//! Where the matrix is assembled and in which precision: `DeviceArgs`.

use clap::Args;
use radiosity::gpu::Precision;
use radiosity::pipeline::{Backend, BackendName, RunOptions};

use super::named::named;

/// Where the matrix is assembled.
#[derive(Args)]
pub(crate) struct DeviceArgs {
    /// Where the collocation matrix is assembled
    #[arg(
        long,
        value_parser = named::<BackendName>(),
        default_value_t = RunOptions::default().backend
    )]
    pub(crate) backend: BackendName,
    /// Precision of the GPU kernels
    #[arg(
        long,
        value_parser = named::<Precision>(),
        default_value_t = RunOptions::default().precision
    )]
    pub(crate) precision: Precision,
}

impl DeviceArgs {
    /// The backend these arguments name.
    pub(crate) fn backend(&self) -> Backend {
        Backend::named(self.backend, self.precision)
    }
}
