//! Branch-free f64 elementary functions over lanes `[f64; N]`, for the vectorised kernels: each
//! step is a loop over the lanes without branches, so that the caller, compiled for AVX2, runs it
//! in vector registers (the library's `atan2`, `exp` and `ln_1p` are scalar calls). With `FUSED`
//! (for callers compiled for FMA) the polynomials' Horner steps are fused multiply-adds.
//!
//! The algorithms are those of `shaders/math_f64.wgsl` (own code): atan by the reduction points of
//! fdlibm's s_atan.c and a fitted polynomial; exp by `x = k ln 2 + r` and a degree-13 Taylor
//! series of `e^r - 1` (split in even and odd parts, which give `e^-x` too); log1p on [0, 1] by `log(1 + f) = f - s (f - R)`, `s = f / (2 + f)`, R the
//! minimax fit of `2 atanh(s)/s - 2` in s² from fdlibm's e_log.c. Their errors against the library are measured in the
//! tests below (at most 2 ulp).

/// `ln 2 = LN2_HI + LN2_LO` with 42 significant bits in the high part, so `k LN2_HI` is exact for
/// the exponents `k` of f64.
const LN2_HI: f64 = 0.6931471805598903;
const LN2_LO: f64 = 5.497923018708371e-14;

/// `a b + c`, fused (one rounding) when `FUSED`: callers compiled for FMA ask for it, the
/// portable ones not, for whom the fused form would be a library call.
#[inline(always)]
fn mul_add<const FUSED: bool>(a: f64, b: f64, c: f64) -> f64 {
    if FUSED { a.mul_add(b, c) } else { a * b + c }
}

#[inline(always)]
fn lanes<const N: usize>(f: impl Fn(usize) -> f64) -> [f64; N] {
    std::array::from_fn(f)
}

/// `atan2(y, x)` for `y > 0` (a result in (0, π)): `atan(y/|x|)`, reflected for `x < 0`.
#[inline(always)]
pub fn atan2_positive_y<const N: usize, const FUSED: bool>(y: [f64; N], x: [f64; N]) -> [f64; N] {
    const PI_HI: f64 = std::f64::consts::PI;
    const PI_LO: f64 = 1.2246467991473532e-16;
    let r = atan_of_ratio::<N, FUSED>(y, lanes(|l| x[l].abs()));
    lanes::<N>(|l| if x[l] < 0.0 { (PI_HI - r[l]) + PI_LO } else { r[l] })
}

/// `atan(y/x)` for finite `y >= 0`, `x >= 0`, not both 0 (`x = 0` gives π/2): reduced to
/// `|t| <= 7/16` by `t = (a - c)/(1 + c a)`, `a = y/x`, c in {0, 1/2, 1, 3/2, inf} (breakpoints
/// 7/16, 11/16, 19/16, 39/16), written as `t = (n1 y - n0 x)/(d0 x + d1 y)` with small integer
/// coefficients so that every lane runs one division and no infinity arises; then
/// `atan(t) = t + t u P(u)`, `u = t²`, P a degree-11 near-minimax fit on [0, (7/16)²].
#[inline(always)]
fn atan_of_ratio<const N: usize, const FUSED: bool>(y: [f64; N], x: [f64; N]) -> [f64; N] {
    // (n1, n0, d0, d1, atan(c) high, atan(c) low) per interval.
    const REDUCTIONS: [[f64; 6]; 5] = [
        [1.0, 0.0, 1.0, 0.0, 0.0, 0.0],
        [2.0, 1.0, 2.0, 1.0, 0.4636476090008061, 2.2698777452961687e-17],
        [1.0, 1.0, 1.0, 1.0, std::f64::consts::FRAC_PI_4, 3.061616997868383e-17],
        [2.0, 3.0, 2.0, 3.0, 0.982793723247329, 1.3903311031230998e-17],
        [0.0, 1.0, 0.0, 1.0, std::f64::consts::FRAC_PI_2, 6.123233995736766e-17],
    ];
    const BREAKS: [f64; 4] = [0.4375, 0.6875, 1.1875, 2.4375];
    // P's coefficients from the highest degree down.
    const P: [f64; 12] = [
        0.014773184616983806,
        -0.033128134256069586,
        0.04492259293193656,
        -0.05216679739313656,
        0.05876946456755061,
        -0.06666241923359964,
        0.07692285554889286,
        -0.09090908355602592,
        0.11111111096645038,
        -0.14285714285566806,
        0.1999999999999941,
        -0.3333333333333333,
    ];
    // y/x >= b, as y >= b x (no division; x = 0 falls in the last interval).
    let mut c = [REDUCTIONS[0]; N];
    for (k, &b) in BREAKS.iter().enumerate() {
        for l in 0..N {
            if y[l] >= b * x[l] {
                c[l] = REDUCTIONS[k + 1];
            }
        }
    }
    let t = lanes::<N>(|l| (c[l][0] * y[l] - c[l][1] * x[l]) / (c[l][2] * x[l] + c[l][3] * y[l]));
    let u = lanes::<N>(|l| t[l] * t[l]);
    let mut p = [P[0]; N];
    for &coefficient in &P[1..] {
        p = lanes::<N>(|l| mul_add::<FUSED>(p[l], u[l], coefficient));
    }
    lanes::<N>(|l| c[l][4] + (t[l] + (t[l] * u[l] * p[l] + c[l][5])))
}

/// Largest `|x|` [`exp_and_reciprocal`] accepts: `2^k` stays a normal number for the `k` of the reduction.
pub const EXP_LIMIT: f64 = 700.0;

/// `(e^x, e^-x)` for `|x| <= EXP_LIMIT`: `x = k ln 2 + r`, `|r| <= ln 2 / 2`,
/// `e^±r = 1 + (C(r²) ± r S(r²))` with C and S the even and odd parts of the Taylor series of
/// `e^r - 1` to degree 13 (the first omitted term is below 2^-55 r), and `2^±k` made from the
/// bits of `k`; `k` comes from rounding by the magic constant 1.5 · 2^52 (whose last place is 1).
/// The second value costs no division: integer lane operations only, which AVX2 has.
#[inline(always)]
pub fn exp_and_reciprocal<const N: usize, const FUSED: bool>(x: [f64; N]) -> ([f64; N], [f64; N]) {
    const INV_LN2: f64 = std::f64::consts::LOG2_E;
    const ROUNDER: f64 = 6755399441055744.0;
    // 1/(2j)!, j = 6 down to 1, and 0: C(u) = u (1/2 + u (1/24 + ...)), u = r².
    const EVEN: [f64; 7] = [
        2.08767569878681e-09,
        2.755731922398589e-07,
        2.48015873015873e-05,
        0.001388888888888889,
        0.041666666666666664,
        0.5,
        0.0,
    ];
    // 1/(2j + 1)!, j = 6 down to 0: S(u) = 1 + u (1/6 + u (1/120 + ...)).
    const ODD: [f64; 7] = [
        1.6059043836821613e-10,
        2.505210838544172e-08,
        2.7557319223985893e-06,
        0.0001984126984126984,
        0.008333333333333333,
        0.16666666666666666,
        1.0,
    ];
    let shifted = lanes::<N>(|l| x[l] * INV_LN2 + ROUNDER);
    let k = lanes::<N>(|l| shifted[l] - ROUNDER);
    let r = lanes::<N>(|l| (x[l] - k[l] * LN2_HI) - k[l] * LN2_LO);
    let u = lanes::<N>(|l| r[l] * r[l]);
    let mut even = [EVEN[0]; N];
    for &coefficient in &EVEN[1..] {
        even = lanes::<N>(|l| mul_add::<FUSED>(even[l], u[l], coefficient));
    }
    let mut odd = [ODD[0]; N];
    for &coefficient in &ODD[1..] {
        odd = lanes::<N>(|l| mul_add::<FUSED>(odd[l], u[l], coefficient));
    }
    // k and -k as integers: the bits of `shifted` less those of the rounder.
    let k_bits: [u64; N] =
        std::array::from_fn(|l| shifted[l].to_bits().wrapping_sub(ROUNDER.to_bits()));
    let power = |k: u64| f64::from_bits(k.wrapping_add(1023) << 52);
    (
        lanes::<N>(|l| (1.0 + mul_add::<FUSED>(r[l], odd[l], even[l])) * power(k_bits[l])),
        lanes::<N>(|l| {
            (1.0 + mul_add::<FUSED>(-r[l], odd[l], even[l])) * power(k_bits[l].wrapping_neg())
        }),
    )
}

/// `ln(1 + y)` for `y` in [0, 1]. Above `√2 - 1`, `1 + y = 2 (1 + (y - 1)/2)` with `(y - 1)/2`
/// exact, so every lane reduces to `log(1 + f)` with `f` in [√2/2 - 1, √2 - 1].
#[inline(always)]
pub fn ln_1p_unit<const N: usize, const FUSED: bool>(y: [f64; N]) -> [f64; N] {
    const SQRT2_MINUS_1: f64 = 0.41421356237309515;
    // R(z) = z (LG[6] + z (LG[5] + ... + z LG[0])), z = s²: the minimax fit of
    // 2 atanh(s)/s - 2 on |s| <= 3 - 2√2 from fdlibm's e_log.c (error below 2^-58.45).
    const LG: [f64; 7] = [
        0.14798198605116586,
        0.15313837699209373,
        0.1818357216161805,
        0.22222198432149784,
        0.2857142874366239,
        0.3999999999940942,
        0.6666666666666735,
    ];
    let upper = |l: usize| y[l] >= SQRT2_MINUS_1;
    let f = lanes::<N>(|l| if upper(l) { (y[l] - 1.0) * 0.5 } else { y[l] });
    let s = lanes::<N>(|l| f[l] / (2.0 + f[l]));
    let z = lanes::<N>(|l| s[l] * s[l]);
    let mut p = [LG[0]; N];
    for &coefficient in &LG[1..] {
        p = lanes::<N>(|l| mul_add::<FUSED>(p[l], z[l], coefficient));
    }
    lanes::<N>(|l| {
        let (base, extra) = if upper(l) { (LN2_HI, LN2_LO) } else { (0.0, 0.0) };
        let hfsq = 0.5 * f[l] * f[l];
        base + (f[l] - (hfsq - (s[l] * (hfsq + z[l] * p[l]) + extra)))
    })
}

#[cfg(test)]
mod tests {
    use rand::{Rng, SeedableRng};

    use super::*;

    /// Worst error in ulps of the result, over `args`, of `got` against `want`.
    fn worst_ulps(
        args: impl Iterator<Item = f64>,
        got: impl Fn([f64; 4]) -> [f64; 4],
        want: impl Fn(f64) -> f64,
    ) -> f64 {
        let mut worst = 0.0f64;
        for a in args {
            let (g, w) = (got([a; 4])[0], want(a));
            worst = worst.max((g - w).abs() / (f64::EPSILON * w.abs()));
        }
        worst
    }

    #[test]
    fn arctangent_is_within_two_ulps_of_the_library() {
        let mut rng = rand::rngs::StdRng::seed_from_u64(7);
        // Log-uniform over 1e-12 .. 1e12, and the breakpoints' neighbourhoods.
        let args = (0..200_000).map(|k: usize| {
            if k.is_multiple_of(2) {
                10f64.powf(rng.random_range(-12.0..12.0))
            } else {
                [0.4375, 0.6875, 1.1875, 2.4375][k % 4] * (1.0 + rng.random_range(-1e-3..1e-3))
            }
        });
        let args: Vec<f64> = args.collect();
        let plain =
            worst_ulps(args.iter().copied(), |a| atan_of_ratio::<4, false>(a, [1.0; 4]), f64::atan);
        let fused =
            worst_ulps(args.into_iter(), |a| atan_of_ratio::<4, true>(a, [1.0; 4]), f64::atan);
        assert!(plain <= 2.0 && fused <= 2.0, "{plain} ulp, fused {fused} ulp");
        assert_eq!(atan_of_ratio::<1, false>([1.0], [0.0])[0], std::f64::consts::FRAC_PI_2);
        let (y, x) = ([1.0f64, 1e-300, 3.0, 1.0], [-1.0f64, -1.0, 0.0, -1e-300]);
        for got in [atan2_positive_y::<4, false>(y, x), atan2_positive_y::<4, true>(y, x)] {
            for l in 0..4 {
                let want = y[l].atan2(x[l]);
                assert!((got[l] - want).abs() <= 2.0 * f64::EPSILON * want, "{} vs {want}", got[l]);
            }
        }
    }

    #[test]
    fn exponential_and_its_reciprocal_are_within_two_ulps_of_the_library() {
        let mut rng = rand::rngs::StdRng::seed_from_u64(3);
        let args = (0..200_000).map(|k: usize| match k % 3 {
            0 => rng.random_range(-EXP_LIMIT..EXP_LIMIT),
            1 => rng.random_range(-2.0..2.0),
            // Near the reduction's half-way points, where k changes.
            _ => (k % 41) as f64 * 0.5 * std::f64::consts::LN_2 + rng.random_range(-1e-9..1e-9),
        });
        let args: Vec<f64> = args.collect();
        type Pair = ([f64; 4], [f64; 4]);
        let worst = |f: fn([f64; 4]) -> Pair| {
            let e = worst_ulps(args.iter().copied(), |x| f(x).0, f64::exp);
            let inverse = worst_ulps(args.iter().copied(), |x| f(x).1, |x| (-x).exp());
            e.max(inverse)
        };
        let (plain, fused) =
            (worst(exp_and_reciprocal::<4, false>), worst(exp_and_reciprocal::<4, true>));
        assert!(plain <= 2.0 && fused <= 2.0, "{plain} ulp, fused {fused} ulp");
        assert_eq!(exp_and_reciprocal::<1, false>([0.0]), ([1.0], [1.0]));
    }

    #[test]
    fn log1p_is_within_two_ulps_of_the_library_on_the_unit_interval() {
        let mut rng = rand::rngs::StdRng::seed_from_u64(5);
        let args = (0..200_000).map(|k: usize| match k % 3 {
            0 => rng.random_range(0.0..1.0),
            1 => 10f64.powf(rng.random_range(-300.0..0.0)),
            // Both sides of the switch at √2 - 1.
            _ => 0.41421356237309515 * (1.0 + rng.random_range(-1e-6..1e-6)),
        });
        let args: Vec<f64> = args.collect();
        let plain = worst_ulps(args.iter().copied(), ln_1p_unit::<4, false>, f64::ln_1p);
        let fused = worst_ulps(args.into_iter(), ln_1p_unit::<4, true>, f64::ln_1p);
        assert!(plain <= 2.0 && fused <= 2.0, "{plain} ulp, fused {fused} ulp");
        assert_eq!(ln_1p_unit::<2, true>([0.0, 1.0]), [0.0, std::f64::consts::LN_2]);
    }
}
