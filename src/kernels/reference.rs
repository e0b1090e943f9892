//! Adaptive-quadrature reference for the collocation integrals: integrates `G(P, Q) w(Q)` itself
//! over a convex polygon (fanned into triangles) with iterated adaptive Gauss–Kronrod.
//! Slow and independent of every closed form; for tests.

use glam::DVec2;

use super::Observer;
use crate::quadrature::{Tolerance, integrate_triangle};

/// `∫_poly G(P, Q) w(Q) dS_Q` over a convex polygon, to the given tolerance.
pub fn integral(obs: &Observer, poly: &[DVec2], w: impl Fn(DVec2) -> f64, tol: Tolerance) -> f64 {
    integral_of(poly, |q| obs.kernel(q) * w(q), tol)
}

/// `∫_poly f(Q) dS_Q` over a convex polygon, fanned into triangles.
pub fn integral_of(poly: &[DVec2], f: impl Fn(DVec2) -> f64, tol: Tolerance) -> f64 {
    (1..poly.len() - 1).map(|k| integrate_triangle(&f, [poly[0], poly[k], poly[k + 1]], tol)).sum()
}
