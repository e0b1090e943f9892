//! What a row of the matrix keeps across its pairs: what may come between its element and each
//! face ([`Between`], found once per face), and its tally of work, error and clamped entries
//! ([`Tally`]).

use super::context::Context;
use crate::geometry::bounding_box_3d;
use crate::visibility::OccluderUnit;

/// What may come between the element of a row and the elements of one face, found once per row
/// and face from the shaft between the element and the whole face (each pair's shaft lies
/// inside it).
pub(super) enum Between {
    /// No occluder.
    Nothing,
    /// A building hides the whole face from the element.
    Hidden,
    /// These occluder units, each pair's searched among them.
    Among(Vec<OccluderUnit>),
    /// More units than a pair's search of the scene costs: each pair searches it.
    Search,
}

/// The most occluder units a row keeps for a face ([`Between::Among`]): scanning a list of
/// them costs a box test each, where a search of the scene's tree goes down from its root.
const UNITS_KEPT: usize = 64;

impl Context<'_> {
    /// What may come between element `i` and face `face` ([`Between`]).
    pub(super) fn between(&self, i: usize, face: usize) -> Between {
        let own = self.mesh.elements()[i].face;
        if self.planner.candidates(own, face).is_empty() {
            return Between::Nothing;
        }
        let from = bounding_box_3d(&self.mesh.elements()[i].vertices);
        let to = bounding_box_3d(&self.scene.faces[face].vertices);
        let units = self.planner.shaft_candidates(from, to, None);
        if units.is_empty() {
            Between::Nothing
        } else if self.planner.solid_among_hides(own, face, from, to, &units) {
            Between::Hidden
        } else if units.len() > UNITS_KEPT {
            Between::Search
        } else {
            Between::Among(units)
        }
    }
}

/// Point-to-element integrals evaluated, the largest error estimate and the entries clamped at
/// zero of a row.
#[derive(Default)]
pub(super) struct Tally {
    pub(super) evaluations: u64,
    pub(super) error: f64,
    pub(super) clamped: usize,
}
