//! The GPU backend: the only module that touches wgpu. Shaders live in `shaders/` and are joined
//! in [`shaders`]; host data layouts shared with them are in [`layout`].

mod assembly;
mod compute;
mod context;
pub mod layout;
pub mod math;
pub mod shaders;

pub use assembly::{GpuAssembler, GpuTimings, TileLimits};
pub use context::{AdapterRequest, AdapterSummary, GpuContext, INSTALL_HINT};
pub use shaders::Precision;

use std::sync::OnceLock;

use crate::error::{Error, Result};

static SHARED: OnceLock<std::result::Result<GpuContext, String>> = OnceLock::new();

/// A context shared by the whole process, created on first use with the double-precision
/// request (f64 when the adapter has it; the `RADIOSITY_GPU_ADAPTER` variable picks by name).
pub fn shared_context() -> Result<&'static GpuContext> {
    SHARED
        .get_or_init(|| {
            GpuContext::new(&AdapterRequest { name: None, require_f64: false })
                .map_err(|e| e.to_string())
        })
        .as_ref()
        .map_err(|e| Error::Gpu(e.trim_start_matches("GPU: ").to_string()))
}

/// The shared context when it can run kernels of `precision`: an adapter without `SHADER_F64`
/// does not count as available for f64 work (Mesa's GL llvmpipe, for one, has none), and the
/// error says how to get one that has it.
pub fn context_for(precision: Precision) -> Result<&'static GpuContext> {
    let ctx = shared_context()?;
    if precision == Precision::F64 && !ctx.adapter.f64 {
        return Err(Error::Gpu(format!(
            "adapter '{}' has no SHADER_F64 (double precision in shaders); use --precision f32, \
             or {INSTALL_HINT}",
            ctx.adapter.name
        )));
    }
    Ok(ctx)
}
