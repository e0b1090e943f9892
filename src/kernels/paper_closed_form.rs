//! The paper's own closed form for the constant weight (sec. 4.1), literally: split the triangle into
//! two right triangles, map each to σ_ab = {0 <= ξ/a, η/b, ξ/a + η/b <= 1} with the right angle at
//! the origin, and add
//!
//! - (4.5): `z ∫ (ξ - x)/r⁴` and `z ∫ (η - y)/r⁴` from the printed formula (and its mirror image
//!   under ξ <-> η, a <-> b, x <-> y), times the normal components i and j;
//! - (4.7): `-z² k ∫ 1/r⁴` from (4.10) applied to the six right triangles of (4.11) formed by the
//!   feet of the perpendiculars from P_xy to the three sides.
//!
//! Kept as a cross-check of the edge form in [`super::exact`], which is what the program uses.

use glam::DVec2;

use super::Observer;

/// `∫_T G(P, Q) dS_Q` for a counter-clockwise triangle T, by the paper's formulas.
pub fn constant_weight(obs: &Observer, tri: &[DVec2; 3]) -> f64 {
    right_triangles(tri).iter().map(|rt| right_triangle(obs, rt)).sum()
}

/// Two counter-clockwise right triangles `(v1, v2, v3)`, right angle at v1, that tile `tri`: the
/// altitude from the vertex opposite the longest side.
fn right_triangles(tri: &[DVec2; 3]) -> Vec<[DVec2; 3]> {
    let k = (0..3)
        .max_by(|&a, &b| {
            let la = (tri[(a + 1) % 3] - tri[a]).length_squared();
            let lb = (tri[(b + 1) % 3] - tri[b]).length_squared();
            la.total_cmp(&lb)
        })
        .expect("three sides");
    let (a, b, c) = (tri[k], tri[(k + 1) % 3], tri[(k + 2) % 3]);
    let ab = b - a;
    let foot = a + ab * ((c - a).dot(ab) / ab.length_squared());
    [[foot, b, c], [foot, c, a]]
        .into_iter()
        .filter(|t| (t[1] - t[0]).length() > 0.0 && (t[2] - t[0]).length() > 0.0)
        .collect()
}

/// (4.10): `∫ z² / r⁴` over the right triangle with P above its acute vertex, legs `a` (from P's
/// foot to the right angle) and `b`.
///
/// The paper prints `a z² / (2 (a² + z²)^(1/2)) atan(b / (a² + z²)^(1/2))`, which has the
/// dimension of an area although the integral is dimensionless; the factor z² is a misprint
/// (adaptive quadrature confirms the form below, see the tests).
fn eq_4_10(a: f64, b: f64, z: f64) -> f64 {
    let s = (a * a + z * z).sqrt();
    a / (2.0 * s) * (b / s).atan()
}

/// The printed closed form of `∫_σab z (η - y) / r⁴ dη dξ` (the first example after (4.5)).
///
/// Each bracket `atan(p/w) + atan(q/w)` (w > 0) is summed as one atan2: both terms lie in
/// (-π/2, π/2), so the sum's sine has the sign of `p + q` and its cosine that of `w² - p q`; the
/// sums of the arguments simplify to `a² + b²` and `a`. Same formula, without the cancellation of
/// two nearly opposite arctangents.
fn eq_4_5_eta(a: f64, b: f64, x: f64, y: f64, z: f64) -> f64 {
    let w = ((a * b - a * y - b * x).powi(2) + z * z * (a * a + b * b)).sqrt();
    let yz = (y * y + z * z).sqrt();
    let (p, q) = (a * a + b * y - a * x, b * b - b * y + a * x);
    -a * z / (2.0 * w) * (w * (a * a + b * b)).atan2(w * w - p * q)
        + z / (2.0 * yz) * (yz * a).atan2(yz * yz - (a - x) * x)
}

fn right_triangle(obs: &Observer, rt: &[DVec2; 3]) -> f64 {
    let (v1, v2, v3) = (rt[0], rt[1], rt[2]);
    let (a, b) = ((v2 - v1).length(), (v3 - v1).length());
    let (xi, eta) = ((v2 - v1) / a, (v3 - v1) / b);
    let p = obs.position.truncate() - v1;
    let (x, y, z) = (p.dot(xi), p.dot(eta), obs.position.z);
    let n_plane = obs.normal.truncate();
    let (i, j, k) = (n_plane.dot(xi), n_plane.dot(eta), obs.normal.z);
    // (4.5): the η-integral as printed, the ξ-integral by the symmetry of σ_ab.
    let z_eta = eq_4_5_eta(a, b, x, y, z);
    let z_xi = eq_4_5_eta(b, a, y, x, z);
    // (4.7) via (4.11): for each side (from s to e, counter-clockwise) the foot of the perpendicular
    // from p = (x, y) gives right triangles (p, foot, s) and (p, foot, e); their (4.10) values
    // enter with the signs of the side's distance and of the foot's position.
    let corners = [DVec2::ZERO, DVec2::new(a, 0.0), DVec2::new(0.0, b)];
    let pxy = DVec2::new(x, y);
    let mut z2_inv_r4 = 0.0;
    for side in 0..3 {
        let (s, e) = (corners[side], corners[(side + 1) % 3]);
        let tangent = (e - s).normalize();
        let inward = DVec2::new(-tangent.y, tangent.x);
        let h = (pxy - s).dot(inward); // > 0 when p is on the inner side
        let (ts, te) = ((s - pxy).dot(tangent), (e - pxy).dot(tangent));
        let sign_h = if h >= 0.0 { 1.0 } else { -1.0 };
        z2_inv_r4 += sign_h
            * (te.signum() * eq_4_10(h.abs(), te.abs(), z)
                - ts.signum() * eq_4_10(h.abs(), ts.abs(), z));
    }
    i * z_xi + j * z_eta - k * z2_inv_r4
}
