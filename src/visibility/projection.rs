//! Central projection onto a face: the pyramid over its window, the shadows, their 2-D helpers.

use glam::{DVec2, DVec3};
use smallvec::SmallVec;

use super::occluders::Occluder;
use super::planner::PlannerFace;
use super::solids::Solid;
use super::view::Shadows;
use crate::geometry::{
    HalfPlane, SmallPolygon, bounding_box, clip_polygon_3d, clip_to_convex, clip_to_half_planes,
    convex_contains, convex_hull, signed_area, wholly_inside_3d,
};

/// The segments from a point to the window of a face it sees
/// ([`PairPlanner::face_view`](super::PairPlanner::face_view)).
pub(super) struct Pyramid<'a> {
    pub(super) apex: DVec3,
    /// The apex's height over the face's plane.
    pub(super) z: f64,
    pub(super) face: &'a PlannerFace,
    /// The window in face coordinates and in space, and the inward normals of the sides.
    pub(super) window: &'a [DVec2],
    pub(super) corners: &'a [DVec3],
    pub(super) sides: &'a [DVec3],
}

impl Pyramid<'_> {
    /// Adds the shadow of `piece` on the window to `shadows`, unless a shadow there already
    /// holds it; returns whether the piece hides the whole window. `crosses_all` says whether it
    /// crosses every segment (asked only of a piece that reaches into the pyramid).
    fn cast(
        &self,
        piece: &Occluder,
        crosses_all: impl FnOnce() -> bool,
        shadows: &mut ShadowSet,
    ) -> bool {
        // Most candidates found by boxes miss the pyramid, and a separating plane shows it;
        // the crossing test is cheaper than the shadow, which also catches an occluder whose
        // outline meets the window's.
        if !piece.may_shadow(self.apex, self.corners) {
            return false;
        }
        let outline = self.projection(piece);
        if outline.as_deref().is_some_and(|o| shadows.holds(o)) {
            return false;
        }
        if crosses_all() {
            return true;
        }
        // The shadow is the projection's part in the window, where the projection is known: a
        // clip in the plane instead of the piece's clips in space.
        let shadow = match &outline {
            Some(outline) => in_window(outline, self.window),
            None => shadow(self.apex, self.z, self.face, self.window, self.sides, piece),
        };
        self.settle(outline, shadow, shadows)
    }

    /// Whether `shadow` (a part of the window, if any) covers the whole window; otherwise adds
    /// it to `shadows` (with its occluder's whole projection `outline`, if known).
    fn settle(
        &self,
        outline: Option<SmallPolygon<DVec2>>,
        shadow: Option<Vec<DVec2>>,
        shadows: &mut ShadowSet,
    ) -> bool {
        match shadow {
            Some(s) if covers(&s, self.window) => true,
            Some(s) => {
                shadows.add(outline, s);
                false
            }
            None => false,
        }
    }

    /// As [`Pyramid::cast`], for a piece that bounds the convex solid `solid` (an index
    /// into `solids`), if any: the first of the solid's pieces that may shadow the window casts
    /// the solid's whole shadow ([`Pyramid::cast_solid`]), and its other pieces cast nothing
    /// more; where the solid cannot be projected whole, each piece casts its own.
    /// `lowest`: the solid's [`lowest_height`] over the face's plane, where it is known.
    pub(super) fn cast_part(
        &self,
        piece: &Occluder,
        solid: Option<usize>,
        lowest: Option<f64>,
        solids: &[Solid],
        crosses_all: impl FnOnce() -> bool,
        shadows: &mut ShadowSet,
    ) -> bool {
        let Some(s) = solid else { return self.cast(piece, crosses_all, shadows) };
        match shadows.solids.iter().find(|&&(t, _)| t == s) {
            Some(&(_, true)) => return false,
            Some(&(_, false)) => return self.cast(piece, crosses_all, shadows),
            None => {}
        }
        match self.cast_solid(&solids[s], lowest, shadows) {
            Some(hidden) => {
                shadows.solids.push((s, true));
                hidden
            }
            None => {
                shadows.solids.push((s, false));
                self.cast(piece, crosses_all, shadows)
            }
        }
    }

    /// Adds the shadow of a whole convex solid to `shadows`, as [`Pyramid::cast`] adds a
    /// piece's, and returns whether it hides the whole window: the window's part in the
    /// solid's cone from the apex ([`Pyramid::cast_solid_cone`]); where the solid reaches
    /// behind the face's plane, its central projection, the convex hull of its vertices'
    /// projections, or where a vertex is not between the face's plane and the apex (as
    /// [`Pyramid::projection`] asks), the projection of its part in the pyramid
    /// ([`Pyramid::solid_in_pyramid`]). `None` where none of these can be found, or the hull
    /// has no area.
    fn cast_solid(
        &self,
        solid: &Solid,
        lowest: Option<f64>,
        shadows: &mut ShadowSet,
    ) -> Option<bool> {
        if let Some(hidden) = self.cast_solid_cone(solid, lowest, shadows) {
            return Some(hidden);
        }
        let Some(projected) = self.project::<SmallVec<[DVec2; 16]>>(&solid.vertices) else {
            return self.cast_solid_in_pyramid(solid, shadows);
        };
        let outline: SmallPolygon<DVec2> = convex_hull(&projected).into_iter().collect();
        if outline.len() < 3 || is_sliver(signed_area(&outline), polygon_scale(&outline)) {
            return None;
        }
        Some(self.cast_outline(outline, shadows))
    }

    /// [`Pyramid::cast_solid`] for a solid with no vertex behind the face's plane: its shadow
    /// is the window's part in the cone from the apex over the solid, bounded by the planes
    /// through the apex and the solid's silhouette edges (each between a plane that faces the
    /// apex and one that does not, or the cap, which never does). A segment from the apex to a
    /// point of the window meets the solid exactly where its direction lies in that cone: the
    /// solid's points on the ray lie no lower than the window's plane, so not past the window.
    /// Cheaper than a hull of projections, and the same for a solid taller than the apex.
    /// `None` where the solid reaches behind the plane, the apex lies within rounding of it,
    /// or a silhouette edge points at the apex (the other ways then decide).
    fn cast_solid_cone(
        &self,
        solid: &Solid,
        lowest: Option<f64>,
        shadows: &mut ShadowSet,
    ) -> Option<bool> {
        let frame = &self.face.face.frame;
        let tol = 1e-12 * solid.size;
        let lowest = lowest.unwrap_or_else(|| lowest_height(solid, frame));
        if solid.planes.len() > 32 || lowest < -1e-12 * (solid.size + self.z) {
            return None;
        }
        // The planes that face the apex, by more than rounding.
        let mut facing = 0u32;
        for (k, &(n, c)) in solid.planes.iter().enumerate() {
            facing |= u32::from(n.dot(self.apex) - c > tol) << k;
        }
        if facing == 0 {
            return None;
        }
        let faces_apex = |k: usize| facing >> k & 1 == 1;
        let mut half_planes: SmallVec<[HalfPlane; 8]> = SmallVec::new();
        for (&(a, b), &(p, q)) in solid.edges.iter().zip(&solid.edge_planes) {
            if faces_apex(p) == q.is_some_and(faces_apex) {
                continue;
            }
            let (xa, xb) = (solid.vertices[a] - self.apex, solid.vertices[b] - self.apex);
            let normal = xa.cross(xb);
            let inward = normal.dot(solid.centre - self.apex);
            let length2 = normal.length_squared();
            // Squared: |normal| <= 1e-9 |xa| |xb|, or the centre within 1e-9 of the size.
            if length2 <= 1e-18 * xa.length_squared() * xb.length_squared()
                || inward * inward <= 1e-18 * length2 * solid.size * solid.size
            {
                return None;
            }
            // The side with the solid, in face coordinates: n·(origin + u e1 + v e2 - apex) >= 0.
            let n = if inward > 0.0 { normal } else { -normal };
            half_planes.push(HalfPlane {
                normal: DVec2::new(n.dot(frame.e1), n.dot(frame.e2)),
                offset: n.dot(frame.origin - self.apex),
            });
        }
        if half_planes.len() < 3 {
            return None;
        }
        // A fifth of the solids cast over a city's element hide it whole: no clip for those.
        if half_planes.iter().all(|h| self.window.iter().all(|&w| h.eval(w) >= 0.0)) {
            return Some(true);
        }
        if half_planes.iter().any(|h| self.window.iter().all(|&w| h.eval(w) < 0.0)) {
            return Some(false);
        }
        let part = with_area(clip_to_half_planes(self.window, half_planes), self.window);
        Some(self.settle(None, part, shadows))
    }

    /// [`Pyramid::cast_solid`] for a solid that reaches past [`PROJECTION_REACH`] of the apex's
    /// height or behind the face's plane: its shadow is the projection of its part in the
    /// pyramid ([`Pyramid::solid_in_pyramid`]), which lies in the window. `None` where that
    /// cannot be found (the solid's pieces then cast their own shadows).
    fn cast_solid_in_pyramid(&self, solid: &Solid, shadows: &mut ShadowSet) -> Option<bool> {
        let outline = self.solid_in_pyramid(solid)?;
        let scale = polygon_scale(self.window);
        if outline.len() < 3 || is_sliver(signed_area(&outline), scale) {
            return Some(false);
        }
        Some(self.cast_outline(outline, shadows))
    }

    /// Adds the part in the window of a solid's convex `outline` to `shadows`, unless a shadow
    /// there already holds it; returns whether it covers the whole window.
    fn cast_outline(&self, outline: SmallPolygon<DVec2>, shadows: &mut ShadowSet) -> bool {
        if shadows.holds(&outline) {
            return false;
        }
        let shadow = in_window(&outline, self.window);
        self.settle(Some(outline), shadow, shadows)
    }

    /// The central projection onto the face's plane (face coordinates, counter-clockwise) of
    /// the part of the convex `solid` in the pyramid, the convex hull of the projections of its
    /// corners. Each corner of that part is a corner of the solid in the pyramid, or lies on a
    /// side of the solid where a side of the pyramid or the face's plane cuts it, or on an
    /// edge of the pyramid inside the solid: the ends of those segments' parts that lie in the
    /// other body are the points projected. A point on an edge from the apex projects to its
    /// corner of the window, and one on the window's outline is its own projection. `None`
    /// where the apex lies in the solid or within rounding of it or of the part, or where the
    /// solid or the pyramid has more planes or corners than [`MAX_PLANES`] and [`MAX_CORNERS`].
    fn solid_in_pyramid(&self, solid: &Solid) -> Option<SmallPolygon<DVec2>> {
        let (sides, planes) = (self.sides.len(), solid.planes.len());
        if sides + 1 > MAX_PLANES || planes > MAX_PLANES || solid.vertices.len() > MAX_CORNERS {
            return None;
        }
        let frame = &self.face.face.frame;
        let tol = 1e-12 * self.z.max(polygon_scale(self.window));
        // A point within rounding of a plane counts as on it, as [`clip_polygon_3d`] counts
        // it, by the solid's size (not the window's, so that the views of a face and of its
        // elements agree): the bodies grown by that much. Decided exactly, rounding would move
        // points on a side of the pyramid in and out of it from one point of an outer integral
        // to the next, and the shapes of the views with them, which costs that integral
        // evaluations.
        let grow = ON_PLANE * solid.size;
        let mut margins = [0.0; MAX_PLANES];
        for (m, s) in margins.iter_mut().zip(self.sides) {
            *m = grow * s.length();
        }
        // A point against the solid's planes (outward normals, n·x <= c inside).
        let against_solid = |x: DVec3| {
            let mut o = Outside::default();
            for (k, &(n, c)) in solid.planes.iter().enumerate() {
                o.set(k, n.dot(x) - c - grow);
            }
            o
        };
        let apex = against_solid(self.apex);
        if apex.values[..planes].iter().all(|&v| v <= tol) {
            return None;
        }
        // How far each corner of the solid lies outside each plane of the pyramid (its sides
        // through the apex, then the face's plane): <= 0 inside.
        let mut outside = [Outside::default(); MAX_CORNERS];
        let mut common = u32::MAX;
        for (o, &x) in outside.iter_mut().zip(&solid.vertices) {
            for (k, &s) in self.sides.iter().enumerate() {
                o.set(k, -s.dot(x - self.apex) - margins[k]);
            }
            o.set(sides, -frame.height(x) - grow);
            common &= o.mask;
        }
        // Wholly outside one plane of the pyramid: no part in it.
        if common != 0 {
            return Some(SmallPolygon::new());
        }
        let depth_of = |x: DVec3| Some(self.z - frame.height(x)).filter(|&d| d > tol);
        let project =
            |x: DVec3, depth: f64| frame.to_plane(self.apex + (x - self.apex) * (self.z / depth));
        let mut points: SmallVec<[DVec2; 32]> = SmallVec::new();
        for (&x, o) in solid.vertices.iter().zip(&outside) {
            if o.mask == 0 {
                points.push(project(x, depth_of(x)?));
            }
        }
        for &(a, b) in &solid.edges {
            let Some((t0, t1)) = outside[a].part_inside(&outside[b]) else { continue };
            let (xa, xb) = (solid.vertices[a], solid.vertices[b]);
            for t in [t0, t1].into_iter().filter(|&t| t > 0.0 && t < 1.0) {
                let x = xa + (xb - xa) * t;
                points.push(project(x, depth_of(x)?));
            }
        }
        // The pyramid's edges (from the apex, and the window's sides) against the solid.
        let m = self.window.len();
        let first = against_solid(self.corners[0]);
        let mut this = first;
        for k in 0..m {
            let next = if k + 1 < m { against_solid(self.corners[k + 1]) } else { first };
            if apex.part_inside(&this).is_some() {
                points.push(self.window[k]);
            }
            if let Some((t0, t1)) = this.part_inside(&next) {
                let (a, b) = (self.window[k], self.window[(k + 1) % m]);
                points.extend([a + (b - a) * t0, a + (b - a) * t1]);
            }
            this = next;
        }
        Some(convex_hull(&points).into_iter().collect())
    }

    /// The central projection of the whole of `piece` onto the face's plane (counter-clockwise,
    /// face coordinates), when every vertex lies between that plane and the apex, no more than
    /// [`PROJECTION_REACH`] of the way up (so the projection is convex and no more than ten
    /// times as far out as the piece); its part in the window is the piece's shadow.
    fn projection(&self, piece: &Occluder) -> Option<SmallPolygon<DVec2>> {
        let mut projected: SmallPolygon<DVec2> = self.project(&piece.polygon)?;
        let area = signed_area(&projected);
        let scale = polygon_scale(&projected);
        if is_sliver(area, scale) {
            return None;
        }
        if area < 0.0 {
            projected.reverse();
        }
        Some(projected)
    }

    /// The central projections of `points` onto the face's plane (face coordinates), when each
    /// lies between that plane and the apex, no more than [`PROJECTION_REACH`] of the way up.
    fn project<C: FromIterator<DVec2>>(&self, points: &[DVec3]) -> Option<C> {
        let frame = &self.face.face.frame;
        points
            .iter()
            .map(|&x| {
                let h = frame.height(x);
                (0.0..=PROJECTION_REACH * self.z).contains(&h).then(|| {
                    let t = self.z / (self.z - h);
                    frame.to_plane(self.apex + (x - self.apex) * t)
                })
            })
            .collect()
    }
}

/// Relative distance (of a solid's size) from a plane within which [`Pyramid::solid_in_pyramid`]
/// counts a point as on it.
const ON_PLANE: f64 = 1e-14;

/// Most planes of a solid, or of a pyramid with the face's plane, and most corners of a solid,
/// that [`Pyramid::solid_in_pyramid`] takes (a box has 6 planes and 8 corners; a window 3 to 5
/// sides): on the stack, without a heap allocation (it runs for every point of an outer
/// integral that a tall building shadows).
const MAX_PLANES: usize = 8;
const MAX_CORNERS: usize = 12;

/// The values of a set of affine functions at a point, <= 0 inside each, and the set of those
/// it lies outside of.
#[derive(Clone, Copy)]
struct Outside {
    values: [f64; MAX_PLANES],
    mask: u32,
}

impl Default for Outside {
    fn default() -> Self {
        Self { values: [0.0; MAX_PLANES], mask: 0 }
    }
}

impl Outside {
    fn set(&mut self, k: usize, value: f64) {
        self.values[k] = value;
        self.mask |= u32::from(value > 0.0) << k;
    }

    /// The parameters `[t0, t1]` of the part of the segment from this point to `end` inside
    /// every function, if any (Liang and Barsky's clip, over the functions either end lies
    /// outside of).
    fn part_inside(&self, end: &Outside) -> Option<(f64, f64)> {
        if self.mask & end.mask != 0 {
            return None;
        }
        let (mut lo, mut hi) = (0.0f64, 1.0f64);
        let mut planes = self.mask | end.mask;
        while planes != 0 {
            let k = planes.trailing_zeros() as usize;
            planes &= planes - 1;
            let (start, stop) = (self.values[k], end.values[k]);
            // One end outside, the other inside: the slope is not 0.
            let t = start / (start - stop);
            if start > 0.0 {
                lo = lo.max(t);
            } else {
                hi = hi.min(t);
            }
        }
        (lo <= hi).then_some((lo, hi))
    }
}

/// How far up from the face's plane towards the apex (as a fraction of the apex's height) an
/// occluder's vertices may lie for [`Pyramid::projection`].
const PROJECTION_REACH: f64 = 0.9;

/// The shadows of one view, each kept only while no other holds it: subtracting a shadow that
/// lies in another changes no visible part (in a city, most shadows on a face are those of a
/// building's far side, inside those of its near side).
#[derive(Default)]
pub(super) struct ShadowSet {
    /// The shadows kept, each with an outline that holds it ([`Cast`]).
    pub(super) casts: Vec<Cast>,
    /// The convex solids met so far, and whether each was cast whole.
    solids: SmallVec<[(usize, bool); 4]>,
}

/// A shadow with an outline that holds it: the whole projection of its occluder when known
/// (whose part in the window is the shadow), else the shadow itself; and the boxes that let
/// most containment tests end at four comparisons (a view over a large face, a sky over a
/// city, keeps hundreds of shadows, and each new one is tested against them all).
pub(super) struct Cast {
    outline: SmallPolygon<DVec2>,
    /// The outline's box, grown by [`convex_contains`]'s tolerance: a polygon that it holds
    /// lies in this box.
    reach: (DVec2, DVec2),
    shadow: Vec<DVec2>,
    shadow_box: (DVec2, DVec2),
}

/// Whether the box `inner` lies in the box `outer`.
fn box_inside((ilo, ihi): (DVec2, DVec2), (olo, ohi): (DVec2, DVec2)) -> bool {
    ilo.cmpge(olo).all() && ihi.cmple(ohi).all()
}

/// The box of `outline` grown beyond the tolerance of [`convex_contains`] (1e-13 of the
/// polygon's diagonal past each side, which reaches further out at a sharp corner: 1e-9 covers
/// corners down to 0.01 degrees).
fn reach_of(outline: &[DVec2]) -> (DVec2, DVec2) {
    let (lo, hi) = bounding_box(outline);
    let grow = DVec2::splat(1e-9 * (hi - lo).length());
    (lo - grow, hi + grow)
}

impl ShadowSet {
    /// Whether one of the outlines holds the convex `polygon` (boundary included, up to the
    /// rounding tolerance of [`convex_contains`]).
    fn holds(&self, polygon: &[DVec2]) -> bool {
        let bounds = bounding_box(polygon);
        self.casts
            .iter()
            .any(|c| box_inside(bounds, c.reach) && convex_contains(&c.outline, polygon))
    }

    /// Adds `shadow` (with its occluder's whole projection, if known) unless an outline holds
    /// it, and drops the shadows that its own outline holds.
    pub(super) fn add(&mut self, projection: Option<SmallPolygon<DVec2>>, shadow: Vec<DVec2>) {
        if self.holds(&shadow) {
            return;
        }
        let outline = projection.unwrap_or_else(|| shadow.iter().copied().collect());
        let reach = reach_of(&outline);
        self.casts
            .retain(|c| !(box_inside(c.shadow_box, reach) && convex_contains(&outline, &c.shadow)));
        let shadow_box = bounding_box(&shadow);
        self.casts.push(Cast { outline, reach, shadow, shadow_box });
    }

    /// Whether solid `s` was cast whole (`Some(true)`) or piece by piece (`Some(false)`), if it
    /// was the last solid met (a view that meets each solid once asks right after casting it).
    pub(super) fn solid_cast(&self, s: usize) -> Option<bool> {
        self.solids.last().filter(|&&(t, _)| t == s).map(|&(_, whole)| whole)
    }

    pub(super) fn into_shadows(self) -> Shadows {
        Shadows::with_boxes(self.casts.into_iter().map(|c| (c.shadow, c.shadow_box)))
    }
}

/// The height of `solid`'s lowest corner over the plane of `frame`.
pub(super) fn lowest_height(solid: &Solid, frame: &crate::geometry::PlaneFrame) -> f64 {
    solid.vertices.iter().map(|&x| frame.height(x)).fold(f64::INFINITY, f64::min)
}

pub(super) fn polygon_scale(poly: &[DVec2]) -> f64 {
    let (lo, hi) = bounding_box(poly);
    (hi - lo).length()
}

/// The inward normals (not normalised) of the planes through `p` and each edge of a convex window
/// (its `corners`, in space): the sides of the pyramid with apex `p` over the window.
pub(super) fn pyramid_sides(p: DVec3, corners: &[DVec3]) -> SmallVec<[DVec3; 8]> {
    let centre = corners.iter().sum::<DVec3>() / corners.len() as f64;
    let m = corners.len();
    (0..m)
        .map(|k| {
            let (a, b) = (corners[k], corners[(k + 1) % m]);
            let side = (a - p).cross(b - p);
            if side.dot(centre - p) < 0.0 { -side } else { side }
        })
        .collect()
}

/// The shadow on face `f` (at height `z` below `p`) of a convex occluder polygon, as seen from `p`
/// through the convex `window` of the face: the occluder clipped to the pyramid with apex `p` over
/// the window (its `sides`, [`pyramid_sides`]), centrally projected onto the face's plane.
pub(super) fn shadow(
    p: DVec3,
    z: f64,
    f: &PlannerFace,
    window: &[DVec2],
    sides: &[DVec3],
    occluder: &Occluder,
) -> Option<Vec<DVec2>> {
    if occluder.plane_holds(p) {
        // Seen edge-on from p: it blocks no segment from p (see Occluder::may_shadow).
        return None;
    }
    let normal = f.face.frame.normal;
    // Two buffers in turn, the last clip's result in `current` (none yet: the piece itself);
    // swapping them would copy both inline buffers at every clip.
    let mut buffers: [SmallPolygon<DVec3>; 2] = [SmallPolygon::new(), SmallPolygon::new()];
    let mut current: Option<usize> = None;
    // In front of the face's plane, inside the pyramid. Most planes leave the piece whole, and
    // the piece's own size bounds every tolerance of the clips: those are passed over.
    let planes = std::iter::once((normal, -normal.dot(f.face.frame.origin)))
        .chain(sides.iter().map(|&s| (s, -s.dot(p))));
    for (n, offset) in planes {
        let [first, second] = &mut buffers;
        let (poly, out): (&[DVec3], _) = match current {
            None => (&occluder.polygon, first),
            Some(0) => (first, second),
            Some(_) => (second, first),
        };
        if wholly_inside_3d(poly, n, offset, occluder.diameter) {
            continue;
        }
        if !clip_polygon_3d(poly, n, offset, out) {
            return None;
        }
        current = Some(current.map_or(0, |c| 1 - c));
    }
    let poly: &[DVec3] = match current {
        None => &occluder.polygon,
        Some(c) => &buffers[c],
    };
    // Central projection from p onto the face's plane: heights in (0, z] map to the plane.
    let mut projected: Vec<DVec2> = poly
        .iter()
        .map(|&x| {
            let t = z / (z - f.face.frame.height(x));
            f.face.frame.to_plane(p + (x - p) * t)
        })
        .collect();
    let area = signed_area(&projected);
    let scale = polygon_scale(window);
    if is_sliver(area, scale) {
        return None;
    }
    if area < 0.0 {
        projected.reverse();
    }
    Some(projected)
}

/// The part of the convex counter-clockwise `polygon` in the convex `window` (face
/// coordinates), if it has area as [`shadow`] decides it.
fn in_window(polygon: &[DVec2], window: &[DVec2]) -> Option<Vec<DVec2>> {
    with_area(clip_to_convex(polygon, window), window)
}

/// A `part` of the convex `window`, if it has area as [`shadow`] decides it.
fn with_area(part: Option<SmallPolygon<DVec2>>, window: &[DVec2]) -> Option<Vec<DVec2>> {
    let part = part?;
    let area = signed_area(&part);
    (area > 0.0 && !is_sliver(area, polygon_scale(window))).then(|| part.into_vec())
}

/// Whether a projected polygon's (signed) `area`, measured against a size `scale` (its window's,
/// or its own), is no area at all: not finite, or within 1e-14 of the square of the size (a
/// sliver, or an occluder seen edge-on).
fn is_sliver(area: f64, scale: f64) -> bool {
    area.abs() <= 1e-14 * scale * scale || !area.is_finite()
}

/// Whether the convex counter-clockwise `shadow` contains every point of `window`, up to rounding
/// (shadows are clipped to the window, so a covering shadow has the window's outline).
fn covers(shadow: &[DVec2], window: &[DVec2]) -> bool {
    let scale = polygon_scale(shadow);
    let m = shadow.len();
    (0..m).all(|k| {
        let (a, b) = (shadow[k], shadow[(k + 1) % m]);
        let edge = b - a;
        let margin = 1e-12 * scale * edge.length();
        window.iter().all(|&w| edge.perp_dot(w - a) >= -margin)
    })
}
