//! Lambert's contour formula: an independent closed form for the constant weight.
//!
//! By Stokes' theorem the point-to-polygon integral of G is a sum over the edges of the polygon:
//! with `R_k` the vectors from P to the vertices, `γ_k` the angle between `R_k` and `R_{k+1}` and
//! `u_k` the unit normal of the plane through P and edge k,
//! `∫ G dS = -(1/2) Σ_k γ_k n_P · u_k` (the sign for loops counter-clockwise about the element's
//! normal, which points towards P).

use glam::DVec2;

use super::Observer;

/// `∫_region G(P, Q) dS_Q` by Lambert's formula.
pub fn constant_weight<'a>(obs: &Observer, loops: impl IntoIterator<Item = &'a [DVec2]>) -> f64 {
    let mut total = 0.0;
    for poly in loops {
        let n = poly.len();
        for k in 0..n {
            let ra = poly[k].extend(0.0) - obs.position;
            let rb = poly[(k + 1) % n].extend(0.0) - obs.position;
            let c = ra.cross(rb);
            let len = c.length();
            if len == 0.0 {
                continue;
            }
            let gamma = len.atan2(ra.dot(rb));
            total += gamma * obs.normal.dot(c) / len;
        }
    }
    -0.5 * total
}
