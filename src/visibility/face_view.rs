//! A node's view of a whole face ([`PairPlanner::face_view`], [`PairPlanner::face_view_with`]):
//! the window of the face in front of the node's tangent plane, the view volume in which the
//! candidate occluders are searched (the R*-tree, the pair table or a scan of boxes), and their
//! shadows on the window, the search stopping at one that hides the face. The window
//! ([`PairPlanner::window`]) also serves the views of parts ([`super::part_view`]).

use std::borrow::Cow;

use glam::{DVec2, DVec3};
use smallvec::SmallVec;

use super::cluster_candidates::ClusterCandidates;
use super::hiders::{Hider, RecentHiders};
use super::occluders::{Acceleration, OccluderUnit, ViewVolume};
use super::planner::{HEIGHT_ROUNDING, Height, PairPlanner};
use super::projection::{Pyramid, ShadowSet, pyramid_sides, shadow};
use super::view::{FaceView, Shadows, SkipReason};
use crate::geometry::{HalfPlane, PlaneFrame, clip_convex};

/// Relative tolerance for "on the line" decisions when clipping by a tangent plane (no slivers).
pub(crate) const PLANE_TOLERANCE: f64 = 1e-12;

/// Candidate occluders of a view taken in the search's order before the rest are sorted nearest
/// first ([`PairPlanner::face_view_with`]).
const IN_TREE_ORDER: usize = 16;

impl PairPlanner {
    /// What the point `p` with unit normal `normal`, on face `own_face`, sees of face `face`.
    pub fn face_view(&self, p: DVec3, normal: DVec3, own_face: usize, face: usize) -> FaceView {
        self.face_view_with(p, normal, own_face, face, &mut RecentHiders::default())
    }

    /// As [`PairPlanner::face_view`], for one of many faces seen from `p`: the occluders in
    /// `hiders` (those that hid earlier faces from `p`) are tried before any search, and one that
    /// hides this face joins them. The view is the same as without them.
    pub fn face_view_with(
        &self,
        p: DVec3,
        normal: DVec3,
        own_face: usize,
        face: usize,
        hiders: &mut RecentHiders,
    ) -> FaceView {
        self.face_view_among(p, normal, own_face, face, hiders, None)
    }

    /// As [`PairPlanner::face_view_with`], for a viewer of the cluster that `shared` holds the
    /// candidates of: they are filtered for the view instead of a search of the tree. The view
    /// is the same as without them.
    pub fn face_view_among(
        &self,
        p: DVec3,
        normal: DVec3,
        own_face: usize,
        face: usize,
        hiders: &mut RecentHiders,
        shared: Option<&mut ClusterCandidates>,
    ) -> FaceView {
        let pair = self.pairs.as_ref().map(|t| &t[own_face * self.faces.len() + face]);
        let h = self.height(p, face);
        if let Some(reason) = self.plane_skip(h, own_face, face) {
            return FaceView::Skip(reason);
        }
        let outline = &self.faces[face].hull;
        let Window { z, clip, polygon: window, corners } =
            match self.window(p, h, normal, face, outline) {
                Ok(window) => window,
                Err(view) => return view,
            };
        let f = &self.faces[face];
        let own = &self.faces[own_face];
        if self.occluders.acceleration == Acceleration::BoxScan {
            let sides = pyramid_sides(p, &corners);
            // The core solver's plan: every occluder in the box of the two faces and in front of
            // both, each shadow computed, in index order.
            let shadows = self
                .candidates(own_face, face)
                .iter()
                .filter_map(|&o| shadow(p, z, f, &window, &sides, &self.occluders.pieces[o]))
                .collect();
            return FaceView::Visible { clip, shadows: Shadows::new(shadows) };
        }
        let tol = self.pair_tolerance(own_face, face);
        let pieces = &self.occluders.pieces;
        let hides = |o: usize| {
            let piece = &pieces[o];
            !piece.faces.contains(&own_face)
                && !piece.faces.contains(&face)
                && piece.crosses_every_segment(&[p], &corners, tol, -tol)
        };
        // The segments lie in the pyramid's bounding box: a piece that crosses them all meets
        // it. The recent hiders carry their boxes, so that those elsewhere (most of them) are
        // passed over by six comparisons, without a look at the pieces themselves.
        let (lo, hi) = corners.iter().fold((p, p), |(lo, hi), &c| (lo.min(c), hi.max(c)));
        let meets = |h: &Hider| {
            (h.lo - hi).cmple(DVec3::splat(tol)).all() && (lo - h.hi).cmple(DVec3::splat(tol)).all()
        };
        if let Some(k) = hiders.list.iter().position(|h| meets(h) && hides(h.occluder)) {
            hiders.list[..=k].rotate_right(1);
            return FaceView::Skip(SkipReason::Hidden);
        }
        let sides = pyramid_sides(p, &corners);
        let volume =
            view_volume(p, &corners, &sides, (lo, hi), [&own.face.frame, &f.face.frame], tol);
        // One shadow that covers the whole window hides the face (most faces of a large scene,
        // seen from most nodes): the search stops there.
        let mut shadows = ShadowSet::default();
        // The pair's list holds every occluder in the box of the two faces, a superset of those
        // in the pyramid; the same filter then finds the same ones as the tree. The tree gives
        // units: solids whole, and the pieces of none.
        // Each piece found is one of neither face and reaches into the volume: the tree's units
        // by their boxes only, so its pieces are filtered here, once.
        let candidate = |o: usize| self.occluders.may_block(o, own_face, face, &volume);
        let with_box = |k: usize| {
            let (lo, hi) = pieces[k].bounding_box();
            (OccluderUnit::Piece(k), lo, hi)
        };
        let kept = |&(unit, _, _): &(OccluderUnit, DVec3, DVec3)| match unit {
            OccluderUnit::Piece(o) => candidate(o),
            OccluderUnit::Solid(_) => true,
        };
        // The cluster's units in the tree's order, each that the tree's search with this volume
        // would reach ([`ClusterCandidates`]).
        let listed = match shared {
            Some(shared) if pair.is_none() && shared.holds(p, own_face) => shared.units(self, face),
            _ => None,
        };
        let found: Box<dyn Iterator<Item = (OccluderUnit, DVec3, DVec3)>> = match (pair, listed) {
            (Some((_, list)), _) => Box::new(
                list.iter().copied().filter(|&k| volume.may_hold(&pieces[k])).map(with_box),
            ),
            (None, Some(units)) => Box::new(
                units
                    .iter()
                    .copied()
                    .filter(|&(_, lo, hi)| volume.may_hold_box(lo, hi))
                    .filter(kept),
            ),
            (None, None) => match self.occluders.units_reaching(&volume) {
                Some(units) => Box::new(units.filter(kept)),
                None => Box::new(self.occluders.inside(own_face, face, &volume).map(with_box)),
            },
        };
        let pyramid =
            Pyramid { apex: p, z, face: f, window: &window, corners: &corners, sides: &sides };
        let solids = &self.occluders.solids;
        // The piece of `unit` that hides the whole face, if one does.
        let mut cast = |unit: OccluderUnit| match unit {
            OccluderUnit::Piece(o) => {
                let solid = self.occluders.solid_for_view(o, own_face, face);
                pyramid
                    .cast_part(&pieces[o], solid, None, solids, || hides(o), &mut shadows)
                    .then_some(o)
            }
            OccluderUnit::Solid(s) => {
                let list = &self.occluders.solid_pieces[s];
                // Seen from or on one of its own faces, a solid casts piece by piece.
                let mut whole =
                    list.first().and_then(|&o| self.occluders.solid_for_view(o, own_face, face));
                for &o in list {
                    if !candidate(o) {
                        continue;
                    }
                    if pyramid.cast_part(&pieces[o], whole, None, solids, || hides(o), &mut shadows)
                    {
                        return Some(o);
                    }
                    match whole.and_then(|s| shadows.solid_cast(s)) {
                        // Cast whole: its other pieces cast nothing more.
                        Some(true) => return None,
                        // Not projectable whole: each piece casts its own.
                        Some(false) => whole = None,
                        None => {}
                    }
                }
                None
            }
        };
        // The first candidates in the search's order (most views end or are done there); the
        // rest of a large view (a sky over a city) nearest first: a near occluder's large shadow
        // holds the far ones' (which are then not kept), and one that hides the whole face ends
        // the view sooner.
        let mut found = found;
        let hider = match found.by_ref().take(IN_TREE_ORDER).find_map(|(u, _, _)| cast(u)) {
            Some(o) => Some(o),
            None => {
                let mut rest: Vec<(f64, OccluderUnit)> = found
                    .map(|(u, lo, hi)| ((lo - p).max(p - hi).max(DVec3::ZERO).length_squared(), u))
                    .collect();
                rest.sort_unstable_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
                rest.into_iter().find_map(|(_, u)| cast(u))
            }
        };
        if let Some(o) = hider {
            hiders.remember(o, &pieces[o]);
            return FaceView::Skip(SkipReason::Hidden);
        }
        FaceView::Visible { clip, shadows: shadows.into_shadows() }
    }

    /// The part of face `face` in front of the point `p` with unit normal `normal`: its height
    /// over the face's plane, the half-plane left by the point's tangent plane, and the visible
    /// window (`outline`, the face's hull or a convex part of it, clipped), in face coordinates
    /// and in space; or the view when nothing of it is in front.
    pub(super) fn window<'a>(
        &self,
        p: DVec3,
        Height { z, distance_bound }: Height,
        normal: DVec3,
        face: usize,
        outline: &'a [DVec2],
    ) -> Result<Window<'a>, FaceView> {
        let f = &self.faces[face];
        // On or behind the face's plane, up to the rounding of the height itself: G vanishes
        // there. (A node 1e-12 of the face's size above it still sees it, and K is then near its
        // limit, e.g. 1/2 beside a common edge, so no larger tolerance is right.) The distance's
        // square root is taken only where its bound leaves the decision open.
        let bound = (1.0 + 1e-12) * distance_bound;
        if z <= 0.0
            || (z <= HEIGHT_ROUNDING * bound
                && z <= HEIGHT_ROUNDING * (p - f.face.frame.origin).length())
        {
            return Err(FaceView::Skip(SkipReason::FacingAway));
        }
        // The node's tangent plane n·(Q - P) >= 0 restricted to the face's plane.
        let hp = HalfPlane {
            normal: DVec2::new(normal.dot(f.face.frame.e1), normal.dot(f.face.frame.e2)),
            offset: normal.dot(f.face.frame.origin - p),
        };
        let eps = PLANE_TOLERANCE * f.size;
        let (mut front, mut behind) = (false, false);
        for &q in outline {
            let v = hp.eval(q);
            front |= v > eps;
            behind |= v < -eps;
        }
        if !front {
            return Err(FaceView::Skip(SkipReason::FacingAway));
        }
        let clip = behind.then_some(hp);
        let polygon = match &clip {
            Some(hp) => match clip_convex(outline, hp) {
                Some(w) => Cow::Owned(w),
                None => return Err(FaceView::Skip(SkipReason::FacingAway)),
            },
            None => Cow::Borrowed(outline),
        };
        // Segments from p to the visible window lie in the pyramid with apex p over it, in front
        // of both faces.
        let corners = polygon.iter().map(|&w| f.face.frame.to_global(w)).collect();
        Ok(Window { z, clip, polygon, corners })
    }
}

/// What a point has in front of it of a face ([`PairPlanner::face_view`]).
pub(super) struct Window<'a> {
    /// The point's height over the face's plane.
    pub(super) z: f64,
    /// The half-plane in front of the point's tangent plane, when the face straddles it.
    pub(super) clip: Option<HalfPlane>,
    /// The outline (the face's hull, or an element of it), clipped (face coordinates; the outline
    /// itself where nothing is clipped).
    pub(super) polygon: Cow<'a, [DVec2]>,
    /// The same in space.
    pub(super) corners: SmallVec<[DVec3; 8]>,
}

/// The volume in which a view's candidate occluders are searched, planes that reject most boxes
/// of the index first: the pyramid's bounding box `(lo, hi)`, its `sides` (apex `p`, window
/// `corners`), the front of the two faces' `planes`, and the planes through a lateral edge
/// parallel to an axis.
fn view_volume(
    p: DVec3,
    corners: &[DVec3],
    sides: &[DVec3],
    (lo, hi): (DVec3, DVec3),
    planes: [&PlaneFrame; 2],
    tol: f64,
) -> ViewVolume {
    let mut volume = ViewVolume::default();
    volume.push_box(lo, hi, -tol);
    // A piece that reaches into the pyramid by less than the tolerance (the faces next to
    // the window, touching it along an edge) would shadow a sliver under the clipping's own
    // tolerance: it is no candidate.
    for side in sides {
        let unit = side.normalize_or_zero();
        if unit != DVec3::ZERO {
            volume.push(unit, -unit.dot(p), tol);
        }
    }
    for frame in planes {
        volume.push_front_of(frame, tol);
    }
    let m = corners.len();
    for (k, &c) in corners.iter().enumerate() {
        let edges = [corners[(k + 1) % m] - c, c - corners[(k + m - 1) % m]];
        for axis in [DVec3::X, DVec3::Y, DVec3::Z] {
            // Along an edge of the window, the plane is that edge's side (a plane of the
            // volume unless degenerate): leaving it out only widens the volume.
            if edges.iter().any(|e| e.cross(axis).length_squared() <= 1e-24 * e.length_squared()) {
                continue;
            }
            // Not normalised: the margin is the tolerance times the normal's 1-norm, no
            // less than its length, so the plane admits no fewer pieces than the unit one.
            let n = axis.cross(c - p);
            let side = |q: &DVec3| n.dot(*q - p);
            if n == DVec3::ZERO {
                continue;
            }
            let margin = -tol * n.abs().element_sum();
            if corners.iter().all(|q| side(q) >= 0.0) {
                volume.push(n, -n.dot(p), margin);
            } else if corners.iter().all(|q| side(q) <= 0.0) {
                volume.push(-n, n.dot(p), margin);
            }
        }
    }
    volume
}
