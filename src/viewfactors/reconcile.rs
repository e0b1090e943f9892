//! Close pairs checked by reciprocity ([`Context::reconciled`]): where two elements touch or
//! nearly touch, the integrand is singular or nearly so at their contact, and a rule's levels
//! or orders can agree while missing (a vertex of one triangle on the interior of another's
//! edge: 19 times the estimate off). Each past fix covered one kind of contact, and the next
//! kind broke the estimate. This check does not depend on the kind: F_ij over T_i and F_ji over
//! T_j are integrated each, and A_i F_ij = A_j F_ji must hold within F_ij's estimate; where it
//! does not, both are integrated again at a tighter tolerance, and what still disagrees counts
//! in the estimate.

use super::context::Context;
use super::options::ViewFactorOptions;
use super::outer_rules::OuterRules;
use super::part::box_distance;
use super::row::{Between, Tally};
use crate::geometry::{bounding_box_3d, convex_polygons_distance};

/// Elements this close, as a share of the smaller one's size, are checked by reciprocity: the
/// contacts (distance 0) and the near misses whose integrand peaks within a thousandth of
/// their size.
pub(super) const CLOSE: f64 = 1e-3;

/// Rounds of integrating a close pair again, each at a tenth of the tolerance before.
const ROUNDS: u32 = 3;

/// Relative rounding of an integrated entry (64 ulp): a gap within it is no disagreement.
const ROUNDING: f64 = 64.0 * f64::EPSILON;

/// The tightest tolerance a round asks for: f64 meets about 1e-13 on these integrals.
const TIGHTEST: f64 = 1e-12;

impl Context<'_> {
    /// Whether elements `i` and `j` are close enough for [`Context::reconciled`]: their
    /// distance is at most [`CLOSE`] of the smaller one's size.
    pub(super) fn close(&self, i: usize, j: usize) -> bool {
        let (ei, ej) = (&self.mesh.elements()[i], &self.mesh.elements()[j]);
        let gap = CLOSE * ei.diameter().min(ej.diameter());
        let boxes = (bounding_box_3d(&ei.vertices), bounding_box_3d(&ej.vertices));
        box_distance(boxes.0, boxes.1) <= gap
            && convex_polygons_distance(&ei.vertices, &ej.vertices) <= gap
    }

    /// F_ij of a close pair, already integrated over T_i as `(value, estimate)`, checked
    /// against F_ji integrated over T_j: where `|F_ij - (A_j / A_i) F_ji|` exceeds F_ij's
    /// estimate, both are integrated again at a tenth of the tolerance, up to [`ROUNDS`] times;
    /// a gap that remains counts in F_ij's estimate with F_ji's (in F_ij's units), which then
    /// bounds its error wherever either direction is within its own estimate. `rules` are the
    /// run's, at its tolerance. Returns F_ij and its estimate; the work done goes to `tally`.
    pub(super) fn reconciled(
        &self,
        (i, j): (usize, usize),
        (mut f_ij, mut e_ij): (f64, f64),
        rules: &OuterRules,
        tally: &mut Tally,
    ) -> (f64, f64) {
        let elements = self.mesh.elements();
        let ratio = elements[j].area() / elements[i].area();
        let mut tolerance = self.options.tolerance;
        let (mut f_ji, mut e_ji) = self.pair_alone((j, i), rules, tally);
        for round in 0..=ROUNDS {
            let gap = (f_ij - ratio * f_ji).abs();
            // F_ij's own estimate must explain the gap: where only the two estimates together
            // did, F_ji's large one could hide F_ij's miss (a vertex on a tilted triangle's
            // edge: 4.8e-5 off under an estimate of 3.0e-5 at --tolerance 1e-4, F_ji 7e-7 off).
            if gap <= e_ij.max(ROUNDING * f_ij.abs().max(ratio * f_ji.abs())) {
                break;
            }
            if round == ROUNDS || tolerance <= TIGHTEST {
                e_ij = e_ij.max(gap + ratio * e_ji);
                break;
            }
            tolerance = (0.1 * tolerance).max(TIGHTEST);
            let options = ViewFactorOptions { tolerance, ..*self.options };
            let (tighter, rules) =
                (Context { options: &options, ..*self }, OuterRules::new(&options));
            (f_ij, e_ij) = tighter.pair_alone((i, j), &rules, tally);
            (f_ji, e_ji) = tighter.pair_alone((j, i), &rules, tally);
        }
        (f_ij, e_ij)
    }

    /// F_ij with what comes between found for it alone, and its estimate.
    fn pair_alone(
        &self,
        (i, j): (usize, usize),
        rules: &OuterRules,
        tally: &mut Tally,
    ) -> (f64, f64) {
        let mut own = Tally::default();
        let value = self.pair(i, j, &mut None::<Between>, rules, &mut own);
        tally.evaluations += own.evaluations;
        (value, own.error)
    }
}
