//! The far-field rule: where the element is far from the node, `G φ` is smooth on it and a fixed
//! Gauss rule reaches rounding-level accuracy with no cancellation, while the closed forms, sums of
//! edge terms that cancel, lose about two digits per tenfold distance. Used for the linear method,
//! where it also replaces the per-edge IMT quadrature, and beyond 100 radii for the centroid
//! method.
//!
//! The rule is the collapsed Gauss–Legendre product of the paper's (4.4), n × n points, with n
//! falling as the node's distance grows ([`BANDS`]). It applies from 3 radii on: when the node is
//! at least `(ratio + 1) r` from the element's centroid, r the element's radius about it. Measured
//! against a 28 × 28 rule over random triangles, nodes and weights (test below): worst relative
//! error below 6e-15 in every band.

use glam::DVec2;

use super::{Affine2, Observer};
use crate::quadrature::TriangleRule;

/// Distance bands and orders: from `ratio` radii on, the `order × order` rule. Each order is one
/// above the smallest that kept the worst relative error below 6e-15 at the band's start over 3000
/// random triangles, nodes and weights (against a 28 × 28 rule); the order falls with distance,
/// as the paper's graded rules do (sec. 4.2).
pub const BANDS: [(f64, usize); 7] =
    [(3.0, 11), (5.0, 10), (8.0, 9), (12.0, 8), (20.0, 7), (40.0, 6), (100.0, 5)];

/// Bands for the constant weight (centroid method), whose closed forms stay accurate to a few
/// ulps out to 100 radii and then lose digits as the distance grows (7.5e-13 relative at 2e4
/// radii; `study stability`): only the far band, where the rule is cheaper than the closed form.
pub const CONSTANT_WEIGHT_BANDS: [(f64, usize); 1] = [(100.0, 5)];

/// Bands for single-precision kernels: the smallest orders that kept the worst relative error
/// below 1e-7 (f32's rounding) at each band's start, in the same experiment as [`BANDS`].
pub const SINGLE_PRECISION_BANDS: [(f64, usize); 4] = [(1.5, 7), (3.0, 6), (4.0, 5), (20.0, 4)];

/// One distance band: its ratio and its rule.
#[derive(Clone, Debug, PartialEq)]
pub struct Band {
    /// Used when `|P - C| >= (ratio + 1) r`.
    pub ratio: f64,
    /// The collapsed Gauss rule used in the band.
    pub rule: TriangleRule,
}

/// Collapsed Gauss rules on the unit triangle, graded by the distance of the node.
#[derive(Clone, Debug, PartialEq)]
pub struct FarFieldRule {
    /// Bands by increasing ratio.
    pub bands: Vec<Band>,
}

impl FarFieldRule {
    /// The graded rule of [`BANDS`].
    pub fn standard() -> Self {
        Self::from_bands(&BANDS)
    }

    /// The rule the exact method uses for elements with `basis_functions` weights: [`BANDS`] for
    /// the affine weights of the linear method (3), [`CONSTANT_WEIGHT_BANDS`] for the centroid
    /// method (1).
    pub fn for_weights(basis_functions: usize) -> Self {
        match basis_functions {
            1 => Self::constant_weight(),
            _ => Self::standard(),
        }
    }

    /// The rule of [`CONSTANT_WEIGHT_BANDS`].
    pub fn constant_weight() -> Self {
        Self::from_bands(&CONSTANT_WEIGHT_BANDS)
    }

    /// The graded rule of [`SINGLE_PRECISION_BANDS`].
    pub fn single_precision() -> Self {
        Self::from_bands(&SINGLE_PRECISION_BANDS)
    }

    fn from_bands(bands: &[(f64, usize)]) -> Self {
        Self {
            bands: bands
                .iter()
                .map(|&(ratio, order)| Band { ratio, rule: TriangleRule::collapsed_gauss(order) })
                .collect(),
        }
    }

    /// The band that applies to a node at `obs` (element-local coordinates, centroid at 0) and a
    /// triangle of radius `radius`, if any.
    pub fn band(&self, obs: &Observer, radius: f64) -> Option<&Band> {
        self.band_about(obs, DVec2::ZERO, radius)
    }

    /// The band for a triangle of radius `radius` about `centre`.
    fn band_about(&self, obs: &Observer, centre: DVec2, radius: f64) -> Option<&Band> {
        let d2 = (obs.position - centre.extend(0.0)).length_squared();
        self.bands.iter().rev().find(|b| d2 >= (b.ratio + 1.0) * (b.ratio + 1.0) * radius * radius)
    }

    /// `∫_T G φ_l` for a thin triangle ([`is_thin`]), on which the closed forms cancel (a sliver
    /// of aspect 1e6 seen from 0.36 of its length lost 10 digits in the constant weight and 12
    /// in the affine ones; `study stability`): pieces are bisected across their longest edge, which
    /// halves their aspect ratio, until each is far from the node compared with its size (then
    /// the band's rule), or no longer thin, or within a few of its widths of the node (then
    /// `near`, the closed forms, which do not cancel there). The work grows with the logarithm of
    /// the aspect ratio and of the node's closeness, not with their powers.
    pub fn integrate_subdivided<const L: usize>(
        &self,
        obs: &Observer,
        tri: &[DVec2; 3],
        weights: &[Affine2; L],
        near: impl Fn(&[DVec2; 3]) -> [f64; L],
    ) -> [f64; L] {
        let mut sum = [0.0; L];
        let mut stack = vec![(*tri, 0usize)];
        let mut pieces = 0;
        while let Some((t, depth)) = stack.pop() {
            pieces += 1;
            let centre = (t[0] + t[1] + t[2]) / 3.0;
            let radius = t.iter().map(|v| (*v - centre).length()).fold(0.0, f64::max);
            let exhausted = depth >= MAX_BISECTION_DEPTH || pieces > MAX_PIECES;
            let part = match self.band_about(obs, centre, radius) {
                Some(band) => obs.integrate_by_rule(&band.rule, &t, weights),
                None if !is_thin(&t) || exhausted => near(&t),
                // Within a few widths of the node the closed forms do not cancel either; and a
                // needle's tip region stays thin under any subdivision, so waiting for fat pieces
                // there would never end.
                None if within_widths(obs, &t) => near(&t),
                None => {
                    let k = (0..3)
                        .max_by(|&a, &b| {
                            let la = (t[(a + 1) % 3] - t[a]).length_squared();
                            let lb = (t[(b + 1) % 3] - t[b]).length_squared();
                            la.total_cmp(&lb)
                        })
                        .unwrap_or(0);
                    let (a, b, c) = (t[k], t[(k + 1) % 3], t[(k + 2) % 3]);
                    let m = (a + b) * 0.5;
                    stack.push(([a, m, c], depth + 1));
                    stack.push(([m, b, c], depth + 1));
                    continue;
                }
            };
            sum.iter_mut().zip(part).for_each(|(s, p)| *s += p);
        }
        sum
    }
}

/// Whether the node is within four widths (twice the area over the diameter) of the triangle,
/// where the closed forms' edge terms are no larger than the result.
fn within_widths(obs: &Observer, t: &[DVec2; 3]) -> bool {
    let diameter = (0..3).map(|k| (t[k] - t[(k + 1) % 3]).length()).fold(0.0, f64::max);
    let width = (t[1] - t[0]).perp_dot(t[2] - t[0]).abs() / diameter;
    let ccw = if (t[1] - t[0]).perp_dot(t[2] - t[0]) >= 0.0 { *t } else { [t[0], t[2], t[1]] };
    let in_plane = crate::geometry::distance_to_convex(&ccw, obs.position.truncate());
    in_plane.hypot(obs.position.z) <= 4.0 * width
}

/// Most pieces [`FarFieldRule::integrate_subdivided`] visits before handing the rest to the closed
/// forms. Aspect ratios up to 1e6 need at most about 4000 even with the node 1e-5 above the
/// element; beyond about 1e10, longest-edge bisection stacks needles across the width and the
/// count would grow exponentially (found by fuzzing), so the budget bounds the time.
pub const MAX_PIECES: usize = 16384;

/// Deepest bisection of [`FarFieldRule::integrate_subdivided`]: each level halves a piece's
/// aspect ratio, so 64 levels make any finite aspect ratio fat.
pub const MAX_BISECTION_DEPTH: usize = 64;

/// Elements whose squared diameter exceeds this multiple of their area are "thin" (an equilateral
/// triangle has 2.3, the paper's meshes at most 10.4).
pub const THIN_ASPECT: f64 = 100.0;

/// Whether a triangle is thin: its closed-form integrals sum edge terms much larger than the
/// result, so it is integrated by [`FarFieldRule::integrate_subdivided`] instead.
pub fn is_thin(tri: &[DVec2; 3]) -> bool {
    let diameter2 =
        (0..3).map(|k| (tri[k] - tri[(k + 1) % 3]).length_squared()).fold(0.0, f64::max);
    let area = 0.5 * (tri[1] - tri[0]).perp_dot(tri[2] - tri[0]).abs();
    diameter2 > THIN_ASPECT * area
}

/// The radius of a triangle about the origin (its centroid in element-local coordinates).
pub fn radius(tri: &[DVec2; 3]) -> f64 {
    tri.iter().map(|v| v.length_squared()).fold(0.0, f64::max).sqrt()
}

#[cfg(test)]
mod tests {
    use glam::DVec3;
    use rand::{Rng, SeedableRng, rngs::StdRng};

    use super::*;
    use crate::kernels::Affine2;

    /// Worst relative error of `rule` in every band, over random triangles, nodes and weights,
    /// against a 28 × 28 rule.
    fn worst_error(rule: &FarFieldRule, starts: &[f64]) -> f64 {
        let reference = TriangleRule::collapsed_gauss(28);
        let mut rng = StdRng::seed_from_u64(5);
        let mut worst: f64 = 0.0;
        for _ in 0..2000 {
            let mut tri = [(); 3]
                .map(|_| DVec2::new(rng.random_range(-1.0..1.0), rng.random_range(-1.0..1.0)));
            if (tri[1] - tri[0]).perp_dot(tri[2] - tri[0]) < 0.0 {
                tri.swap(1, 2);
            }
            let c = (tri[0] + tri[1] + tri[2]) / 3.0;
            let tri = tri.map(|v| v - c);
            let r = radius(&tri);
            let dir = loop {
                let d = DVec3::new(
                    rng.random_range(-1.0..1.0),
                    rng.random_range(-1.0..1.0),
                    rng.random_range(0.05..1.0),
                );
                if d.length() < 1.0 {
                    break d.normalize();
                }
            };
            let normal = DVec3::new(
                rng.random_range(-1.0..1.0),
                rng.random_range(-1.0..1.0),
                rng.random_range(-1.0..1.0),
            )
            .normalize();
            let start = starts[rng.random_range(0..starts.len())];
            let obs =
                Observer { position: dir * (start + 1.0) * r * rng.random_range(1.0..1.5), normal };
            let band = rule.band(&obs, r).expect("far enough");
            let w = [Affine2 { c0: 0.3, cx: 1.7 / r, cy: -0.9 / r }, Affine2::ONE];
            // Each rule by the scalar reference sums: the rule's truncation, not the vector
            // lanes' rounding (bounded in `by_rule`), which on a sign-changing G that cancels to
            // 1e-4 of ∫ |G| would dominate the relative error.
            let by_rule = |rule: &TriangleRule| {
                let [g0, gx, gy] = rule.moments(&tri, |q| obs.kernel(q));
                w.map(|phi| phi.c0 * g0 + phi.cx * gx + phi.cy * gy)
            };
            let (got, want) = (by_rule(&band.rule), by_rule(&reference));
            let scale = want[0].abs().max(want[1].abs());
            worst = worst.max((got[0] - want[0]).abs() / scale);
        }
        worst
    }

    #[test]
    fn the_graded_rule_is_at_rounding_level_in_every_band() {
        let starts: Vec<f64> = BANDS.iter().map(|b| b.0).collect();
        let worst = worst_error(&FarFieldRule::standard(), &starts);
        assert!(worst < 6e-15, "worst relative error {worst:e}");
    }

    #[test]
    fn the_single_precision_rule_is_below_f32_rounding() {
        let starts: Vec<f64> = SINGLE_PRECISION_BANDS.iter().map(|b| b.0).collect();
        let worst = worst_error(&FarFieldRule::single_precision(), &starts);
        assert!(worst < 1e-7, "worst relative error {worst:e}");
    }

    #[test]
    fn thin_elements_are_integrated_to_rounding_by_subdivision() {
        use crate::kernels::reference::integral;
        use crate::quadrature::{ImtRule, Tolerance};
        let c = DVec2::new(0.5, 1e-6 / 3.0);
        let tri = [DVec2::new(0.0, 0.0) - c, DVec2::new(1.0, 0.0) - c, DVec2::new(0.5, 1e-6) - c];
        assert!(is_thin(&tri));
        // A steep affine weight (a linear basis function of the sliver) and the constant one.
        let weights = [Affine2::ONE, Affine2 { c0: 1.0 / 3.0, cx: 0.0, cy: 2e6 }];
        let tol = Tolerance { absolute: 1e-300, relative: 1e-15, max_intervals: 20000 };
        let rule = FarFieldRule::standard();
        let imt = ImtRule::new(128);
        for (position, normal) in [
            (DVec3::new(0.0, 0.3, 0.2), DVec3::new(0.0, -0.6, -0.8)),
            (DVec3::new(0.1, -1e-3, 1e-3), DVec3::new(0.0, 1.0, -1.0).normalize()),
        ] {
            let obs = Observer { position, normal };
            let near = |piece: &[DVec2; 3]| {
                crate::kernels::exact::affine_weights(&obs, [&piece[..]], &weights, &imt)
            };
            let ours = rule.integrate_subdivided(&obs, &tri, &weights, near);
            let closed = crate::kernels::exact::affine_weights(&obs, [&tri[..]], &weights, &imt);
            for l in 0..2 {
                let want = integral(&obs, &tri, |q| weights[l].eval(q), tol);
                let e = ((ours[l] - want) / want).abs();
                assert!(e < 1e-13, "{position}, weight {l}: {e}");
                // The closed forms lose digits here; the test would pass without the rule if not.
                if l == 1 {
                    assert!(((closed[l] - want) / want).abs() > 1e3 * e.max(1e-16));
                }
            }
        }
    }

    #[test]
    fn the_paper_meshes_have_no_thin_elements() {
        // S5's triangles (legs 5 and 1) are the paper's thinnest.
        let s5 = [DVec2::new(0.0, 0.0), DVec2::new(5.0, 0.0), DVec2::new(0.0, 1.0)];
        let equilateral =
            [DVec2::new(0.0, 0.0), DVec2::new(1.0, 0.0), DVec2::new(0.5, 0.75f64.sqrt())];
        assert!(!is_thin(&s5) && !is_thin(&equilateral));
    }
}
