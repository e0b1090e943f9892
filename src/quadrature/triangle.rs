//! Fixed rules on the unit triangle σ = {(u, v) : u, v >= 0, u + v <= 1} (paper sec. 4): the
//! 7-point rule T2:5-1 of Stroud (4.3), its composites over 4^L congruent subtriangles, and the
//! collapsed Gauss–Legendre product rule of (4.4).

use glam::DVec2;

use super::GaussLegendre;

/// Points per lane group ([`PointLanes`]) and independent sums in [`TriangleRule::moments`].
pub const LANES: usize = 4;

/// A rule on σ: points `(u, v, w)`, the weights summing to |σ| = 1/2, also grouped in lanes.
#[derive(Clone, Debug, PartialEq)]
pub struct TriangleRule {
    points: Vec<[f64; 3]>,
    lanes: Vec<PointLanes>,
}

/// [`LANES`] consecutive points of a rule as structure of arrays, for vectorised evaluation; the
/// last group is padded with the rule's first point at weight zero. Point `k` is in lane
/// `k % LANES`, as in the sums of [`TriangleRule::moments`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PointLanes {
    /// First coordinates.
    pub u: [f64; LANES],
    /// Second coordinates.
    pub v: [f64; LANES],
    /// Weights.
    pub w: [f64; LANES],
}

impl TriangleRule {
    /// Stroud's T2:5-1 (degree 5): the centroid and two orbits of three points on the medians.
    pub fn stroud_t2_5_1() -> Self {
        let s15 = 15f64.sqrt();
        let mut points = vec![[1.0 / 3.0, 1.0 / 3.0, 9.0 / 80.0]];
        for (a, w) in [
            ((6.0 - s15) / 21.0, (155.0 - s15) / 2400.0),
            ((6.0 + s15) / 21.0, (155.0 + s15) / 2400.0),
        ] {
            let b = 1.0 - 2.0 * a;
            points.extend([[a, a, w], [b, a, w], [a, b, w]]);
        }
        Self::from_points(points)
    }

    /// The `order × order` collapsed Gauss–Legendre rule of (4.4): `s = (1 - y) x`, `t = y x`,
    /// Jacobian `x`, Gauss–Legendre in x and y on [0, 1]. Exact for degree `2 order - 2`; the
    /// points cluster at the vertex (0, 0).
    pub fn collapsed_gauss(order: usize) -> Self {
        let gl = GaussLegendre::new(order.max(1));
        let mut points = Vec::with_capacity(order * order);
        for (x, wx) in gl.nodes().iter().zip(gl.weights()) {
            let x = 0.5 * (x + 1.0);
            for (y, wy) in gl.nodes().iter().zip(gl.weights()) {
                let y = 0.5 * (y + 1.0);
                points.push([(1.0 - y) * x, y * x, 0.25 * wx * wy * x]);
            }
        }
        Self::from_points(points)
    }

    /// This rule applied on each of the 4^`level` congruent triangles that `level` rounds of
    /// midpoint subdivision make of σ.
    pub fn composite(&self, level: u32) -> Self {
        let mut cells = vec![[DVec2::ZERO, DVec2::X, DVec2::Y]];
        for _ in 0..level {
            cells = cells
                .iter()
                .flat_map(|&[a, b, c]| {
                    let (ab, bc, ca) = ((a + b) / 2.0, (b + c) / 2.0, (c + a) / 2.0);
                    [[a, ab, ca], [ab, b, bc], [ca, bc, c], [bc, ca, ab]]
                })
                .collect();
        }
        let scale = 0.25f64.powi(level as i32);
        let points = cells
            .iter()
            .flat_map(|&[a, b, c]| {
                self.points.iter().map(move |&[u, v, w]| {
                    let q = a + (b - a) * u + (c - a) * v;
                    [q.x, q.y, w * scale]
                })
            })
            .collect();
        Self::from_points(points)
    }

    /// The rule of `points` (at least one), grouped in lanes.
    fn from_points(points: Vec<[f64; 3]>) -> Self {
        let lanes = points
            .chunks(LANES)
            .map(|chunk| {
                let at =
                    |l: usize| chunk.get(l).copied().unwrap_or([points[0][0], points[0][1], 0.0]);
                PointLanes {
                    u: std::array::from_fn(|l| at(l)[0]),
                    v: std::array::from_fn(|l| at(l)[1]),
                    w: std::array::from_fn(|l| at(l)[2]),
                }
            })
            .collect();
        Self { points, lanes }
    }

    /// Points `(u, v, w)`.
    pub fn points(&self) -> &[[f64; 3]] {
        &self.points
    }

    /// The points in groups of [`LANES`].
    pub fn lanes(&self) -> &[PointLanes] {
        &self.lanes
    }

    /// `[∫ f, ∫ f X, ∫ f Y]` over the triangle `tri` (any orientation) of the plane, in
    /// [`LANES`] independent sums. The scalar reference of the vectorised kernel rule
    /// (`kernels::by_rule`), whose portable form does the same operations in the same order.
    pub fn moments(&self, tri: &[DVec2; 3], mut f: impl FnMut(DVec2) -> f64) -> [f64; 3] {
        let [a, b, c] = *tri;
        let jacobian = (b - a).perp_dot(c - a).abs();
        let mut sums = [[0.0f64; LANES]; 3];
        let chunks = self.points.chunks_exact(LANES);
        let rest = chunks.remainder();
        for chunk in chunks {
            for (lane, &[u, v, w]) in chunk.iter().enumerate() {
                let q = a + (b - a) * u + (c - a) * v;
                let g = w * f(q);
                sums[0][lane] += g;
                sums[1][lane] += g * q.x;
                sums[2][lane] += g * q.y;
            }
        }
        for (lane, &[u, v, w]) in rest.iter().enumerate() {
            let q = a + (b - a) * u + (c - a) * v;
            let g = w * f(q);
            sums[0][lane] += g;
            sums[1][lane] += g * q.x;
            sums[2][lane] += g * q.y;
        }
        sums.map(|s| jacobian * ((s[0] + s[1]) + (s[2] + s[3])))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// ∫_σ u^p v^q = p! q! / (p + q + 2)!.
    fn exact_monomial(p: i32, q: i32) -> f64 {
        let fact = |n: i32| (1..=n).map(f64::from).product::<f64>();
        fact(p) * fact(q) / fact(p + q + 2)
    }

    /// Worst relative error of `rule` over the monomials of total degree `degree`.
    fn worst_error_at_degree(rule: &TriangleRule, degree: i32) -> f64 {
        (0..=degree)
            .map(|p| {
                let q = degree - p;
                let got: f64 =
                    rule.points().iter().map(|&[u, v, w]| w * u.powi(p) * v.powi(q)).sum();
                (got - exact_monomial(p, q)).abs() / exact_monomial(p, q)
            })
            .fold(0.0, f64::max)
    }

    #[test]
    fn stroud_rule_has_degree_five_exactly() {
        let rule = TriangleRule::stroud_t2_5_1();
        assert_eq!(rule.points().len(), 7);
        for degree in 0..=5 {
            assert!(worst_error_at_degree(&rule, degree) < 1e-14, "degree {degree}");
        }
        assert!(worst_error_at_degree(&rule, 6) > 1e-6, "degree 6 is not integrated exactly");
    }

    #[test]
    fn composites_keep_the_degree_and_converge_at_order_six() {
        let base = TriangleRule::stroud_t2_5_1();
        for level in 1..=3 {
            let rule = base.composite(level);
            assert_eq!(rule.points().len(), 7 * 4usize.pow(level));
            assert!(rule.points().iter().all(|&[u, v, _]| u >= 0.0 && v >= 0.0 && u + v <= 1.0));
            for degree in 0..=5 {
                assert!(worst_error_at_degree(&rule, degree) < 1e-13, "level {level}, {degree}");
            }
        }
        // The error of a smooth integrand falls by 2^6 per level.
        let f = |u: f64, v: f64| (2.0 * u + 3.0 * v).exp();
        // ∫_σ e^{2u + 3v} = ∫_0^1 e^{2u} (e^{3(1-u)} - 1)/3 du = (e^3 (1 - 1/e) - (e^2 - 1)/2) / 3.
        let e = std::f64::consts::E;
        let exact = (e.powi(3) * (1.0 - 1.0 / e) - (e * e - 1.0) / 2.0) / 3.0;
        let err = |level| {
            let r = base.composite(level);
            (r.points().iter().map(|&[u, v, w]| w * f(u, v)).sum::<f64>() - exact).abs()
        };
        let ratio = err(2) / err(3);
        assert!((50.0..80.0).contains(&ratio), "error ratio per level {ratio}");
    }

    #[test]
    fn collapsed_gauss_has_degree_two_n_minus_two() {
        for order in 1..=8 {
            let rule = TriangleRule::collapsed_gauss(order);
            let top = 2 * order as i32 - 2;
            for degree in 0..=top {
                assert!(worst_error_at_degree(&rule, degree) < 1e-13, "order {order}, {degree}");
            }
        }
    }

    #[test]
    fn moments_scale_with_the_triangle_and_ignore_orientation() {
        let rule = TriangleRule::stroud_t2_5_1();
        let tri = [DVec2::new(1.0, 1.0), DVec2::new(4.0, 1.0), DVec2::new(1.0, 3.0)];
        let flipped = [tri[0], tri[2], tri[1]];
        for t in [tri, flipped] {
            let [area, mx, my] = rule.moments(&t, |_| 1.0);
            assert!((area - 3.0).abs() < 1e-14);
            assert!((mx / area - 2.0).abs() < 1e-14 && (my / area - 5.0 / 3.0).abs() < 1e-14);
        }
    }
}
