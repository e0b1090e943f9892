//! The GPU backend: the only module that touches wgpu. Shaders live in `shaders/` and are joined
//! in [`shaders`]; host data layouts shared with them are in [`layout`].

mod assembly;
mod blocks;
mod compute;
mod context;
mod cuts;
pub mod layout;
pub mod math;
mod pair_cuts;
mod pairs;
mod passes;
mod resident;
pub mod shaders;
mod storage;
mod tables;
mod tile_plan;

pub use assembly::{GpuAssembler, GpuTimings, TileLimits};
pub use blocks::{BlockArrays, DeviceBlocks};
pub use context::{AdapterRequest, AdapterSummary, GpuContext, INSTALL_HINT};
pub use pairs::PairEvaluator;
pub use resident::{DeviceOperator, DeviceTraffic};
pub use shaders::Precision;
pub use storage::StorageError;

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
    let ctx = capable_context(precision)?;
    if precision == Precision::F64 {
        F64_VERIFIED.get_or_init(|| verify_f64_math(ctx)).clone().map_err(Error::Gpu)?;
    }
    Ok(ctx)
}

/// The shared context when its adapter has what kernels of `precision` need, before the f64 math
/// library has been checked on it: for `gpu-check`, which measures the math library itself (and
/// so must be able to show the table on an adapter that [`context_for`] refuses).
pub fn capable_context(precision: Precision) -> Result<&'static GpuContext> {
    let ctx = shared_context()?;
    if precision == Precision::F64 && !ctx.adapter.f64 {
        return Err(Error::Gpu(format!(
            "adapter '{}' has no SHADER_F64 (double precision in shaders); use single precision, \
             or {INSTALL_HINT}",
            ctx.adapter.name
        )));
    }
    Ok(ctx)
}

static F64_VERIFIED: OnceLock<std::result::Result<(), String>> = OnceLock::new();

/// Worst error, in ulps against Rust's functions, that the f64 math library is verified to
/// (docs/gpu.md: 1 to 3 ulp on lavapipe over 1e7 samples).
pub const F64_ULP_BOUND: f64 = 4.0;

/// Samples per function of the check before the first f64 assembly on an adapter.
const F64_CHECK_SAMPLES: usize = 4096;

/// Vulkan promises f64 arithmetic of "at least single precision" only, and drivers reassociate
/// (docs/gpu.md): before the first f64 assembly on an adapter and driver, the math library (built
/// from + - * / and sqrt) is measured on a few thousand samples, and the GPU is refused if it is
/// off by more than [`F64_ULP_BOUND`]. A passed check is remembered per adapter, driver and
/// program version in the user's cache directory, so it runs once per machine.
fn verify_f64_math(ctx: &GpuContext) -> std::result::Result<(), String> {
    let a = &ctx.adapter;
    let key = format!("{} | {} | {} | {}", a.name, a.backend, a.driver, env!("CARGO_PKG_VERSION"));
    let marker = cache_dir().map(|d| d.join(format!("f64-check-{:016x}", fnv1a(&key))));
    if marker.as_ref().is_some_and(|m| std::fs::read_to_string(m).is_ok_and(|t| t == key)) {
        return Ok(());
    }
    let reports =
        math::measure(ctx, Precision::F64, F64_CHECK_SAMPLES).map_err(|e| e.to_string())?;
    if let Some(r) = reports.iter().find(|r| r.worst_ulp.is_nan() || r.worst_ulp > F64_ULP_BOUND) {
        return Err(format!(
            "adapter '{}' (driver {}) computes the f64 math library's {:?} {} ulp off at {:?}, above \
             the {F64_ULP_BOUND} ulp it is verified to: its f64 arithmetic is not IEEE-exact \
             enough for the GPU backend; use the CPU backend (or single precision)",
            a.name, a.driver, r.function, r.worst_ulp, r.worst_at
        ));
    }
    if let Some(m) = marker {
        // A cache that cannot be written only costs the check next time.
        let _ = std::fs::create_dir_all(m.parent().expect("in a directory"))
            .and_then(|()| std::fs::write(&m, &key));
    }
    Ok(())
}

/// `$XDG_CACHE_HOME/radiosity` or `~/.cache/radiosity`.
fn cache_dir() -> Option<std::path::PathBuf> {
    let base = std::env::var_os("XDG_CACHE_HOME")
        .map(std::path::PathBuf::from)
        .or_else(|| std::env::var_os("HOME").map(|h| std::path::Path::new(&h).join(".cache")))?;
    Some(base.join("radiosity"))
}

/// 64-bit FNV-1a: a stable file name for a key.
fn fnv1a(text: &str) -> u64 {
    text.bytes()
        .fold(0xcbf2_9ce4_8422_2325, |h, b| (h ^ u64::from(b)).wrapping_mul(0x0100_0000_01b3))
}
