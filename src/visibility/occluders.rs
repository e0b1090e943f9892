//! Occluders: the scene's faces as convex pieces (non-convex faces triangulated, the two sides of a
//! double-sided plate merged), an index over their bounding boxes, and which of them can come
//! between a point and a face.

use glam::DVec3;
use rstar::primitives::{GeomWithData, Rectangle};
use rstar::{AABB, RTree};

use crate::geometry::PlaneFrame;
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

/// How candidate occluders are found.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Acceleration {
    /// An R*-tree (the `rstar` crate) over the occluders' bounding boxes.
    #[default]
    Tree,
    /// Every occluder tested for every query (the baseline the tree is measured against).
    None,
}

type Boxed = GeomWithData<Rectangle<[f64; 3]>, usize>;

/// The occluders and the structure that finds those overlapping a box.
#[derive(Clone, Debug)]
pub(super) struct OccluderIndex {
    pub(super) pieces: Vec<Occluder>,
    tree: Option<RTree<Boxed>>,
}

impl OccluderIndex {
    pub(super) fn new(scene: &Scene, acceleration: Acceleration) -> Self {
        let pieces = convex_pieces(scene);
        let tree = (acceleration == Acceleration::Tree).then(|| {
            RTree::bulk_load(
                pieces
                    .iter()
                    .enumerate()
                    .map(|(k, o)| {
                        GeomWithData::new(Rectangle::from_corners(o.lo.into(), o.hi.into()), k)
                    })
                    .collect(),
            )
        });
        Self { pieces, tree }
    }

    /// Occluders that may block a segment from a point of the box `[lo, hi]` to another point of
    /// it, between faces `a` and `b` (planes `fa`, `fb`; `tol` a length below rounding of the
    /// scene). Conservative: a piece is dropped only when it belongs to `a` or `b`, lies in the
    /// plane of either or wholly behind it, or outside the box.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn between(
        &self,
        a: usize,
        b: usize,
        fa: &PlaneFrame,
        fb: &PlaneFrame,
        lo: DVec3,
        hi: DVec3,
        tol: f64,
    ) -> Vec<usize> {
        let keep = |k: usize| {
            let o = &self.pieces[k];
            if o.faces.contains(&a) || o.faces.contains(&b) {
                return false;
            }
            // In the plane of a or b, or wholly behind it: no segment between a and b crosses it.
            let in_front = |f: &PlaneFrame| o.polygon.iter().any(|&v| f.height(v) > tol);
            in_front(fa)
                && in_front(fb)
                && (0..3).all(|axis| o.lo[axis] < hi[axis] - tol && o.hi[axis] > lo[axis] + tol)
        };
        let mut found: Vec<usize> = match &self.tree {
            Some(tree) => tree
                .locate_in_envelope_intersecting(AABB::from_corners(lo.into(), hi.into()))
                .map(|g| g.data)
                .filter(|&k| keep(k))
                .collect(),
            None => (0..self.pieces.len()).filter(|&k| keep(k)).collect(),
        };
        // The tree returns pieces in its own order; shadows are subtracted in index order.
        found.sort_unstable();
        found
    }
}

/// Convex pieces of every face, without duplicates.
fn convex_pieces(scene: &Scene) -> Vec<Occluder> {
    let mut pieces: Vec<Occluder> = Vec::new();
    // Pieces by their rounded lowest corner, to find the other side of a plate without a scan.
    let mut by_corner: std::collections::HashMap<[i64; 3], Vec<usize>> = Default::default();
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
            let (lo, hi) = polygon.iter().fold(
                (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY)),
                |(lo, hi), &p| (lo.min(p), hi.max(p)),
            );
            let key = |c: DVec3| (c / (64.0 * tol).max(f64::MIN_POSITIVE)).round().as_i64vec3();
            let near: Vec<[i64; 3]> = neighbour_keys(key(lo));
            let same = near
                .iter()
                .flat_map(|c| by_corner.get(c).into_iter().flatten())
                .find(|&&o| same_vertex_set(&pieces[o].polygon, &polygon, tol));
            if let Some(&o) = same {
                pieces[o].faces.push(k);
                continue;
            }
            by_corner.entry(key(lo).into()).or_default().push(pieces.len());
            pieces.push(Occluder { faces: vec![k], polygon, lo, hi });
        }
    }
    pieces
}

/// The 27 grid keys around `c` (a corner within the tolerance may round to a neighbouring cell).
fn neighbour_keys(c: glam::I64Vec3) -> Vec<[i64; 3]> {
    let mut keys = Vec::with_capacity(27);
    for dx in -1..=1 {
        for dy in -1..=1 {
            for dz in -1..=1 {
                keys.push([c.x + dx, c.y + dy, c.z + dz]);
            }
        }
    }
    keys
}

fn same_vertex_set(a: &[DVec3], b: &[DVec3], tol: f64) -> bool {
    a.len() == b.len() && a.iter().all(|p| b.iter().any(|q| (*p - *q).length() <= tol))
}
