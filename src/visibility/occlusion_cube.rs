//! A conservative occlusion buffer around one viewpoint: the half of a cube map in front of the
//! viewer's tangent plane, each pixel holding the farthest depth at which an occluder already
//! drawn covers the whole pixel. A box whose every pixel is so covered, nearer than the box's
//! nearest point, is hidden from the viewer: proved, not sampled, so that culling with it never
//! drops a face that any ray from the viewer reaches ([`super::seen_faces`]).
//!
//! Occluders are drawn inside out (a pixel counts only where all four corners of its square lie
//! inside the occluder's projection, so the occluder covers every ray through it) at their depth
//! farthest over the pixel; boxes are tested outside in (every pixel their projection may touch,
//! at a depth no larger than any of their points'). Several occluders that each cover part of a
//! box's pixels hide it together: a street's houses hide the city behind them although no one
//! house does. Margins of a millionth of a pixel and a billionth of a depth keep rounding on the
//! side of "seen".
//!
//! Depth along a cube face is the coordinate along its axis, so that the ray through (u, v) of
//! face k is `t (a_k + u b_k + v c_k)` at depth t, and an occluder's plane `n · x = c` is at depth
//! `c / (n · (a_k + u b_k + v c_k))`: its reciprocal is affine in (u, v), so its largest depth
//! over a pixel is at one of the pixel's corners.

use glam::{DVec2, DVec3};
use smallvec::SmallVec;

use crate::geometry::{bounding_box, bounding_box_3d, box_corners, convex_hull};

/// A polygon's vertices, kept on the stack when it has few.
type Points3 = SmallVec<[DVec3; 16]>;
type Points2 = SmallVec<[DVec2; 16]>;

/// Pixels along a cube face's side: the front face has `SIDE²`, each of the four side faces
/// `SIDE * SIDE / 2` (their halves above the tangent plane).
const SIDE: usize = 32;
/// Rows of a side face above the tangent plane.
const HALF: usize = SIDE / 2;
/// A pixel's side in the (u, v) coordinates of a face, which run over [-1, 1].
const PIXEL: f64 = 2.0 / SIDE as f64;
/// Relative margin on depths: an occluder counts a billionth farther than it is.
const DEPTH_MARGIN: f64 = 1e-9;
/// Margin of a pixel's corner inside an occluder's projection, in (u, v) units per unit of the
/// projection's size.
const INSIDE_MARGIN: f64 = 1e-9;

/// The five cube faces in front of the viewer, in its frame (x, y along its tangent plane, z
/// along its normal): (axis, u, v). The side faces' v is the normal, so their rows v > 0 are in
/// front of the tangent plane.
const FACES: [(DVec3, DVec3, DVec3); 5] = [
    (DVec3::Z, DVec3::X, DVec3::Y),
    (DVec3::X, DVec3::Y, DVec3::Z),
    (DVec3::NEG_X, DVec3::Y, DVec3::Z),
    (DVec3::Y, DVec3::X, DVec3::Z),
    (DVec3::NEG_Y, DVec3::X, DVec3::Z),
];

/// The buffer of one viewpoint; reused from one viewpoint to the next ([`OcclusionCube::reset`]).
#[derive(Clone, Debug)]
pub struct OcclusionCube {
    origin: DVec3,
    /// The viewer's frame: rows are x, y (in its tangent plane) and z (its normal).
    axes: [DVec3; 3],
    /// Per face, its pixels row by row (v), each the largest depth of a covering occluder
    /// (infinite where none covers the whole pixel).
    depth: [Vec<f64>; 5],
}

impl Default for OcclusionCube {
    fn default() -> Self {
        Self {
            origin: DVec3::ZERO,
            axes: [DVec3::X, DVec3::Y, DVec3::Z],
            depth: std::array::from_fn(|k| vec![f64::INFINITY; SIDE * rows(k)]),
        }
    }
}

/// Rows of face k: the front face's all, a side face's upper half.
fn rows(k: usize) -> usize {
    if k == 0 { SIDE } else { HALF }
}

/// The lowest v of face k's rows.
fn v_start(k: usize) -> f64 {
    if k == 0 { -1.0 } else { 0.0 }
}

impl OcclusionCube {
    /// A polygon whose diameter is below this many times its distance covers no whole pixel:
    /// the smallest pixel, at a face's corner, is seen under an angle of about a third of
    /// [`PIXEL`] across (a margin of two below that).
    pub const SMALLEST_ANGLE: f64 = PIXEL / 6.0;

    /// Empties the buffer for a viewer at `origin` with unit normal `normal`.
    pub fn reset(&mut self, origin: DVec3, normal: DVec3) {
        // Axes along the world's where the normal is (a city's walls and roofs): a box of the
        // world stays as thin in the viewer's frame.
        let least = normal.abs().min_position();
        let x = (DVec3::AXES[least] - normal * normal[least]).normalize();
        let y = normal.cross(x);
        self.origin = origin;
        self.axes = [x, y, normal];
        for face in &mut self.depth {
            face.fill(f64::INFINITY);
        }
    }

    /// A point in the viewer's frame (relative to the viewer).
    fn local(&self, p: DVec3) -> DVec3 {
        let d = p - self.origin;
        DVec3::new(self.axes[0].dot(d), self.axes[1].dot(d), self.axes[2].dot(d))
    }

    /// Draws the convex planar polygon `polygon` (world coordinates) as an occluder.
    pub fn draw(&mut self, polygon: &[DVec3]) {
        if polygon.len() < 3 {
            return;
        }
        let local: Points3 = polygon.iter().map(|&p| self.local(p)).collect();
        let normal = plane_normal(&local);
        let offset = normal.dot(local[0]);
        let reach = local.iter().map(|q| q.abs().max_element()).fold(0.0, f64::max);
        // A plane through the viewer (or nearly) is seen edge on: it covers no pixel.
        if !above(offset.abs(), 1e-9 * reach) {
            return;
        }
        for (k, &(a, b, c)) in FACES.iter().enumerate() {
            if !may_touch(&local, (a, b, c), k != 0) {
                continue;
            }
            let depths: SmallVec<[f64; 16]> = local.iter().map(|&q| a.dot(q)).collect();
            let near = 1e-9 * reach;
            let Some(projected) = clip_and_project(&local, &depths, near, b, c) else {
                continue;
            };
            self.draw_on_face(k, &projected, (normal, offset), (a, b, c));
        }
    }

    /// Draws the convex solid with corners `vertices` (world coordinates) as one occluder, the
    /// viewer outside it: on each cube face that the whole solid lies in front of (along the
    /// face's axis), the hull of its corners' projections at the depth of its farthest corner.
    /// A ray through that hull meets the solid, and enters it through a face nearer than that
    /// corner, so each pixel inside counts; drawn face by face, the pixels on the lines where
    /// its faces meet would not (a building's edge, behind which the next street hides).
    /// Where the solid reaches behind a face's plane its projection is unbounded: nothing is
    /// drawn there, its faces draw their own.
    pub fn draw_solid(&mut self, vertices: &[DVec3]) {
        if vertices.len() < 4 {
            return;
        }
        let local: Points3 = vertices.iter().map(|&p| self.local(p)).collect();
        let reach = local.iter().map(|q| q.abs().max_element()).fold(0.0, f64::max);
        for (k, &(a, b, c)) in FACES.iter().enumerate() {
            if !may_touch(&local, (a, b, c), k != 0) {
                continue;
            }
            let depths: SmallVec<[f64; 16]> = local.iter().map(|&q| a.dot(q)).collect();
            let (nearest, farthest) = depths
                .iter()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &d| (lo.min(d), hi.max(d)));
            if !above(nearest, 1e-9 * reach) {
                continue;
            }
            let projected: Points2 = local
                .iter()
                .zip(&depths)
                .map(|(&q, &d)| DVec2::new(b.dot(q), c.dot(q)) / d)
                .collect();
            let hull = convex_hull(&projected);
            if hull.len() >= 3 {
                // The plane a·x = farthest: at that depth over every pixel.
                self.draw_on_face(k, &hull, (a, farthest), (a, b, c));
            }
        }
    }

    /// Covers the pixels of face k that lie inside `projected` (convex, in (u, v)).
    fn draw_on_face(
        &mut self,
        k: usize,
        projected: &[DVec2],
        (normal, offset): (DVec3, f64),
        (a, b, c): (DVec3, DVec3, DVec3),
    ) {
        let Some(edges) = Edges::new(projected, k != 0) else { return };
        let (lo, hi) = bounding_box(projected);
        let v0 = v_start(k);
        // Rows of corners that may lie inside: those within the box.
        let first = |x: f64, start: f64| ((x - start) / PIXEL).ceil().max(0.0) as usize;
        let last = |x: f64, start: f64, count: usize| {
            (((x - start) / PIXEL).floor().min(count as f64)) as usize
        };
        let (j0, j1) = (first(lo.y, v0), last(hi.y, v0, rows(k)));
        if j0 >= j1 {
            return;
        }
        // The depth of the occluder's plane along the ray through (u, v) is offset / (na + u nb
        // + v nc).
        let (na, nb, nc) = (normal.dot(a), normal.dot(b), normal.dot(c));
        let face = &mut self.depth[k];
        // Corner columns inside on the row below, from row to row.
        let mut below = edges.inside_columns(v0 + j0 as f64 * PIXEL);
        for j in j0..j1 {
            let v_low = v0 + j as f64 * PIXEL;
            let v_high = v_low + PIXEL;
            let above = edges.inside_columns(v_high);
            // Pixels whose four corners are inside: both rows hold columns i and i + 1.
            let (from, to) = (below.0.max(above.0), below.1.min(above.1).saturating_sub(1));
            // The plane's depth is offset / den with den affine in (u, v): where den has the
            // sign of offset at all four corners, the farthest depth is at the corner where
            // |den| is least (one division a pixel), the corner its slopes point away from.
            let den = |u: f64, v: f64| (na + u * nb + v * nc) * offset.signum();
            let least_at = least_corner(nb * offset.signum(), nc * offset.signum());
            let v_least = least_at.1.pick(v_low, v_high);
            for i in from..to {
                let (u, w) = (-1.0 + i as f64 * PIXEL, -1.0 + (i + 1) as f64 * PIXEL);
                let least = den(least_at.0.pick(u, w), v_least);
                let farthest = offset.abs() / least;
                if least > 0.0 && farthest.is_finite() {
                    let pixel = &mut face[j * SIDE + i];
                    *pixel = pixel.min(farthest * (1.0 + DEPTH_MARGIN));
                }
            }
            below = above;
        }
    }

    /// Whether the box `[lo, hi]` (world coordinates) is hidden from the viewer: each of its
    /// points in front of the tangent plane lies behind occluders drawn so far.
    pub fn hides_box(&self, lo: DVec3, hi: DVec3) -> bool {
        // The box's corners in the viewer's frame, and the box around them there.
        let (blo, bhi) = bounding_box_3d(&box_corners((lo, hi)).map(|c| self.local(c)));
        if bhi.z <= 0.0 {
            return true;
        }
        // Every point of the box is at least this far along the axis of the face it lies on.
        let gap = (blo.max(-bhi)).max(DVec3::ZERO).max_element();
        let scale = blo.abs().max(bhi.abs()).max_element();
        if !above(gap, 1e-9 * scale) {
            return false;
        }
        for (k, &(a, b, c)) in FACES.iter().enumerate() {
            let along = |axis: DVec3| interval(axis, blo, bhi);
            let (dlo, dhi) = along(a);
            // Its points on face k are at depths of at least `gap` there.
            let dlo = dlo.max(gap);
            if dhi < dlo {
                continue;
            }
            let ratio = |(nlo, nhi): (f64, f64)| {
                let lo = (nlo / dlo).min(nlo / dhi);
                let hi = (nhi / dlo).max(nhi / dhi);
                (lo, hi)
            };
            let (ulo, uhi) = ratio(along(b));
            let (vlo, vhi) = ratio(along(c));
            let v0 = v_start(k);
            if ulo > 1.0 || uhi < -1.0 || vlo > 1.0 || vhi < v0 {
                continue;
            }
            let index = |x: f64, start: f64, count: usize| {
                (((x - start) / PIXEL).floor().max(0.0) as usize).min(count - 1)
            };
            let (i0, i1) = (index(ulo, -1.0, SIDE), index(uhi, -1.0, SIDE));
            let (j0, j1) = (index(vlo, v0, rows(k)), index(vhi, v0, rows(k)));
            let face = &self.depth[k];
            for j in j0..=j1 {
                for i in i0..=i1 {
                    if !above(dlo, face[j * SIDE + i]) {
                        return false;
                    }
                }
            }
        }
        true
    }
}

impl OcclusionCube {
    /// Whether the planar polygon `polygon` (world coordinates; its convex hull is tested) is
    /// hidden from the viewer: as [`OcclusionCube::hides_box`], each pixel it may touch held
    /// to the nearest depth of its plane over the pixel rather than the box's nearest point.
    pub fn hides_polygon(&self, polygon: &[DVec3], lo: DVec3, hi: DVec3) -> bool {
        let local: Points3 = polygon.iter().map(|&p| self.local(p)).collect();
        if local.iter().all(|q| q.z <= 0.0) {
            return true;
        }
        let normal = plane_normal(&local);
        let offset = normal.dot(local[0]);
        let reach = local.iter().map(|q| q.abs().max_element()).fold(0.0, f64::max);
        if !above(offset.abs(), 1e-9 * reach) {
            return self.hides_box(lo, hi);
        }
        let gap = {
            let (blo, bhi) = bounding_box_3d(&local);
            (blo.max(-bhi)).max(DVec3::ZERO).max_element()
        };
        if !above(gap, 1e-9 * reach) {
            return false;
        }
        for (k, &(a, b, c)) in FACES.iter().enumerate() {
            if !may_touch(&local, (a, b, c), k != 0) {
                continue;
            }
            let depths: SmallVec<[f64; 16]> = local.iter().map(|&q| a.dot(q)).collect();
            let dhi = depths.iter().copied().fold(f64::NEG_INFINITY, f64::max);
            if dhi < gap {
                continue;
            }
            // Its part on face k is at depth `gap` at least: project what lies beyond.
            let Some(projected) = clip_and_project(&local, &depths, gap, b, c) else {
                continue;
            };
            let (plo, phi) = bounding_box(&projected);
            let v0 = v_start(k);
            if plo.x > 1.0 || phi.x < -1.0 || plo.y > 1.0 || phi.y < v0 {
                continue;
            }
            let index = |x: f64, start: f64, count: usize| {
                (((x - start) / PIXEL).floor().max(0.0) as usize).min(count - 1)
            };
            let (i0, i1) = (index(plo.x, -1.0, SIDE), index(phi.x, -1.0, SIDE));
            let (j0, j1) = (index(plo.y, v0, rows(k)), index(phi.y, v0, rows(k)));
            let face = &self.depth[k];
            // The plane's depth over a pixel is offset / den with den affine in (u, v): where
            // den has the sign of offset at all four corners, the nearest depth is at the
            // corner where |den| is largest; elsewhere the polygon's nearest depth on this face
            // bounds it.
            let (na, nb, nc) = (normal.dot(a), normal.dot(b), normal.dot(c));
            let den = |u: f64, v: f64| (na + u * nb + v * nc) * offset.signum();
            let least_at = least_corner(nb * offset.signum(), nc * offset.signum());
            for j in j0..=j1 {
                let (va, vb) = (v0 + j as f64 * PIXEL, v0 + (j + 1) as f64 * PIXEL);
                let (v_least, v_most) = (least_at.1.pick(va, vb), least_at.1.pick(vb, va));
                for i in i0..=i1 {
                    let stored = face[j * SIDE + i];
                    if !above(f64::INFINITY, stored) {
                        return false;
                    }
                    let (ua, ub) = (-1.0 + i as f64 * PIXEL, -1.0 + (i + 1) as f64 * PIXEL);
                    let least = den(least_at.0.pick(ua, ub), v_least);
                    let most = den(least_at.0.pick(ub, ua), v_most);
                    let nearest = if least > 0.0 { (offset.abs() / most).max(gap) } else { gap };
                    if !above(nearest * (1.0 - DEPTH_MARGIN), stored) {
                        return false;
                    }
                }
            }
        }
        true
    }
}

/// One end of a pixel's side: the lower or the upper.
#[derive(Clone, Copy)]
enum End {
    Lower,
    Upper,
}

impl End {
    /// `lower` or `upper`, as this end says.
    fn pick(self, lower: f64, upper: f64) -> f64 {
        match self {
            End::Lower => lower,
            End::Upper => upper,
        }
    }
}

/// The corner of a pixel where `(a + u su + v sv) * s` is least, given its slopes `su` and `sv`
/// times s (the opposite corner is where it is largest). Each rounded step of the sum grows
/// with u where su >= 0 and with v where sv >= 0, so the value there is the least of the four
/// corners' as computed, to the bit.
fn least_corner(su: f64, sv: f64) -> (End, End) {
    let end = |slope: f64| if slope >= 0.0 { End::Lower } else { End::Upper };
    (end(su), end(sv))
}

/// Whether `a > b`; never where either is NaN, so that a NaN from a degenerate polygon or box
/// proves nothing hidden.
fn above(a: f64, b: f64) -> bool {
    a > b
}

/// Whether points `local` (viewer's frame) may have a part in the view of face k (`a`, `b`,
/// `c` its axes): none is when all lie beyond one of the four planes through the viewer that
/// bound the face's pyramid, or, for a side face, all below the tangent plane.
fn may_touch(local: &[DVec3], (a, b, c): (DVec3, DVec3, DVec3), side: bool) -> bool {
    let beyond = |plane: DVec3| local.iter().all(|&q| plane.dot(q) > 0.0);
    !(beyond(b - a) || beyond(-b - a) || beyond(c - a) || beyond(-c - a) || side && beyond(-c))
}

/// The range of `axis · q` over the box `[lo, hi]` (axis one of ±x, ±y, ±z).
fn interval(axis: DVec3, lo: DVec3, hi: DVec3) -> (f64, f64) {
    let (a, b) = (axis.dot(lo), axis.dot(hi));
    (a.min(b), a.max(b))
}

/// The unit normal of a planar polygon (Newell's method), or zero for a degenerate one.
fn plane_normal(polygon: &[DVec3]) -> DVec3 {
    let mut n = DVec3::ZERO;
    for (k, &p) in polygon.iter().enumerate() {
        let q = polygon[(k + 1) % polygon.len()];
        n += (p - q).cross(p + q) * 0.5;
    }
    n.normalize_or_zero()
}

/// The part of `polygon` (viewer's frame) at depth at least `near` along a face's axis
/// (`depths`), projected to that face's (u, v); `None` where nothing is left.
fn clip_and_project(
    polygon: &[DVec3],
    depths: &[f64],
    near: f64,
    b: DVec3,
    c: DVec3,
) -> Option<Points2> {
    if depths.iter().all(|&d| d < near) {
        return None;
    }
    let mut kept: SmallVec<[(DVec3, f64); 16]> = SmallVec::new();
    for k in 0..polygon.len() {
        let (p, dp) = (polygon[k], depths[k]);
        let (q, dq) = (polygon[(k + 1) % polygon.len()], depths[(k + 1) % polygon.len()]);
        if dp >= near {
            kept.push((p, dp));
        }
        if (dp >= near) != (dq >= near) {
            let s = (near - dp) / (dq - dp);
            kept.push((p + (q - p) * s, near));
        }
    }
    (kept.len() >= 3)
        .then(|| kept.iter().map(|&(p, d)| DVec2::new(b.dot(p), c.dot(p)) / d).collect())
}

/// The edges of a convex polygon in (u, v), oriented so that its inside is on their left.
struct Edges {
    /// Per edge: a point, the unit normal pointing inside, and whether it lies along the
    /// tangent plane's line v = 0 of a side face (its inside above).
    lines: SmallVec<[(DVec2, DVec2, bool); 16]>,
    margin: f64,
}

/// An edge of a side face's projection whose ends are this close to v = 0 lies along the
/// tangent plane: an occluder standing on the viewer's plane (a house on the ground around a
/// node of the ground, the ground below a node of a wall).
const ON_TANGENT_PLANE: f64 = 1e-12;

impl Edges {
    /// The edges of `polygon`; on a side face (`side`), those along v = 0 are marked.
    fn new(polygon: &[DVec2], side: bool) -> Option<Self> {
        let n = polygon.len();
        let twice_area: f64 = (0..n).map(|k| polygon[k].perp_dot(polygon[(k + 1) % n])).sum();
        let size = polygon.iter().map(|q| q.abs().max_element()).fold(1.0, f64::max);
        if !above(twice_area.abs(), 1e-12 * size * size) {
            return None;
        }
        let sign = twice_area.signum();
        let mut lines = SmallVec::new();
        for k in 0..n {
            let (p, q) = (polygon[k], polygon[(k + 1) % n]);
            let along = q - p;
            let length = along.length();
            if length > 0.0 {
                let inward = along.perp() * (sign / length);
                let floor = side && p.y.abs().max(q.y.abs()) <= ON_TANGENT_PLANE && inward.y > 0.0;
                lines.push((p, inward, floor));
            }
        }
        Some(Self { lines, margin: INSIDE_MARGIN * size })
    }

    /// The corner columns (i from the first to one before the second) of the row at `v`
    /// that lie inside every edge by more than the margin. A corner on the tangent plane (v = 0
    /// of a side face) is not held to an edge along that plane: the pixel's rays above it are
    /// inside that edge, and its rays along the plane see nothing (G = 0 there).
    fn inside_columns(&self, v: f64) -> (usize, usize) {
        let (mut lo, mut hi) = (f64::NEG_INFINITY, f64::INFINITY);
        for &(p, inward, floor) in &self.lines {
            if floor && v == 0.0 {
                continue;
            }
            // inward.x (u - p.x) + inward.y (v - p.y) > margin.
            let rest = self.margin - inward.y * (v - p.y);
            if inward.x > 0.0 {
                lo = lo.max(p.x + rest / inward.x);
            } else if inward.x < 0.0 {
                hi = hi.min(p.x + rest / inward.x);
            } else if rest >= 0.0 {
                return (0, 0);
            }
        }
        // Columns strictly inside (lo, hi), kept a little inside for the division's rounding.
        let slack = 1e-12 * (1.0 + lo.abs().max(hi.abs()).min(1e300));
        let first = ((lo + slack + 1.0) / PIXEL).floor() + 1.0;
        let past = ((hi - slack + 1.0) / PIXEL).ceil();
        let first = first.clamp(0.0, (SIDE + 1) as f64) as usize;
        let past = past.clamp(0.0, (SIDE + 1) as f64) as usize;
        if first >= past { (0, 0) } else { (first, past) }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn square(centre: DVec3, half: f64) -> Vec<DVec3> {
        [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)]
            .iter()
            .map(|&(x, y)| centre + DVec3::new(x * half, y * half, 0.0))
            .collect()
    }

    #[test]
    fn a_wide_wall_hides_what_is_behind_it_and_nothing_in_front() {
        let mut cube = OcclusionCube::default();
        cube.reset(DVec3::ZERO, DVec3::Z);
        cube.draw(&square(DVec3::new(0.0, 0.0, 1.0), 10.0));
        let behind = (DVec3::new(-0.5, -0.5, 2.0), DVec3::new(0.5, 0.5, 3.0));
        assert!(cube.hides_box(behind.0, behind.1));
        let in_front = (DVec3::new(-0.5, -0.5, 0.5), DVec3::new(0.5, 0.5, 0.9));
        assert!(!cube.hides_box(in_front.0, in_front.1));
        // Touching the wall from behind: not proved hidden.
        let touching = (DVec3::new(-0.5, -0.5, 1.0), DVec3::new(0.5, 0.5, 2.0));
        assert!(!cube.hides_box(touching.0, touching.1));
        // Past the wall's edge, at grazing angles, is seen.
        let aside = (DVec3::new(20.0, -0.5, 1.5), DVec3::new(21.0, 0.5, 2.0));
        assert!(!cube.hides_box(aside.0, aside.1));
        // Behind the tangent plane: nothing of it is in front.
        assert!(cube.hides_box(DVec3::new(5.0, 5.0, -3.0), DVec3::new(6.0, 6.0, 0.0)));
    }

    #[test]
    fn two_walls_hide_together_what_neither_hides_alone() {
        let mut cube = OcclusionCube::default();
        cube.reset(DVec3::ZERO, DVec3::Z);
        let left: Vec<DVec3> = [(-10.0, -10.0), (0.2, -10.0), (0.2, 10.0), (-10.0, 10.0)]
            .iter()
            .map(|&(x, y)| DVec3::new(x, y, 1.0))
            .collect();
        let right: Vec<DVec3> = [(-0.2, -10.0), (10.0, -10.0), (10.0, 10.0), (-0.2, 10.0)]
            .iter()
            .map(|&(x, y)| DVec3::new(x, y, 1.5))
            .collect();
        let target = (DVec3::new(-1.0, -0.5, 3.0), DVec3::new(1.0, 0.5, 4.0));
        cube.draw(&left);
        assert!(!cube.hides_box(target.0, target.1));
        cube.draw(&right);
        assert!(cube.hides_box(target.0, target.1));
        // A gap between them (in angle: the left one's edge at u = 0.2, the right one's at
        // 0.27) lets the target be seen.
        let mut gapped = OcclusionCube::default();
        gapped.reset(DVec3::ZERO, DVec3::Z);
        gapped.draw(&left);
        let apart: Vec<DVec3> = right.iter().map(|p| *p + DVec3::new(0.6, 0.0, 0.0)).collect();
        gapped.draw(&apart);
        assert!(!gapped.hides_box(target.0, target.1));
    }

    #[test]
    fn an_occluder_seen_edge_on_or_behind_the_viewer_covers_nothing() {
        let mut cube = OcclusionCube::default();
        cube.reset(DVec3::new(1.0, 2.0, 3.0), DVec3::new(0.0, 1.0, 1.0).normalize());
        // In a plane through the viewer.
        let through: Vec<DVec3> = [(0.0, 0.0, 0.0), (5.0, 0.0, 0.0), (5.0, 5.0, -5.0)]
            .map(|(x, y, z)| DVec3::new(1.0, 2.0, 3.0) + DVec3::new(x, y, z))
            .to_vec();
        cube.draw(&through);
        assert!(cube.depth.iter().flatten().all(|d| d.is_infinite()));
        // Behind the viewer.
        let behind: Vec<DVec3> = square(DVec3::new(1.0, -10.0, -10.0), 3.0);
        cube.draw(&behind);
        assert!(cube.depth.iter().flatten().all(|d| d.is_infinite()));
    }

    /// The covered pixels of `cube` whose centre ray meets none of `drawn` (world polygons) by
    /// the depth the pixel holds: (face, column, row, held depth, first hit).
    fn pixels_not_covered(
        cube: &OcclusionCube,
        drawn: &[Vec<DVec3>],
    ) -> Vec<(usize, usize, usize, f64, f64)> {
        let mut bad = Vec::new();
        for (k, &(a, b, c)) in FACES.iter().enumerate() {
            for j in 0..rows(k) {
                for i in 0..SIDE {
                    let held = cube.depth[k][j * SIDE + i];
                    if !held.is_finite() {
                        continue;
                    }
                    let u = -1.0 + (i as f64 + 0.5) * PIXEL;
                    let v = v_start(k) + (j as f64 + 0.5) * PIXEL;
                    let ray = a + u * b + v * c;
                    let first = drawn
                        .iter()
                        .filter_map(|polygon| {
                            let local: Vec<DVec3> =
                                polygon.iter().map(|&p| cube.local(p)).collect();
                            let n = plane_normal(&local);
                            let t = n.dot(local[0]) / n.dot(ray);
                            let x = ray * t;
                            let m = local.len();
                            let sides: Vec<f64> = (0..m)
                                .map(|e| (local[(e + 1) % m] - local[e]).cross(x - local[e]).dot(n))
                                .collect();
                            let inside =
                                sides.iter().all(|&s| s >= 0.0) || sides.iter().all(|&s| s <= 0.0);
                            (t > 0.0 && inside).then_some(t)
                        })
                        .fold(f64::INFINITY, f64::min);
                    if first > held * (1.0 + 1e-9) {
                        bad.push((k, i, j, held, first));
                    }
                }
            }
        }
        bad
    }

    /// Numbers uniform in [-1, 1) from a xorshift generator started at `state`.
    fn uniform(mut state: u64) -> impl FnMut() -> f64 {
        move || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
        }
    }

    #[test]
    fn a_pixel_s_least_and_largest_depth_denominators_are_at_the_corners_its_slopes_tell() {
        // To the bit: the pixel loops evaluate one corner instead of four.
        let mut random = uniform(0x5851_f42d_4c95_7f2d_u64);
        for _ in 0..20_000 {
            // Slopes of all sizes, some of them naught.
            let slope = |x: f64, r: f64| if r > 0.8 { 0.0 } else { x * 1e3f64.powf(r) };
            let (na, nb, nc) = (random(), slope(random(), random()), slope(random(), random()));
            let sign = if random() > 0.0 { 1.0 } else { -1.0 };
            let den = |u: f64, v: f64| (na + u * nb + v * nc) * sign;
            let (i, j) = ((16.0 * (random() + 1.0)) as usize, (16.0 * (random() + 1.0)) as usize);
            let (u, w) = (-1.0 + i as f64 * PIXEL, -1.0 + (i + 1) as f64 * PIXEL);
            let (v, z) = (-1.0 + j as f64 * PIXEL, -1.0 + (j + 1) as f64 * PIXEL);
            let corners = [den(u, v), den(w, v), den(u, z), den(w, z)];
            let least = corners.iter().copied().fold(f64::INFINITY, f64::min);
            let most = corners.iter().copied().fold(f64::NEG_INFINITY, f64::max);
            let (at_u, at_v) = least_corner(nb * sign, nc * sign);
            assert_eq!(den(at_u.pick(u, w), at_v.pick(v, z)).to_bits(), least.to_bits());
            assert_eq!(den(at_u.pick(w, u), at_v.pick(z, v)).to_bits(), most.to_bits());
        }
    }

    #[test]
    fn every_covered_pixel_is_covered_by_what_was_drawn() {
        // Random triangles and quadrilaterals around viewers of random normals.
        let mut random = uniform(0x2545_f491_4f6c_dd1d_u64);
        for _ in 0..20 {
            let mut cube = OcclusionCube::default();
            let normal = DVec3::new(random(), random(), random()).normalize();
            cube.reset(DVec3::new(random(), random(), random()), normal);
            let mut drawn = Vec::new();
            for _ in 0..12 {
                let centre = DVec3::new(random(), random(), random()) * 4.0;
                let (e1, e2) =
                    DVec3::new(random(), random(), random()).normalize().any_orthonormal_pair();
                let size = 0.5 + 2.0 * random().abs();
                let corners = if random() > 0.0 { 3 } else { 4 };
                let polygon: Vec<DVec3> = (0..corners)
                    .map(|k| {
                        let angle = std::f64::consts::TAU * k as f64 / corners as f64;
                        centre + (e1 * angle.cos() + e2 * angle.sin()) * size
                    })
                    .collect();
                cube.draw(&polygon);
                drawn.push(polygon);
            }
            let bad = pixels_not_covered(&cube, &drawn);
            assert!(bad.is_empty(), "{:?}", &bad[..bad.len().min(4)]);
            assert!(cube.depth.iter().flatten().any(|d| d.is_finite()), "nothing drawn");
        }
    }

    /// The corners and faces (quadrilaterals) of the box with centre `centre` and half axes
    /// `axes` (orthogonal).
    fn box_of(centre: DVec3, axes: [DVec3; 3]) -> (Vec<DVec3>, Vec<Vec<DVec3>>) {
        let corner = |bits: [usize; 3]| {
            centre + (0..3).map(|k| axes[k] * (2.0 * bits[k] as f64 - 1.0)).sum::<DVec3>()
        };
        let corners = (0..8).map(|i| corner([i & 1, (i >> 1) & 1, (i >> 2) & 1])).collect();
        let mut faces = Vec::new();
        for k in 0..3 {
            let (k1, k2) = ((k + 1) % 3, (k + 2) % 3);
            for side in 0..2 {
                let at = |a: usize, b: usize| {
                    let mut bits = [0; 3];
                    (bits[k], bits[k1], bits[k2]) = (side, a, b);
                    corner(bits)
                };
                faces.push(vec![at(0, 0), at(1, 0), at(1, 1), at(0, 1)]);
            }
        }
        (corners, faces)
    }

    #[test]
    fn a_solid_drawn_whole_covers_only_pixels_its_faces_cover() {
        let mut random = uniform(0x9e37_79b9_7f4a_7c15_u64);
        let mut drawn_somewhere = false;
        for _ in 0..20 {
            let mut cube = OcclusionCube::default();
            let viewer = DVec3::new(random(), random(), random());
            cube.reset(viewer, DVec3::new(random(), random(), random()).normalize());
            let mut faces = Vec::new();
            for _ in 0..8 {
                let centre = DVec3::new(random(), random(), random()) * 4.0;
                let (e1, e2) =
                    DVec3::new(random(), random(), random()).normalize().any_orthonormal_pair();
                let e3 = e1.cross(e2);
                let half = [e1, e2, e3].map(|e| e * (0.3 + random().abs()));
                let inside = half.iter().all(|h| (viewer - centre).dot(*h).abs() < h.dot(*h));
                if inside {
                    continue;
                }
                let (corners, box_faces) = box_of(centre, half);
                cube.draw_solid(&corners);
                faces.extend(box_faces);
            }
            let bad = pixels_not_covered(&cube, &faces);
            assert!(bad.is_empty(), "{:?}", &bad[..bad.len().min(4)]);
            drawn_somewhere |= cube.depth.iter().flatten().any(|d| d.is_finite());
        }
        assert!(drawn_somewhere, "no solid drawn");
    }

    #[test]
    fn a_solid_drawn_whole_hides_what_lies_behind_the_edge_between_its_faces() {
        // A box turned 45 degrees about x shows the viewer two faces that meet along an edge
        // across a row of pixels: neither face covers that row whole, the box does.
        let (c, s) = (std::f64::consts::FRAC_1_SQRT_2, std::f64::consts::FRAC_1_SQRT_2);
        let axes = [DVec3::X * 2.0, DVec3::new(0.0, c, s), DVec3::new(0.0, -s, c)];
        let (corners, faces) = box_of(DVec3::new(0.0, 0.03, 5.0), axes);
        let behind = (DVec3::new(-0.2, 0.0, 8.0), DVec3::new(0.2, 0.1, 8.5));
        let mut by_faces = OcclusionCube::default();
        by_faces.reset(DVec3::ZERO, DVec3::Z);
        faces.iter().for_each(|f| by_faces.draw(f));
        assert!(!by_faces.hides_box(behind.0, behind.1));
        let mut whole = OcclusionCube::default();
        whole.reset(DVec3::ZERO, DVec3::Z);
        whole.draw_solid(&corners);
        assert!(whole.hides_box(behind.0, behind.1));
        // In front of its farthest corner, nothing is proved hidden by it.
        let between = (DVec3::new(-0.2, 0.0, 6.0), DVec3::new(0.2, 0.1, 6.2));
        assert!(!whole.hides_box(between.0, between.1));
        assert!(pixels_not_covered(&whole, &faces).is_empty());
    }
}
