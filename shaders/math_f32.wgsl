// f32 math: the algorithms of math_f64.wgsl with polynomials cut for f32. The built-ins are not
// used: on lavapipe f32 atan is ~300 ulp off, log loses relative accuracy near 1 and sinh/asinh
// near 0. Same names as math_f64.wgsl so the kernels compile against either.

// atan(a), a >= 0, as m_atan_pos in math_f64.wgsl (lavapipe's f32 atan is ~300 ulp off).
fn m_atan_pos(a: f32) -> f32 {
    let b1 = a >= 0.4375f;
    let b2 = a >= 0.6875f;
    let b3 = a >= 1.1875f;
    let b4 = a >= 2.4375f;
    let n1 = select(select(select(select(1.0f, 2.0f, b1), 1.0f, b2), 2.0f, b3), 0.0f, b4);
    let n0 = select(select(select(select(0.0f, 1.0f, b1), 1.0f, b2), 3.0f, b3), 1.0f, b4);
    let d1 = select(select(select(select(0.0f, 1.0f, b1), 1.0f, b2), 3.0f, b3), 1.0f, b4);
    let d0 = select(select(select(select(1.0f, 2.0f, b1), 1.0f, b2), 2.0f, b3), 0.0f, b4);
    let hi = select(select(select(select(0.0f, 0.4636476f, b1), 0.7853982f, b2), 0.9827937f, b3), 1.5707964f, b4);
    let t = (n1 * a - n0) / (d0 + d1 * a);
    let u = t * t;
    let p = -0.33333334f + u * (0.2f + u * (-0.14285715f + u * (0.11111111f + u * (-0.09090909f
        + u * (0.07692286f + u * (-0.06666242f + u * 0.05876946f))))));
    return hi + (t + t * u * p);
}

fn m_atan(x: f32) -> f32 {
    let r = m_atan_pos(abs(x));
    return select(r, -r, x < 0.0f);
}

fn m_atan2(y: f32, x: f32) -> f32 {
    let ax = abs(x);
    let ay = abs(y);
    if (ax == 0.0f && ay == 0.0f) {
        return select(0.0f, 3.1415927f, x < 0.0f);
    }
    var r: f32;
    if (ay <= ax) {
        r = m_atan_pos(ay / ax);
    } else {
        r = 1.5707964f - m_atan_pos(ax / ay);
    }
    if (x < 0.0f) {
        r = 3.1415927f - r;
    }
    return select(r, -r, y < 0.0f);
}

const M32_LN2_HI: f32 = 0.693145751953125f;
const M32_LN2_LO: f32 = 1.4286068e-06f;
const M32_SQRT2: f32 = 1.4142135f;
const LN2: f32 = 0.6931472f;

// log(1 + f) + extra for f in [sqrt(2)/2 - 1, sqrt(2) - 1] (m_log1p_core of math_f64.wgsl with
// the series of 2 atanh(s)/s cut for f32).
fn m_log1p_core(f: f32, extra: f32) -> f32 {
    let s = f / (2.0f + f);
    let z = s * s;
    let r = z * (0.666666667f + z * (0.4f + z * (0.285714286f + z * (0.222222222f + z * 0.181818182f))));
    let hfsq = 0.5f * f * f;
    return f - (hfsq - (s * (hfsq + r) + extra));
}

fn m_log(x: f32) -> f32 {
    // The exponent from the built-in log2 (to within one), corrected exactly.
    var k = i32(floor(log2(x)));
    var m = ldexp(x, -k);
    if (m >= 2.0f) {
        m = m * 0.5f;
        k = k + 1;
    }
    if (m < 1.0f) {
        m = m * 2.0f;
        k = k - 1;
    }
    if (m > M32_SQRT2) {
        m = m * 0.5f;
        k = k + 1;
    }
    let dk = f32(k);
    return dk * M32_LN2_HI + m_log1p_core(m - 1.0f, dk * M32_LN2_LO);
}

// log(1 + y) for y in [0, 1].
fn m_log1p_unit(y: f32) -> f32 {
    if (y < 0.41421357f) {
        return m_log1p_core(y, 0.0f);
    }
    return M32_LN2_HI + m_log1p_core((y - 1.0f) * 0.5f, M32_LN2_LO);
}

fn m_log1p(x: f32) -> f32 {
    if (x > -0.29289323f && x < 0.41421357f) {
        return m_log1p_core(x, 0.0f);
    }
    if (x > 0.0f && x <= 1.0f) {
        return M32_LN2_HI + m_log1p_core((x - 1.0f) * 0.5f, M32_LN2_LO);
    }
    if (x > 1.0f) {
        return m_log(x) + m_log1p_unit(1.0f / x);
    }
    if (x > -0.5f) {
        return m_log1p_core(1.0f + 2.0f * x, -M32_LN2_LO) - M32_LN2_HI;
    }
    return m_log(1.0f + x);
}

fn m_exp(x: f32) -> f32 {
    if (x > 88.72283f) {
        return ldexp(1.0f, 128);
    }
    if (x < -103.9f) {
        return 0.0f;
    }
    let k = round(x * 1.44269504f);
    let r = (x - k * M32_LN2_HI) - k * M32_LN2_LO;
    let p = r * (1.0f + r * (0.5f + r * (0.166666667f + r * (0.0416666667f + r * (0.00833333333f
        + r * (0.00138888889f + r * 0.000198412698f))))));
    return ldexp(1.0f + p, i32(k));
}

fn m_sinh(x: f32) -> f32 {
    let a = abs(x);
    var s: f32;
    if (a <= 2.0f) {
        let a2 = a * a;
        s = a + a * a2 * (0.166666667f + a2 * (0.00833333333f + a2 * (0.000198412698f
            + a2 * (2.75573192e-06f + a2 * (2.50521084e-08f + a2 * 1.60590438e-10f)))));
    } else {
        let e = m_exp(a);
        s = 0.5f * (e - 1.0f / e);
    }
    return select(s, -s, x < 0.0f);
}

fn m_asinh(x: f32) -> f32 {
    let a = abs(x);
    var r: f32;
    if (a > 4096.0f) {
        r = m_log(a) + (M32_LN2_HI + M32_LN2_LO);
    } else if (a >= 2.0f) {
        r = m_log(2.0f * a + 1.0f / (a + sqrt(a * a + 1.0f)));
    } else {
        r = m_log1p(a + a * a / (1.0f + sqrt(1.0f + a * a)));
    }
    return select(r, -r, x < 0.0f);
}
