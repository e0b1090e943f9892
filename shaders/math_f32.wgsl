// f32 math: the built-in functions, which are reliable for 32-bit floats. Same names as
// math_f64.wgsl so the kernels compile against either.

fn m_atan(x: f32) -> f32 { return atan(x); }
fn m_atan2(y: f32, x: f32) -> f32 { return atan2(y, x); }
fn m_log(x: f32) -> f32 { return log(x); }
fn m_log1p(x: f32) -> f32 {
    let u = 1.0f + x;
    if (u == 1.0f) {
        return x;
    }
    return log(u) * (x / (u - 1.0f));
}
fn m_exp(x: f32) -> f32 { return exp(x); }
fn m_sinh(x: f32) -> f32 { return sinh(x); }
fn m_asinh(x: f32) -> f32 { return asinh(x); }
