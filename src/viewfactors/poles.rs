//! The poles of a piece's integrand: the planes where a corner of the visible part of T_j, made by
//! an occluder's shadow, runs off to infinity. Their distance bounds the Gauss order a patch needs.

use glam::{DVec2, DVec3};
use smallvec::SmallVec;

use super::events::{SolidRepeats, centroid};
use crate::geometry::PlaneFrame;
use crate::visibility::PairPlanner;

/// Where the integrand over a piece of T_i (unit normal `ni`, corners `piece`) stops being
/// analytic, besides T_j (frame `frame_j`, vertices `target`): a corner of the visible part of
/// T_j that is the shadow of an occluder vertex runs off to infinity where the viewer is level
/// with that vertex (over T_j's plane), and one where a shadow edge cuts an edge of T_j where the
/// two become parallel. Each happens on a plane, so on a line of T_i's plane; a piece that such
/// a line crosses does not have that corner (it would cross an event plane first). Only the
/// corners the piece has count: whether a vertex's shadow falls in T_j, or a shadow edge cuts
/// an edge of T_j within both, changes only across the event planes the piece was cut along, so
/// it is decided at the piece's centroid (a corner within rounding of existing counts). An
/// occluder edge that reaches behind T_j's plane, or up to the viewer's level over it, shadows
/// only with its part between the two (a segment, or a ray where it reaches the level: a
/// partition standing on T_i); where that part ends moves with the viewer, so such an edge's
/// corners are looked for from the piece's corners too (from the centroid alone, a louvre's
/// slat beside a jamb missed the jamb edge's corner on the floor, and an entry was 7.3e-8 off
/// at --tolerance 1e-8). A vertex behind T_j's plane or above the viewer's level makes no
/// corner: it bounds no shadow edge that crosses T_j, and counting it would add poles, and
/// evaluations, without changing an entry. A shadow edge that turns about a point that stays
/// put crosses an edge of T_j through that point only, and makes no pole: an occluder edge in
/// T_i's plane (a wall's foot, seen from the ground), or one whose line meets T_j's plane on
/// the line of T_j's edge; nor does a viewer on a pole count where the shadow there runs
/// beside T_j's edge, not along it. Counting them would put poles along the sides of ground
/// triangles at buildings' corners and send those triangles to the costlier tanh-sinh rule.
/// A corner or an edge that several faces of one convex solid share makes its poles once
/// ([`SolidRepeats`]): they depend on the corner or the edge alone. `faces`: T_i's and T_j's.
/// Returns each plane's unit normal, a point and the sine of its angle with T_i's plane.
pub(super) fn poles(
    ni: DVec3,
    piece: &[DVec3],
    frame_j: &PlaneFrame,
    target: &[DVec3; 3],
    occluders: &[usize],
    planner: &PairPlanner,
    faces: (usize, usize),
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
    // From the centroid first, then from the corners.
    let viewers = std::iter::once(centroid(piece)).chain(piece.iter().copied());
    let seen: SmallVec<[ShadowCorners; 8]> =
        viewers.map(|viewer| ShadowCorners::new(viewer, frame_j, target)).collect();
    let from_centroid = &seen[0];
    let polygons: Vec<&[DVec3]> =
        occluders.iter().map(|&o| planner.occluders()[o].polygon.as_slice()).collect();
    let solids: Vec<Option<usize>> =
        occluders.iter().map(|&o| planner.solid_between(o, faces.0, faces.1)).collect();
    let repeats = SolidRepeats::new(&polygons, &solids);
    for (o, polygon) in polygons.iter().enumerate() {
        let m = polygon.len();
        let shadows: SmallVec<[Option<DVec2>; 8]> =
            polygon.iter().map(|&v| from_centroid.shadow(v)).collect();
        for k in 0..m {
            if !repeats.vertex(o, k) && from_centroid.vertex_corner(shadows[k], polygon[k]) {
                pole(frame_j.normal, polygon[k]);
            }
            if repeats.edge(o, k) {
                continue;
            }
            let (a, b) = (polygon[k], polygon[(k + 1) % m]);
            // From every viewer on T_i, an edge in T_i's plane (a wall's foot) casts the line
            // where T_i's plane meets T_j's: it does not turn, and crosses each edge of T_j at
            // one point or nowhere.
            let rounding = 1e-12 * (a.distance(b) + a.distance(piece[0]));
            if [a, b].iter().all(|&x| ni.dot(x - piece[0]).abs() <= rounding) {
                continue;
            }
            // Every shadow of the edge's line passes through the point where that line meets
            // T_j's plane (an edge parallel to the plane has none: its shadow runs off whole
            // where the viewer is level with it). Where that point lies on the line of T_j's
            // edge l, the shadow crosses the edge's line there, from every viewer: the crossing
            // stays put instead of running off (a roof's edge whose line meets a wall on the
            // line of the wall element's side).
            let (ha, hb) = (frame_j.height(a), frame_j.height(b));
            let pivot = (ha != hb).then(|| frame_j.to_local(a + (b - a) * (ha / (ha - hb))));
            let whole = shadows[k].is_some() && shadows[(k + 1) % m].is_some();
            let viewing = if whole { &seen[..1] } else { &seen[..] };
            for l in 0..3 {
                if pivot.is_some_and(|x| from_centroid.on_edge_line(x.truncate(), l)) {
                    continue;
                }
                if viewing.iter().any(|s| s.edge_corner(a, b, l)) {
                    pole((b - a).cross(target[(l + 1) % 3] - target[l]), a);
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
    /// T_j's longest side.
    size: f64,
    /// How far outside T_j a shadow corner still counts, as a side's cross product: each is
    /// the side's length times the distance from it, so T_j's size squared times the margin.
    margin: f64,
}

/// Within this fraction of T_j's size (or of a segment's length) a shadow corner counts as on
/// T_j: a corner that rounding puts just outside keeps its pole.
const CORNER_MARGIN: f64 = 1e-6;

/// Within this fraction of T_j's size a point where an occluder edge's line meets T_j's plane
/// counts as on the line of an edge of T_j (only rounding puts it off a line it lies on: a
/// crossing that runs off to infinity from a point that near makes a pole too weak to matter).
const PIVOT_ON_LINE: f64 = 1e-9;

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
            size,
            margin: CORNER_MARGIN * size * size,
        }
    }

    /// Where `v` casts its shadow on T_j's plane, if it lies strictly between the viewer and
    /// that plane (otherwise its shadow is at infinity or behind: unknown, so every corner of it
    /// counts).
    fn shadow(&self, v: DVec3) -> Option<DVec2> {
        let h = self.frame.height(v);
        (h > 0.0 && h < self.height).then(|| self.project(v, h))
    }

    /// Where the line from the viewer through `x`, at height `h` over T_j's plane (below the
    /// viewer's), meets that plane, in T_j's local coordinates.
    fn project(&self, x: DVec3, h: f64) -> DVec2 {
        let p = self.viewer + (x - self.viewer) * (self.height / (self.height - h));
        self.frame.to_local(p).truncate()
    }

    /// Whether the vertex `v`, with this shadow, can be a corner of the visible part: its
    /// shadow falls in T_j. A vertex behind T_j's plane never is (its edges' crossings of the
    /// plane are, which stay put); nor is one above the viewer's level, on this piece: its
    /// shadow comes from infinity where the viewer passes that level, and enters T_j only
    /// across an event plane. One on either plane counts, for rounding.
    fn vertex_corner(&self, shadow: Option<DVec2>, v: DVec3) -> bool {
        let h = self.frame.height(v);
        if h < 0.0 || h > self.height {
            return false;
        }
        let Some(p) = shadow else { return true };
        let [a, b, c] = self.corners;
        let side = |u: DVec2, w: DVec2| (w - u).perp_dot(p - u) * self.orientation;
        side(a, b) >= -self.margin && side(b, c) >= -self.margin && side(c, a) >= -self.margin
    }

    /// T_j's edge `l` (from corner `l` to `l + 1`): its start and its direction, in T_j's plane.
    fn side(&self, l: usize) -> (DVec2, DVec2) {
        (self.corners[l], self.corners[(l + 1) % 3] - self.corners[l])
    }

    /// Whether the point `x` of T_j's plane (local coordinates) lies on the line of T_j's edge
    /// `l`, within rounding of T_j's size.
    fn on_edge_line(&self, x: DVec2, l: usize) -> bool {
        let (c, e) = self.side(l);
        e.perp_dot(x - c).abs() <= PIVOT_ON_LINE * self.size * e.length()
    }

    /// Whether the shadow of the occluder edge from `a` to `b` can cut T_j's edge `l` (from
    /// corner `l` to `l + 1`): the shadow of its part in front of T_j's plane and short of the
    /// viewer's level over it (a part behind either hides nothing) meets that edge. Where the
    /// part reaches the viewer's level (a partition standing on T_i's plane, parallel to T_j),
    /// its shadow is a ray, to infinity along the direction from the viewer to that point.
    fn edge_corner(&self, a: DVec3, b: DVec3, l: usize) -> bool {
        let (ha, hb, level) = (self.frame.height(a), self.frame.height(b), self.height);
        if ha < 0.0 && hb < 0.0 || ha >= level && hb >= level {
            return false;
        }
        let at = |h: f64| a + (b - a) * ((h - ha) / (hb - ha));
        let in_front = |x: DVec3, h: f64| if h < 0.0 { at(0.0) } else { x };
        let (a, b) = (in_front(a, ha), in_front(b, hb));
        let project = |x: DVec3| self.project(x, self.frame.height(x).max(0.0));
        // The shadow: from p along d, for r in [0, 1] (a segment) or r >= 0 (a ray).
        let (p, d, ray) = if ha >= level || hb >= level {
            let (finite, to_level) = if ha >= level { (b, at(level)) } else { (a, at(level)) };
            let d = self.frame.dir_to_local(to_level - self.viewer).truncate();
            if d.length_squared() == 0.0 {
                return true; // the edge through the viewer
            }
            (project(finite), d, true)
        } else {
            let p = project(a);
            (p, project(b) - p, false)
        };
        let (c, e) = self.side(l);
        let det = d.perp_dot(e);
        let w = c - p;
        if det.abs() <= 1e-12 * d.length() * e.length() {
            // Parallel here, the viewer on the pole itself: the shadow meets the edge only
            // along its line, and from viewers nearby it crosses that line far off, outside T_j.
            if w.perp_dot(d).abs() > CORNER_MARGIN * d.length() * e.length() {
                return false;
            }
            let along = |x: DVec2| (x - c).dot(e) / e.length_squared();
            let (s0, s1) = (along(p), along(p + d));
            let (lo, hi) = match (ray, s1 >= s0) {
                (false, _) => (s0.min(s1), s0.max(s1)),
                (true, true) => (s0, f64::INFINITY),
                (true, false) => (f64::NEG_INFINITY, s0),
            };
            return lo <= 1.0 + CORNER_MARGIN && hi >= -CORNER_MARGIN;
        }
        let (r, s) = (w.perp_dot(e) / det, w.perp_dot(d) / det);
        let within = |t: f64| (-CORNER_MARGIN..=1.0 + CORNER_MARGIN).contains(&t);
        (r >= -CORNER_MARGIN && (ray || r <= 1.0 + CORNER_MARGIN)) && within(s)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::{Face, Scene};
    use rand::{Rng, SeedableRng, rngs::StdRng};

    /// The poles that `poles` finds on the ground (T_i, the piece) for the element `target`
    /// among one occluder `polygon`.
    fn poles_among(target: [DVec3; 3], polygon: &[DVec3]) -> Vec<(DVec3, DVec3, f64)> {
        let v = |x: f64, y: f64| DVec3::new(x, y, 0.0);
        let ground = vec![v(0.0, 0.0), v(12.0, 0.0), v(0.0, 12.0)];
        let faces = vec![
            Face::new("ground", ground.clone(), 0.5).unwrap(),
            Face::new("element", target.to_vec(), 0.5).unwrap(),
            Face::new("occluder", polygon.to_vec(), 0.5).unwrap(),
        ];
        let scene = Scene::new("poles", faces).unwrap();
        let planner = PairPlanner::new(&scene);
        let occluders: Vec<usize> = (0..planner.occluders().len())
            .filter(|&o| planner.occluders()[o].polygon.iter().all(|x| polygon.contains(x)))
            .collect();
        assert!(!occluders.is_empty());
        let frame = &scene.faces[1].frame;
        poles(DVec3::Z, &ground, frame, &target, &occluders, &planner, (0, 1))
    }

    /// Whether a pole's line in the ground's plane is the line y = 5 there.
    fn on_the_line_y_5(&(m, point, _): &(DVec3, DVec3, f64)) -> bool {
        m.x.abs() < 1e-12 && m.dot(DVec3::new(0.0, 5.0, 0.0) - point).abs() < 1e-12
    }

    /// Edges whose shadows turn about a point that stays put make no pole. A wall segment
    /// standing on the ground (T_i) along y = 5, T_j a wall element at x = -4 that reaches
    /// below the ground: from every viewer on the ground the segment's foot casts the line
    /// where the ground meets T_j's plane, which crosses T_j's side at one point. And a slat
    /// whose edge leaves T_j's vertical side (y = 5) at a point: its shadow turns about that
    /// point, where it crosses the side. The formula for a shadow edge parallel to T_j's side
    /// would put a pole on the line y = 5 for each (it did before both were left out).
    #[test]
    fn edges_whose_shadows_turn_about_a_fixed_point_make_no_poles() {
        let v = |x: f64, y: f64, z: f64| DVec3::new(x, y, z);
        let reaching_below = [v(-4.0, 2.0, -3.0), v(-4.0, 12.0, -3.0), v(-4.0, 7.0, 6.0)];
        let segment = [v(2.0, 5.0, 0.0), v(6.0, 5.0, 0.0), v(6.0, 5.0, 3.0), v(2.0, 5.0, 3.0)];
        let found = poles_among(reaching_below, &segment);
        assert!(!found.iter().any(on_the_line_y_5), "{found:?}");
        // The segment's top corners keep the poles of their level.
        let levels = found.iter().filter(|(m, _, _)| m.cross(DVec3::X).length() < 1e-12);
        assert!(levels.count() >= 2, "{found:?}");
        let upright = [v(-4.0, 5.0, 0.0), v(-4.0, 9.0, 0.0), v(-4.0, 5.0, 6.0)];
        let slat = [v(-4.0, 5.0, 2.5), v(2.0, 5.0, 4.0), v(2.0, 7.0, 4.0), v(-4.0, 7.0, 2.5)];
        let found = poles_among(upright, &slat);
        assert!(!found.iter().any(on_the_line_y_5), "{found:?}");
        assert!(!found.is_empty());
    }

    /// Where the viewer is on an edge's pole, its shadow is parallel to T_j's edge: it meets
    /// the edge only where it runs along the edge's line over part of it. T_j lies in z = 0 with
    /// side 0 along x; each occluder edge rises from height 1 to 3 past the viewer's level 2,
    /// so its shadow is a ray from its lower end's, along x.
    #[test]
    fn a_shadow_parallel_to_an_edge_meets_it_only_along_its_line() {
        let target = [DVec3::ZERO, DVec3::new(4.0, 0.0, 0.0), DVec3::new(0.0, 4.0, 0.0)];
        let frame = PlaneFrame::new(DVec3::ZERO, DVec3::Z, DVec3::X);
        // A ray along y = -3, off side 0's line.
        let off = ShadowCorners::new(DVec3::new(1.0, -3.0, 2.0), &frame, &target);
        assert!(!off.edge_corner(DVec3::new(1.0, -3.0, 1.0), DVec3::new(5.0, -3.0, 3.0), 0));
        // A ray along y = 0 from x = 1: along side 0.
        let on = ShadowCorners::new(DVec3::new(-1.0, 0.0, 2.0), &frame, &target);
        assert!(on.edge_corner(DVec3::new(0.0, 0.0, 1.0), DVec3::new(4.0, 0.0, 3.0), 0));
        // From x = 6.5: on side 0's line, past its end.
        assert!(!on.edge_corner(DVec3::new(2.75, 0.0, 1.0), DVec3::new(4.0, 0.0, 3.0), 0));
    }

    /// Whether the polyline through `points` meets the segment from `c` to `d`.
    fn polyline_meets(points: &[DVec2], c: DVec2, d: DVec2) -> bool {
        let side = |p: DVec2, q: DVec2, x: DVec2| (q - p).perp_dot(x - p);
        points.windows(2).any(|w| {
            let (p, q) = (w[0], w[1]);
            side(p, q, c) * side(p, q, d) < 0.0 && side(c, d, p) * side(c, d, q) < 0.0
        })
    }

    /// An occluder edge's shadow cuts an edge of T_j (the floor) where the shadows of points
    /// sampled along its part between the floor and the viewer's level cross it: edges that
    /// reach below the floor, or up to the viewer's level and past it (a ray to infinity), or
    /// both. Where the sampled shadow crosses the edge shortened by 1e-3 at either end, from
    /// 1e-2 over the floor, a corner must be found; where it misses the edge lengthened by 1e-3
    /// at either end, none.
    #[test]
    fn an_edge_s_shadow_cuts_t_j_s_edges_where_sampled_shadows_of_its_points_do() {
        let target = [DVec3::ZERO, DVec3::new(4.0, 0.0, 0.0), DVec3::new(0.0, 4.0, 0.0)];
        let frame = PlaneFrame::new(DVec3::ZERO, DVec3::Z, DVec3::X);
        let mut rng = StdRng::seed_from_u64(7);
        let (mut found, mut missed, mut rays) = (0, 0, 0);
        for _ in 0..2000 {
            let level = 1.5;
            let viewer =
                DVec3::new(rng.random_range(-1.0..5.0), rng.random_range(-1.0..5.0), level);
            let mut point = || {
                let xy = (rng.random_range(-2.0..6.0), rng.random_range(-2.0..6.0));
                DVec3::new(xy.0, xy.1, rng.random_range(-1.0..3.0))
            };
            let (a, b) = (point(), point());
            let seen = ShadowCorners::new(viewer, &frame, &target);
            let shadows = |from: f64| -> Vec<DVec2> {
                (0..=100_000)
                    .map(|k| a + (b - a) * (k as f64 / 100_000.0))
                    .filter(|x| x.z >= from && x.z < level)
                    .map(|x| {
                        let p = viewer + (x - viewer) * (level / (level - x.z));
                        DVec2::new(p.x, p.y)
                    })
                    .collect()
            };
            let (strict, loose) = (shadows(1e-2), shadows(0.0));
            rays += usize::from(a.z.max(b.z) >= level && a.z.min(b.z) < level);
            for l in 0..3 {
                let (c, d) = (target[l].truncate(), target[(l + 1) % 3].truncate());
                let along = (d - c) * 1e-3 / (d - c).length();
                let exact = seen.edge_corner(a, b, l);
                if polyline_meets(&strict, c + along, d - along) {
                    assert!(exact, "missed: viewer {viewer}, edge {a} -> {b}, side {l}");
                    found += 1;
                } else if !polyline_meets(&loose, c - along, d + along) {
                    assert!(!exact, "extra: viewer {viewer}, edge {a} -> {b}, side {l}");
                    missed += 1;
                }
            }
        }
        assert!(found > 300 && missed > 300 && rays > 300, "{found} {missed} {rays}");
    }

    /// On a city, whose buildings' roof corners are corners of three of their faces and whose
    /// upper edges are edges of two, the poles among all of a pair's occluders lie on the
    /// planes of each occluder's own, and on all of them, with fewer repeats.
    #[test]
    fn a_city_s_shared_corners_and_edges_make_the_same_poles_fewer_times() {
        let fixture = super::super::tests::Fixture::new(crate::scene::city(3, 2).unwrap());
        let (scene, elements) = (&fixture.scene, fixture.mesh.elements());
        let same = |&(m, p, _): &(DVec3, DVec3, f64), &(q, r, _): &(DVec3, DVec3, f64)| {
            m.cross(q).length() < 1e-12 && m.dot(r - p).abs() < 1e-9 * (1.0 + p.length())
        };
        let (mut together, mut alone) = (0, 0);
        for (i, j, occluders) in fixture.pairs_among_occluders(5) {
            let (ei, ej) = (&elements[i], &elements[j]);
            let (ni, frame_j) = (scene.faces[ei.face].frame.normal, &scene.faces[ej.face].frame);
            let faces = (ei.face, ej.face);
            let among = |occluders: &[usize]| {
                let planner = &fixture.planner;
                poles(ni, &ei.vertices, frame_j, &ej.vertices, occluders, planner, faces)
            };
            let all = among(&occluders);
            let each: Vec<_> = occluders.iter().flat_map(|&o| among(&[o])).collect();
            assert!(each.iter().all(|x| all.iter().any(|y| same(x, y))), "pair ({i}, {j})");
            assert!(all.iter().all(|x| each.iter().any(|y| same(x, y))), "pair ({i}, {j})");
            (together, alone) = (together + all.len(), alone + each.len());
        }
        assert!(together > 100 && 10 * together < 9 * alone, "{together} against {alone}");
    }
}
