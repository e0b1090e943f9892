//! The tanh-sinh rule on [0, 1]: its points cluster double-exponentially at the ends, so it
//! integrates endpoint singularities (log, d log d) that defeat Gauss rules.

use std::f64::consts::PI;

/// The tanh-sinh rule on [0, 1] at steps 2^-l, l = 0 ..= max_level, as one list of points
/// indexed on the finest grid.
pub(crate) struct TanhSinh {
    pub(crate) max_level: u32,
    /// (index on the finest grid, x, 1 - x, weight per unit step) for |t| <= T_MAX.
    pub(crate) points: Vec<(i64, f64, f64, f64)>,
}

/// Truncation of the t axis: the weights beyond are below 1e-20.
const T_MAX: f64 = 3.5;

impl TanhSinh {
    pub(crate) fn new(max_level: u32) -> Self {
        let h = (-(max_level as f64)).exp2();
        let m = (T_MAX / h).floor() as i64;
        let points = (-m..=m)
            .map(|k| {
                let t = k as f64 * h;
                let s = PI * t.sinh();
                // x = 1 / (1 + e^-s) and 1 - x = 1 / (1 + e^s), each without cancellation.
                let (x, rest) = (1.0 / (1.0 + (-s).exp()), 1.0 / (1.0 + s.exp()));
                let weight = PI * t.cosh() * x * rest;
                (k, x, rest, weight)
            })
            .collect();
        Self { max_level, points }
    }
}
