// f64 math library: the transcendental functions the kernels need, from + - * / sqrt and ldexp.
//
// Why: naga emits GLSL.std.450 Atan/Log/Exp for f64, which that instruction set defines only for
// 16/32-bit floats; on lavapipe they return garbage (docs/gpu.md, "f64 transcendentals"). naga also rejects frexp
// and bitcast on f64 here, so exponents come from the f32 log2 and an exact correction, or a
// cascade of comparisons with powers of two outside f32's range. Worst errors, measured against Rust's f64 functions, are in docs/gpu.md.
//
// Algorithms (own code): atan by the reduction points of fdlibm's s_atan.c and a fitted polynomial; log by x = 2^k m, m in [sqrt(2)/2, sqrt(2)), log(1 + f) = f - s (f - R),
// s = f / (2 + f), R the series of 2 atanh(s)/s - 2 in s²; exp by x = k ln2 + r and a degree-13
// Taylor series of e^r - 1; sinh by its series for |x| <= 2; asinh through log1p / log.
// Domain notes: m_log expects x > 0; results for NaN and infinities are not specified.

const M_PIO2_HI: f64 = 1.5707963267948966lf;
const M_PIO2_LO: f64 = 6.123233995736766e-17lf;
const M_PI_HI: f64 = 3.141592653589793lf;
const M_PI_LO: f64 = 1.2246467991473532e-16lf;
// ln 2 = M_LN2_HI + M_LN2_LO with 42 significant bits in the high part, so k * M_LN2_HI is exact.
const M_LN2_HI: f64 = 0.6931471805598903lf;
const M_LN2_LO: f64 = 5.497923018708371e-14lf;
const M_INV_LN2: f64 = 1.4426950408889634lf;
const M_SQRT2: f64 = 1.4142135623730951lf;
const LN2: f64 = 0.6931471805599453lf;

// atan(c) = hi + lo for the reduction points c = 1/2, 1, 3/2 (and pi/2 for c = infinity).
const M_ATAN_HALF_HI: f64 = 0.4636476090008061lf;
const M_ATAN_HALF_LO: f64 = 2.2698777452961687e-17lf;
const M_PIO4_HI: f64 = 0.7853981633974483lf;
const M_PIO4_LO: f64 = 3.061616997868383e-17lf;
const M_ATAN_3HALF_HI: f64 = 0.982793723247329lf;
const M_ATAN_3HALF_LO: f64 = 1.3903311031230998e-17lf;

// atan(a) for a >= 0: reduce to |t| <= 7/16 with t = (a - c)/(1 + c a), c in {0, 1/2, 1, 3/2, inf}
// (breakpoints 7/16, 11/16, 19/16, 39/16), written as t = (n1 a - n0)/(d0 + d1 a) with small
// integer coefficients so every lane runs one division; then atan(t) = t + t u P(u), u = t², with
// P a degree-11 near-minimax (Chebyshev) fit on [0, (7/16)²]: truncation below 1e-18 relative.
fn m_atan_pos(a: f64) -> f64 {
    let b1 = a >= 0.4375lf;
    let b2 = a >= 0.6875lf;
    let b3 = a >= 1.1875lf;
    let b4 = a >= 2.4375lf;
    // (n1, n0, d0, d1) for c = 0, 1/2, 1, 3/2, inf: (1,0,1,0), (2,1,2,1), (1,1,1,1), (2,3,2,3), (0,1,0,1).
    let n1 = select(select(select(select(1.0lf, 2.0lf, b1), 1.0lf, b2), 2.0lf, b3), 0.0lf, b4);
    let n0 = select(select(select(select(0.0lf, 1.0lf, b1), 1.0lf, b2), 3.0lf, b3), 1.0lf, b4);
    let d1 = select(select(select(select(0.0lf, 1.0lf, b1), 1.0lf, b2), 3.0lf, b3), 1.0lf, b4);
    let d0 = select(select(select(select(1.0lf, 2.0lf, b1), 1.0lf, b2), 2.0lf, b3), 0.0lf, b4);
    let hi = select(select(select(select(0.0lf, M_ATAN_HALF_HI, b1), M_PIO4_HI, b2), M_ATAN_3HALF_HI, b3), M_PIO2_HI, b4);
    let lo = select(select(select(select(0.0lf, M_ATAN_HALF_LO, b1), M_PIO4_LO, b2), M_ATAN_3HALF_LO, b3), M_PIO2_LO, b4);
    let t = (n1 * a - n0) / (d0 + d1 * a);
    let u = t * t;
    let p = -0.3333333333333333lf + u * (0.1999999999999941lf + u * (-0.14285714285566806lf
        + u * (0.11111111096645038lf + u * (-0.09090908355602592lf + u * (0.07692285554889286lf
        + u * (-0.06666241923359964lf + u * (0.05876946456755061lf + u * (-0.05216679739313656lf
        + u * (0.04492259293193656lf + u * (-0.033128134256069586lf + u * 0.014773184616983806lf))))))))));
    return hi + (t + (t * u * p + lo));
}

fn m_atan(x: f64) -> f64 {
    let r = m_atan_pos(abs(x));
    return select(r, -r, x < 0.0lf);
}

fn m_atan2(y: f64, x: f64) -> f64 {
    let ax = abs(x);
    let ay = abs(y);
    if (ax == 0.0lf && ay == 0.0lf) {
        return select(0.0lf, M_PI_HI, x < 0.0lf);
    }
    var r: f64;
    if (ay <= ax) {
        r = m_atan_pos(ay / ax);
    } else {
        r = M_PIO2_HI - (m_atan_pos(ax / ay) - M_PIO2_LO);
    }
    if (x < 0.0lf) {
        r = M_PI_HI - (r - M_PI_LO);
    }
    return select(r, -r, y < 0.0lf);
}

// x = m 2^k with m in [1, 2), for finite x > 0: exact scalings by powers of two.
struct M_Split {
    m: f64,
    k: i32,
}

fn m_split(x: f64) -> M_Split {
    // Inside f32's normal range the f32 log2 gives the exponent to within one (the rounding of x
    // to f32 may reach the next power of two); one exact correction step follows.
    if (x > 1.0e-37lf && x < 1.0e37lf) {
        var k = i32(floor(log2(f32(x))));
        var m = ldexp(x, -k);
        if (m >= 2.0lf) {
            m = m * 0.5lf;
            k = k + 1;
        }
        if (m < 1.0lf) {
            m = m * 2.0lf;
            k = k - 1;
        }
        return M_Split(m, k);
    }
    var m = x;
    var k = 0;
    if (m < 2.2250738585072014e-308lf) {
        m = m * 1.8014398509481984e+16lf;
        k = -54;
    }
    if (m >= 1.3407807929942597e+154lf) { m = ldexp(m, -512); k += 512; }
    if (m >= 1.157920892373162e+77lf) { m = ldexp(m, -256); k += 256; }
    if (m >= 3.402823669209385e+38lf) { m = ldexp(m, -128); k += 128; }
    if (m >= 1.8446744073709552e+19lf) { m = ldexp(m, -64); k += 64; }
    if (m >= 4294967296.0lf) { m = ldexp(m, -32); k += 32; }
    if (m >= 65536.0lf) { m = ldexp(m, -16); k += 16; }
    if (m >= 256.0lf) { m = ldexp(m, -8); k += 8; }
    if (m >= 16.0lf) { m = ldexp(m, -4); k += 4; }
    if (m >= 4.0lf) { m = ldexp(m, -2); k += 2; }
    if (m >= 2.0lf) { m = ldexp(m, -1); k += 1; }
    if (m < 1.4916681462400413e-154lf) { m = ldexp(m, 512); k -= 512; }
    if (m < 1.727233711018889e-77lf) { m = ldexp(m, 256); k -= 256; }
    if (m < 5.877471754111438e-39lf) { m = ldexp(m, 128); k -= 128; }
    if (m < 1.0842021724855044e-19lf) { m = ldexp(m, 64); k -= 64; }
    if (m < 4.656612873077393e-10lf) { m = ldexp(m, 32); k -= 32; }
    if (m < 3.0517578125e-05lf) { m = ldexp(m, 16); k -= 16; }
    if (m < 0.0078125lf) { m = ldexp(m, 8); k -= 8; }
    if (m < 0.125lf) { m = ldexp(m, 4); k -= 4; }
    if (m < 0.5lf) { m = ldexp(m, 2); k -= 2; }
    if (m < 1.0lf) { m = ldexp(m, 1); k -= 1; }
    return M_Split(m, k);
}

// log(1 + f) + extra for f in [sqrt(2)/2 - 1, sqrt(2) - 1], where `extra` is a small term added
// before the last rounding (k ln2_lo in m_log).
fn m_log1p_core(f: f64, extra: f64) -> f64 {
    let s = f / (2.0lf + f);
    let z = s * s;
    // R = 2z/3 + 2z^2/5 + ... + 2z^10/21, so 2 atanh(s) = 2s + s R.
    let r = z * (0.6666666666666666lf + z * (0.4lf + z * (0.2857142857142857lf
        + z * (0.2222222222222222lf + z * (0.18181818181818182lf + z * (0.15384615384615385lf
        + z * (0.13333333333333333lf + z * (0.11764705882352941lf + z * (0.10526315789473684lf
        + z * 0.09523809523809523lf)))))))));
    let hfsq = 0.5lf * f * f;
    return f - (hfsq - (s * (hfsq + r) + extra));
}

fn m_log(x: f64) -> f64 {
    if (x <= 0.0lf) {
        return (x - x) / (x - x);
    }
    let sp = m_split(x);
    var m = sp.m;
    var k = sp.k;
    if (m > M_SQRT2) {
        m = m * 0.5lf;
        k = k + 1;
    }
    let dk = f64(k);
    return dk * M_LN2_HI + m_log1p_core(m - 1.0lf, dk * M_LN2_LO);
}

// log(1 + y) for y in [0, 1]. Every argument reaches m_log1p_core exactly: for y > sqrt(2) - 1,
// 1 + y = 2 (1 + (y - 1)/2) and (y - 1)/2 is exact. (No compensated sums: the driver's optimizer
// may simplify x - ((1 + x) - 1) to 0, as Mesa's does.)
fn m_log1p_unit(y: f64) -> f64 {
    if (y < 0.41421356237309515lf) {
        return m_log1p_core(y, 0.0lf);
    }
    return M_LN2_HI + m_log1p_core((y - 1.0lf) * 0.5lf, M_LN2_LO);
}

fn m_log1p(x: f64) -> f64 {
    if (x > -0.2928932188134524lf && x <= 1.0lf) {
        if (x >= 0.0lf) {
            return m_log1p_unit(x);
        }
        return m_log1p_core(x, 0.0lf);
    }
    if (x > 1.0lf) {
        // log(1 + x) = log(x) + log(1 + 1/x).
        return m_log(x) + m_log1p_unit(1.0lf / x);
    }
    if (x > -0.5lf) {
        // 1 + x = (1 + (1 + 2x)) / 2 with 1 + 2x exact.
        return m_log1p_core(1.0lf + 2.0lf * x, -M_LN2_LO) - M_LN2_HI;
    }
    // 1 + x is exact for x in [-1, -0.5].
    return m_log(1.0lf + x);
}

// e^r - 1 for |r| <= ln2 / 2 (degree 13; the first omitted term is below 2^-55 r).
fn m_expm1_small(r: f64) -> f64 {
    return r * (1.0lf + r * (0.5lf + r * (0.16666666666666666lf + r * (0.041666666666666664lf
        + r * (0.008333333333333333lf + r * (0.001388888888888889lf + r * (0.0001984126984126984lf
        + r * (2.48015873015873e-05lf + r * (2.7557319223985893e-06lf + r * (2.755731922398589e-07lf
        + r * (2.505210838544172e-08lf + r * (2.08767569878681e-09lf + r * 1.6059043836821613e-10lf))))))))))));
}

fn m_exp(x: f64) -> f64 {
    if (x > 709.782712893384lf) {
        return ldexp(1.0lf, 1024);
    }
    if (x < -745.1332191019412lf) {
        return 0.0lf;
    }
    // x = k ln2 + r with r = (x - k M_LN2_HI) exact and the tail c = k M_LN2_LO (|c| < 6e-11)
    // taken out as the factor e^-c = 1 - c (c² is below 2^-60), not subtracted from r: the NVIDIA
    // driver folds (x - k HI) - k LO into x - k (HI + LO) = x - k ln2 rounded, 200 ulp off at
    // k = -1004 (docs/gpu.md), and a product cannot be folded that way.
    let k = round(x * M_INV_LN2);
    let r = x - k * M_LN2_HI;
    let c = k * M_LN2_LO;
    let p = 1.0lf + m_expm1_small(r);
    return ldexp(p - p * c, i32(k));
}

fn m_sinh(x: f64) -> f64 {
    let a = abs(x);
    var s: f64;
    if (a <= 2.0lf) {
        // x + x^3/3! + ... + x^25/25!: positive terms, the first omitted below 2^-60 sinh(x).
        let a2 = a * a;
        s = a + a * a2 * (0.16666666666666666lf + a2 * (0.008333333333333333lf
            + a2 * (0.0001984126984126984lf + a2 * (2.7557319223985893e-06lf + a2 * (2.505210838544172e-08lf
            + a2 * (1.6059043836821613e-10lf + a2 * (7.647163731819816e-13lf + a2 * (2.8114572543455206e-15lf
            + a2 * (8.22063524662433e-18lf + a2 * (1.9572941063391263e-20lf + a2 * (3.868170170630684e-23lf
            + a2 * 6.446950284384474e-26lf)))))))))));
    } else {
        let e = m_exp(a);
        s = 0.5lf * (e - 1.0lf / e);
    }
    return select(s, -s, x < 0.0lf);
}

fn m_asinh(x: f64) -> f64 {
    let a = abs(x);
    var r: f64;
    if (a > 268435456.0lf) {
        r = m_log(a) + (M_LN2_HI + M_LN2_LO);
    } else if (a >= 2.0lf) {
        r = m_log(2.0lf * a + 1.0lf / (a + sqrt(a * a + 1.0lf)));
    } else {
        // asinh(a) = log1p(a + a² / (1 + sqrt(1 + a²))).
        r = m_log1p(a + a * a / (1.0lf + sqrt(1.0lf + a * a)));
    }
    return select(r, -r, x < 0.0lf);
}
