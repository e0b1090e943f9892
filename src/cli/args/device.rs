//! Where the matrix is assembled and in which precision: `DeviceArgs`.

use clap::Args;
use radiosity::gpu::Precision;
use radiosity::pipeline::{BackendName, RunOptions};

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
    /// The backend and its precision, into `options`.
    pub(crate) fn fill(&self, options: &mut RunOptions) {
        options.backend = self.backend;
        options.precision = self.precision;
    }
}
