//! The tanh-sinh rule on [0, 1]: its points cluster double-exponentially at the ends, so it
//! integrates endpoint singularities (log, d log d) that defeat Gauss rules.

use std::f64::consts::PI;

/// The tanh-sinh rule on [0, 1] at steps 2^-l, l = 0 ..= max_level, as one list of points
/// indexed on the finest grid, truncated where the weights fall below what the integral needs.
pub(crate) struct TanhSinh {
    pub(crate) max_level: u32,
    /// (index on the finest grid, x, 1 - x, weight per unit step) for |t| up to the truncation.
    pub(crate) points: Vec<(i64, f64, f64, f64)>,
    /// The weight per unit step below which a point is left out.
    pub(crate) tail: f64,
}

/// Widest truncation of the t axis: the weights beyond are below 1e-20.
const T_MAX: f64 = 3.5;

impl TanhSinh {
    /// The rule to step 2^-max_level, truncated at the first point of the finest grid whose
    /// weight per unit step is below `tail` (at T_MAX at the latest): for an integrand bounded
    /// by 1, the points left out change the integral by about that much. A tail of 1e-8
    /// instead of 1e-20 leaves 21 points on a level-2 axis instead of 29, half the evaluations
    /// of the two-dimensional rule.
    pub(crate) fn new(max_level: u32, tail: f64) -> Self {
        let h = (-(max_level as f64)).exp2();
        let widest = (T_MAX / h).floor() as i64;
        let point = |k: i64| {
            let t = k as f64 * h;
            let s = PI * t.sinh();
            // x = 1 / (1 + e^-s) and 1 - x = 1 / (1 + e^s), each without cancellation.
            let (x, rest) = (1.0 / (1.0 + (-s).exp()), 1.0 / (1.0 + s.exp()));
            let weight = PI * t.cosh() * x * rest;
            (k, x, rest, weight)
        };
        let m = (0..=widest).find(|&k| point(k).3 < tail).unwrap_or(widest);
        let points = (-m..=m).map(point).collect();
        Self { max_level, points, tail }
    }
}
