//! Globally adaptive Gauss–Kronrod (7/15) integration, and its iterated use over triangles.
//!
//! This is the independent high-accuracy reference against which the closed forms are tested, and
//! the integrator for the emissivity of non-polynomial true solutions. It knows nothing about the
//! radiosity kernel: it only sees the integrand.

use std::collections::BinaryHeap;

use glam::DVec2;

/// Kronrod nodes (positive half, decreasing; the last is 0) of the 15-point rule (QUADPACK qk15).
const XGK: [f64; 8] = [
    0.991_455_371_120_812_6,
    0.949_107_912_342_758_5,
    0.864_864_423_359_769_1,
    0.741_531_185_599_394_4,
    0.586_087_235_467_691_1,
    0.405_845_151_377_397_2,
    0.207_784_955_007_898_5,
    0.0,
];
/// Kronrod weights matching [`XGK`].
const WGK: [f64; 8] = [
    0.022_935_322_010_529_22,
    0.063_092_092_629_978_55,
    0.104_790_010_322_250_2,
    0.140_653_259_715_525_9,
    0.169_004_726_639_267_9,
    0.190_350_578_064_785_4,
    0.204_432_940_075_298_9,
    0.209_482_141_084_727_8,
];
/// Weights of the embedded 7-point Gauss rule, on the odd-indexed Kronrod nodes 1, 3, 5, 7.
const WG: [f64; 4] = [
    0.129_484_966_168_869_7,
    0.279_705_391_489_276_7,
    0.381_830_050_505_118_9,
    0.417_959_183_673_469_4,
];

/// Requested accuracy: stop when the estimated error is below `max(absolute, relative * |I|)`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Tolerance {
    /// Absolute error bound.
    pub absolute: f64,
    /// Relative error bound.
    pub relative: f64,
    /// Most subintervals one 1-D integral may use.
    pub max_intervals: usize,
}

impl Default for Tolerance {
    /// Near full double precision: relative 1e-14, absolute 1e-300, at most 2000 subintervals.
    fn default() -> Self {
        Self { absolute: 1e-300, relative: 1e-14, max_intervals: 2000 }
    }
}

struct Interval {
    a: f64,
    b: f64,
    value: f64,
    error: f64,
}

impl PartialEq for Interval {
    fn eq(&self, other: &Self) -> bool {
        self.error == other.error
    }
}
impl Eq for Interval {}
impl PartialOrd for Interval {
    fn partial_cmp(&self, other: &Self) -> Option<std::cmp::Ordering> {
        Some(self.cmp(other))
    }
}
impl Ord for Interval {
    fn cmp(&self, other: &Self) -> std::cmp::Ordering {
        self.error.total_cmp(&other.error)
    }
}

fn gauss_kronrod_15(f: &mut impl FnMut(f64) -> f64, a: f64, b: f64) -> Interval {
    let half = 0.5 * (b - a);
    let mid = 0.5 * (a + b);
    let fc = f(mid);
    let mut kronrod = WGK[7] * fc;
    let mut gauss = WG[3] * fc;
    for j in 0..7 {
        let dx = half * XGK[j];
        let pair = f(mid - dx) + f(mid + dx);
        kronrod += WGK[j] * pair;
        if j % 2 == 1 {
            gauss += WG[j / 2] * pair;
        }
    }
    Interval { a, b, value: kronrod * half, error: ((kronrod - gauss) * half).abs() }
}

/// Adaptive integral of `f` over `[a, b]`; returns `(value, estimated error)`.
pub fn integrate_adaptive(
    mut f: impl FnMut(f64) -> f64,
    a: f64,
    b: f64,
    tol: Tolerance,
) -> (f64, f64) {
    if a == b {
        return (0.0, 0.0);
    }
    let first = gauss_kronrod_15(&mut f, a, b);
    let (mut value, mut error) = (first.value, first.error);
    let mut heap = BinaryHeap::from([first]);
    while error > tol.absolute.max(tol.relative * value.abs()) && heap.len() < tol.max_intervals {
        let worst = heap.pop().expect("heap is never empty here");
        let m = 0.5 * (worst.a + worst.b);
        if m <= worst.a || m >= worst.b {
            heap.push(worst);
            break; // interval at the resolution of f64
        }
        let left = gauss_kronrod_15(&mut f, worst.a, m);
        let right = gauss_kronrod_15(&mut f, m, worst.b);
        value += left.value + right.value - worst.value;
        error += left.error + right.error - worst.error;
        heap.push(left);
        heap.push(right);
    }
    // Re-sum to avoid the drift of the running updates.
    let value = heap.iter().map(|i| i.value).sum();
    let error = heap.iter().map(|i| i.error).sum();
    (value, error)
}

/// Integral of `f` over the triangle `(v0, v1, v2)` by iterated adaptive Gauss–Kronrod, with
/// `Q = v0 + s (v1 - v0) + t (v2 - v0)`, `0 <= t <= 1 - s`. Features along the triangle's edges
/// and at its vertices (end points of the iterated integrals) are resolved by bisection. Returns
/// the value and an estimate of its absolute error.
pub fn integrate_triangle(f: impl Fn(DVec2) -> f64, tri: [DVec2; 3], tol: Tolerance) -> (f64, f64) {
    let (v0, d1, d2) = (tri[0], tri[1] - tri[0], tri[2] - tri[0]);
    let jacobian = d1.perp_dot(d2).abs();
    let inner_tol = Tolerance {
        absolute: tol.absolute / jacobian.max(f64::MIN_POSITIVE),
        relative: tol.relative * 0.25,
        ..tol
    };
    // The error of the iterated integral: the outer rule's, plus at most the worst inner
    // estimate over the unit length of the outer interval.
    let worst_inner = std::cell::Cell::new(0.0f64);
    let outer = |s: f64| {
        let (value, error) =
            integrate_adaptive(|t| f(v0 + d1 * s + d2 * t), 0.0, 1.0 - s, inner_tol);
        worst_inner.set(worst_inner.get().max(error));
        value
    };
    let outer_tol = Tolerance { absolute: tol.absolute / jacobian.max(f64::MIN_POSITIVE), ..tol };
    let (value, error) = integrate_adaptive(outer, 0.0, 1.0, outer_tol);
    (jacobian * value, jacobian * (error + worst_inner.get()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_15_point_kronrod_rule_is_exact_to_degree_22_and_gauss_to_13() {
        for deg in 0..=22 {
            let mut f = |x: f64| x.powi(deg);
            let r = gauss_kronrod_15(&mut f, 0.0, 1.0);
            let want = 1.0 / (deg as f64 + 1.0);
            assert!((r.value - want).abs() < 1e-15, "K15 deg {deg}: {}", r.value);
            if deg <= 13 {
                assert!(r.error < 1e-15, "G7 deg {deg}: error estimate {}", r.error);
            }
        }
    }

    #[test]
    fn adaptive_handles_an_end_point_singularity_and_a_sharp_peak() {
        let (v, _) = integrate_adaptive(|x| x.sqrt(), 0.0, 1.0, Tolerance::default());
        assert!((v - 2.0 / 3.0).abs() < 1e-14, "{v}");
        let eps: f64 = 1e-6;
        let (v, _) =
            integrate_adaptive(|x| eps / (x * x + eps * eps), -1.0, 2.0, Tolerance::default());
        let want = (2.0 / eps).atan() + (1.0 / eps).atan();
        assert!((v - want).abs() < 1e-13 * want, "{v} vs {want}");
    }

    #[test]
    fn triangle_integral_of_a_quadratic() {
        // ∫ over the unit right triangle of x² y = 1/60.
        let tri = [DVec2::ZERO, DVec2::X, DVec2::Y];
        let (v, e) = integrate_triangle(|q| q.x * q.x * q.y, tri, Tolerance::default());
        assert!((v - 1.0 / 60.0).abs() < 1e-16, "{v}");
        assert!(e < 1e-15, "estimate {e}");
    }

    #[test]
    fn the_triangle_error_estimate_covers_the_error_when_subdivision_runs_out() {
        // ∫ over the unit right triangle of (x + y)^(-1/2) = 2/3 ... computed: ∫0^1 r^(-1/2) r dr
        // over the lines x + y = r: ∫0^1 r^{1/2} dr = 2/3. The singular corner needs subdivision.
        let tri = [DVec2::ZERO, DVec2::X, DVec2::Y];
        let f = |q: DVec2| (q.x + q.y).powf(-0.5);
        for max_intervals in [2, 4, 8, 2000] {
            let tol = Tolerance { max_intervals, ..Tolerance::default() };
            let (v, e) = integrate_triangle(f, tri, tol);
            let error = (v - 2.0 / 3.0).abs();
            assert!(error <= e.max(1e-15), "{max_intervals} intervals: error {error:e} > {e:e}");
            if max_intervals == 2 {
                assert!(e > 1e-6, "a starved rule must say so: {e:e}");
            }
        }
    }
}
