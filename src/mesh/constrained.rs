//! Triangulations of a face that respect given segments (the shadow lines of the discontinuity
//! mesh): a convex face cut by chords is split into its convex cells, each triangulated as the
//! face itself would be (a parallelogram cell by the diagonal parallel to the face's, as in the
//! paper's mesh); otherwise a constrained Delaunay triangulation by the `spade` crate.

use glam::{DVec2, DVec3};
use spade::{ConstrainedDelaunayTriangulation, Point2, Triangulation};

use super::shadow_lines::Segment;
use crate::error::{Error, Result};
use crate::geometry::{HalfPlane, clip_convex, polygon_contains};
use crate::scene::{Diagonal, Face};

/// Triangles (3-D, counter-clockwise about the face's normal) of `face` such that no segment of
/// `segments` (face coordinates, inside the face) crosses a triangle.
pub(crate) fn triangulate_with_segments(
    face: &Face,
    segments: &[Segment],
) -> Result<Vec<[DVec3; 3]>> {
    if face.is_convex() && segments.iter().all(|s| is_chord(face, s)) {
        let cells = cut_into_cells(face, segments);
        // Chords meeting nearly at one point leave slivers: then the snapping triangulation.
        let size = face.size();
        let area = |t: &[DVec3; 3]| 0.5 * (t[1] - t[0]).cross(t[2] - t[0]).length();
        if cells.iter().all(|t| area(t) > SNAP * size * size) {
            return Ok(cells);
        }
    }
    constrained_delaunay(face, segments)
}

/// Whether both ends of the segment lie on the outline of the face.
fn is_chord(face: &Face, (a, b): &Segment) -> bool {
    let polygon = face.local_polygon();
    let tol = 1e-9 * face.size();
    let on_outline = |p: DVec2| {
        let n = polygon.len();
        (0..n).any(|k| {
            let (u, v) = (polygon[k], polygon[(k + 1) % n]);
            let e = v - u;
            let t = (p - u).dot(e) / e.length_squared();
            (-1e-12..=1.0 + 1e-12).contains(&t) && (u + e * t - p).length() <= tol
        })
    };
    on_outline(*a) && on_outline(*b)
}

/// The convex cells of a convex face cut by chords, triangulated.
fn cut_into_cells(face: &Face, chords: &[Segment]) -> Vec<[DVec3; 3]> {
    let mut cells = vec![face.local_polygon()];
    for &(a, b) in chords {
        let left = HalfPlane::left_of(a, b);
        cells = cells
            .into_iter()
            .flat_map(|c| [clip_convex(&c, &left), clip_convex(&c, &left.flipped())])
            .flatten()
            .collect();
    }
    // The face's own diagonal direction, for parallelogram cells.
    let v = face.local_polygon();
    let diagonal = match (v.len(), face.diagonal) {
        (4, Diagonal::FromFirst) => Some(v[2] - v[0]),
        (4, Diagonal::FromSecond) => Some(v[3] - v[1]),
        _ => None,
    };
    let mut out = Vec::new();
    for cell in cells {
        let n = cell.len();
        // Start the fan at the vertex whose diagonal is most nearly parallel to the face's.
        let start = match (n, diagonal) {
            (4, Some(d)) => {
                let along = |k: usize| {
                    (cell[(k + 2) % 4] - cell[k]).normalize().perp_dot(d.normalize()).abs()
                };
                if along(0) <= along(1) { 0 } else { 1 }
            }
            _ => 0,
        };
        for k in 1..n - 1 {
            let t = [cell[start], cell[(start + k) % n], cell[(start + k + 1) % n]];
            out.push(t.map(|p| face.frame.to_global(p)));
        }
    }
    out
}

/// Points closer than this (relative to the face's size) are one vertex: shadow lines meet at
/// points computed by different events, which agree only to rounding.
const SNAP: f64 = 1e-7;

/// Constrained Delaunay triangulation of the face with the segments as constraints. The
/// segments are first cut at their crossings and at the outline, and nearby points merged, so
/// that the triangulation never sees two versions of one point.
fn constrained_delaunay(face: &Face, segments: &[Segment]) -> Result<Vec<[DVec3; 3]>> {
    let failed = |what: String| Error::InvalidParameter {
        name: "discontinuity mesh",
        value: format!("face '{}'", face.name),
        reason: what,
    };
    let polygon = face.local_polygon();
    let (points, constraints) = snapped_constraints(&polygon, segments, SNAP * face.size());
    let mut cdt: ConstrainedDelaunayTriangulation<Point2<f64>> = Default::default();
    let handles = points
        .iter()
        .map(|p| cdt.insert(Point2::new(p.x, p.y)))
        .collect::<std::result::Result<Vec<_>, _>>()
        .map_err(|e| failed(format!("{e:?}")))?;
    for (a, b) in constraints {
        if handles[a] != handles[b] {
            cdt.add_constraint_and_split(handles[a], handles[b], |p| p);
        }
    }
    let mut triangles = Vec::new();
    for f in cdt.inner_faces() {
        let [a, b, c] = f.vertices().map(|v| {
            let p = v.position();
            DVec2::new(p.x, p.y)
        });
        // Triangles of the convex hull outside a non-convex face are dropped.
        if !polygon_contains(&polygon, (a + b + c) / 3.0) {
            continue;
        }
        let t = if (b - a).perp_dot(c - a) >= 0.0 { [a, b, c] } else { [a, c, b] };
        triangles.push(t.map(|p| face.frame.to_global(p)));
    }
    Ok(triangles)
}

/// The points and constraint edges (pairs of point indices) of the outline of `polygon` and the
/// `segments`: each cut at its ends and its crossings with the others, points closer than `tol`
/// merged into the first of them (the outline's vertices come first).
fn snapped_constraints(
    polygon: &[DVec2],
    segments: &[Segment],
    tol: f64,
) -> (Vec<DVec2>, Vec<(usize, usize)>) {
    let n = polygon.len();
    // Every constraint: the outline's edges, then the segments.
    let lines: Vec<Segment> = (0..n)
        .map(|k| (polygon[k], polygon[(k + 1) % n]))
        .chain(segments.iter().copied())
        .collect();
    // Points on each constraint (as parameters), its ends and its crossings with the others.
    let mut on_line: Vec<Vec<f64>> = vec![vec![0.0, 1.0]; lines.len()];
    for i in 0..lines.len() {
        for j in i + 1..lines.len() {
            let ((a, b), (c, d)) = (lines[i], lines[j]);
            let (e, f) = (b - a, d - c);
            let denom = e.perp_dot(f);
            if denom.abs() <= 1e-14 * e.length() * f.length() {
                continue;
            }
            let t = (c - a).perp_dot(f) / denom;
            let u = (c - a).perp_dot(e) / denom;
            let (ti, tj) = (tol / e.length(), tol / f.length());
            if t > -ti && t < 1.0 + ti && u > -tj && u < 1.0 + tj {
                on_line[i].push(t.clamp(0.0, 1.0));
                on_line[j].push(u.clamp(0.0, 1.0));
            }
        }
    }
    // Merge nearby points: each gets the index of the first point within the tolerance.
    let mut points: Vec<DVec2> = polygon.to_vec();
    let mut vertex_of = |p: DVec2| -> usize {
        match points.iter().position(|q| (*q - p).length() <= tol) {
            Some(k) => k,
            None => {
                points.push(p);
                points.len() - 1
            }
        }
    };
    let mut constraints: Vec<(usize, usize)> = Vec::new();
    for (k, &(a, b)) in lines.iter().enumerate() {
        let mut ts = on_line[k].clone();
        ts.sort_by(f64::total_cmp);
        let ids: Vec<usize> = ts.iter().map(|&t| vertex_of(a + (b - a) * t)).collect();
        for w in ids.windows(2) {
            if w[0] != w[1] {
                constraints.push((w[0], w[1]));
            }
        }
    }
    (points, constraints)
}
