//! Accuracy of the GPU math library (shaders/math_f64.wgsl) against Rust's f64 functions, in units
//! in the last place, over each function's whole domain.

use rand::{Rng, SeedableRng, rngs::StdRng};
use serde::Serialize;

use super::GpuContext;
use super::compute;
use super::layout;
use super::shaders::{self, Precision};
use crate::error::Result;

/// A function of the math library.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum MathFunction {
    /// atan(x)
    Atan,
    /// atan2(y, x)
    Atan2,
    /// log(x), x > 0
    Log,
    /// log(1 + x), x > -1
    Log1p,
    /// exp(x)
    Exp,
    /// sinh(x)
    Sinh,
    /// asinh(x)
    Asinh,
}

impl MathFunction {
    /// All functions, in the index order of shaders/math_test.wgsl.
    pub const ALL: [Self; 7] =
        [Self::Atan, Self::Atan2, Self::Log, Self::Log1p, Self::Exp, Self::Sinh, Self::Asinh];

    /// The Rust reference.
    pub fn reference(&self, x: f64, y: f64) -> f64 {
        match self {
            Self::Atan => x.atan(),
            Self::Atan2 => x.atan2(y),
            Self::Log => x.ln(),
            Self::Log1p => x.ln_1p(),
            Self::Exp => x.exp(),
            Self::Sinh => x.sinh(),
            Self::Asinh => x.asinh(),
        }
    }

    /// Deterministic samples over the domain (log-uniform magnitudes of both signs, and the
    /// regions where the algorithms switch branches).
    pub fn samples(&self, count: usize) -> Vec<(f64, f64)> {
        let mut rng = StdRng::seed_from_u64(*self as u64 + 1);
        let signed_pow = |rng: &mut StdRng, lo: f64, hi: f64| {
            let v = 10f64.powf(rng.random_range(lo..hi));
            if rng.random_bool(0.5) { v } else { -v }
        };
        (0..count)
            .map(|k| {
                let near = k % 2 == 0;
                match self {
                    Self::Atan => (
                        if near {
                            rng.random_range(-4.0..4.0)
                        } else {
                            signed_pow(&mut rng, -20.0, 20.0)
                        },
                        0.0,
                    ),
                    Self::Atan2 => {
                        (signed_pow(&mut rng, -10.0, 10.0), signed_pow(&mut rng, -10.0, 10.0))
                    }
                    Self::Log => {
                        if near {
                            (1.0 + signed_pow(&mut rng, -16.0, -0.5), 0.0)
                        } else {
                            (10f64.powf(rng.random_range(-300.0..300.0)), 0.0)
                        }
                    }
                    Self::Log1p => {
                        if near {
                            (signed_pow(&mut rng, -20.0, -0.01), 0.0)
                        } else {
                            (10f64.powf(rng.random_range(-20.0..15.0)), 0.0)
                        }
                    }
                    Self::Exp => (
                        if near {
                            rng.random_range(-1.0..1.0)
                        } else {
                            rng.random_range(-700.0..700.0)
                        },
                        0.0,
                    ),
                    Self::Sinh => (
                        if near {
                            signed_pow(&mut rng, -10.0, 0.2)
                        } else {
                            rng.random_range(-30.0..30.0)
                        },
                        0.0,
                    ),
                    Self::Asinh => (signed_pow(&mut rng, -10.0, 15.0), 0.0),
                }
            })
            .collect()
    }
}

/// Distance between `got` and `want` in units of the last place of `want` in `precision`.
pub fn ulp_error(got: f64, want: f64, precision: Precision) -> f64 {
    if got == want {
        return 0.0;
    }
    if !got.is_finite() || !want.is_finite() {
        return f64::INFINITY;
    }
    let ulp = match precision {
        Precision::F64 => {
            let a = want.abs();
            if a == 0.0 { f64::from_bits(1) } else { a.next_up() - a }
        }
        Precision::F32 => {
            let a = (want as f32).abs();
            f64::from(if a == 0.0 { f32::from_bits(1) } else { a.next_up() - a })
        }
    };
    (got - want).abs() / ulp
}

/// The worst error of one function.
#[derive(Clone, Debug, Serialize)]
pub struct UlpReport {
    /// Function.
    pub function: MathFunction,
    /// Precision of the kernel.
    pub precision: Precision,
    /// Samples evaluated.
    pub samples: usize,
    /// Largest error in ulp of the reference in the kernel's precision.
    pub worst_ulp: f64,
    /// Arguments where it occurred.
    pub worst_at: (f64, f64),
}

/// Evaluates `function` on the device at each sample, in as many dispatches as the device's grid
/// and binding limits need.
pub fn evaluate(
    ctx: &GpuContext,
    precision: Precision,
    function: MathFunction,
    samples: &[(f64, f64)],
) -> Result<Vec<f64>> {
    let code = MathFunction::ALL.iter().position(|f| *f == function).expect("listed") as u32;
    let source = shaders::math_test(precision);
    let (layout_, pipelines) = compute::pipeline(ctx, &source, &["math_eval"], 3, &[0], &[2])?;
    // One dispatch: a 1-D grid, and two arguments per sample within one binding.
    let grid_limit =
        u64::from(ctx.limits.max_compute_workgroups_per_dimension) * u64::from(layout::WORKGROUP);
    let binding_limit =
        ctx.limits.max_storage_buffer_binding_size.min(1 << 26) / (2 * precision.bytes() as u64);
    let chunk = grid_limit.min(binding_limit).max(1) as usize;
    let mut values = Vec::with_capacity(samples.len());
    for part in samples.chunks(chunk) {
        let flat: Vec<f64> = part.iter().flat_map(|&(x, y)| [x, y]).collect();
        let params: [u32; 4] = [code, part.len() as u32, 0, 0];
        let size = (part.len() * precision.bytes()) as u64;
        let staging = compute::checked(ctx, "gpu-check", || {
            let uniform = compute::uniform(ctx, bytemuck::cast_slice(&params));
            let input = compute::storage(ctx, &layout::real_bytes(&flat, precision));
            let (out, staging) = compute::output(ctx, size);
            let group = compute::bind_group(ctx, &layout_, &[&uniform, &input, &out]);
            let (x, _, _) = compute::grid(ctx, part.len() as u64);
            let mut encoder = ctx.device.create_command_encoder(&Default::default());
            {
                let mut pass = encoder.begin_compute_pass(&Default::default());
                pass.set_pipeline(&pipelines[0]);
                pass.set_bind_group(0, &group, &[]);
                pass.dispatch_workgroups(x, 1, 1);
            }
            encoder.copy_buffer_to_buffer(&out, 0, &staging, 0, size.max(16));
            ctx.queue.submit([encoder.finish()]);
            staging
        })?;
        values.extend(compute::read_back(ctx, &staging, size, precision)?);
    }
    Ok(values)
}

/// Worst ulp error of each function over `count` samples.
pub fn measure(ctx: &GpuContext, precision: Precision, count: usize) -> Result<Vec<UlpReport>> {
    MathFunction::ALL
        .iter()
        .map(|&function| {
            let samples = function.samples(count);
            // f32 kernels see the arguments rounded to f32 (normal numbers only): compare with
            // the reference there.
            let rounded: Vec<(f64, f64)> = match precision {
                Precision::F64 => samples.clone(),
                Precision::F32 => samples
                    .iter()
                    .map(|&(x, y)| (f64::from(x as f32), f64::from(y as f32)))
                    .filter(|&(x, y)| [x, y].iter().all(|&v| v == 0.0 || (v as f32).is_normal()))
                    .collect(),
            };
            let got = evaluate(ctx, precision, function, &rounded)?;
            let mut report = UlpReport {
                function,
                precision,
                samples: rounded.len(),
                worst_ulp: 0.0,
                worst_at: (0.0, 0.0),
            };
            for (&(x, y), g) in rounded.iter().zip(got) {
                let want = function.reference(x, y);
                // f32 results are compared where they are normal numbers: drivers may flush
                // subnormal f32 results to zero (NVIDIA does for exp below -87.34), and the
                // kernels never produce them.
                let representable = match precision {
                    Precision::F64 => want.is_finite(),
                    Precision::F32 => {
                        want == 0.0
                            || (f64::from(f32::MIN_POSITIVE)..f64::from(f32::MAX))
                                .contains(&want.abs())
                    }
                };
                if !representable {
                    continue;
                }
                let e = ulp_error(g, want, precision);
                if e > report.worst_ulp || e.is_nan() {
                    report.worst_ulp = e;
                    report.worst_at = (x, y);
                }
            }
            Ok(report)
        })
        .collect()
}
