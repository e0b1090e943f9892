//! Adaptive-quadrature references for the collocation integrals, slow and independent of every
//! closed form: [`integral`] integrates `G(P, Q) w(Q)` itself over a convex polygon (fanned into
//! triangles) with iterated adaptive Gauss–Kronrod; [`polar_integral`] integrates in polar
//! coordinates around the node's foot, accurate also at extreme node–element distances (the
//! stability study's reference).

use glam::DVec2;

use super::{Affine2, Observer};
use crate::quadrature::{Tolerance, integrate_triangle};

/// `∫_poly G(P, Q) w(Q) dS_Q` over a convex polygon, to the given tolerance.
pub fn integral(obs: &Observer, poly: &[DVec2], w: impl Fn(DVec2) -> f64, tol: Tolerance) -> f64 {
    integral_of(poly, |q| obs.kernel(q) * w(q), tol)
}

/// `∫_poly f(Q) dS_Q` over a convex polygon, fanned into triangles.
pub fn integral_of(poly: &[DVec2], f: impl Fn(DVec2) -> f64, tol: Tolerance) -> f64 {
    (1..poly.len() - 1)
        .map(|k| integrate_triangle(&f, [poly[0], poly[k], poly[k + 1]], tol).0)
        .sum()
}

/// `∫_poly G(P, Q) w(Q) dS_Q` for an affine weight `w`, over any simple polygon (counter-clockwise),
/// by a formulation that shares nothing with the closed forms and stays accurate when the node is
/// extremely close to the element's plane or edges: polar coordinates (ρ, θ) around the foot F of
/// the node, the radial integral in closed form, the angular one adaptively, edge by edge.
///
/// For the edge AB with outward normal `n` and signed distance `h = (A − F)·n` from F to its line,
/// the ray from F in direction `u` meets the line at `ρ = |h| cosh ω` where `u = (sign(h) n +
/// sinh ω τ) / cosh ω`, and `dθ = sign(h) dω / cosh ω`: the substitution takes the
/// multi-scale angular integrand (features at ρ ≈ |h| and ρ ≈ z) to one of unit scale in ω.
pub fn polar_integral(obs: &Observer, poly: &[DVec2], w: Affine2, tol: Tolerance) -> f64 {
    let (foot, z) = (obs.position.truncate(), obs.position.z);
    let n_p = obs.normal;
    let w_foot = w.eval(foot);
    // The radial integral ∫_0^R G w ρ dρ along direction u, in terms of t = R / z (see module
    // docs of kernels for G): with a = n_P·u, b = ∇w·u,
    // a w_F A(t)/2 + a b z L(t)/2 − k w_F T(t)/2 − k b z A(t)/2.
    let radial = |u: DVec2, rho: f64| {
        let t = rho / z;
        let (a, b) = (n_p.x * u.x + n_p.y * u.y, w.cx * u.x + w.cy * u.y);
        let (at, lt, tt) = (atan_minus_rational(t), log_minus_rational(t), t * t / (1.0 + t * t));
        0.5 * (a * w_foot * at + a * b * z * lt - n_p.z * w_foot * tt - n_p.z * b * z * at)
    };
    let mut total = 0.0;
    for k in 0..poly.len() {
        let (a, b) = (poly[k], poly[(k + 1) % poly.len()]);
        let length = (b - a).length();
        if length == 0.0 {
            continue;
        }
        let tangent = (b - a) / length;
        let normal = DVec2::new(tangent.y, -tangent.x);
        let h = (a - foot).dot(normal);
        if h == 0.0 {
            continue; // F on the edge's line: the edge sweeps no angle
        }
        let (s_a, s_b) = ((a - foot).dot(tangent), (b - foot).dot(tangent));
        let (w_a, w_b) = ((s_a / h.abs()).asinh(), (s_b / h.abs()).asinh());
        let integrand = |omega: f64| {
            let (sh, ch) = (omega.sinh(), omega.cosh());
            let u = (normal * h.signum() + tangent * sh) / ch;
            radial(u, h.abs() * ch) / ch
        };
        // Split where ρ crosses z (t = 1) and at the foot of the perpendicular (ω = 0).
        let knee = (z / h.abs()).asinh();
        let mut cuts = vec![w_a, w_b];
        cuts.extend([-knee, 0.0, knee].into_iter().filter(|&c| c > w_a && c < w_b));
        cuts.sort_by(f64::total_cmp);
        let edge: f64 = cuts
            .windows(2)
            .map(|c| crate::quadrature::integrate_adaptive(integrand, c[0], c[1], tol).0)
            .sum();
        total += h.signum() * edge;
    }
    total
}

/// `atan t − t / (1 + t²)`, without cancellation for small t (series 2t³/3 − 4t⁵/5 + ...).
fn atan_minus_rational(t: f64) -> f64 {
    if t < 0.1 {
        let t2 = t * t;
        let mut term = t * t2;
        let mut sum = 0.0;
        for n in 1..=14 {
            let n = n as f64;
            sum += 2.0 * n / (2.0 * n + 1.0) * term;
            term *= -t2;
        }
        sum
    } else {
        t.atan() - t / (1.0 + t * t)
    }
}

/// `ln(1 + t²) − t² / (1 + t²)`, without cancellation for small t (series t⁴/2 − 2t⁶/3 + ...).
fn log_minus_rational(t: f64) -> f64 {
    if t < 0.1 {
        let t2 = t * t;
        let mut term = t2 * t2;
        let mut sum = 0.0;
        for n in 2..=16 {
            let n = n as f64;
            sum += (n - 1.0) / n * term;
            term *= -t2;
        }
        sum
    } else {
        (t * t).ln_1p() - t * t / (1.0 + t * t)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DVec3;

    #[test]
    fn the_polar_reference_agrees_with_plain_adaptive_quadrature() {
        let tri = [DVec2::new(0.0, 0.0), DVec2::new(1.0, 0.1), DVec2::new(0.3, 0.8)];
        let weights = [Affine2::ONE, Affine2 { c0: 0.2, cx: -1.0, cy: 0.7 }];
        // Foot inside, outside, beyond a vertex; normals tilted and parallel.
        let cases = [
            (DVec3::new(0.4, 0.3, 0.5), DVec3::new(0.3, -0.2, -0.9)),
            (DVec3::new(1.5, -0.4, 0.2), DVec3::new(-0.6, 0.0, -0.8)),
            (DVec3::new(-0.3, -0.3, 1.2), DVec3::new(0.0, 0.0, -1.0)),
            (DVec3::new(0.5, 0.5, 0.05), DVec3::new(0.0, 0.6, -0.8)),
        ];
        for (position, normal) in cases {
            let obs = Observer { position, normal: normal.normalize() };
            for w in weights {
                let want = integral(&obs, &tri, |q| w.eval(q), Tolerance::default());
                let got = polar_integral(&obs, &tri, w, Tolerance::default());
                assert!(
                    (got - want).abs() <= 1e-13 * want.abs().max(1e-3),
                    "{position}: {got} vs {want}"
                );
            }
        }
    }

    #[test]
    fn the_series_match_the_direct_forms_where_both_are_accurate() {
        for t in [0.05f64, 0.099] {
            let direct = t.atan() - t / (1.0 + t * t);
            assert!((atan_minus_rational(t) - direct).abs() < 1e-15 * t, "{t}");
            let direct = (t * t).ln_1p() - t * t / (1.0 + t * t);
            assert!((log_minus_rational(t) - direct).abs() < 1e-15 * t * t, "{t}");
        }
        // Leading terms far below the switch.
        let t = 1e-6;
        assert!((atan_minus_rational(t) / (2.0 / 3.0 * t * t * t) - 1.0).abs() < 1e-11);
        assert!((log_minus_rational(t) / (0.5 * t.powi(4)) - 1.0).abs() < 1e-11);
    }
}
