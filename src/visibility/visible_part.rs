//! What a view shows of an element: its exactly visible part ([`PairPlanner::visible`]), the
//! element clipped by the tangent plane's half-plane minus each shadow, as disjoint convex
//! pieces; the same answer for a whole run of elements from their box where the box alone tells
//! ([`PairPlanner::visible_in_box`]); and a face as convex parts and their visible pieces.

use glam::DVec2;

use super::face_view::PLANE_TOLERANCE;
use super::planner::PairPlanner;
use super::view::{FaceView, SkipReason, Visibility};
use crate::geometry::{
    HalfPlane, bounding_box, boxes_overlap, clip_convex, convex_apart, convex_contains,
    subtract_convex,
};

/// The square of the tolerance within which a polygon in the box `(lo, hi)` counts as on the
/// line of the tangent plane's clip `hp`: PLANE_TOLERANCE times the box's diagonal times
/// |normal|, compared as squares (no square roots for every element of a face). It grows with
/// the box, so a box's test bounds those of the polygons inside it.
fn clip_tolerance_squared(hp: &HalfPlane, (lo, hi): (DVec2, DVec2)) -> f64 {
    PLANE_TOLERANCE.powi(2) * (hi - lo).length_squared() * hp.normal.length_squared()
}

impl PairPlanner {
    /// What `view` shows of every convex polygon inside the box `(lo, hi)` (face coordinates),
    /// where the box alone tells and it is the same for all: nothing where the box lies behind
    /// the tangent plane's clip or inside one shadow, the whole polygon where the box is clear
    /// of both the clip (past its tolerance) and every shadow's box; `None` otherwise. Where it
    /// answers, [`PairPlanner::visible`] answers the same for each polygon in the box: its
    /// tests are linear in the points (a polygon's are convex combinations of the box's
    /// corners) and its tolerance grows with the polygon's size, which the box bounds.
    pub fn visible_in_box(&self, view: &FaceView, (lo, hi): (DVec2, DVec2)) -> Option<Visibility> {
        let (clip, shadows) = match view {
            FaceView::Skip(reason) => return Some(Visibility::Skip(*reason)),
            FaceView::Visible { clip, shadows } => (clip, shadows),
        };
        let corners = [lo, DVec2::new(hi.x, lo.y), hi, DVec2::new(lo.x, hi.y)];
        if let Some(hp) = clip {
            let eps2 = clip_tolerance_squared(hp, (lo, hi));
            let values = corners.map(|q| hp.eval(q));
            if values.iter().all(|&v| v <= 0.0) {
                return Some(Visibility::Skip(SkipReason::FacingAway));
            }
            if !values.iter().all(|&v| v > 0.0 && v * v > eps2) {
                return None;
            }
        }
        let mut clear = true;
        for (s, &shadow_box) in shadows.iter().zip(shadows.boxes()) {
            if boxes_overlap((lo, hi), shadow_box) {
                if convex_contains(s, &corners) {
                    return Some(Visibility::Skip(SkipReason::Hidden));
                }
                clear = false;
            }
        }
        clear.then_some(Visibility::Full)
    }

    /// The visible part of a convex counter-clockwise polygon `poly` (face coordinates) under `view`.
    pub fn visible(&self, view: &FaceView, poly: &[DVec2]) -> Visibility {
        let (clip, shadows) = match view {
            FaceView::Skip(reason) => return Visibility::Skip(*reason),
            FaceView::Visible { clip, shadows } => (clip, shadows),
        };
        let poly_box = bounding_box(poly);
        let clipped = match clip {
            Some(hp) => {
                let eps2 = clip_tolerance_squared(hp, poly_box);
                let within = |v: f64| v <= 0.0 || v * v <= eps2;
                let below = |v: f64| v < 0.0 && v * v > eps2;
                if poly.iter().all(|&q| within(hp.eval(q))) {
                    return Visibility::Skip(SkipReason::FacingAway);
                }
                if poly.iter().any(|&q| below(hp.eval(q))) {
                    match clip_convex(poly, hp) {
                        Some(c) => Some(c),
                        None => return Visibility::Skip(SkipReason::FacingAway),
                    }
                } else {
                    None
                }
            }
            None => None,
        };
        // Most elements of a face seen in part are seen whole or not at all: while the shadows
        // leave the one piece as it is, nothing is allocated.
        let one = clipped.as_deref().unwrap_or(poly);
        let (lo, hi) = clipped.as_deref().map_or(poly_box, bounding_box);
        let mut shadows = shadows.iter().zip(shadows.boxes());
        let mut cut = None;
        for (s, &shadow_box) in shadows.by_ref() {
            if !boxes_overlap((lo, hi), shadow_box) || convex_apart(one, s) {
                continue;
            }
            if convex_contains(s, one) {
                return Visibility::Skip(SkipReason::Hidden);
            }
            let parts = subtract_convex(one, s);
            if parts.is_empty() {
                return Visibility::Skip(SkipReason::Hidden);
            }
            if parts.len() != 1 || parts[0] != one {
                cut = Some(parts);
                break;
            }
        }
        let Some(mut pieces) = cut else {
            return match clipped {
                Some(c) => Visibility::Partial(vec![c]),
                None => Visibility::Full,
            };
        };
        let mut next = Vec::with_capacity(pieces.len());
        for (s, &shadow_box) in shadows {
            for piece in pieces.drain(..) {
                if !boxes_overlap(bounding_box(&piece), shadow_box) || convex_apart(&piece, s) {
                    next.push(piece);
                    continue;
                }
                // A piece inside the shadow (every vertex, boundary included) is gone without
                // cutting it along each of the shadow's edges.
                if convex_contains(s, &piece) {
                    continue;
                }
                next.extend(subtract_convex(&piece, s));
            }
            std::mem::swap(&mut pieces, &mut next);
            if pieces.is_empty() {
                return Visibility::Skip(SkipReason::Hidden);
            }
        }
        Visibility::Partial(pieces)
    }

    /// The face `face` as convex pieces (face coordinates, counter-clockwise): itself when it is
    /// convex, else its triangles.
    pub fn convex_parts(&self, face: usize) -> Vec<Vec<DVec2>> {
        let f = &self.faces[face];
        if f.hull.len() == f.polygon.len() {
            return vec![f.polygon.clone()];
        }
        crate::geometry::triangulate(&f.polygon)
            .expect(crate::scene::TRIANGULABLE)
            .into_iter()
            .map(|t| t.map(|k| f.polygon[k]).to_vec())
            .collect()
    }

    /// The visible part of the whole face `face` under `view`: convex pieces in face
    /// coordinates, or an empty list.
    pub fn visible_part_of_face(&self, view: &FaceView, face: usize) -> Vec<Vec<DVec2>> {
        self.convex_parts(face)
            .into_iter()
            .flat_map(|part| match self.visible(view, &part) {
                Visibility::Skip(_) => vec![],
                Visibility::Full => vec![part],
                Visibility::Partial(pieces) => pieces,
            })
            .collect()
    }
}
