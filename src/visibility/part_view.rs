//! A node's view of a part of a face when the occluders that can come between them are known
//! (a shaft's candidates, [`super::Shaft`]): the [`Caster`]s found once per pair of faces, and
//! [`PairPlanner::part_view_among`], which casts only those, without any search.

use glam::{DVec2, DVec3};

use super::face_view::Window;
use super::planner::PairPlanner;
use super::projection::{Pyramid, ShadowSet, lowest_height, pyramid_sides};
use super::view::{FaceView, Shadows, SkipReason};

impl PairPlanner {
    /// The convex solid that occluder piece `piece` bounds, where that solid may occlude
    /// between faces `own_face` and `face` (it has neither as a face).
    pub fn solid_between(&self, piece: usize, own_face: usize, face: usize) -> Option<usize> {
        self.occluders.solid_for_view(piece, own_face, face)
    }

    /// The occluder pieces `candidates` as they cast shadows between faces `own_face` and
    /// `face`, each with the convex solid it bounds where that solid may occlude between them:
    /// found once for the many points of a piece that [`PairPlanner::part_view_among`] takes.
    pub fn casters(&self, own_face: usize, face: usize, candidates: &[usize]) -> Vec<Caster> {
        candidates
            .iter()
            .map(|&piece| Caster {
                piece,
                solid: self.solid_between(piece, own_face, face).map(|s| {
                    (s, lowest_height(&self.occluders.solids[s], &self.faces[face].face.frame))
                }),
            })
            .collect()
    }

    /// What the point `p` (normal `normal`, on face `own_face`) sees of `part`, a convex
    /// counter-clockwise part of face `face` (face coordinates: an element, or the face's hull),
    /// when the occluders that can come between `p` and it are known: only `candidates` cast
    /// shadows (pieces of neither face, a superset of those meeting a segment from `p` to
    /// `part`, e.g. [`PairPlanner::polygon_shaft`]'s, as [`PairPlanner::casters`] gives them),
    /// clipped to `part`, and one that covers it hides it. [`PairPlanner::visible`] then gives
    /// the same visible part of `part` as with [`PairPlanner::face_view`], without any search.
    pub fn part_view_among(
        &self,
        p: DVec3,
        normal: DVec3,
        own_face: usize,
        face: usize,
        part: &[DVec2],
        candidates: &[Caster],
    ) -> FaceView {
        let h = self.height(p, face);
        if self.same_plane_seen_from(h, own_face, face) {
            return FaceView::Skip(SkipReason::SamePlane);
        }
        let Window { z, clip, polygon: window, corners } =
            match self.window(p, h, normal, face, part) {
                Ok(window) => window,
                Err(view) => return view,
            };
        if candidates.is_empty() {
            return FaceView::Visible { clip, shadows: Shadows::default() };
        }
        let f = &self.faces[face];
        let tol = self.pair_tolerance(own_face, face);
        let sides = pyramid_sides(p, &corners);
        let pyramid =
            Pyramid { apex: p, z, face: f, window: &window, corners: &corners, sides: &sides };
        let mut shadows = ShadowSet::default();
        for &Caster { piece: o, solid } in candidates {
            let piece = &self.occluders.pieces[o];
            let crosses_all = || piece.crosses_every_segment(&[p], &corners, tol, -tol);
            let (solid, lowest) = (solid.map(|(s, _)| s), solid.map(|(_, h)| h));
            let solids = &self.occluders.solids;
            if pyramid.cast_part(piece, solid, lowest, solids, crosses_all, &mut shadows) {
                return FaceView::Skip(SkipReason::Hidden);
            }
        }
        FaceView::Visible { clip, shadows: shadows.into_shadows() }
    }
}

/// An occluder piece as it casts between two faces ([`PairPlanner::casters`]): with the convex
/// solid it bounds, if that solid may occlude between them (it casts its shadow whole), and
/// the height of the solid's lowest corner over the second face's plane (the same for every
/// point that casts it there).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Caster {
    piece: usize,
    solid: Option<(usize, f64)>,
}
