//! Collocation integrals `∫ G(P, Q) φ(Q) dS_Q` over (visible parts of) elements (paper sec. 4).
//!
//! All kernels work in an element's local frame: the element lies in the plane height = 0 with
//! normal (0, 0, 1), the node P = (x, y, z) is above it (z > 0) with unit normal n_P = (i, j, k),
//! so (paper (1.2), sec. 4.1)
//!
//! ```text
//!     G(P, Q) = [(X - x) i + (Y - y) j - z k] z / ((X - x)² + (Y - y)² + z²)²,   Q = (X, Y, 0).
//! ```
//!
//! Regions are given as closed loops of 2-D vertices, counter-clockwise for area and clockwise for
//! holes; any set of loops whose winding number is the indicator of the region will do.
//!
//! Lengths are expected in units of the element's size (the assembly scales every pair by a power
//! of two so), with the node within 1e60 of the element (the scene's scale range guarantees it):
//! squares and fourth powers of lengths then stay inside f64's normal range.
//!
//! - [`exact`]: the production kernel: closed forms in edge form for the constant weight, closed
//!   forms plus one IMT quadrature per edge for affine weights (eqs. 4.5–4.9, 4.13); the IMT sum
//!   runs eight nodes at a time in vector lanes.
//! - [`lanes`]: the constant weight's closed form for eight (node, element) pairs at a time.
//! - [`by_rule`]: fixed triangle rules applied to G, four points at a time.
//! - [`far_field`]: a collapsed Gauss rule for elements far from the node (linear method).
//! - [`graded`]: the paper's 7-point and Gauss methods (sec. 4.2), distance-graded fixed rules.
//! - [`lambert`]: Lambert's contour formula, an independent closed form for the constant weight.
//! - [`paper_closed_form`]: the paper's own formulas over right triangles σ_ab, (4.5), (4.10), (4.11).
//! - [`reference`]: adaptive quadrature of G φ itself, for tests.

pub mod by_rule;
pub mod exact;
pub mod far_field;
pub mod graded;
pub mod lambert;
mod lane_math;
pub mod lanes;
mod moments;
pub mod paper_closed_form;
pub mod reference;

pub use moments::{LOG_PANEL_WIDTH, Moments, ThirdOrderMoments, edge_log_moment};

use glam::{DVec2, DVec3};

use crate::quadrature::TriangleRule;

/// A collocation node seen from an element's frame: its local position (x, y, z) and unit normal
/// (i, j, k).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Observer {
    /// Local position; `z` is the height above the element's plane.
    pub position: DVec3,
    /// Unit normal of the node's face, in local components.
    pub normal: DVec3,
}

impl Observer {
    /// The kernel G(P, Q) at an in-plane point Q (paper (1.2)).
    #[inline(always)]
    pub fn kernel(&self, q: DVec2) -> f64 {
        let d = q.extend(0.0) - self.position;
        let r2 = d.length_squared();
        d.dot(self.normal) * self.position.z / (r2 * r2)
    }

    /// `∫_T G φ_l` over the triangle `tri` for each affine weight, by a fixed rule: the rule
    /// accumulates `∫ G`, `∫ G X`, `∫ G Y` and the weights are applied once.
    pub fn integrate_by_rule<const L: usize>(
        &self,
        rule: &TriangleRule,
        tri: &[DVec2; 3],
        weights: &[Affine2; L],
    ) -> [f64; L] {
        let [g0, gx, gy] = by_rule::kernel_moments(self, rule, tri);
        weights.map(|phi| phi.c0 * g0 + phi.cx * gx + phi.cy * gy)
    }
}

/// An affine function `c0 + cx X + cy Y` of in-plane local coordinates: a basis function on an element.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Affine2 {
    /// Constant term.
    pub c0: f64,
    /// Coefficient of X.
    pub cx: f64,
    /// Coefficient of Y.
    pub cy: f64,
}

impl Affine2 {
    /// The constant function 1 (the centroid method's basis function).
    pub const ONE: Self = Self { c0: 1.0, cx: 0.0, cy: 0.0 };
    /// The function 0.
    pub const ZERO: Self = Self { c0: 0.0, cx: 0.0, cy: 0.0 };

    /// Value at `q`.
    pub fn eval(&self, q: DVec2) -> f64 {
        self.c0 + self.cx * q.x + self.cy * q.y
    }
}

/// A quadratic `Σ c[a][b] X^a Y^b` (a + b <= 2) of in-plane local coordinates: a polynomial true
/// solution restricted to a face.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Quadratic2 {
    /// Coefficients `c[a][b]` of `X^a Y^b`; entries with a + b > 2 are ignored.
    pub c: [[f64; 3]; 3],
}

impl Quadratic2 {
    /// Value at `q`.
    pub fn eval(&self, q: DVec2) -> f64 {
        let mut s = 0.0;
        for a in 0..3 {
            for b in 0..3 - a {
                s += self.c[a][b] * q.x.powi(a as i32) * q.y.powi(b as i32);
            }
        }
        s
    }

    /// The same polynomial in coordinates centred at `o`: `p(o + X')`.
    pub fn shifted(&self, o: DVec2) -> Self {
        let c = &self.c;
        let mut s = [[0.0; 3]; 3];
        s[0][0] = self.eval(o);
        s[1][0] = c[1][0] + 2.0 * c[2][0] * o.x + c[1][1] * o.y;
        s[0][1] = c[0][1] + c[1][1] * o.x + 2.0 * c[0][2] * o.y;
        s[2][0] = c[2][0];
        s[1][1] = c[1][1];
        s[0][2] = c[0][2];
        Self { c: s }
    }
}
