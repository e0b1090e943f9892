//! `radiosity gpu-check`: the adapter and the WGSL math library's worst ulp errors.

use serde::Serialize;

use radiosity::error::Result;
use radiosity::gpu::Precision;
use radiosity::report;

/// What `gpu-check` prints.
#[derive(Serialize)]
pub(crate) struct GpuCheck {
    adapter: radiosity::gpu::AdapterSummary,
    functions: Vec<radiosity::gpu::math::UlpReport>,
}

pub(crate) fn gpu_check(samples: usize, precision: Precision, json: Option<&str>) -> Result<()> {
    // Measured without the f64 gate of `context_for`: this is the table that explains a refusal.
    let ctx = radiosity::gpu::capable_context(precision)?;
    let functions = radiosity::gpu::math::measure(ctx, precision, samples)?;
    let out = GpuCheck { adapter: ctx.adapter.clone(), functions };
    if let Some(target) = json {
        return report::write_json(&out, target);
    }
    let a = &out.adapter;
    println!("adapter: {} ({}, {}), SHADER_F64: {}", a.name, a.backend, a.device_type, a.f64);
    println!(
        "math library in {}, {} samples per function, against Rust's f64 functions:",
        precision.name(),
        samples
    );
    for r in &out.functions {
        println!(
            "  {:<6} worst {:>6.2} ulp at {:?}",
            format!("{:?}", r.function).to_lowercase(),
            r.worst_ulp,
            r.worst_at
        );
    }
    Ok(())
}
