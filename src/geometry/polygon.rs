//! Convex polygon operations in a plane's 2-D coordinates, and clipping of 3-D planar polygons.
//!
//! The pair plan describes the visible part of an element as a set of disjoint convex polygons:
//! a triangle clipped by half-planes (the node's tangent plane) minus convex shadows. Subtracting a
//! convex polygon from a convex polygon by its edge lines keeps every piece convex and needs no
//! general polygon Boolean, so the pieces are exact up to rounding of line intersections.

use glam::{DVec2, DVec3};
use smallvec::SmallVec;

/// Vertices a clipped polygon holds without a heap allocation (clipping runs for every candidate
/// occluder of every view). Fewer make the polygons cheaper to move, which they are more often
/// than they grow past it; with fewer still, more of them spill to the heap. Six was the
/// fastest of 4, 6, 8 and 12 on the occluded box's view factors and the city's pair plan.
const INLINE_VERTICES: usize = 6;

/// A polygon as clipping returns it.
pub type SmallPolygon<P> = SmallVec<[P; INLINE_VERTICES]>;

/// Relative tolerance (of a polygon's size) under which a vertex counts as lying on a clipping line.
pub(crate) const ON_LINE: f64 = 1e-13;

/// The closed half-plane `{ x : normal·x + offset >= 0 }`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HalfPlane {
    /// Normal pointing into the half-plane (need not be a unit vector).
    pub normal: DVec2,
    /// Offset.
    pub offset: f64,
}

impl HalfPlane {
    /// The half-plane to the left of the directed line from `p` to `q` (the inside of a CCW edge).
    pub fn left_of(p: DVec2, q: DVec2) -> Self {
        let d = q - p;
        let normal = DVec2::new(-d.y, d.x);
        Self { normal, offset: -normal.dot(p) }
    }

    /// The complementary closed half-plane.
    pub fn flipped(&self) -> Self {
        Self { normal: -self.normal, offset: -self.offset }
    }

    /// Signed value `normal·x + offset` (positive inside).
    pub fn eval(&self, x: DVec2) -> f64 {
        self.normal.dot(x) + self.offset
    }
}

/// The signed area of a polygon (positive when counter-clockwise).
pub fn signed_area(poly: &[DVec2]) -> f64 {
    let n = poly.len();
    let mut s = 0.0;
    for k in 0..n {
        let a = poly[k];
        let b = poly[(k + 1) % n];
        s += a.perp_dot(b);
    }
    0.5 * s
}

/// Axis-aligned bounding box `(min, max)` of a non-empty point set.
pub fn bounding_box(points: &[DVec2]) -> (DVec2, DVec2) {
    points
        .iter()
        .fold((DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY)), |(lo, hi), &p| {
            (lo.min(p), hi.max(p))
        })
}

/// Whether two axis-aligned boxes (smallest and largest corners) share interior points.
pub fn boxes_overlap((alo, ahi): (DVec2, DVec2), (blo, bhi): (DVec2, DVec2)) -> bool {
    alo.x < bhi.x && blo.x < ahi.x && alo.y < bhi.y && blo.y < ahi.y
}

/// The eight corners of the box `[lo, hi]`: bit 0 of the index picks x from `hi`, bit 1 y,
/// bit 2 z.
pub fn box_corners((lo, hi): (DVec3, DVec3)) -> [DVec3; 8] {
    std::array::from_fn(|k| {
        DVec3::new(
            if k & 1 == 0 { lo.x } else { hi.x },
            if k & 2 == 0 { lo.y } else { hi.y },
            if k & 4 == 0 { lo.z } else { hi.z },
        )
    })
}

/// Smallest and largest corner of the axis-aligned box around 3-D points.
pub fn bounding_box_3d(points: &[DVec3]) -> (DVec3, DVec3) {
    points
        .iter()
        .fold((DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY)), |(lo, hi), &p| {
            (lo.min(p), hi.max(p))
        })
}

fn scale_of(poly: &[DVec2]) -> f64 {
    scale_squared_of(poly).sqrt()
}

/// The square of [`scale_of`]: the tolerance tests below compare squares, which spares a
/// square root per element and per edge where every element of a face is clipped.
fn scale_squared_of(poly: &[DVec2]) -> f64 {
    let (lo, hi) = bounding_box(poly);
    (hi - lo).length_squared()
}

/// Removes repeated vertices (within `sqrt(eps2)`) in place and returns whether three distinct
/// vertices and some area are left.
fn clean(poly: &mut SmallPolygon<DVec2>, eps2: f64) -> bool {
    poly.dedup_by(|a, b| (*a - *b).length_squared() <= eps2);
    while poly.len() > 1 && (poly[0] - poly[poly.len() - 1]).length_squared() <= eps2 {
        poly.pop();
    }
    poly.len() >= 3 && signed_area(poly).abs() > eps2
}

/// Clips a convex polygon to a half-plane (Sutherland–Hodgman, one plane). Vertices within a relative
/// tolerance of the line count as on it, so no slivers are made. Returns `None` if nothing with area
/// is left.
pub fn clip_convex(poly: &[DVec2], hp: &HalfPlane) -> Option<Vec<DVec2>> {
    let mut out = SmallPolygon::new();
    clip_convex_into(poly, hp, &mut out).then(|| out.into_vec())
}

/// [`clip_convex`] into `out` (cleared first), without a heap allocation for small polygons;
/// returns whether anything with area is left.
pub fn clip_convex_into(poly: &[DVec2], hp: &HalfPlane, out: &mut SmallPolygon<DVec2>) -> bool {
    let scale2 = scale_squared_of(poly);
    let d = line_values(poly, hp, scale2);
    keep_side(poly, &d, scale2, out)
}

/// The part of the convex polygon `poly` inside the convex counter-clockwise `window`: clipped
/// ([`clip_convex_into`]) by each edge of the window that leaves a vertex outside; `None` when
/// nothing with area is left.
pub fn clip_to_convex(poly: &[DVec2], window: &[DVec2]) -> Option<SmallPolygon<DVec2>> {
    let m = window.len();
    clip_to_half_planes(poly, (0..m).map(|k| HalfPlane::left_of(window[k], window[(k + 1) % m])))
}

/// The part of the convex polygon `poly` inside every one of `half_planes`: clipped
/// ([`clip_convex_into`]) by each that leaves a vertex outside; `None` when nothing with area
/// is left.
pub fn clip_to_half_planes(
    poly: &[DVec2],
    half_planes: impl IntoIterator<Item = HalfPlane>,
) -> Option<SmallPolygon<DVec2>> {
    // Two buffers in turn, the last clip's result in `current` (none yet: `poly` itself);
    // swapping them would copy both inline buffers at every clip.
    let mut buffers: [SmallPolygon<DVec2>; 2] = [SmallVec::new(), SmallVec::new()];
    let mut current: Option<usize> = None;
    for half_plane in half_planes {
        let next = current.map_or(0, |c| 1 - c);
        let [first, second] = &mut buffers;
        let (part, out) = match current {
            None => (poly, first),
            Some(0) => (&first[..], second),
            Some(_) => (&second[..], first),
        };
        if part.iter().any(|&x| half_plane.eval(x) < 0.0) {
            if !clip_convex_into(part, &half_plane, out) {
                return None;
            }
            current = Some(next);
        }
    }
    match current {
        None => Some(SmallVec::from_slice(poly)),
        Some(c) => Some(std::mem::take(&mut buffers[c])),
    }
}

/// The half-plane's values at the vertices of a polygon of size `sqrt(scale2)`, those within the
/// tolerance of the line (`ON_LINE` of the size, times the normal's length) snapped to 0.
fn line_values(poly: &[DVec2], hp: &HalfPlane, scale2: f64) -> SmallVec<[f64; INLINE_VERTICES]> {
    let eps2 = ON_LINE * ON_LINE * scale2 * hp.normal.length_squared();
    poly.iter()
        .map(|&p| {
            let v = hp.eval(p);
            if v * v <= eps2 { 0.0 } else { v }
        })
        .collect()
}

/// The part of a convex polygon of size `sqrt(scale2)` where the values `d` at its vertices are
/// non-negative, into `out` (cleared first); returns whether it has area. Where `d` holds
/// the values of a half-plane ([`line_values`]), this is [`clip_convex`]; their negatives (to
/// the bit) give the part outside.
fn keep_side(poly: &[DVec2], d: &[f64], scale2: f64, out: &mut SmallPolygon<DVec2>) -> bool {
    out.clear();
    if d.iter().all(|&v| v >= 0.0) {
        out.extend_from_slice(poly);
    } else if d.iter().all(|&v| v <= 0.0) {
        return false;
    } else {
        keep_nonnegative_side(poly, d, out);
    }
    clean(out, ON_LINE * ON_LINE * scale2)
}

/// Whether every point of `points` lies in a counter-clockwise convex polygon, boundary included
/// up to a relative tolerance (of the polygon's size, measured once).
pub fn convex_contains(poly: &[DVec2], points: &[DVec2]) -> bool {
    // A point is inside an edge where its cross product is at least -eps |q - p|: compared
    // as squares where it is negative.
    let eps2 = ON_LINE * ON_LINE * scale_squared_of(poly);
    let n = poly.len();
    (0..n).all(|k| {
        let (p, q) = (poly[k], poly[(k + 1) % n]);
        let margin2 = eps2 * (q - p).length_squared();
        points.iter().all(|&x| {
            let cross = (q - p).perp_dot(x - p);
            cross >= 0.0 || cross * cross <= margin2
        })
    })
}

/// Whether `p` lies inside the simple polygon `polygon`, convex or not (crossing number).
pub fn polygon_contains(polygon: &[DVec2], p: DVec2) -> bool {
    let n = polygon.len();
    let mut inside = false;
    for k in 0..n {
        let (a, b) = (polygon[k], polygon[(k + 1) % n]);
        if (a.y > p.y) != (b.y > p.y) {
            let x = a.x + (p.y - a.y) / (b.y - a.y) * (b.x - a.x);
            if p.x < x {
                inside = !inside;
            }
        }
    }
    inside
}

/// Distance from a point to a counter-clockwise convex polygon (0 inside).
pub fn distance_to_convex(poly: &[DVec2], x: DVec2) -> f64 {
    let n = poly.len();
    if (0..n).all(|k| (poly[(k + 1) % n] - poly[k]).perp_dot(x - poly[k]) >= 0.0) {
        return 0.0;
    }
    (0..n)
        .map(|k| {
            let (p, q) = (poly[k], poly[(k + 1) % n]);
            let t = ((x - p).dot(q - p) / (q - p).length_squared()).clamp(0.0, 1.0);
            (x - (p + (q - p) * t)).length()
        })
        .fold(f64::INFINITY, f64::min)
}

/// Convex hull (counter-clockwise) of points, by Andrew's monotone chain; on the stack for up
/// to [`HULL_ON_STACK`] points (a projected box's eight corners, or the corners of its part in
/// a pyramid, once per point of an outer integral).
pub fn convex_hull(points: &[DVec2]) -> SmallVec<[DVec2; 16]> {
    if points.len() > HULL_ON_STACK {
        let mut pts = points.to_vec();
        let mut hull = vec![DVec2::ZERO; 2 * points.len()];
        let corners = monotone_chain(&mut pts, &mut hull);
        return SmallVec::from_slice(&hull[..corners]);
    }
    let mut pts = [DVec2::ZERO; HULL_ON_STACK];
    let pts = &mut pts[..points.len()];
    pts.copy_from_slice(points);
    let mut hull = [DVec2::ZERO; 2 * HULL_ON_STACK];
    let corners = monotone_chain(pts, &mut hull);
    SmallVec::from_slice(&hull[..corners])
}

/// Most points whose hull [`convex_hull`] finds without a heap allocation.
const HULL_ON_STACK: usize = 32;

/// Andrew's monotone chain: sorts `pts` and drops repeated points in place, and writes the
/// hull's corners counter-clockwise into `hull` (room for twice as many as `pts`); returns how
/// many there are (fewer than three distinct points are returned as they are).
fn monotone_chain(pts: &mut [DVec2], hull: &mut [DVec2]) -> usize {
    pts.sort_unstable_by(|a, b| a.x.total_cmp(&b.x).then(a.y.total_cmp(&b.y)));
    let mut m = 0;
    for k in 0..pts.len() {
        if m == 0 || pts[k] != pts[m - 1] {
            pts[m] = pts[k];
            m += 1;
        }
    }
    if m < 3 {
        hull[..m].copy_from_slice(&pts[..m]);
        return m;
    }
    let cross = |o: DVec2, a: DVec2, b: DVec2| (a - o).perp_dot(b - o);
    let mut corners = 0;
    // The lower chain left to right, then the upper one right to left.
    for pass in 0..2 {
        let start = corners;
        for k in 0..m {
            let q = if pass == 0 { pts[k] } else { pts[m - 1 - k] };
            while corners >= start + 2 && cross(hull[corners - 2], hull[corners - 1], q) <= 0.0 {
                corners -= 1;
            }
            hull[corners] = q;
            corners += 1;
        }
        corners -= 1;
    }
    corners
}

/// Whether a side of the convex counter-clockwise polygon `hole` has every corner of `piece`
/// strictly outside its line: then the two do not meet, and [`subtract_convex`] would leave
/// `piece` whole (a shadow whose box meets an element's but not the element).
pub fn convex_apart(piece: &[DVec2], hole: &[DVec2]) -> bool {
    let n = hole.len();
    (0..n).any(|k| {
        let outside = HalfPlane::left_of(hole[k], hole[(k + 1) % n]);
        piece.iter().all(|&p| outside.eval(p) < 0.0)
    })
}

/// `piece \ hole` for convex counter-clockwise polygons, as disjoint convex pieces.
///
/// Walks the hole's edges: the part of what is left that lies outside an edge's line is a piece of
/// the difference; the part inside goes on to the next edge. What remains at the end is
/// `piece ∩ hole` and is dropped.
pub fn subtract_convex(piece: &[DVec2], hole: &[DVec2]) -> Vec<Vec<DVec2>> {
    if !boxes_overlap(bounding_box(piece), bounding_box(hole)) {
        return vec![piece.to_vec()];
    }
    // What is left (inside every hole edge so far) and the next such part, by turns.
    let mut parts: [SmallPolygon<DVec2>; 2] = [SmallVec::from_slice(piece), SmallVec::new()];
    let mut outside = SmallPolygon::new();
    let mut rest = 0;
    // Whether what is left is as `keep_side` leaves it (once it has been through it): a line
    // that leaves all of it inside then changes nothing, and most of a hole's lines do.
    let mut kept = false;
    let mut out = Vec::new();
    let n = hole.len();
    for k in 0..n {
        let inside = HalfPlane::left_of(hole[k], hole[(k + 1) % n]);
        // What is left lies in `piece`: a line that leaves every corner of `piece` inside
        // leaves all of what is left inside, its values there as well, and changes nothing.
        // Most of a hole's lines do (an element that a shadow's side crosses is cut by that
        // side alone), and this test of `piece`'s corners costs less than taking the values of
        // what is left with their tolerance.
        if piece.iter().all(|&p| inside.eval(p) >= 0.0) {
            continue;
        }
        let [a, b] = &mut parts;
        let (current, next) = if rest == 0 { (a, b) } else { (b, a) };
        let scale2 = scale_squared_of(current);
        let d = line_values(current, &inside, scale2);
        if kept && d.iter().all(|&v| v >= 0.0) {
            continue;
        }
        let flipped: SmallVec<[f64; INLINE_VERTICES]> = d.iter().map(|&v| -v).collect();
        if keep_side(current, &flipped, scale2, &mut outside) {
            out.push(outside.to_vec());
        }
        if !keep_side(current, &d, scale2, next) {
            return out;
        }
        rest = 1 - rest;
        kept = true;
    }
    out
}

/// One Sutherland–Hodgman pass: the part of the polygon where the signed distances `d` (one per
/// vertex, snapped to 0 on the line) are non-negative, with the crossing points interpolated.
fn keep_nonnegative_side<P>(poly: &[P], d: &[f64], out: &mut SmallPolygon<P>)
where
    P: Copy
        + std::ops::Add<Output = P>
        + std::ops::Sub<Output = P>
        + std::ops::Mul<f64, Output = P>,
{
    let n = poly.len();
    for k in 0..n {
        let (p, q) = (poly[k], poly[(k + 1) % n]);
        let (dp, dq) = (d[k], d[(k + 1) % n]);
        if dp >= 0.0 {
            out.push(p);
        }
        if (dp > 0.0 && dq < 0.0) || (dp < 0.0 && dq > 0.0) {
            out.push(p + (q - p) * (dp / (dp - dq)));
        }
    }
}

/// Whether [`clip_polygon_3d`] would keep `poly` whole, as decided for any polygon no larger than
/// `scale` (the bounding box's diagonal): every vertex inside by more than the tolerance of that
/// size. A piece cut from a larger one is no larger, so one size serves all its clips.
pub fn wholly_inside_3d(poly: &[DVec3], normal: DVec3, offset: f64, scale: f64) -> bool {
    let eps = ON_LINE * scale * normal.length();
    poly.iter().all(|&p| normal.dot(p) + offset > eps)
}

/// Clips a planar 3-D polygon (convex or not) to the closed half-space `{ x : normal·x + offset >= 0 }`,
/// into `out` (cleared first; no allocation for small polygons: clipping runs for every candidate
/// occluder of every view). For a convex polygon the result is convex; returns whether anything
/// with area is left.
pub fn clip_polygon_3d(
    poly: &[DVec3],
    normal: DVec3,
    offset: f64,
    out: &mut SmallPolygon<DVec3>,
) -> bool {
    out.clear();
    let (lo, hi) = bounding_box_3d(poly);
    let scale = (hi - lo).length();
    let eps = ON_LINE * scale * normal.length();
    let d: SmallVec<[f64; INLINE_VERTICES]> = poly
        .iter()
        .map(|&p| {
            let v = normal.dot(p) + offset;
            if v.abs() <= eps { 0.0 } else { v }
        })
        .collect();
    if d.iter().all(|&v| v <= 0.0) {
        return false;
    }
    if d.iter().all(|&v| v > 0.0) {
        out.extend_from_slice(poly); // wholly inside: nothing to cut
        return true;
    }
    keep_nonnegative_side(poly, &d, out);
    out.dedup_by(|a, b| (*a - *b).length() <= ON_LINE * scale);
    while out.len() > 1 && (out[0] - out[out.len() - 1]).length() <= ON_LINE * scale {
        out.pop();
    }
    let area2 = (1..out.len().saturating_sub(1))
        .map(|k| (out[k] - out[0]).cross(out[k + 1] - out[0]))
        .sum::<DVec3>()
        .length();
    out.len() >= 3 && area2 > (ON_LINE * scale).powi(2)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn square(lo: f64, hi: f64) -> Vec<DVec2> {
        vec![DVec2::new(lo, lo), DVec2::new(hi, lo), DVec2::new(hi, hi), DVec2::new(lo, hi)]
    }

    #[test]
    fn distance_to_a_square_from_inside_beside_and_off_a_corner() {
        let sq = square(0.0, 2.0);
        assert_eq!(distance_to_convex(&sq, DVec2::new(1.0, 0.5)), 0.0);
        assert!((distance_to_convex(&sq, DVec2::new(1.0, -0.5)) - 0.5).abs() < 1e-15);
        assert!((distance_to_convex(&sq, DVec2::new(5.0, 6.0)) - 5.0).abs() < 1e-15);
    }

    #[test]
    fn clipping_a_square_by_a_diagonal_half_plane_keeps_half() {
        let sq = square(0.0, 2.0);
        let hp = HalfPlane::left_of(DVec2::new(0.0, 0.0), DVec2::new(2.0, 2.0));
        let part = clip_convex(&sq, &hp).unwrap();
        assert!((signed_area(&part) - 2.0).abs() < 1e-15);
        assert_eq!(part.len(), 3, "a vertex on the line must not double: {part:?}");
    }

    #[test]
    fn clipping_away_everything_or_nothing() {
        let sq = square(0.0, 1.0);
        let keep_all = HalfPlane { normal: DVec2::X, offset: 0.0 };
        assert_eq!(clip_convex(&sq, &keep_all).unwrap().len(), 4);
        assert!(clip_convex(&sq, &keep_all.flipped()).is_none());
    }

    #[test]
    fn subtraction_conserves_area_and_keeps_pieces_disjoint() {
        let piece = vec![DVec2::new(0.0, 0.0), DVec2::new(4.0, 0.0), DVec2::new(0.0, 3.0)];
        let hole = square(0.5, 1.5);
        let parts = subtract_convex(&piece, &hole);
        let total: f64 = parts.iter().map(|p| signed_area(p)).sum();
        assert!((total - (6.0 - 1.0)).abs() < 1e-13, "area {total}");
        assert!(parts.iter().all(|p| signed_area(p) > 0.0));
        // Disjoint: sample points belong to at most one piece.
        for i in 0..40 {
            for j in 0..40 {
                let x = DVec2::new(0.05 + 0.1 * i as f64, 0.037 + 0.075 * j as f64);
                let count = parts.iter().filter(|p| strictly_inside(p, x)).count();
                assert!(count <= 1, "{x} in {count} pieces");
            }
        }
    }

    fn strictly_inside(poly: &[DVec2], x: DVec2) -> bool {
        let n = poly.len();
        (0..n).all(|k| (poly[(k + 1) % n] - poly[k]).perp_dot(x - poly[k]) > 1e-12)
    }

    /// Triangles against random convex holes (hulls of six points, round or long and thin, so
    /// that many cross a triangle from side to side): the pieces lie in the triangle and outside
    /// the hole, and
    /// their area is the triangle's less its intersection with the hole, clipped by the hole's
    /// half-planes one after another (an independent path). Among them are holes whose lines
    /// leave every corner of the triangle inside but one or two, which the subtraction passes
    /// over without testing what is left, and holes that [`convex_apart`] finds apart (none of
    /// them meets the triangle).
    #[test]
    fn subtraction_leaves_the_triangle_less_its_intersection_with_the_hole() {
        use rand::{Rng, SeedableRng, rngs::StdRng};
        let mut rng = StdRng::seed_from_u64(11);
        let (mut cut_by_fewer_lines, mut apart) = (0, 0);
        for trial in 0..4000 {
            let mut point = |r: f64| DVec2::new(rng.random_range(-r..r), rng.random_range(-r..r));
            let triangle = {
                let t = [point(1.0), point(1.0), point(1.0)];
                let area = (t[1] - t[0]).perp_dot(t[2] - t[0]);
                if area.abs() < 1e-3 {
                    continue;
                }
                if area > 0.0 { t.to_vec() } else { vec![t[0], t[2], t[1]] }
            };
            let centre = point(1.0);
            let stretch = if trial % 2 == 0 { DVec2::new(1.0, 1.0) } else { DVec2::new(3.0, 0.05) };
            let corners: Vec<DVec2> = (0..6).map(|_| centre + point(0.8) * stretch).collect();
            let hole = convex_hull(&corners).to_vec();
            if hole.len() < 3 {
                continue;
            }
            let parts = subtract_convex(&triangle, &hole);
            let inside_hole =
                hole.iter().enumerate().try_fold(triangle.clone(), |part, (k, &a)| {
                    let line = HalfPlane::left_of(a, hole[(k + 1) % hole.len()]);
                    clip_convex(&part, &line).map(|c| c.to_vec())
                });
            let taken = inside_hole.as_deref().map_or(0.0, signed_area);
            if convex_apart(&triangle, &hole) {
                assert!(taken == 0.0, "{trial}: apart, yet {taken} of the hole in the triangle");
                apart += 1;
            }
            let left: f64 = parts.iter().map(|p| signed_area(p)).sum();
            let want = signed_area(&triangle) - taken;
            assert!((left - want).abs() < 1e-12, "{trial}: area {left} against {want}");
            for p in &parts {
                assert!(signed_area(p) > 0.0, "{trial}: {p:?}");
                let centroid = p.iter().copied().sum::<DVec2>() / p.len() as f64;
                assert!(strictly_inside(&triangle, centroid) && !strictly_inside(&hole, centroid));
            }
            let lines_crossing = (0..hole.len())
                .filter(|&k| {
                    let line = HalfPlane::left_of(hole[k], hole[(k + 1) % hole.len()]);
                    triangle.iter().any(|&x| line.eval(x) < 0.0)
                })
                .count();
            cut_by_fewer_lines += usize::from(taken > 0.0 && lines_crossing < hole.len());
        }
        assert!(cut_by_fewer_lines > 500, "{cut_by_fewer_lines} holes with lines passed over");
        assert!(apart > 200, "{apart} holes apart from the triangle");
    }

    #[test]
    fn subtracting_a_covering_hole_leaves_nothing() {
        let piece = square(0.2, 0.8);
        assert!(subtract_convex(&piece, &square(0.0, 1.0)).is_empty());
        assert_eq!(subtract_convex(&piece, &square(2.0, 3.0)), vec![piece.clone()]);
    }

    #[test]
    fn containment_includes_the_boundary() {
        let sq = square(0.0, 1.0);
        assert!(convex_contains(&sq, &[DVec2::new(1.0, 0.5)]));
        assert!(convex_contains(&sq, &[DVec2::new(0.5, 0.5)]));
        assert!(!convex_contains(&sq, &[DVec2::new(1.0 + 1e-9, 0.5)]));
        assert!(!convex_contains(&sq, &[DVec2::new(0.5, 0.5), DVec2::new(1.0 + 1e-9, 0.5)]));
    }

    #[test]
    fn clipping_in_3d_cuts_a_square_in_half() {
        let sq: Vec<DVec3> = square(0.0, 1.0).iter().map(|p| p.extend(1.0)).collect();
        let mut half = SmallPolygon::new();
        assert!(clip_polygon_3d(&sq, DVec3::X, -0.5, &mut half));
        let area2: f64 =
            (1..half.len() - 1).map(|k| (half[k] - half[0]).cross(half[k + 1] - half[0]).z).sum();
        assert!((0.5 * area2 - 0.5).abs() < 1e-15);
        assert!(!clip_polygon_3d(&sq, DVec3::X, -2.0, &mut half));
    }
}

/// Triangulates a simple polygon (convex or not) by ear clipping (the `earcut` crate); triangles are
/// returned as vertex indices, counter-clockwise. `None` if the polygon cannot be triangulated.
pub fn triangulate(poly: &[DVec2]) -> Option<Vec<[usize; 3]>> {
    let mut earcut = earcut::Earcut::new();
    let mut indices: Vec<u32> = Vec::new();
    earcut.earcut(poly.iter().map(|p| [p.x, p.y]), &[], &mut indices);
    if indices.is_empty() {
        return None;
    }
    Some(
        indices
            .chunks_exact(3)
            .map(|t| {
                let [a, b, c] = [t[0] as usize, t[1] as usize, t[2] as usize];
                if (poly[b] - poly[a]).perp_dot(poly[c] - poly[a]) >= 0.0 {
                    [a, b, c]
                } else {
                    [a, c, b]
                }
            })
            .collect(),
    )
}

/// Convex pieces of a simple polygon (convex or not), as counter-clockwise lists of vertex
/// indices: its triangles ([`triangulate`]), merged across a shared diagonal wherever the union
/// stays strictly convex (Hertel and Mehlhorn: at most four times the fewest pieces). An L-shaped
/// plate is two pieces instead of four triangles, so it casts two shadows. `None` if the polygon
/// cannot be triangulated.
pub fn convex_partition(poly: &[DVec2]) -> Option<Vec<Vec<usize>>> {
    let mut pieces: Vec<Vec<usize>> = triangulate(poly)?.into_iter().map(Vec::from).collect();
    let eps = ON_LINE * scale_of(poly);
    let strictly_convex = |piece: &[usize]| {
        let m = piece.len();
        (0..m).all(|k| {
            let (a, b, c) = (poly[piece[k]], poly[piece[(k + 1) % m]], poly[piece[(k + 2) % m]]);
            (b - a).perp_dot(c - b) > eps * ((b - a).length() + (c - b).length())
        })
    };
    // Piece a runs u -> v where piece b runs v -> u: the union runs around a from v to u, then
    // around b from u to v, the diagonal left out.
    let merged = |a: &[usize], b: &[usize]| -> Option<Vec<usize>> {
        let (m, n) = (a.len(), b.len());
        let k = (0..m).find(|&k| {
            let (u, v) = (a[k], a[(k + 1) % m]);
            (0..n).any(|l| b[l] == v && b[(l + 1) % n] == u)
        })?;
        let (u, v) = (a[k], a[(k + 1) % m]);
        let l = (0..n).find(|&l| b[l] == v)?;
        let union: Vec<usize> =
            (1..=m).map(|i| a[(k + i) % m]).chain((1..n - 1).map(|i| b[(l + 1 + i) % n])).collect();
        debug_assert!(union[0] == v && union[m - 1] == u);
        strictly_convex(&union).then_some(union)
    };
    // Each piece takes in the later ones it can, looking again at all of them after each
    // merge (quadratic in the number of triangles).
    let mut i = 0;
    while i < pieces.len() {
        let mut j = i + 1;
        while j < pieces.len() {
            match merged(&pieces[i], &pieces[j]) {
                Some(union) => {
                    pieces[i] = union;
                    pieces.swap_remove(j);
                    j = i + 1;
                }
                None => j += 1,
            }
        }
        i += 1;
    }
    Some(pieces)
}

#[cfg(test)]
mod triangulation_tests {
    use super::*;

    /// An L of three unit squares.
    fn l_shape() -> [DVec2; 6] {
        [
            DVec2::new(0.0, 0.0),
            DVec2::new(2.0, 0.0),
            DVec2::new(2.0, 1.0),
            DVec2::new(1.0, 1.0),
            DVec2::new(1.0, 2.0),
            DVec2::new(0.0, 2.0),
        ]
    }

    #[test]
    fn an_l_shape_is_two_convex_pieces_and_a_square_one() {
        let l = l_shape();
        let pieces = convex_partition(&l).unwrap();
        assert_eq!(pieces.len(), 2, "{pieces:?}");
        let polygons: Vec<Vec<DVec2>> =
            pieces.iter().map(|p| p.iter().map(|&k| l[k]).collect()).collect();
        let area: f64 = polygons.iter().map(|p| signed_area(p)).sum();
        assert!((area - 3.0).abs() < 1e-15, "{area}");
        for p in &polygons {
            let m = p.len();
            assert!((0..m).all(|k| (p[(k + 1) % m] - p[k]).perp_dot(p[(k + 2) % m] - p[k]) > 0.0));
        }
        let square = [DVec2::ZERO, DVec2::X, DVec2::ONE, DVec2::Y];
        assert_eq!(convex_partition(&square).unwrap().len(), 1);
    }

    #[test]
    fn an_l_shape_triangulates_into_four_ccw_triangles_of_total_area_three() {
        let l = l_shape();
        let tris = triangulate(&l).unwrap();
        assert_eq!(tris.len(), 4);
        let area: f64 = tris.iter().map(|t| signed_area(&t.map(|k| l[k]))).sum();
        assert!((area - 3.0).abs() < 1e-14);
        assert!(tris.iter().all(|t| signed_area(&t.map(|k| l[k])) > 0.0));
    }
}
