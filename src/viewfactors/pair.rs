//! The adaptive outer integral of one pair, F_ij: T_i cut into pieces where the integrand is not
//! smooth, each covered by cells whose Gauss or tanh-sinh estimates decide where to refine.
//! The cells' integrals are in `cells.rs`, touching triangles in `touching.rs`, what each piece
//! sees in `part.rs`.

use glam::DVec3;

use super::cells::{Cells, Refine};
use super::context::Context;
use super::events::{clip_polygon_3d, contact_cuts, event_planes, split};
use super::opening::Opening;
use super::outer_rules::OuterRules;
use super::part::Part;
use super::patch::Patch;
use super::poles::poles;
use super::row::{Between, Tally};
use super::sight::{Among, Sight};
use crate::geometry::bounding_box_3d;
use crate::visibility::Caster;

/// The share of a pair's error budget that patches taken by their bounds may take at first
/// ([`Context::bounded_cell`]), the patches that can hold the least first.
const BOUNDED_SHARE: f64 = 0.5;

impl Context<'_> {
    /// F_ij.
    pub(super) fn pair(
        &self,
        i: usize,
        j: usize,
        between: &mut Option<Between>,
        rules: &OuterRules,
        tally: &mut Tally,
    ) -> f64 {
        let (ei, ej) = (&self.mesh.elements()[i], &self.mesh.elements()[j]);
        let (fa, fb) = (&self.scene.faces[ei.face], &self.scene.faces[ej.face]);
        if self.planner.same_plane(ei.face, ej.face) {
            return 0.0;
        }
        let tol = 1e-12 * ei.diameter().max(ej.diameter());
        let heights = |f: &crate::scene::Face, t: &[DVec3; 3]| t.map(|v| f.frame.height(v));
        let (hj, hi) = (heights(fa, &ej.vertices), heights(fb, &ei.vertices));
        if hj.iter().all(|&h| h <= tol) || hi.iter().all(|&h| h <= tol) {
            return 0.0; // one wholly behind the other's plane
        }
        let (box_i, box_j) = (bounding_box_3d(&ei.vertices), bounding_box_3d(&ej.vertices));
        let (a, b) = (ei.face, ej.face);
        // Found once for the face, by the first of its pairs that gets this far.
        let (mut occluders, hidden) = match between.get_or_insert_with(|| self.between(i, b)) {
            Between::Nothing => (Vec::new(), false),
            Between::Hidden => return 0.0,
            Between::Among(units) => self.planner.shaft_occluders_among(a, b, box_i, box_j, units),
            Between::Search => self.planner.shaft_occluders(a, b, box_i, box_j),
        };
        if hidden {
            return 0.0;
        }
        // In the order of their numbers, whichever search found them.
        occluders.sort_unstable();
        let in_front = |h: [f64; 3]| h.iter().all(|&h| h >= -tol);
        let pieces = self.smooth_pieces((i, j), !in_front(hi), &occluders, tol);
        // Each piece has its own occluders, among the pair's: a piece in the light of all of
        // them sees T_j whole (no per-point visibility), one behind an occluder that crosses
        // every segment to T_j sees nothing, and the others shadow T_j by their own occluders
        // only, without any search; where a plate of them leaves one opening, through that
        // opening and by the others.
        let shafts: Vec<Shaft> = pieces
            .into_iter()
            .filter_map(|piece| {
                let (blocking, hidden) = if occluders.is_empty() {
                    (Vec::new(), false)
                } else {
                    self.planner.polygon_shaft(ei.face, ej.face, &piece, &ej.vertices, &occluders)
                };
                if hidden {
                    return None;
                }
                let casters = |pieces: &[usize]| self.planner.casters(ei.face, ej.face, pieces);
                let opening =
                    Opening::find(&piece, &ej.vertices, &blocking, self.planner).map(|o| {
                        let others: Vec<usize> =
                            blocking.iter().copied().filter(|b| !o.pieces.contains(b)).collect();
                        (o, casters(&others))
                    });
                let casting = casters(&blocking);
                Some(Shaft { piece, blocking, casting, opening })
            })
            .collect();
        let parts: Vec<Part> = shafts
            .iter()
            .map(|shaft| Part {
                target: ej.vertices,
                target_box: box_j,
                target_area: ej.area(),
                clipped: !in_front(hj),
                poles: poles(
                    fa.frame.normal,
                    &shaft.piece,
                    &fb.frame,
                    &ej.vertices,
                    &shaft.blocking,
                    self.planner,
                    (ei.face, ej.face),
                ),
                obstacles: self.obstacles(i, &shaft.blocking),
                sight: if shaft.blocking.is_empty() && in_front(hj) {
                    Sight::Whole
                } else {
                    Sight::PerPoint(Among {
                        occluders: &shaft.casting,
                        opening: shaft.opening.as_ref().map(|(o, others)| (o, others.as_slice())),
                    })
                },
            })
            .collect();
        // Globally adaptive over the pair: the cell with the largest estimated error is split
        // until the estimates together are within the tolerance on F_ij. Patches that can hold
        // little of F_ij at most, the least first, take their bounds' share of the budget
        // ([`Context::bounded_cell`]); the others take the rules.
        let budget = self.options.tolerance * ei.area();
        let mut patches: Vec<(f64, usize, Patch)> = shafts
            .iter()
            .enumerate()
            .flat_map(|(k, shaft)| Patch::cover(&shaft.piece).into_iter().map(move |p| (k, p)))
            .map(|(k, patch)| (parts[k].most(&patch), k, patch))
            .collect();
        patches.sort_unstable_by(|a, b| a.0.total_cmp(&b.0));
        let mut bounded_share = BOUNDED_SHARE * budget;
        let mut cells = Cells::default();
        for (most, k, patch) in patches {
            let cell = if most <= bounded_share {
                bounded_share -= most;
                self.bounded_cell((i, j), patch, &parts[k], k, most, tally)
            } else {
                self.cell(i, j, patch, &parts[k], k, 0, rules, tally)
            };
            cells.place(cell);
        }
        // Settled cells (at the split limit, or certified) keep their error: the open ones are
        // refined until the two together meet the budget, or until they meet half of it where
        // the settled ones already take more than the other half (refining every open cell to
        // the limit would not help).
        while cells.open_error > (budget - cells.settled_error).max(0.5 * budget) {
            let Some(cell) = cells.open.pop() else { break };
            cells.open_error -= cell.error;
            let part = &parts[cell.part];
            if cell.refine == Refine::ByRules {
                cells.place(self.cell(i, j, cell.patch, part, cell.part, 0, rules, tally));
                continue;
            }
            for child in cell.patch.quarters() {
                cells.place(self.cell(i, j, child, part, cell.part, cell.depth + 1, rules, tally));
            }
        }
        let (value, error) = cells.total();
        tally.error = tally.error.max(error / ei.area());
        value / ei.area()
    }

    /// Element i of the pair `(i, j)` cut where the integrand is not smooth: behind element
    /// j's plane (when it reaches there, `behind`) it sees nothing, and across the event lines of
    /// the `occluders` the visible part of element j changes its shape.
    fn smooth_pieces(
        &self,
        (i, j): (usize, usize),
        behind: bool,
        occluders: &[usize],
        tol: f64,
    ) -> Vec<Vec<DVec3>> {
        let (ei, ej) = (&self.mesh.elements()[i], &self.mesh.elements()[j]);
        let (fa, fb) = (&self.scene.faces[ei.face], &self.scene.faces[ej.face]);
        let mut pieces = vec![ei.vertices.to_vec()];
        if behind {
            let (n, o) = (fb.frame.normal, fb.frame.origin);
            pieces = pieces.iter().filter_map(|p| clip_polygon_3d(p, n, -n.dot(o))).collect();
        }
        let (ti, tj) = ((&ei.vertices, &fa.frame), (&ej.vertices, &fb.frame));
        let events =
            event_planes(&ei.vertices, &ej.vertices, occluders, self.planner, (ei.face, ej.face));
        for event in contact_cuts(ti, tj, tol).into_iter().chain(events) {
            let mut next = Vec::with_capacity(pieces.len() + 1);
            for piece in pieces {
                if !event.crosses(&piece, fa.frame.normal) {
                    next.push(piece);
                    continue;
                }
                match split(&piece, event.normal, event.point) {
                    Some(parts) => next.extend(parts),
                    None => next.push(piece),
                }
            }
            pieces = next;
        }
        pieces
    }
}

/// A piece of a pair's outer element and what can come between it and the other element.
struct Shaft {
    piece: Vec<DVec3>,
    /// The pair's occluder pieces in its shaft.
    blocking: Vec<usize>,
    /// The same as they cast shadows.
    casting: Vec<Caster>,
    /// The opening that a plate of them leaves, if any, and the other pieces as they cast.
    opening: Option<(Opening, Vec<Caster>)>,
}
