//! The cells of the outer integral: triangles and convex quadrilaterals of a piece of T_i, with
//! Gauss rules on each.
//!
//! The pieces between event lines are mostly quadrilaterals (on the occluded box 22 268 of
//! 46 534, and 7 756 more with five or six corners). A tensor Gauss rule of order q on a
//! quadrilateral (bilinear map from the square) has q² points where its two triangles need 2q²,
//! and the points do not crowd into one corner as the collapsed rule's do.

use glam::DVec3;

use crate::quadrature::{GaussLegendre, TriangleRule};

/// A triangle or a convex quadrilateral (corners counter-clockwise or clockwise, in one plane).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) enum Patch {
    Triangle([DVec3; 3]),
    Quad([DVec3; 4]),
}

/// Gauss rules by order (index 0 unused): collapsed on the unit triangle, and on [0, 1].
pub(super) struct GaussRules {
    triangles: Vec<TriangleRule>,
    /// (node, weight) on [0, 1].
    lines: Vec<Vec<(f64, f64)>>,
}

impl GaussRules {
    /// Rules of orders 1 to `max`.
    pub(super) fn new(max: usize) -> Self {
        let lines = (0..=max)
            .map(|q| {
                let gl = GaussLegendre::new(q.max(1));
                gl.nodes()
                    .iter()
                    .zip(gl.weights())
                    .map(|(&x, &w)| (0.5 * (x + 1.0), 0.5 * w))
                    .collect()
            })
            .collect();
        Self {
            triangles: (0..=max).map(|q| TriangleRule::collapsed_gauss(q.max(1))).collect(),
            lines,
        }
    }
}

impl Patch {
    /// A convex polygon as patches: quadrilaterals fanned from its first corner, and a triangle
    /// where a corner is left over.
    pub(super) fn cover(polygon: &[DVec3]) -> Vec<Patch> {
        let m = polygon.len();
        let v0 = polygon[0];
        let mut patches = Vec::with_capacity(m / 2);
        let mut k = 1;
        while k + 2 < m {
            patches.push(Patch::Quad([v0, polygon[k], polygon[k + 1], polygon[k + 2]]));
            k += 2;
        }
        if k + 1 < m {
            patches.push(Patch::Triangle([v0, polygon[k], polygon[k + 1]]));
        }
        patches
    }

    pub(super) fn corners(&self) -> &[DVec3] {
        match self {
            Patch::Triangle(t) => t,
            Patch::Quad(q) => q,
        }
    }

    pub(super) fn area(&self) -> f64 {
        match *self {
            Patch::Triangle([a, b, c]) => 0.5 * (b - a).cross(c - a).length(),
            Patch::Quad([a, b, c, d]) => 0.5 * (c - a).cross(d - b).length(),
        }
    }

    /// The longest side: every segment along which the rule's coordinates run is no longer.
    pub(super) fn size(&self) -> f64 {
        let c = self.corners();
        let m = c.len();
        (0..m).map(|k| c[k].distance(c[(k + 1) % m])).fold(0.0, f64::max)
    }

    /// The four patches of the same kind that joining the sides' midpoints (and, in a
    /// quadrilateral, the centre) makes.
    pub(super) fn quarters(&self) -> [Patch; 4] {
        match *self {
            Patch::Triangle(t) => triangle_quarters(t).map(Patch::Triangle),
            Patch::Quad([a, b, c, d]) => {
                let (ab, bc, cd, da) = ((a + b) * 0.5, (b + c) * 0.5, (c + d) * 0.5, (d + a) * 0.5);
                let m = (a + b + c + d) * 0.25;
                [[a, ab, m, da], [ab, b, bc, m], [m, bc, c, cd], [da, m, cd, d]].map(Patch::Quad)
            }
        }
    }

    /// Its triangles: itself, or a quadrilateral's two halves along the diagonal from its first
    /// corner.
    pub(super) fn triangles(&self) -> impl Iterator<Item = [DVec3; 3]> {
        let (first, second) = match *self {
            Patch::Triangle(t) => (t, None),
            Patch::Quad([a, b, c, d]) => ([a, b, c], Some([a, c, d])),
        };
        std::iter::once(first).chain(second)
    }

    /// The points and weights of the order-`q` Gauss rule on it (`q²` points): collapsed on a
    /// triangle, the tensor rule through the bilinear map of the unit square on a
    /// quadrilateral.
    pub(super) fn gauss_points(&self, rules: &GaussRules, q: usize) -> Vec<(DVec3, f64)> {
        match *self {
            Patch::Triangle([a, b, c]) => {
                let area = self.area();
                rules.triangles[q]
                    .points()
                    .iter()
                    .map(|&[u, v, w]| (a + (b - a) * u + (c - a) * v, 2.0 * area * w))
                    .collect()
            }
            Patch::Quad([a, b, c, d]) => {
                let line = &rules.lines[q];
                let mut points = Vec::with_capacity(q * q);
                for &(s, ws) in line {
                    for &(t, wt) in line {
                        // P(s, t) = a (1-s)(1-t) + b s (1-t) + c s t + d (1-s) t.
                        let p = a * ((1.0 - s) * (1.0 - t))
                            + b * (s * (1.0 - t))
                            + c * (s * t)
                            + d * ((1.0 - s) * t);
                        let ds = (b - a) * (1.0 - t) + (c - d) * t;
                        let dt = (d - a) * (1.0 - s) + (c - b) * s;
                        points.push((p, ws * wt * ds.cross(dt).length()));
                    }
                }
                points
            }
        }
    }
}

/// The four triangles that joining a triangle's side midpoints makes.
pub(super) fn triangle_quarters([a, b, c]: [DVec3; 3]) -> [[DVec3; 3]; 4] {
    let (ab, bc, ca) = ((a + b) * 0.5, (b + c) * 0.5, (c + a) * 0.5);
    [[a, ab, ca], [ab, b, bc], [ca, bc, c], [ab, bc, ca]]
}

#[cfg(test)]
mod tests {
    use super::*;

    fn pentagon() -> Vec<DVec3> {
        [(0.0, 0.0), (2.0, 0.0), (2.5, 1.0), (1.0, 2.0), (-0.5, 1.0)]
            .iter()
            .map(|&(x, y)| DVec3::new(x, y, 0.3 * x - 0.2 * y))
            .collect()
    }

    /// The patches of a polygon cover it: areas add up, and each rule integrates a cubic over
    /// them to rounding (the collapsed rule of order q is exact to degree 2q - 2, the tensor
    /// rule through a bilinear map to degree 2q - 1 in each coordinate, times the Jacobian's
    /// degree one).
    #[test]
    fn patches_of_a_pentagon_integrate_a_cubic_exactly() {
        let polygon = pentagon();
        let patches = Patch::cover(&polygon);
        assert_eq!(patches.len(), 2);
        assert!(matches!(patches[0], Patch::Quad(_)) && matches!(patches[1], Patch::Triangle(_)));
        let rules = GaussRules::new(6);
        let f = |p: DVec3| 1.0 + p.x * p.x * p.y - 2.0 * p.y * p.y * p.y + p.x;
        let triangles: Vec<[DVec3; 3]> =
            (1..polygon.len() - 1).map(|k| [polygon[0], polygon[k], polygon[k + 1]]).collect();
        let reference: f64 = triangles
            .iter()
            .flat_map(|&t| Patch::Triangle(t).gauss_points(&rules, 6))
            .map(|(p, w)| w * f(p))
            .sum();
        let area: f64 = triangles.iter().map(|&t| Patch::Triangle(t).area()).sum();
        assert!((patches.iter().map(Patch::area).sum::<f64>() - area).abs() < 1e-14);
        for q in 3..=6 {
            let got: f64 =
                patches.iter().flat_map(|p| p.gauss_points(&rules, q)).map(|(p, w)| w * f(p)).sum();
            assert!((got - reference).abs() < 1e-13 * reference.abs(), "q {q}: {got} {reference}");
        }
        // Quarters cover their patch.
        for patch in &patches {
            let quarters: f64 = patch.quarters().iter().map(Patch::area).sum();
            assert!((quarters - patch.area()).abs() < 1e-14);
            let halves: f64 = patch.triangles().map(|t| Patch::Triangle(t).area()).sum();
            assert!((halves - patch.area()).abs() < 1e-14);
        }
    }
}
