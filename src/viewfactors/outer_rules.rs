//! The outer rules ([`OuterRules`]): tanh-sinh for triangles that touch, Gauss of an order
//! chosen from a patch's separation (the Bernstein-ellipse bound) otherwise.

use super::options::ViewFactorOptions;
use super::patch::GaussRules;
use crate::quadrature::TanhSinh;

/// The outer rules: tanh-sinh for elements that touch, Gauss of a chosen order otherwise.
pub(super) struct OuterRules {
    pub(super) tanh_sinh: TanhSinh,
    pub(super) gauss: GaussRules,
}

/// Highest order of the Gauss rules on a patch (GAUSS_MAX² points).
pub(super) const GAUSS_MAX: usize = 16;

/// The outer rule's target error where T_j is seen whole, relative to the integrand's size near
/// the element: a tenth of the tolerance, and no less than 1e-13. The Gauss order is chosen from
/// the separation so that the Bernstein-ellipse bound meets it ([`OuterRules::bound_order`]);
/// the integrand is analytic away from T_j and the bound is trusted (one rule, no estimate). A
/// tenth leaves the bound's constant (the rule's, and the integrand's growth off the real
/// patch) a factor of ten within the tolerance. Aimed at a ten-thousandth with the ellipse of a
/// point beyond a side's end instead, two facing walls of city:4x4 6 m apart (elements 35 m
/// across) came out 2.1e-6 off at --tolerance 1e-6, with an estimate of 1e-6.
pub(super) fn certified_target(tolerance: f64) -> f64 {
    (0.1 * tolerance).max(1e-13)
}

impl OuterRules {
    /// The rules for `options`: the tanh-sinh rule truncated where its weights fall below a
    /// hundredth of the tolerance (the integrand, a point-to-element factor, is at most 1):
    /// points whose weights are below that move the integral by less than the tolerance can
    /// resolve, so truncating further only adds evaluations.
    pub(super) fn new(options: &ViewFactorOptions) -> Self {
        let tail = 1e-2 * options.tolerance;
        Self {
            tanh_sinh: TanhSinh::new(options.max_level, tail),
            gauss: GaussRules::new(GAUSS_MAX),
        }
    }

    /// The Gauss order for a patch of size `size` at distance `distance` from the nearest
    /// point where the integrand is not analytic (the other element, an occluder), as a first
    /// guess that the cell's estimate checks: the integrand is analytic in an ellipse with foci
    /// at a side's ends, and where the point lies beyond a side's end, its semi-axis sum is
    /// rho = a + sqrt(a² - 1), a = 1 + 2 distance / size; the q-point rule's error falls like
    /// rho^-2q. `None` when even the highest order but one does not reach the target (the cell
    /// then takes that order and the highest, and its estimate decides whether to split).
    pub(super) fn guessed_order(&self, size: f64, distance: f64, target: f64) -> Option<usize> {
        let a = 1.0 + 2.0 * distance / size;
        self.order_for(a + (a * a - 1.0).sqrt(), target)
    }

    /// The Gauss order whose a priori bound meets the target wherever the point at `distance`
    /// lies: the smallest ellipse is that through a point at that distance from a side's
    /// middle, a = sqrt(1 + (2 distance / size)²). Where the distance is small against the
    /// patch (two facing walls across a street) it is far smaller than beyond a side's end,
    /// whose order missed the target by 2e4 there. `None` where no order up to the highest but
    /// one meets it.
    pub(super) fn bound_order(&self, size: f64, distance: f64, target: f64) -> Option<usize> {
        let across = 2.0 * distance / size;
        let a = (1.0 + across * across).sqrt();
        self.order_for(a + (a * a - 1.0).sqrt(), target)
    }

    /// The Gauss order whose error, falling like rho^-2q, meets the target, where the integrand
    /// is analytic inside the Bernstein ellipse of parameter `rho`, from 2; `None` where even
    /// the highest order but one does not. From 2, not 1: a one-point rule checked against two
    /// agrees by chance often enough to drive a pair to the split limit (a pair of the 12 x 12
    /// tessellated city at 1e-6).
    pub(super) fn order_for(&self, rho: f64, target: f64) -> Option<usize> {
        let q = ((1.0 / target).ln() / (2.0 * rho.ln())).ceil();
        (q < GAUSS_MAX as f64).then(|| (q as usize).max(2))
    }
}
