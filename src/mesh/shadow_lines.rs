//! Shadow lines for automatic discontinuity meshing: on each receiving face, the lines where the
//! visibility of a source face changes (the paper's sec. 2.6, where u is not smooth). For a source
//! S, an occluder piece O between S and the receiver R, they are
//!
//! - EV events: the central projection onto R of an edge of O from a vertex of S, and
//! - VE events: the projection onto R of an edge of S through a vertex of O,
//!
//! each clipped to R. On the paper's 4-piece surface they are x, y = 2B - C and 2B on S1 (S4 seen
//! past the square S2/S3). Lines may be kept as segments (where the events are) or extended across
//! the face to chords (the paper's mesh, whose cuts run across S1).

use glam::{DVec2, DVec3};

use crate::geometry::polygon_contains;
use crate::scene::{Face, Scene};
use crate::visibility::PairPlanner;

/// Which faces count as sources of light.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Sources {
    /// Faces with E > 0 (all faces if none emits).
    Emitting,
    /// Every face (a true solution is known everywhere, as in the paper's test problems).
    All,
}

crate::vocabulary::named_options! {
    /// How far a shadow line of `--mesh auto-discontinuity` reaches.
    #[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
    #[serde(rename_all = "kebab-case")]
    pub enum LineExtent as "shadow-lines" {
        /// Only where the visibility events are (far fewer elements in scenes with many
        /// occluders)
        Segments = "segments",
        /// Each shadow line extended across its face (as the paper's mesh)
        Chords = "chords",
    }
}

/// A segment in a face's 2-D coordinates.
pub type Segment = (DVec2, DVec2);

/// The shadow lines on every face of `scene` (its occluders in `planner`), in each face's own
/// coordinates, without duplicates and without pieces along the face's outline.
pub fn shadow_lines(
    scene: &Scene,
    planner: &PairPlanner,
    sources: Sources,
    extent: LineExtent,
) -> Vec<Vec<Segment>> {
    let emitting: Vec<usize> =
        (0..scene.faces.len()).filter(|&k| scene.faces[k].emission > 0.0).collect();
    let sources: Vec<usize> = match sources {
        Sources::Emitting if !emitting.is_empty() => emitting,
        _ => (0..scene.faces.len()).collect(),
    };
    let mut raw: Vec<Vec<Segment>> = (0..scene.faces.len())
        .map(|r| {
            let receiver = &scene.faces[r];
            let mut raw = Vec::new();
            for &s in sources.iter().filter(|&&s| s != r) {
                for o in planner.candidates(r, s) {
                    let occluder = &planner.occluders()[o].polygon;
                    raw.extend(events(receiver, &scene.faces[s].vertices, occluder));
                }
            }
            raw
        })
        .collect();
    let tidied = |raw: &[Vec<Segment>]| -> Vec<Vec<Segment>> {
        raw.iter()
            .zip(&scene.faces)
            .map(|(r, f)| tidy(&f.local_polygon(), r.clone(), extent, f.size()))
            .collect()
    };
    if extent == LineExtent::Segments {
        return tidied(&raw);
    }
    // A chord that ends on an edge shared with another face goes on across it, at the same
    // angle to the edge (the two faces unfolded), so that the neighbour's elements conform.
    for (r, chords) in tidied(&raw).iter().enumerate() {
        for &(a, b) in chords {
            for (end, other) in [(a, b), (b, a)] {
                if let Some((g, segment)) = continuation(scene, r, end, other) {
                    raw[g].push(segment);
                }
            }
        }
    }
    tidied(&raw)
}

/// The continuation into a neighbouring face of the chord from `other` to `end` (face `r`'s
/// coordinates) that ends on an edge `r` shares with it: the neighbour's index and a segment of
/// the continued line in the neighbour's coordinates.
fn continuation(scene: &Scene, r: usize, end: DVec2, other: DVec2) -> Option<(usize, Segment)> {
    let face = &scene.faces[r];
    let (p, q) = (face.frame.to_global(end), face.frame.to_global(other));
    let tol = 1e-9 * face.size();
    for (g, neighbour) in scene.faces.iter().enumerate() {
        if g == r || neighbour.is_coplanar_with(face) {
            continue;
        }
        let v = &neighbour.vertices;
        let n = v.len();
        for k in 0..n {
            let (u, w) = (v[k], v[(k + 1) % n]);
            let e = (w - u).normalize();
            let on_edge = |x: DVec3| (x - u - e * (x - u).dot(e)).length() <= tol;
            let t = (p - u).dot(e);
            // The edge must be an edge of r too (both faces along it), and hold the chord's end.
            let shared = face.vertices.iter().filter(|&&x| on_edge(x)).count() >= 2;
            if !(shared && on_edge(p) && t > tol && t < (w - u).length() - tol) {
                continue;
            }
            let d = p - q;
            let along = d.dot(e);
            let across = (d - e * along).length();
            // Inward direction of the neighbour, perpendicular to the edge, in its plane.
            let inward = neighbour.frame.normal.cross(e);
            let direction = e * along + inward * across;
            let start = neighbour.frame.to_plane(p);
            let next = neighbour.frame.to_plane(p + direction);
            return Some((g, (start, next)));
        }
    }
    None
}

/// EV and VE event segments on `receiver` (face coordinates, unclipped) of a source polygon and a
/// convex occluder polygon.
fn events(receiver: &Face, source: &[DVec3], occluder: &[DVec3]) -> Vec<Segment> {
    let frame = &receiver.frame;
    let reach = 1e3 * receiver.size();
    // The point where the ray from `from` through `through` meets the receiver's plane, if it
    // does beyond `through` (`through` between `from` and the plane).
    let project = |from: DVec3, through: DVec3| -> Option<DVec2> {
        let (hf, ht) = (frame.height(from), frame.height(through));
        if !(hf > 0.0 && ht >= 0.0 && hf > ht) {
            return None;
        }
        let t = hf / (hf - ht);
        let x = from + (through - from) * t;
        let local = frame.to_plane(x);
        (local.length() < reach).then_some(local)
    };
    let mut out = Vec::new();
    let (m, k) = (source.len(), occluder.len());
    for &v in source {
        for i in 0..k {
            if let (Some(a), Some(b)) = (project(v, occluder[i]), project(v, occluder[(i + 1) % k]))
            {
                out.push((a, b));
            }
        }
    }
    for &w in occluder {
        for i in 0..m {
            if let (Some(a), Some(b)) = (project(source[i], w), project(source[(i + 1) % m], w)) {
                out.push((a, b));
            }
        }
    }
    out
}

/// A line `normal·x = offset` with intervals of its parameter along `normal.perp()`.
type Line = (DVec2, f64, Vec<(f64, f64)>);

/// Lines closer than this (relative to the face's size, in offset and in angle) are one line:
/// nearly coincident shadow lines would only make slivers.
const SAME_LINE: f64 = 1e-6;

/// Clips the segments to the polygon, extends them to chords if asked, drops those along its
/// outline, and merges overlapping collinear ones.
fn tidy(polygon: &[DVec2], raw: Vec<Segment>, extent: LineExtent, size: f64) -> Vec<Segment> {
    let tol = 1e-9 * size;
    let reach = polygon.iter().map(|p| p.length()).fold(0.0, f64::max) + size;
    let mut lines: Vec<Line> = Vec::new();
    for (a, b) in raw {
        let d = b - a;
        if d.length() <= tol {
            continue;
        }
        // Canonical direction, so that one line has one key.
        let dir = d.normalize();
        let dir = if dir.x < -1e-12 || (dir.x.abs() <= 1e-12 && dir.y < 0.0) { -dir } else { dir };
        let normal = -dir.perp();
        let offset = normal.dot(a);
        if along_outline(polygon, normal, offset, tol) {
            continue;
        }
        // Points of the line are base + dir s.
        let base = normal * offset;
        let (lo, hi) = match extent {
            LineExtent::Segments => (dir.dot(a).min(dir.dot(b)), dir.dot(a).max(dir.dot(b))),
            LineExtent::Chords => (-reach, reach),
        };
        let pieces: Vec<(f64, f64)> = clip_to_polygon(polygon, base + dir * lo, dir, hi - lo)
            .into_iter()
            .filter(|&(p, q)| q - p > tol)
            .map(|(p, q)| (lo + p, lo + q))
            .collect();
        if pieces.is_empty() {
            continue;
        }
        match lines.iter_mut().find(|(n, o, _)| {
            n.perp_dot(normal).abs() < SAME_LINE && (o - offset).abs() <= SAME_LINE * size
        }) {
            Some((_, _, intervals)) => intervals.extend(pieces),
            None => lines.push((normal, offset, pieces)),
        }
    }
    let mut out = Vec::new();
    for (normal, offset, mut intervals) in lines {
        let dir = normal.perp();
        intervals.sort_by(|a, b| a.0.total_cmp(&b.0));
        let mut merged: Vec<(f64, f64)> = Vec::new();
        for (p, q) in intervals {
            match merged.last_mut() {
                Some(last) if p <= last.1 + tol => last.1 = last.1.max(q),
                _ => merged.push((p, q)),
            }
        }
        for (p, q) in merged {
            out.push((normal * offset + dir * p, normal * offset + dir * q));
        }
    }
    out
}

/// Whether the line `normal·x = offset` runs along an edge of the polygon.
fn along_outline(polygon: &[DVec2], normal: DVec2, offset: f64, tol: f64) -> bool {
    let n = polygon.len();
    (0..n).any(|k| {
        let (a, b) = (polygon[k], polygon[(k + 1) % n]);
        (normal.dot(a) - offset).abs() <= tol && (normal.dot(b) - offset).abs() <= tol
    })
}

/// The parts of the segment `start + dir s`, s in [0, length], inside the simple polygon, as
/// parameter intervals.
fn clip_to_polygon(polygon: &[DVec2], start: DVec2, dir: DVec2, length: f64) -> Vec<(f64, f64)> {
    let n = polygon.len();
    let mut cuts = vec![0.0, length];
    for k in 0..n {
        let (a, b) = (polygon[k], polygon[(k + 1) % n]);
        let e = b - a;
        let denom = dir.perp_dot(e);
        if denom.abs() < 1e-300 {
            continue;
        }
        // start + dir s = a + e t
        let w = a - start;
        let s = w.perp_dot(e) / denom;
        let t = w.perp_dot(dir) / denom;
        if (0.0..=1.0).contains(&t) && s > 0.0 && s < length {
            cuts.push(s);
        }
    }
    cuts.sort_by(f64::total_cmp);
    cuts.windows(2)
        .filter(|w| w[1] > w[0] && polygon_contains(polygon, start + dir * (0.5 * (w[0] + w[1]))))
        .map(|w| (w[0], w[1]))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::{Mesh, MeshKind, S5Diagonals, paper_discontinuity_cuts};
    use crate::scene::{SurfaceParameters, five_piece, four_piece};

    #[test]
    fn the_four_piece_surface_has_the_papers_shadow_lines_on_s1() {
        let p = SurfaceParameters::default();
        let scene = four_piece(p).unwrap();
        let chords =
            shadow_lines(&scene, &PairPlanner::new(&scene), Sources::All, LineExtent::Chords);
        // S1's frame: origin (0,0,0), first axis x: local = (x, y).
        let mut lines: Vec<String> = chords[0]
            .iter()
            .map(|(a, b)| {
                if (a.x - b.x).abs() < 1e-12 {
                    format!("x={:.6}", a.x)
                } else {
                    format!("y={:.6}", a.y)
                }
            })
            .collect();
        lines.sort();
        assert_eq!(lines, ["x=3.000000", "x=4.000000", "y=3.000000", "y=4.000000"], "{chords:?}");
        for (a, b) in &chords[0] {
            assert!(((*a - *b).length() - 5.0).abs() < 1e-12, "a chord spans S1");
        }
        // The segments stop where the events do: x = 3 from y = 0 to 4.
        let segments =
            shadow_lines(&scene, &PairPlanner::new(&scene), Sources::All, LineExtent::Segments);
        let x3 = segments[0]
            .iter()
            .find(|(a, b)| (a.x - 3.0).abs() < 1e-12 && (b.x - 3.0).abs() < 1e-12);
        let (a, b) = x3.expect("x = 3 found");
        assert!((a.y.min(b.y)).abs() < 1e-12 && (a.y.max(b.y) - 4.0).abs() < 1e-12, "{a} {b}");
        // Nothing else on the other faces: S4 sees S1 past the square only along its outline.
        assert!(chords[1..].iter().all(Vec::is_empty), "{chords:?}");
    }

    #[test]
    fn automatic_meshing_of_the_four_piece_surface_is_the_papers_mesh() {
        let p = SurfaceParameters::default();
        let scene = four_piece(p).unwrap();
        let lines =
            shadow_lines(&scene, &PairPlanner::new(&scene), Sources::All, LineExtent::Chords);
        let auto = Mesh::new(&scene, &MeshKind::Constrained(lines), 1).unwrap();
        let cuts = paper_discontinuity_cuts(&scene, &p, S5Diagonals::Paper).unwrap();
        let hand = Mesh::new(&scene, &MeshKind::Discontinuity(cuts), 1).unwrap();
        assert_eq!(auto.len(), hand.len());
        // The same triangles, in any order and with any starting vertex.
        let key = |e: &crate::mesh::Element| {
            let mut v: Vec<[i64; 3]> =
                e.vertices.iter().map(|x| (*x * 1e9).round().as_i64vec3().to_array()).collect();
            v.sort();
            v
        };
        let mut a: Vec<_> = auto.elements().iter().map(key).collect();
        let mut b: Vec<_> = hand.elements().iter().map(key).collect();
        a.sort();
        b.sort();
        assert_eq!(a, b);
    }

    #[test]
    fn chords_continue_across_a_shared_edge_and_segments_triangulate_by_cdt() {
        let scene = five_piece(SurfaceParameters::default()).unwrap();
        let chords =
            shadow_lines(&scene, &PairPlanner::new(&scene), Sources::All, LineExtent::Chords);
        let s5 = &scene.faces[4];
        // S1's x = 3 and x = 4 go on up S5, plus S5's own events x + z = 3 and x + 2z = 4.
        let ends: Vec<(DVec3, DVec3)> = chords[4]
            .iter()
            .map(|(a, b)| (s5.frame.to_global(*a), s5.frame.to_global(*b)))
            .collect();
        let vertical =
            |x: f64| ends.iter().any(|(a, b)| (a.x - x).abs() < 1e-9 && (b.x - x).abs() < 1e-9);
        assert!(vertical(3.0) && vertical(4.0), "{ends:?}");
        assert_eq!(ends.len(), 4, "{ends:?}");
        let segments =
            shadow_lines(&scene, &PairPlanner::new(&scene), Sources::All, LineExtent::Segments);
        let mesh = Mesh::new(&scene, &MeshKind::Constrained(segments.clone()), 0).unwrap();
        for (f, lines) in segments.iter().enumerate() {
            let area: f64 = mesh.elements()[mesh.face_range(f)].iter().map(|e| e.area()).sum();
            assert!((area - scene.faces[f].area()).abs() < 1e-12, "face {f}");
            // No element crosses a segment: no point of the segment is strictly inside one.
            let frame = &scene.faces[f].frame;
            for &(a, b) in lines {
                for e in &mesh.elements()[mesh.face_range(f)] {
                    let [p, q, r] = e.vertices.map(|v| frame.to_plane(v));
                    let area = (q - p).perp_dot(r - p);
                    for k in 1..100 {
                        let x = a + (b - a) * (k as f64 / 100.0);
                        let l = [
                            (r - q).perp_dot(x - q),
                            (p - r).perp_dot(x - r),
                            (q - p).perp_dot(x - p),
                        ]
                        .map(|v| v / area);
                        assert!(l.iter().any(|&v| v < 1e-9), "face {f}: {e:?} crosses {a} {b}");
                    }
                }
            }
        }
    }
}
