//! The pair plan (ARCHITECTURE.md): for every (collocation node, element) pair, decide once what the
//! collocation integral (4.1) needs: nothing, the whole element, or the exactly visible part.
//!
//! Work is organised per (node, face): the node's [`FaceView`] of a face holds the half-plane left
//! by the node's tangent plane (when the face straddles it) and the shadows of the occluders that
//! can lie between the node's face and this one, centrally projected from the node onto the face's
//! plane. Each element of the face is then classified against the view ([`PairPlanner::visible`]),
//! or a run of them at once by their box ([`PairPlanner::visible_in_box`]): no clip and no shadow
//! means every element is fully visible, without per-element work.
//!
//! Shadows are convex (occluders are split into convex pieces; a convex solid among them casts
//! one shadow, the window's part in its cone from the node), and the visible part of an element
//! is the element clipped by the half-plane minus each shadow, kept as disjoint convex pieces: exact
//! up to rounding (paper sec. 2.7: any O(h) error here destroys the convergence rates). A view keeps
//! no shadow that another of its shadows holds (a building's far side behind its near side), which
//! changes no visible part.
//! Candidate occluders of a view are those that may reach into the pyramid with apex at the node
//! over the face's visible window, in front of both faces. Scenes of more than 512 faces find
//! them in an R*-tree over the occluders' bounding boxes; smaller ones filter a table of the
//! occluders between each pair of faces (built with the tree). A face covered by one shadow is
//! hidden, and the search stops. So a scene in which no face can come between two others never
//! runs shadow code, and a scene of thousands of faces does not test every occluder for every
//! pair ([`Acceleration`]).

mod hiders;
mod occluders;
mod projection;
mod row;
mod shaft;
mod solids;
mod stats;

use hiders::Hider;
pub use hiders::RecentHiders;
use occluders::ViewVolume;
pub use occluders::{Acceleration, Occluder, OccluderUnit};
use projection::{Pyramid, ShadowSet, lowest_height, pyramid_sides, shadow};
pub use row::{ElementBoxes, FaceSight, KeptViews, PartSight, Viewer, Views, by_face};
pub use shaft::Shaft;
pub use stats::PairStats;

use std::borrow::Cow;

use glam::{DVec2, DVec3};
use smallvec::SmallVec;

use crate::geometry::{
    HalfPlane, PlaneFrame, bounding_box, boxes_overlap, clip_convex, convex_apart, convex_contains,
    convex_hull, subtract_convex,
};
use crate::scene::{COPLANAR_DISTANCE, Scene};

/// Why a pair contributes nothing.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SkipReason {
    /// The node and the element lie in one plane: G = 0.
    SamePlane,
    /// The element is behind the node's tangent plane or the node behind the element: G <= 0.
    FacingAway,
    /// Occluders hide the whole element.
    Hidden,
    /// The node's face reflects nothing (rho = 0): its row of K is zero, u = E there.
    NotReflecting,
}

/// What a node sees of one face.
#[derive(Clone, Debug, PartialEq)]
pub enum FaceView {
    /// Nothing of the face.
    Skip(SkipReason),
    /// The face is in front of the node; parts may be clipped or shadowed.
    Visible {
        /// Half-plane (face coordinates) in front of the node's tangent plane, when the face
        /// straddles that plane.
        clip: Option<HalfPlane>,
        /// Convex shadows (face coordinates, counter-clockwise) of the occluders.
        shadows: Shadows,
    },
}

/// The convex shadows of a view (face coordinates, counter-clockwise), each with its bounding
/// box: a view serves every element of its face, and each element is tested against every
/// shadow's box first.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Shadows {
    polygons: Vec<Vec<DVec2>>,
    boxes: Vec<(DVec2, DVec2)>,
}

impl Shadows {
    /// Shadows with their boxes measured.
    pub fn new(polygons: Vec<Vec<DVec2>>) -> Self {
        let boxes = polygons.iter().map(|s| bounding_box(s)).collect();
        Self { polygons, boxes }
    }

    /// Shadows whose boxes are known.
    pub(super) fn with_boxes(shadows: impl Iterator<Item = (Vec<DVec2>, (DVec2, DVec2))>) -> Self {
        let (polygons, boxes) = shadows.unzip();
        Self { polygons, boxes }
    }

    /// Each shadow's bounding box, in order.
    pub fn boxes(&self) -> &[(DVec2, DVec2)] {
        &self.boxes
    }

    /// The polygons alone.
    pub fn into_polygons(self) -> Vec<Vec<DVec2>> {
        self.polygons
    }
}

impl std::ops::Deref for Shadows {
    type Target = [Vec<DVec2>];

    fn deref(&self) -> &[Vec<DVec2>] {
        &self.polygons
    }
}

impl FaceView {
    /// Whether every element of the face is fully visible.
    pub fn is_unobstructed(&self) -> bool {
        matches!(self, Self::Visible { clip: None, shadows } if shadows.is_empty())
    }
}

/// The visible part of a convex polygon (an element) under a [`FaceView`].
#[derive(Clone, Debug, PartialEq)]
pub enum Visibility {
    /// Nothing is visible, for the given reason.
    Skip(SkipReason),
    /// All of it.
    Full,
    /// Disjoint convex pieces, counter-clockwise, in face coordinates.
    Partial(Vec<Vec<DVec2>>),
}

/// Relative tolerance for "on the line" decisions when clipping by a tangent plane (no slivers).
const PLANE_TOLERANCE: f64 = 1e-12;

/// The square of the tolerance within which a polygon in the box `(lo, hi)` counts as on the
/// line of the tangent plane's clip `hp`: PLANE_TOLERANCE times the box's diagonal times
/// |normal|, compared as squares (no square roots for every element of a face). It grows with
/// the box, so a box's test bounds those of the polygons inside it.
fn clip_tolerance_squared(hp: &HalfPlane, (lo, hi): (DVec2, DVec2)) -> f64 {
    PLANE_TOLERANCE.powi(2) * (hi - lo).length_squared() * hp.normal.length_squared()
}

/// A point's height above a plane is known to within this many ulps of its distance from the
/// plane's origin.
const HEIGHT_ROUNDING: f64 = 8.0 * f64::EPSILON;

/// Decides visibility for a scene; built once per scene.
#[derive(Clone, Debug)]
pub struct PairPlanner {
    faces: Vec<PlannerFace>,
    occluders: occluders::OccluderIndex,
    /// For scenes of at most [`PAIR_TABLE_FACES`] faces, per ordered pair of faces (a * F + b):
    /// whether they are coplanar, and the occluders that may lie between them, so that a view
    /// only filters a short list.
    pairs: Option<Vec<(bool, Vec<usize>)>>,
}

/// Largest scene whose pairs of faces are tabulated (512² entries).
const PAIR_TABLE_FACES: usize = 512;

/// Candidate occluders of a view taken in the search's order before the rest are sorted nearest
/// first ([`PairPlanner::face_view_with`]).
const IN_TREE_ORDER: usize = 16;

#[derive(Clone, Debug)]
struct PlannerFace {
    face: crate::scene::Face,
    polygon: Vec<DVec2>,
    hull: Vec<DVec2>,
    size: f64,
    lo: DVec3,
    hi: DVec3,
}

impl PairPlanner {
    /// Prepares the occluders of `scene` and their index.
    pub fn new(scene: &Scene) -> Self {
        Self::with_acceleration(scene, Acceleration::default())
    }

    /// As [`PairPlanner::new`], choosing how candidate occluders are found (the views are the
    /// same either way; only the time differs).
    pub fn with_acceleration(scene: &Scene, acceleration: Acceleration) -> Self {
        let faces = scene
            .faces
            .iter()
            .map(|f| {
                let polygon = f.local_polygon();
                let (lo, hi) = f.bounding_box();
                PlannerFace {
                    face: f.clone(),
                    hull: convex_hull(&polygon).into_vec(),
                    polygon,
                    size: f.size(),
                    lo,
                    hi,
                }
            })
            .collect();
        let mut planner = Self {
            faces,
            occluders: occluders::OccluderIndex::new(scene, acceleration),
            pairs: None,
        };
        let n = planner.faces.len();
        if n <= PAIR_TABLE_FACES && acceleration == Acceleration::Tree {
            let table = (0..n * n)
                .map(|k| {
                    let (a, b) = (k / n, k % n);
                    let coplanar = planner.same_plane(a, b);
                    (coplanar, if coplanar { Vec::new() } else { planner.occluders_between(a, b) })
                })
                .collect();
            planner.pairs = Some(table);
        }
        planner
    }

    /// Whether any pair of faces can have an occluder between them (one query per pair of faces).
    pub fn has_occlusion(&self) -> bool {
        let n = self.faces.len();
        (0..n).any(|a| (0..n).any(|b| a != b && !self.candidates(a, b).is_empty()))
    }

    /// Occluders that may lie between faces `a` and `b` (none for one face or one plane).
    pub fn candidates(&self, a: usize, b: usize) -> Vec<usize> {
        if self.same_plane(a, b) { Vec::new() } else { self.occluders_between(a, b) }
    }

    /// Whether faces `a` and `b` are one face or lie in one plane ([`crate::scene::Face::is_coplanar_with`],
    /// with the sizes measured once for the planner).
    pub fn same_plane(&self, a: usize, b: usize) -> bool {
        let (fa, fb) = (&self.faces[a], &self.faces[b]);
        a == b || fa.face.is_coplanar_at_size(&fb.face, || fa.size.max(fb.size))
    }

    /// The height of `p` over the plane of `face`, with a bound of its distance from the plane's
    /// origin (the sum of the coordinates' sizes: no square root) for the height's rounding.
    fn height(&self, p: DVec3, face: usize) -> Height {
        let frame = &self.faces[face].face.frame;
        Height { z: frame.height(p), distance_bound: (p - frame.origin).abs().element_sum() }
    }

    /// [`PairPlanner::same_plane`] for a point of face `own_face` at height `h` over the plane
    /// of `face`: the height of a point of a face is an average of its vertices' heights, all
    /// within the coplanarity tolerance of a face in its plane, so a larger height (beyond
    /// twice that tolerance and the height's rounding) decides it without measuring the faces.
    fn same_plane_seen_from(&self, h: Height, own_face: usize, face: usize) -> bool {
        let (own, f) = (&self.faces[own_face], &self.faces[face]);
        let rounding = HEIGHT_ROUNDING * h.distance_bound;
        let reach = 2.0 * COPLANAR_DISTANCE * own.size.max(f.size) + rounding;
        h.z.abs() <= reach && self.same_plane(own_face, face)
    }

    /// The tolerance of the planes and segments between faces `a` and `b` (shafts, view
    /// volumes, occluders crossing segments): 1e-12 of the larger face's size.
    fn pair_tolerance(&self, a: usize, b: usize) -> f64 {
        1e-12 * self.faces[a].size.max(self.faces[b].size)
    }

    /// Occluders in the box of faces `a` and `b` and in front of both, in index order.
    fn occluders_between(&self, a: usize, b: usize) -> Vec<usize> {
        let (fa, fb) = (&self.faces[a], &self.faces[b]);
        let tol = self.pair_tolerance(a, b);
        let mut volume = ViewVolume::between(&fa.face.frame, &fb.face.frame, tol);
        volume.push_box(fa.lo.min(fb.lo), fa.hi.max(fb.hi), tol);
        let mut found: Vec<usize> = self.occluders.inside(a, b, &volume).collect();
        found.sort_unstable();
        found
    }

    /// The convex occluder pieces of the scene.
    pub fn occluders(&self) -> &[Occluder] {
        &self.occluders.pieces
    }

    /// Why the point `p` on face `own_face` sees nothing of face `face`, where the planes alone
    /// tell: the two faces share a plane, or `p` is on or behind `face`'s plane. Most faces
    /// met by a node of a compressed operator's exact blocks are such (41 of 61 million views
    /// on city:20x20:lit at refine 1); [`PairPlanner::face_view`] gives the same skip.
    pub fn plane_skip_of(&self, p: DVec3, own_face: usize, face: usize) -> Option<SkipReason> {
        self.plane_skip(self.height(p, face), own_face, face)
    }

    /// [`PairPlanner::plane_skip_of`] for a point at height `h` over `face`'s plane.
    fn plane_skip(&self, h: Height, own_face: usize, face: usize) -> Option<SkipReason> {
        let coplanar = match &self.pairs {
            Some(table) => table[own_face * self.faces.len() + face].0,
            None => self.same_plane_seen_from(h, own_face, face),
        };
        if coplanar {
            Some(SkipReason::SamePlane)
        } else {
            (h.z <= 0.0).then_some(SkipReason::FacingAway)
        }
    }

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
        let found: Box<dyn Iterator<Item = (OccluderUnit, DVec3, DVec3)>> =
            match (pair, self.occluders.units_reaching(&volume)) {
                (Some((_, list)), _) => Box::new(
                    list.iter().copied().filter(|&k| volume.may_hold(&pieces[k])).map(with_box),
                ),
                (None, Some(units)) => Box::new(units.filter(|&(unit, _, _)| match unit {
                    OccluderUnit::Piece(o) => candidate(o),
                    OccluderUnit::Solid(_) => true,
                })),
                (None, None) => {
                    Box::new(self.occluders.inside(own_face, face, &volume).map(with_box))
                }
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
    fn window<'a>(
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

/// A point's height over a face's plane ([`PairPlanner::height`]).
#[derive(Clone, Copy)]
struct Height {
    z: f64,
    /// At least the point's distance from the plane's origin.
    distance_bound: f64,
}

/// What a point has in front of it of a face ([`PairPlanner::face_view`]).
struct Window<'a> {
    /// The point's height over the face's plane.
    z: f64,
    /// The half-plane in front of the point's tangent plane, when the face straddles it.
    clip: Option<HalfPlane>,
    /// The outline (the face's hull, or an element of it), clipped (face coordinates; the outline
    /// itself where nothing is clipped).
    polygon: Cow<'a, [DVec2]>,
    /// The same in space.
    corners: SmallVec<[DVec3; 8]>,
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

/// An occluder piece as it casts between two faces ([`PairPlanner::casters`]): with the convex
/// solid it bounds, if that solid may occlude between them (it casts its shadow whole), and
/// the height of the solid's lowest corner over the second face's plane (the same for every
/// point that casts it there).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Caster {
    piece: usize,
    solid: Option<(usize, f64)>,
}

#[cfg(test)]
mod tests;
