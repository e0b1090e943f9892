//! Closed convex solids among the occluder pieces: a cube of six faces, a box of furniture.
//!
//! Seen from a point outside it, a convex solid lying wholly between the point and a plane casts
//! one convex shadow on that plane, the convex hull of its vertices' central projections. Its
//! faces cast up to six overlapping shadows, and subtracting those cuts the visible part of an
//! element into many more pieces than subtracting the one hull (the floating cube of the
//! occluded box, seen by a wall). The hull is the same set as the union of the faces' shadows,
//! so the visible parts are the same up to rounding.

use std::collections::HashMap;

use glam::DVec3;

use super::Occluder;

/// A closed convex polyhedron whose faces are occluder pieces.
#[derive(Clone, Debug, PartialEq)]
pub(super) struct Solid {
    /// The scene faces of its pieces (a view from or of one of them does not use the solid).
    pub(super) faces: Vec<usize>,
    /// Its vertices, each once.
    pub(super) vertices: Vec<DVec3>,
}

/// The closed convex solids among `pieces`, and per piece the solid it bounds, if any.
///
/// Pieces that share an edge (the same two vertices, to the bit, as faces of one scene file or
/// OBJ mesh share them) are joined; a group is a closed convex solid when each of its edges
/// bounds exactly two of its pieces and all its vertices lie on one side of each piece's plane
/// (within 1e-12 of its size). Anything else (an open box, a T-junction, a dent) is left as
/// pieces, which is always right, only slower.
pub(super) fn closed_convex_solids(pieces: &[Occluder]) -> (Vec<Solid>, Vec<Option<usize>>) {
    let key = |v: DVec3| v.to_array().map(f64::to_bits);
    let edge_key = |a: DVec3, b: DVec3| {
        let (a, b) = (key(a), key(b));
        if a <= b { (a, b) } else { (b, a) }
    };
    let mut edges: HashMap<_, Vec<usize>> = HashMap::new();
    for (k, piece) in pieces.iter().enumerate() {
        let m = piece.polygon.len();
        for l in 0..m {
            edges
                .entry(edge_key(piece.polygon[l], piece.polygon[(l + 1) % m]))
                .or_default()
                .push(k);
        }
    }
    let mut group: Vec<usize> = (0..pieces.len()).collect();
    fn root(group: &mut [usize], mut k: usize) -> usize {
        while group[k] != k {
            group[k] = group[group[k]];
            k = group[k];
        }
        k
    }
    for sharing in edges.values() {
        for w in sharing.windows(2) {
            let (a, b) = (root(&mut group, w[0]), root(&mut group, w[1]));
            group[a.max(b)] = a.min(b);
        }
    }
    let mut members: HashMap<usize, Vec<usize>> = HashMap::new();
    for k in 0..pieces.len() {
        let r = root(&mut group, k);
        members.entry(r).or_default().push(k);
    }
    let mut groups: Vec<Vec<usize>> = members.into_values().filter(|g| g.len() >= 4).collect();
    groups.sort_unstable();
    let mut solids = Vec::new();
    let mut solid_of = vec![None; pieces.len()];
    for g in groups {
        let closed = g.iter().all(|&k| {
            let polygon = &pieces[k].polygon;
            let m = polygon.len();
            (0..m).all(|l| edges[&edge_key(polygon[l], polygon[(l + 1) % m])].len() == 2)
        });
        if !closed {
            continue;
        }
        let mut vertices: Vec<DVec3> = Vec::new();
        for &k in &g {
            for &v in &pieces[k].polygon {
                if !vertices.iter().any(|&w| key(w) == key(v)) {
                    vertices.push(v);
                }
            }
        }
        let (lo, hi) = crate::geometry::bounding_box_3d(&vertices);
        let tol = 1e-12 * (hi - lo).length();
        let convex = g.iter().all(|&k| {
            let (n, origin) = (pieces[k].normal(), pieces[k].polygon[0]);
            let heights = || vertices.iter().map(move |&v| n.dot(v - origin));
            n != DVec3::ZERO
                && (heights().all(|h| h >= -tol) || heights().all(|h| h <= tol))
                && heights().any(|h| h.abs() > tol)
        });
        if !convex {
            continue;
        }
        let mut faces: Vec<usize> =
            g.iter().flat_map(|&k| pieces[k].faces.iter().copied()).collect();
        faces.sort_unstable();
        faces.dedup();
        for &k in &g {
            solid_of[k] = Some(solids.len());
        }
        solids.push(Solid { faces, vertices });
    }
    (solids, solid_of)
}
