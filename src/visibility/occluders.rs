//! Occluders: the scene's faces as convex pieces (non-convex faces triangulated, the two sides of a
//! double-sided plate merged), and which of them can come between two faces.

use glam::DVec3;

use crate::scene::Scene;

/// A convex planar piece of one or more faces that blocks light.
#[derive(Clone, Debug, PartialEq)]
pub struct Occluder {
    /// Faces this piece belongs to (both sides of a plate share one piece).
    pub faces: Vec<usize>,
    /// Vertices (convex polygon).
    pub polygon: Vec<DVec3>,
    lo: DVec3,
    hi: DVec3,
}

/// Convex pieces of every face, without duplicates.
pub(super) fn convex_pieces(scene: &Scene) -> Vec<Occluder> {
    let mut pieces: Vec<Occluder> = Vec::new();
    for (k, face) in scene.faces.iter().enumerate() {
        let polygons: Vec<Vec<DVec3>> = if face.is_convex() {
            vec![face.vertices.clone()]
        } else {
            crate::geometry::triangulate(&face.local_polygon())
                .unwrap_or_default()
                .into_iter()
                .map(|t| t.map(|i| face.vertices[i]).to_vec())
                .collect()
        };
        for polygon in polygons {
            let tol = 1e-12 * face.size();
            if let Some(same) =
                pieces.iter_mut().find(|o| same_vertex_set(&o.polygon, &polygon, tol))
            {
                same.faces.push(k);
                continue;
            }
            let (lo, hi) = polygon.iter().fold(
                (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY)),
                |(lo, hi), &p| (lo.min(p), hi.max(p)),
            );
            pieces.push(Occluder { faces: vec![k], polygon, lo, hi });
        }
    }
    pieces
}

fn same_vertex_set(a: &[DVec3], b: &[DVec3], tol: f64) -> bool {
    a.len() == b.len() && a.iter().all(|p| b.iter().any(|q| (*p - *q).length() <= tol))
}

/// Occluders that may block some segment from a point of face `a` to a point of face `b` (both in
/// front of each other). Conservative: a piece is dropped only when it lies in the plane of `a` or
/// `b`, entirely behind either plane, or outside the bounding box of the two faces.
pub(super) fn candidates_between(
    scene: &Scene,
    a: usize,
    b: usize,
    occluders: &[Occluder],
) -> Vec<usize> {
    let (fa, fb) = (&scene.faces[a], &scene.faces[b]);
    let size = fa.size().max(fb.size());
    let tol = 1e-12 * size;
    let (lo, hi) =
        fa.vertices.iter().chain(&fb.vertices).fold(
            (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY)),
            |(lo, hi), &p| (lo.min(p), hi.max(p)),
        );
    occluders
        .iter()
        .enumerate()
        .filter(|(_, o)| {
            if o.faces.contains(&a) || o.faces.contains(&b) {
                return false;
            }
            for f in [fa, fb] {
                let heights: Vec<f64> = o.polygon.iter().map(|&v| f.frame.height(v)).collect();
                // In the plane of a or b, or wholly behind it: no segment between a and b crosses it.
                if heights.iter().all(|&h| h <= tol) {
                    return false;
                }
            }
            (0..3).all(|axis| o.lo[axis] < hi[axis] - tol && o.hi[axis] > lo[axis] + tol)
        })
        .map(|(k, _)| k)
        .collect()
}
