//! The planes T_i is cut along so that the integrand is smooth on every piece: where the visible
//! part of T_j changes shape (occluders' planes, vertex–edge events) and where T_j touches T_i.

use glam::DVec3;
use smallvec::SmallVec;

use crate::geometry::{self, PlaneFrame, SmallPolygon, bounding_box_3d};
use crate::visibility::PairPlanner;

/// Planes (normal, a point) through which the visible part of `target` changes shape as the
/// viewing point crosses them inside `viewer`: for each occluder, its own plane (seen from it the
/// occluder is an edge, and its shadow changes side); through a vertex of the target and an edge
/// of the occluder (EV: the viewer sees the vertex just past the edge), through an edge of the
/// target and a vertex of the occluder (VE), and between two occluders the same (a shadow's
/// corner crossing another shadow's edge), unless both bound one convex solid that may occlude
/// between `faces` (T_i's and T_j's). A vertex–edge event happens only where the viewer can
/// be on its plane: on the rays through the vertex and the edge on the side the event needs,
/// a segment of the viewing element (most planes miss it), and only the pieces that segment
/// reaches are cut along it. Curved (EEE) events between three mutually skew edges are not
/// among them.
pub(super) fn event_planes(
    viewer: &[DVec3; 3],
    target: &[DVec3; 3],
    occluders: &[usize],
    planner: &PairPlanner,
    faces: (usize, usize),
) -> Vec<Event> {
    let polygons: Vec<&[DVec3]> =
        occluders.iter().map(|&o| planner.occluders()[o].polygon.as_slice()).collect();
    let normals: Vec<DVec3> = occluders.iter().map(|&o| planner.occluders()[o].normal()).collect();
    let mut planes: Vec<Event> = normals
        .iter()
        .zip(&polygons)
        .map(|(&normal, polygon)| Event::across(normal, polygon[0]))
        .collect();
    let twins = EdgeTwins::new(&polygons, &normals);
    let solids: Vec<Option<usize>> =
        occluders.iter().map(|&o| planner.solid_between(o, faces.0, faces.1)).collect();
    let repeats = SolidRepeats::new(&polygons, &solids);
    // The vertices of one polygon against the edges of another; `None` is the target.
    let mut vertex_edge = |vertex_owner: Option<usize>, edge_owner: Option<usize>, side| {
        let corners = |owner: Option<usize>| owner.map_or(target.as_slice(), |o| polygons[o]);
        let (vertices, edges) = (corners(vertex_owner), corners(edge_owner));
        let m = edges.len();
        for (l, &v) in vertices.iter().enumerate() {
            if vertex_owner.is_some_and(|o| repeats.vertex(o, l)) {
                continue;
            }
            let reach = viewer.map(|x| x - v);
            for k in 0..m {
                if edge_owner.is_some_and(|o| repeats.edge(o, k)) {
                    continue;
                }
                let (e0, e1) = (edges[k], edges[(k + 1) % m]);
                let wedge = Wedge { apex: v, d1: e0 - v, d2: e1 - v };
                // The cheap tests first: most planes miss the viewer (in a city 97 % of them),
                // most edges of a solid are not on its outline from the vertex, and most
                // planes that cut the viewer miss the target.
                if wedge.may_cut(&reach)
                    && edge_owner.is_none_or(|o| twins.edge_may_outline(o, k, v))
                    && let Some(normal) = wedge.normal()
                    && cuts(normal, v, viewer)
                    && (!matches!(side, EventSide::Either) || cuts(normal, v, target))
                    && let Some(extent) = wedge.extent(viewer, side)
                    && vertex_owner.is_none_or(|o| twins.vertex_may_outline(o, l, e0, e1))
                {
                    planes.push(Event { normal, point: v, extent: Some(extent) });
                }
            }
        }
    };
    for k in 0..polygons.len() {
        // The viewer sees a target vertex past an occluder edge: beyond the edge from the vertex.
        vertex_edge(None, Some(k), EventSide::Beyond);
        // ... or an occluder vertex in front of a target edge: behind the vertex from the edge.
        vertex_edge(Some(k), None, EventSide::Behind);
        // Two shadows' corner and edge meet on T_j only if the plane of the three cuts T_j.
        for l in k + 1..polygons.len() {
            // Two faces of one convex solid have none: a line through a vertex of one and a
            // point of an edge of the other lies in a face's plane (that face's own event) or
            // passes through the solid, where neither is on its outline from the viewer. The
            // solids' faces make most of a city's pairs of occluders (tessellated city 5 x 5
            // without its sky at --tolerance 1e-6: the same .npz to the byte, for fewer cuts).
            if solids[k].is_some() && solids[k] == solids[l] {
                continue;
            }
            vertex_edge(Some(k), Some(l), EventSide::Either);
            vertex_edge(Some(l), Some(k), EventSide::Either);
        }
    }
    planes
}

/// How far past its ends, as a share of the viewing element's chord on its plane, an event's
/// segment is taken to reach. Where a segment ends (the vertex lines up with an end of the
/// edge) the integrand is not smooth in any direction, so every piece around that point must
/// have it as a corner, also where rounding puts the end on a piece's side: occluded box at the
/// default tolerance, reciprocity 2.5e-9 with the bare segments; with 0.02, 1.0e-9, as with
/// whole planes, which cut far more.
const END_MARGIN: f64 = 0.02;

/// A plane across which the integrand stops being smooth, and where on the viewing element it
/// does so.
pub(super) struct Event {
    /// The plane's unit normal and a point of it.
    pub(super) normal: DVec3,
    pub(super) point: DVec3,
    /// The segment of the viewing element where the event happens (a vertex–edge event happens
    /// only on the rays through its vertex and edge), or `None` across the whole element.
    pub(super) extent: Option<[DVec3; 2]>,
}

impl Event {
    /// The plane through `point` with unit normal `normal`, across the whole element.
    pub(super) fn across(normal: DVec3, point: DVec3) -> Self {
        Self { normal, point, extent: None }
    }

    /// Whether the event happens inside the convex planar polygon `piece` (unit normal
    /// `normal`), so that the piece must be cut along its plane: a piece its segment misses is
    /// smooth across the plane.
    pub(super) fn crosses(&self, piece: &[DVec3], normal: DVec3) -> bool {
        let Some([x1, x2]) = self.extent else { return true };
        let m = piece.len();
        let area = (0..m).map(|k| piece[k].cross(piece[(k + 1) % m])).sum::<DVec3>().dot(normal);
        // Inside edge k, with the piece's orientation: its value at x1 and at x2.
        let inside_edges = (0..m).map(|k| {
            let (a, b) = (piece[k], piece[(k + 1) % m]);
            let inside = |x: DVec3| (b - a).cross(x - a).dot(normal) * area.signum();
            (inside(x1), inside(x2))
        });
        // Rounding: a segment that only touches the piece's boundary leaves it whole.
        parameter_range(inside_edges, false).is_some_and(|(lo, hi)| {
            (hi - lo) * (x2 - x1).length() > 1e-12 * bounding_box_diameter(piece)
        })
    }
}

/// The range [lo, hi] of λ in [0, 1] where each constraint (c0, c1) holds, that is where the
/// linear function from c0 at 0 to c1 at 1 is not negative, if any: the part of a segment
/// inside a convex region. A segment that lies on a side's line (a constraint 0 at both ends) is
/// inside where `side_inside`, else outside.
fn parameter_range(
    constraints: impl IntoIterator<Item = (f64, f64)>,
    side_inside: bool,
) -> Option<(f64, f64)> {
    let (mut lo, mut hi) = (0.0f64, 1.0f64);
    for (c0, c1) in constraints {
        let slope = c1 - c0;
        if slope == 0.0 {
            if c0 < 0.0 || (c0 == 0.0 && !side_inside) {
                return None;
            }
        } else if slope > 0.0 {
            lo = lo.max(-c0 / slope);
        } else {
            hi = hi.min(-c0 / slope);
        }
    }
    (lo <= hi).then_some((lo, hi))
}

fn bounding_box_diameter(polygon: &[DVec3]) -> f64 {
    let (lo, hi) = bounding_box_3d(polygon);
    (hi - lo).length()
}

/// For each edge of the occluder polygons, the normal of another polygon among them that shares
/// it (a solid's neighbouring face, or the other convex piece of a non-convex face).
struct EdgeTwins<'a> {
    polygons: &'a [&'a [DVec3]],
    normals: &'a [DVec3],
    twins: Vec<Vec<Option<DVec3>>>,
}

impl<'a> EdgeTwins<'a> {
    fn new(polygons: &'a [&'a [DVec3]], normals: &'a [DVec3]) -> Self {
        let twins = polygons
            .iter()
            .enumerate()
            .map(|(a, p)| {
                (0..p.len())
                    .map(|k| {
                        let (u, v) = (p[k], p[(k + 1) % p.len()]);
                        polygons
                            .iter()
                            .enumerate()
                            .find_map(|(b, q)| (b != a && has_edge(q, u, v)).then_some(normals[b]))
                    })
                    .collect()
            })
            .collect();
        Self { polygons, normals, twins }
    }

    /// Whether edge `k` of polygon `o` can be on the outline of the occluders' shadow for a
    /// viewer on the plane through it and `apex` (away from the edge's line). The viewer's
    /// height over either polygon's plane is the apex's times one factor, the same for both,
    /// so unless the apex is in front of exactly one of the two polygons that share the edge,
    /// both face every such viewer the same way, the edge lies inside the shadow, and no event
    /// happens on that plane.
    fn edge_may_outline(&self, o: usize, k: usize, apex: DVec3) -> bool {
        let Some(twin) = self.twins[o][k] else { return true };
        let r = apex - self.polygons[o][k];
        let rounding = 1e-12 * r.length();
        let (own, other) = (r.dot(self.normals[o]), r.dot(twin));
        own.abs() <= rounding || other.abs() <= rounding || (own > 0.0) != (other > 0.0)
    }

    /// Whether vertex `k` of polygon `o` can be a corner of the shadow's outline for a viewer on
    /// the plane through it and a segment from `y0` to `y1` (on either side of the vertex). The
    /// viewer's height over each plane through the vertex is a multiple of some point's of the
    /// segment, one factor for all planes; so where every edge at the vertex is shared by two
    /// polygons among the occluders and the whole segment is in front of all of them, or behind
    /// all of them, every viewer on the plane sees all of them from one side, none of those
    /// edges is on the outline, and neither is the vertex.
    fn vertex_may_outline(&self, o: usize, k: usize, y0: DVec3, y1: DVec3) -> bool {
        let w = self.polygons[o][k];
        let rounding = 1e-12 * (y0 - w).length().max((y1 - w).length());
        let mut side = None;
        for (b, polygon) in self.polygons.iter().enumerate() {
            let m = polygon.len();
            let Some(l) = polygon.iter().position(|&x| x == w) else { continue };
            if self.twins[b][l].is_none() || self.twins[b][(l + m - 1) % m].is_none() {
                return true; // an edge at the vertex bounds the occluders
            }
            for y in [y0, y1] {
                let h = (y - w).dot(self.normals[b]);
                if h.abs() <= rounding || *side.get_or_insert(h > 0.0) != (h > 0.0) {
                    return true;
                }
            }
        }
        false
    }
}

/// For each occluder polygon, which of its vertices and edges an earlier polygon of the same
/// convex solid has too (a building's roof corner is a corner of three of its faces, each of its
/// upper edges an edge of two). The vertex–edge events through those are the earlier polygon's,
/// the same planes with the same segments (an edge's reversal only turns the normal), found
/// first; a second cut along a plane leaves the pieces whole or cuts off a sliver of rounding,
/// so they are looked for once: a repeated cut changes no entry beyond rounding. The pairs of
/// occluders that take one polygon or the other are skipped alike, since both bound the same
/// solid.
pub(super) struct SolidRepeats {
    vertices: Vec<u32>,
    edges: Vec<u32>,
}

impl SolidRepeats {
    pub(super) fn new(polygons: &[&[DVec3]], solids: &[Option<usize>]) -> Self {
        let mut repeats =
            Self { vertices: vec![0; polygons.len()], edges: vec![0; polygons.len()] };
        for (o, polygon) in polygons.iter().enumerate() {
            let Some(solid) = solids[o] else { continue };
            let m = polygon.len().min(32);
            let earlier = (0..o).filter(|&b| solids[b] == Some(solid)).map(|b| polygons[b]);
            for other in earlier {
                for k in 0..m {
                    let (u, v) = (polygon[k], polygon[(k + 1) % polygon.len()]);
                    repeats.vertices[o] |= u32::from(other.contains(&u)) << k;
                    repeats.edges[o] |= u32::from(has_edge(other, u, v)) << k;
                }
            }
        }
        repeats
    }

    pub(super) fn vertex(&self, o: usize, k: usize) -> bool {
        k < 32 && self.vertices[o] >> k & 1 == 1
    }

    pub(super) fn edge(&self, o: usize, k: usize) -> bool {
        k < 32 && self.edges[o] >> k & 1 == 1
    }
}

/// Whether the segment from `u` to `v` is an edge of `polygon`, either way round (faces of one
/// scene file share their vertices to the bit).
fn has_edge(polygon: &[DVec3], u: DVec3, v: DVec3) -> bool {
    let n = polygon.len();
    (0..n).any(|l| {
        let (x, y) = (polygon[l], polygon[(l + 1) % n]);
        (x == v && y == u) || (x == u && y == v)
    })
}

/// Whether the plane through `point` with `normal` has corners of `polygon` strictly on both
/// sides.
fn cuts(normal: DVec3, point: DVec3, polygon: &[DVec3]) -> bool {
    let h = polygon.iter().map(|&x| normal.dot(x - point));
    h.clone().any(|x| x > 0.0) && h.into_iter().any(|x| x < 0.0)
}

/// Which rays through a vertex and an edge an event needs the viewer on.
#[derive(Clone, Copy)]
enum EventSide {
    /// Beyond the edge, seen from the vertex: `apex + s (x - apex)`, s >= 1, x on the edge.
    Beyond,
    /// Behind the vertex, seen from the edge: `apex + s (apex - x)`, s >= 0.
    Behind,
    /// Either (two occluders: whichever is nearer the viewer).
    Either,
}

/// The plane through a vertex `apex` and an edge `apex + d1`, `apex + d2`.
struct Wedge {
    apex: DVec3,
    d1: DVec3,
    d2: DVec3,
}

impl Wedge {
    /// Whether the plane may have some of the points `apex + reach` strictly on either side:
    /// false only where all of them are on one side by far more than rounding, so that
    /// [`cuts`] with the unit normal says the same. No square root: most planes are settled
    /// here.
    fn may_cut(&self, reach: &[DVec3]) -> bool {
        let n = self.d1.cross(self.d2);
        let margin = 1e-18 * n.length_squared();
        let (mut above, mut below) = (false, false);
        for &r in reach {
            let h = n.dot(r);
            if h * h <= margin * r.length_squared() {
                return true;
            }
            above |= h > 0.0;
            below |= h < 0.0;
        }
        above && below
    }

    fn normal(&self) -> Option<DVec3> {
        let n = self.d1.cross(self.d2);
        (n.length_squared() > 0.0).then(|| n.normalize())
    }

    /// The segment where the region of the plane on `side` cuts the convex polygon `viewer`
    /// (which must straddle the plane for the plane to split it at all), if it does.
    fn extent(&self, viewer: &[DVec3], side: EventSide) -> Option<[DVec3; 2]> {
        let n = self.d1.cross(self.d2);
        let h: SmallVec<[f64; 4]> = viewer.iter().map(|&x| n.dot(x - self.apex)).collect();
        let m = viewer.len();
        // The segment where the plane cuts the viewer: the crossings of its edges.
        let crossings: SmallVec<[DVec3; 4]> = (0..m)
            .filter(|&k| (h[k] < 0.0) != (h[(k + 1) % m] < 0.0))
            .map(|k| {
                let (a, b) = (viewer[k], viewer[(k + 1) % m]);
                a + (b - a) * (h[k] / (h[k] - h[(k + 1) % m]))
            })
            .collect();
        let [x1, x2] = match crossings[..] {
            [x1, x2] => [x1, x2],
            _ => return None,
        };
        // Coordinates (α, β) of x - apex = α d1 + β d2 along the segment x1 + λ (x2 - x1).
        let nn = n.length_squared();
        let coords = |x: DVec3| {
            let r = x - self.apex;
            (r.cross(self.d2).dot(n) / nn, self.d1.cross(r).dot(n) / nn)
        };
        let ((a1, b1), (a2, b2)) = (coords(x1), coords(x2));
        let admits =
            |constraints: &[(f64, f64)]| parameter_range(constraints.iter().copied(), true);
        let beyond = || admits(&[(a1, a2), (b1, b2), (a1 + b1 - 1.0, a2 + b2 - 1.0)]);
        let behind = || admits(&[(-a1, -a2), (-b1, -b2)]);
        let (lo, hi) = match side {
            EventSide::Beyond => beyond()?,
            EventSide::Behind => behind()?,
            // The two regions are apart on the chord: the span of both covers them.
            EventSide::Either => match (beyond(), behind()) {
                (Some((l1, h1)), Some((l2, h2))) => (l1.min(l2), h1.max(h2)),
                (one, other) => one.or(other)?,
            },
        };
        let (lo, hi) = ((lo - END_MARGIN).max(0.0), (hi + END_MARGIN).min(1.0));
        Some([x1 + (x2 - x1) * lo, x1 + (x2 - x1) * hi])
    }
}

/// Where T_j touches T_i (frame `frame_i`) at one of its corners, T_i is cut across: the
/// integrand has a log singularity along the contact and jumps where the contact ends, and the
/// tanh-sinh rule of a touching triangle resolves such points at its corners, not inside its
/// sides (a ceiling tile along part of a wall element's top edge: reciprocity 4e-3 without).
/// Each corner of T_j on T_i gets the plane through it across each edge of T_j that lies in
/// T_i's plane from it (the contact's end), or across both of T_i's axes where none does (a
/// point contact). An edge of T_i that lies in T_j's plane touches T_j along the part inside
/// it, which ends where an edge of T_j crosses it: T_i is cut across that edge there (a
/// partition standing on a floor element whose diagonal passes under it: F_ij 3.4e-4 off
/// while its estimate said 1e-6 before). Each cut is across the whole element.
pub(super) fn contact_cuts(
    (ti, frame_i): (&[DVec3; 3], &PlaneFrame),
    (tj, frame_j): (&[DVec3; 3], &PlaneFrame),
    tol: f64,
) -> Vec<Event> {
    let on_plane = |v: DVec3| frame_i.height(v).abs() <= tol;
    let local = ti.map(|v| frame_i.to_local(v).truncate());
    let orientation = (local[1] - local[0]).perp_dot(local[2] - local[0]).signum();
    let on_ti = |v: DVec3| {
        let p = frame_i.to_local(v).truncate();
        (0..3).all(|k| {
            let (a, b) = (local[k], local[(k + 1) % 3]);
            (b - a).perp_dot(p - a) * orientation >= -tol * (b - a).length()
        })
    };
    let mut cuts = Vec::new();
    for (k, &v) in tj.iter().enumerate() {
        if !on_plane(v) || !on_ti(v) {
            continue;
        }
        let before = cuts.len();
        for w in [tj[(k + 1) % 3], tj[(k + 2) % 3]] {
            if on_plane(w) {
                let d = w - v;
                let along = d - frame_i.normal * d.dot(frame_i.normal);
                cuts.push(Event::across(along.normalize(), v));
            }
        }
        if cuts.len() == before {
            cuts.extend([Event::across(frame_i.e1, v), Event::across(frame_i.e2, v)]);
        }
    }
    let on_plane_j = |v: DVec3| frame_j.height(v).abs() <= tol;
    let in_j = |v: DVec3| frame_j.to_local(v).truncate();
    for k in 0..3 {
        let (a, b) = (ti[k], ti[(k + 1) % 3]);
        if !on_plane_j(a) || !on_plane_j(b) {
            continue;
        }
        let (pa, pb) = (in_j(a), in_j(b));
        let (along, length) = (pb - pa, (pb - pa).length());
        for m in 0..3 {
            let (pc, pd) = (in_j(tj[m]), in_j(tj[(m + 1) % 3]));
            let across = pd - pc;
            let denominator = along.perp_dot(across);
            if denominator.abs() <= tol * length * across.length() {
                continue; // parallel: no crossing that ends the contact
            }
            let s = (pc - pa).perp_dot(across) / denominator;
            let t = (pc - pa).perp_dot(along) / denominator;
            let (inside_edge, margin) = (tol / length, tol / across.length());
            if s > inside_edge && s < 1.0 - inside_edge && (-margin..=1.0 + margin).contains(&t) {
                cuts.push(Event::across((b - a).normalize(), a + (b - a) * s));
            }
        }
    }
    cuts
}

/// The mean of a polygon's corners (inside it, for a convex one).
pub(super) fn centroid(poly: &[DVec3]) -> DVec3 {
    poly.iter().copied().sum::<DVec3>() / poly.len() as f64
}

/// The parts of the convex planar polygon `poly` on either side of a plane (those with area),
/// or `None` where the plane leaves it whole on one side (most planes do, beyond the tolerance
/// of the clip, which would keep it whole on that side and drop it on the other).
pub(super) fn split(poly: &[DVec3], normal: DVec3, point: DVec3) -> Option<Vec<Vec<DVec3>>> {
    let offset = -normal.dot(point);
    let (lo, hi) = bounding_box_3d(poly);
    let scale = (hi - lo).length();
    if geometry::wholly_inside_3d(poly, normal, offset, scale)
        || geometry::wholly_inside_3d(poly, -normal, -offset, scale)
    {
        return None;
    }
    Some(
        [clip_polygon_3d(poly, normal, offset), clip_polygon_3d(poly, -normal, -offset)]
            .into_iter()
            .flatten()
            .collect(),
    )
}

/// The convex planar polygon clipped to `normal·x + offset >= 0`, if anything with area is left.
pub(super) fn clip_polygon_3d(poly: &[DVec3], normal: DVec3, offset: f64) -> Option<Vec<DVec3>> {
    let mut out = SmallPolygon::new();
    geometry::clip_polygon_3d(poly, normal, offset, &mut out).then(|| out.into_vec())
}

#[cfg(test)]
mod tests {
    use glam::DVec3;
    use rand::{Rng, SeedableRng, rngs::StdRng};

    use super::super::tests::Fixture;
    use super::{Event, Wedge, cuts, event_planes};

    /// Wherever `Wedge::may_cut` settles a plane without its unit normal, `cuts` with the unit
    /// normal says the same; triangles within rounding of the plane are never settled.
    #[test]
    fn planes_settled_without_the_unit_normal_miss_the_polygon() {
        let mut rng = StdRng::seed_from_u64(7);
        let mut next = move || rng.random_range(-0.5..0.5);
        let mut settled = 0;
        for trial in 0..20_000 {
            let apex = DVec3::new(next(), next(), next()) * 10.0;
            let (d1, d2) = (DVec3::new(next(), next(), next()), DVec3::new(next(), next(), next()));
            let wedge = Wedge { apex, d1, d2 };
            let normal = wedge.normal().unwrap();
            // Points of the plane lifted off it by heights of rounding or of the triangle's size.
            let lift = if trial % 2 == 0 { 1e-15 } else { 1.0 };
            let triangle: [DVec3; 3] = std::array::from_fn(|_| {
                apex + 3.0 * (d1 * next() + d2 * next()) + normal * (lift * next())
            });
            let reach = triangle.map(|x| x - apex);
            if wedge.may_cut(&reach) {
                continue;
            }
            assert!(lift == 1.0, "settled within rounding: {triangle:?}");
            assert!(!cuts(normal, apex, &triangle), "{trial}: {triangle:?}");
            settled += 1;
        }
        assert!(settled > 1_000, "{settled} settled");
    }

    /// A city's buildings are convex solids whose roof corners are corners of three of their
    /// faces and whose upper edges are edges of two: each vertex–edge event is still found once.
    #[test]
    fn a_city_s_vertex_edge_events_are_found_once() {
        let fixture = Fixture::new(crate::scene::city(3, 2).unwrap());
        let elements = fixture.mesh.elements();
        let mut found = 0;
        for (i, j, occluders) in fixture.pairs_among_occluders(3) {
            let (ei, ej) = (&elements[i], &elements[j]);
            let faces = (ei.face, ej.face);
            let events =
                event_planes(&ei.vertices, &ej.vertices, &occluders, &fixture.planner, faces);
            // Those through a corner of the occluders (a corner of T_j may be one too, as where
            // a ground triangle's corner is a building's).
            let at_occluders = |e: &&Event| {
                e.extent.is_some()
                    && !ei.vertices.contains(&e.point)
                    && !ej.vertices.contains(&e.point)
            };
            let segments: Vec<_> = events.iter().filter(at_occluders).collect();
            for (a, x) in segments.iter().enumerate() {
                let same = |y: &&&Event| {
                    x.point == y.point
                        && (x.normal == y.normal || x.normal == -y.normal)
                        && x.extent == y.extent
                };
                assert!(
                    !segments[a + 1..].iter().any(|y| same(&y)),
                    "pair ({i}, {j}): {:?}",
                    x.point
                );
            }
            found += segments.len();
        }
        assert!(found > 500, "{found} vertex–edge events");
    }
}
