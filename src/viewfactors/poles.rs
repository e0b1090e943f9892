//! The poles of a piece's integrand: the planes where a corner of the visible part of T_j, made by
//! an occluder's shadow, runs off to infinity. Their distance bounds the Gauss order a patch needs.

use glam::{DVec2, DVec3};
use smallvec::SmallVec;

use crate::geometry::PlaneFrame;
use crate::visibility::PairPlanner;

/// Where the integrand over a piece of T_i (unit normal `ni`, a point `viewer` inside it) stops
/// being analytic, besides T_j (frame `frame_j`, vertices `target`): a corner of the visible
/// part of T_j that is the shadow of an occluder vertex runs off to infinity where the viewer is
/// level with that vertex (over T_j's plane), and one where a shadow edge cuts an edge of T_j
/// where the two become parallel. Each happens on a plane, so on a line of T_i's plane; a piece
/// that such a line crosses does not have that corner (it would cross an event plane first).
/// Only the corners the piece has count: whether a vertex's shadow falls in T_j, or a shadow
/// edge's line cuts an edge of T_j within both, changes only across the event planes the piece
/// was cut along, so it is decided at `viewer` (a corner within rounding of existing counts).
/// Returns each plane's unit normal, a point and the sine of its angle with T_i's plane.
pub(super) fn poles(
    ni: DVec3,
    viewer: DVec3,
    frame_j: &PlaneFrame,
    target: &[DVec3; 3],
    occluders: &[usize],
    planner: &PairPlanner,
) -> Vec<(DVec3, DVec3, f64)> {
    let mut poles: Vec<(DVec3, DVec3, f64)> = Vec::new();
    let mut pole = |normal: DVec3, point: DVec3| {
        if let Some(m) = normal.try_normalize() {
            // Distances in T_i's plane: heights over the pole's plane over this sine.
            let sin = (m - ni * m.dot(ni)).length();
            if sin > 1e-9 {
                poles.push((m, point, sin));
            }
        }
    };
    let seen = ShadowCorners::new(viewer, frame_j, target);
    for &o in occluders {
        let polygon = &planner.occluders()[o].polygon;
        let m = polygon.len();
        let shadows: SmallVec<[Option<DVec2>; 8]> =
            polygon.iter().map(|&v| seen.shadow(v)).collect();
        for k in 0..m {
            if seen.vertex_corner(shadows[k]) {
                pole(frame_j.normal, polygon[k]);
            }
            let edge = polygon[(k + 1) % m] - polygon[k];
            for l in 0..3 {
                if seen.edge_corner(shadows[k], shadows[(k + 1) % m], l) {
                    pole(edge.cross(target[(l + 1) % 3] - target[l]), polygon[k]);
                }
            }
        }
    }
    poles
}

/// The shadows that occluder vertices cast on T_j's plane from one viewing point, in T_j's
/// local coordinates, and which corners of the visible part of T_j they can make.
struct ShadowCorners {
    viewer: DVec3,
    /// The viewer's height over T_j's plane.
    height: f64,
    frame: PlaneFrame,
    /// T_j's corners in its plane.
    corners: [DVec2; 3],
    /// The sign of T_j's orientation in its plane's coordinates.
    orientation: f64,
    /// How far outside T_j a shadow corner still counts, as a side's cross product: each is
    /// the side's length times the distance from it, so T_j's size squared times the margin.
    margin: f64,
}

/// Within this fraction of T_j's size (or of a segment's length) a shadow corner counts as on
/// T_j: a corner that rounding puts just outside keeps its pole.
const CORNER_MARGIN: f64 = 1e-6;

impl ShadowCorners {
    fn new(viewer: DVec3, frame: &PlaneFrame, target: &[DVec3; 3]) -> Self {
        let corners = target.map(|v| frame.to_local(v).truncate());
        let [a, b, c] = corners;
        let size = (b - a).length().max((c - b).length()).max((a - c).length());
        Self {
            viewer,
            height: frame.height(viewer),
            frame: *frame,
            corners,
            orientation: (b - a).perp_dot(c - a).signum(),
            margin: CORNER_MARGIN * size * size,
        }
    }

    /// Where `v` casts its shadow on T_j's plane, if it lies strictly between the viewer and
    /// that plane (otherwise its shadow is at infinity or behind: unknown, so every corner of it
    /// counts).
    fn shadow(&self, v: DVec3) -> Option<DVec2> {
        let h = self.frame.height(v);
        (h > 0.0 && h < self.height).then(|| {
            let p = self.viewer + (v - self.viewer) * (self.height / (self.height - h));
            self.frame.to_local(p).truncate()
        })
    }

    /// Whether a vertex with this shadow can be a corner of the visible part: its shadow falls
    /// in T_j.
    fn vertex_corner(&self, shadow: Option<DVec2>) -> bool {
        let Some(p) = shadow else { return true };
        let [a, b, c] = self.corners;
        let side = |u: DVec2, w: DVec2| (w - u).perp_dot(p - u) * self.orientation;
        side(a, b) >= -self.margin && side(b, c) >= -self.margin && side(c, a) >= -self.margin
    }

    /// Whether the shadow of the edge between vertices with these shadows can cut T_j's edge
    /// `l` (from corner `l` to `l + 1`): the two segments meet.
    fn edge_corner(&self, from: Option<DVec2>, to: Option<DVec2>, l: usize) -> bool {
        let (Some(p), Some(q)) = (from, to) else { return true };
        let (a, b) = (self.corners[l], self.corners[(l + 1) % 3]);
        let (d, e) = (q - p, b - a);
        let det = d.perp_dot(e);
        if det.abs() <= 1e-12 * d.length() * e.length() {
            return true; // parallel here: on the pole itself
        }
        let w = a - p;
        let (r, s) = (w.perp_dot(e) / det, w.perp_dot(d) / det);
        let within = |t: f64| (-CORNER_MARGIN..=1.0 + CORNER_MARGIN).contains(&t);
        within(r) && within(s)
    }
}
