//! The paper's numerical alternatives to the exact method (sec. 4.2), for comparing error against
//! run time: fixed rules on each (visible piece of an) element, refined where the node is close.
//!
//! - The *7-point method*: Stroud's T2:5-1 (4.3) composed over the 4^L congruent subtriangles of
//!   L rounds of midpoint subdivision.
//! - The *Gauss method*: the collapsed Gauss–Legendre rule (4.4) with 2^(IBase + L) points per
//!   dimension, collapsed at the element's first vertex.
//!
//! The level L runs from MaxLev near the node down to 0 far away. The paper defers the rule to
//! [3, p. 460]; ours is: with d the distance from the node to the element and h the element's
//! diameter, L = MaxLev while d <= near·h, and L falls by one each time d doubles,
//!
//! ```text
//!     L = max(0, MaxLev - ceil(log2(d / (near h)))).
//! ```
//!
//! Elements in a band [2^k, 2^(k+1)) near·h number O(4^k) per node and each costs O(4^-k) of the
//! nearest rule, so every band costs about the same and a row costs O(MaxLev 4^MaxLev) points.
//! `study grading` shows how the errors depend on `near`.

use glam::DVec2;

use super::{Affine2, Observer};
use crate::geometry::distance_to_convex;
use crate::quadrature::TriangleRule;

/// The default `near` of the grading rule: full level within one element diameter.
pub const DEFAULT_NEAR: f64 = 1.0;

/// A rule for each level 0..=MaxLev and the grading that picks one.
#[derive(Clone, Debug, PartialEq)]
pub struct GradedRule {
    levels: Vec<TriangleRule>,
    near: f64,
}

impl GradedRule {
    /// The 7-point method with `max_level` rounds of subdivision near the node.
    pub fn seven_point(max_level: u32, near: f64) -> Self {
        let base = TriangleRule::stroud_t2_5_1();
        Self { levels: (0..=max_level).map(|l| base.composite(l)).collect(), near }
    }

    /// The Gauss method: 2^(`base` + L) points per dimension, L up to `max_level`.
    pub fn gauss(base: u32, max_level: u32, near: f64) -> Self {
        let levels =
            (0..=max_level).map(|l| TriangleRule::collapsed_gauss(1 << (base + l))).collect();
        Self { levels, near }
    }

    /// The level for a node at `distance` from an element of diameter `diameter`.
    pub fn level(&self, distance: f64, diameter: f64) -> usize {
        let max_level = self.levels.len() - 1;
        let mut reach = self.near * diameter;
        for level in (1..=max_level).rev() {
            if distance <= reach {
                return level;
            }
            reach *= 2.0;
        }
        0
    }

    /// The level for a node at `obs` (element-local) and the triangle `element`; the exact distance
    /// is computed only where a cheap lower bound (distance to the centroid minus the radius) does
    /// not already give level 0.
    fn level_for(&self, obs: &Observer, element: &[DVec2; 3]) -> usize {
        let max_level = self.levels.len() - 1;
        let diameter =
            (0..3).map(|k| element[k].distance(element[(k + 1) % 3])).fold(0.0, f64::max);
        let centroid = (element[0] + element[1] + element[2]) / 3.0;
        let radius = element.iter().map(|v| v.distance(centroid)).fold(0.0, f64::max);
        let p = obs.position;
        let lower_bound = p.distance(centroid.extend(0.0)) - radius;
        let level0_from = self.near * diameter * f64::from(1u32 << max_level.saturating_sub(1));
        if max_level == 0 || lower_bound > level0_from {
            return 0;
        }
        let in_plane = distance_to_convex(element, p.truncate());
        self.level((in_plane * in_plane + p.z * p.z).sqrt(), diameter)
    }

    /// The rule of `level`.
    pub fn rule(&self, level: usize) -> &TriangleRule {
        &self.levels[level]
    }

    /// `∫ G φ_l` over `pieces` (convex, counter-clockwise, element-local) of the element `element`
    /// (counter-clockwise, element-local), with the level the element's distance from the node
    /// calls for; each piece is cut into a fan of triangles.
    pub fn integrate<const L: usize>(
        &self,
        obs: &Observer,
        element: &[DVec2; 3],
        pieces: &[&[DVec2]],
        weights: &[Affine2; L],
    ) -> [f64; L] {
        let rule = self.rule(self.level_for(obs, element));
        let mut sum = [0.0; L];
        for piece in pieces {
            for k in 1..piece.len() - 1 {
                let part =
                    obs.integrate_by_rule(rule, &[piece[0], piece[k], piece[k + 1]], weights);
                sum.iter_mut().zip(part).for_each(|(s, p)| *s += p);
            }
        }
        sum
    }
}

#[cfg(test)]
mod tests {
    use glam::DVec3;

    use super::*;
    use crate::kernels::reference;
    use crate::quadrature::Tolerance;

    #[test]
    fn the_level_falls_by_one_per_doubling_of_distance() {
        let rule = GradedRule::seven_point(3, 1.0);
        let levels: Vec<usize> =
            [0.0, 0.5, 1.0, 1.5, 2.0, 3.0, 4.0, 7.9, 8.1, 100.0].map(|d| rule.level(d, 1.0)).into();
        assert_eq!(levels, [3, 3, 3, 2, 2, 1, 1, 0, 0, 0]);
        let wider = GradedRule::seven_point(3, 2.0);
        assert_eq!(wider.level(3.0, 1.0), 2);
        assert_eq!(wider.level(3.0, 0.5), 1);
    }

    #[test]
    fn point_counts_follow_the_paper() {
        let seven = GradedRule::seven_point(3, 1.0);
        assert_eq!(seven.rule(3).points().len(), 7 * 64);
        assert_eq!(seven.rule(0).points().len(), 7);
        let gauss = GradedRule::gauss(1, 5, 1.0);
        assert_eq!(gauss.rule(5).points().len(), 64 * 64);
        assert_eq!(gauss.rule(0).points().len(), 4);
    }

    /// Relative error of both methods against adaptive quadrature for a node at height `z` over
    /// the element's edge (the near-singular case of the paper's Fig. 4.1).
    fn errors_near_an_edge(z: f64, max_level: u32) -> (f64, f64) {
        let tri = [DVec2::new(0.0, 0.0), DVec2::new(1.0, 0.0), DVec2::new(0.0, 1.0)];
        let obs =
            Observer { position: DVec3::new(0.4, -0.02, z), normal: DVec3::new(0.0, 1.0, 0.0) };
        let t = Tolerance { relative: 1e-13, ..Tolerance::default() };
        let want = reference::integral(&obs, &tri, |_| 1.0, t);
        let err = |rule: GradedRule| {
            let got = rule.integrate(&obs, &tri, &[&tri[..]], &[Affine2::ONE])[0];
            ((got - want) / want).abs()
        };
        (err(GradedRule::seven_point(max_level, 1.0)), err(GradedRule::gauss(1, max_level, 1.0)))
    }

    #[test]
    fn both_methods_converge_with_max_level_but_not_near_the_edge() {
        // Away from the element (z = 0.5): the composite 7-point rule gains 2^6 per level, the
        // Gauss rule converges spectrally.
        let (seven3, _) = errors_near_an_edge(0.5, 3);
        let (seven4, gauss4) = errors_near_an_edge(0.5, 4);
        assert!((40.0..100.0).contains(&(seven3 / seven4)), "{seven3:e} {seven4:e}");
        assert!(gauss4 < 1e-14, "{gauss4:e}");
        // At 1/50 of the element's size above its edge (the paper's Fig. 4.1) neither gets
        // anywhere near rounding error at level 5 (4^5 subtriangles, or 64 x 64 points).
        let (seven3, gauss3) = errors_near_an_edge(0.02, 3);
        let (seven5, gauss5) = errors_near_an_edge(0.02, 5);
        assert!(seven5 < seven3 && gauss5 < gauss3, "{seven3:e} {seven5:e} {gauss3:e} {gauss5:e}");
        assert!(seven5 > 1e-5 && gauss5 > 1e-4, "{seven5:e} {gauss5:e}");
    }

    #[test]
    fn pieces_add_up_to_the_element() {
        let tri = [DVec2::new(-0.5, -0.3), DVec2::new(0.6, -0.2), DVec2::new(0.1, 0.7)];
        let obs = Observer {
            position: DVec3::new(0.2, 0.4, 0.3),
            normal: DVec3::new(0.3, -0.2, -0.9).normalize(),
        };
        let mid = (tri[0] + tri[1]) / 2.0;
        let halves: [&[DVec2]; 2] = [&[tri[0], mid, tri[2]], &[mid, tri[1], tri[2]]];
        let w = [Affine2 { c0: 1.0, cx: 0.5, cy: -0.25 }];
        let rule = GradedRule::gauss(3, 3, 1.0);
        let whole = rule.integrate(&obs, &tri, &[&tri[..]], &w)[0];
        let split = rule.integrate(&obs, &tri, &halves, &w)[0];
        let t = Tolerance { relative: 1e-13, ..Tolerance::default() };
        let want = reference::integral(&obs, &tri, |q| w[0].eval(q), t);
        assert!((whole - want).abs() < 1e-9 * want.abs(), "{whole} {want}");
        assert!((split - want).abs() < 1e-9 * want.abs(), "{split} {want}");
    }
}
