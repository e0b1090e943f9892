//! Convex solids among the occluder pieces: a cube of six faces, a box of furniture, a building
//! standing open on the ground.
//!
//! Seen from a point outside it, a convex solid with no point behind a plane casts one convex
//! shadow on that plane: the plane's part in the solid's cone from the point, bounded by the
//! planes through the point and the silhouette edges (between a face that faces the point and
//! one that does not), whether the solid lies below the point or reaches above it (a building
//! taller than a point on a wall across the street that sees the ground). One that reaches
//! behind the plane casts the convex hull of its vertices' central projections, or of its part
//! in the pyramid over the window. Its faces cast up to six overlapping shadows, and
//! subtracting those cuts the visible part of an element into many more pieces than
//! subtracting the one shadow (the floating cube of the occluded box, seen by a wall). The one
//! shadow is the same set as the union of the faces' shadows, so the visible parts are the
//! same up to rounding. A solid may lack one face (its cap) where
//! no segment between two points of the scene can cross the cap's plane: the whole scene lies
//! on one side of it.

use std::collections::HashMap;

use glam::DVec3;

use super::occluders::Occluder;

/// A convex polyhedron whose faces are occluder pieces, but for a cap that no segment of the
/// scene crosses.
#[derive(Clone, Debug, PartialEq)]
pub(super) struct Solid {
    /// The scene faces of its pieces (a view from or of one of them does not use the solid).
    pub(super) faces: Vec<usize>,
    /// Its vertices, each once.
    pub(super) vertices: Vec<DVec3>,
    /// Its pieces' sides, each once, as pairs of indices into `vertices` (with the sides that
    /// split a face into pieces: segments on its surface, as good as edges for a hull).
    pub(super) edges: Vec<(usize, usize)>,
    /// Per edge, the planes (indices into `planes`) of the pieces on either side of it; `None`
    /// on the cap's side.
    pub(super) edge_planes: Vec<(usize, Option<usize>)>,
    /// The mean of its vertices, a point inside it.
    pub(super) centre: DVec3,
    /// Its pieces' planes, as an outward unit normal n and c with n·x <= c inside (no cap:
    /// no segment of the scene crosses it).
    pub(super) planes: Vec<(DVec3, f64)>,
    /// The diagonal of its vertices' box.
    pub(super) size: f64,
}

impl Solid {
    /// Whether `p` lies outside the solid, beyond one of its planes by more than `tol` (a point
    /// on the ground under a building open at the bottom is inside).
    pub(super) fn is_outside(&self, p: DVec3, tol: f64) -> bool {
        self.planes.iter().any(|&(n, c)| n.dot(p) > c + tol)
    }

    /// Whether the solid hides every point of the convex hull of `from` from every point of the
    /// convex hull of `to`: each set lies outside it (beyond one of its planes, or on it, within
    /// `tol`), and every segment between their corners passes through its interior (deeper than
    /// `tol`). For a fixed end q, the points p whose segment to q meets the interior of a convex
    /// solid form a convex set (p1, p2 in it: the segment between the interior points on p1q
    /// and p2q separates q from p1p2 within the triangle p1 p2 q, so every pq crosses it), so
    /// the corners' segments decide for the hulls. A segment from outside that meets the
    /// interior crosses one of the pieces on its way in (not the cap, which no segment of the
    /// scene crosses): hidden by several occluders together, as a building hides the ground
    /// behind it from a wall although no single wall crosses every segment.
    pub(super) fn hides(&self, from: &[DVec3], to: &[DVec3], tol: f64) -> bool {
        let outside = |points: &[DVec3]| {
            self.planes.iter().any(|&(n, c)| points.iter().all(|&x| n.dot(x) >= c - tol))
        };
        outside(from)
            && outside(to)
            && from.iter().all(|&p| to.iter().all(|&q| self.passes_inside(p, q, tol)))
    }

    /// Whether the segment from `p` to `q` meets the solid shrunk by `tol`: the parameters t of
    /// p + t (q - p) inside each plane's half-space, intersected, leave an interval.
    fn passes_inside(&self, p: DVec3, q: DVec3, tol: f64) -> bool {
        let (mut lo, mut hi) = (0.0f64, 1.0f64);
        for &(n, c) in &self.planes {
            // n·x(t) - c + tol < 0 on the part inside.
            let (start, slope) = (n.dot(p) - c + tol, n.dot(q - p));
            if slope == 0.0 {
                if start >= 0.0 {
                    return false;
                }
            } else if slope > 0.0 {
                hi = hi.min(-start / slope);
            } else {
                lo = lo.max(-start / slope);
            }
            if lo >= hi {
                return false;
            }
        }
        true
    }
}

/// The convex solids among `pieces`, and per piece the solid it bounds, if any.
///
/// From each piece not yet in a solid, a group grows across shared edges (the same two
/// vertices, to the bit, as faces of one scene file or OBJ mesh share them) by every neighbour
/// that keeps all the group's vertices on one side of each of its pieces' planes (within 1e-12
/// of the scene's size). The group is a solid when each of its edges bounds two of its pieces,
/// or when the edges that bound one form a single planar loop, the cap, whose plane has every
/// vertex of the scene on the group's side: then no segment between two points of the scene
/// crosses the cap (a building standing on the ground, a box on the floor), and the group
/// shadows as the closed solid does. Anything else (a T-junction, a dent, an open box in
/// mid-air) is left as pieces, which is always right, only slower.
pub(super) fn convex_solids(pieces: &[Occluder]) -> (Vec<Solid>, Vec<Option<usize>>) {
    let key = vertex_key;
    let edges_of = |k: usize| {
        let polygon = &pieces[k].polygon;
        let m = polygon.len();
        (0..m).map(move |l| edge_key(polygon[l], polygon[(l + 1) % m]))
    };
    let mut edges: HashMap<_, Vec<usize>> = HashMap::new();
    for k in 0..pieces.len() {
        for e in edges_of(k) {
            edges.entry(e).or_default().push(k);
        }
    }
    let mut scene = SceneVertices::new(pieces);
    let tol = 1e-12 * scene.size;
    let mut solids = Vec::new();
    let mut solid_of = vec![None; pieces.len()];
    // Pieces already in a solid are no seeds and join no group; a group that is no solid
    // leaves its pieces to others (a wall that a ground tile's group took in is still its
    // building's).
    for seed in 0..pieces.len() {
        if solid_of[seed].is_some() || pieces[seed].normal() == DVec3::ZERO {
            continue;
        }
        let mut group = vec![seed];
        let mut vertices: Vec<DVec3> = Vec::new();
        let add_vertices = |vertices: &mut Vec<DVec3>, k: usize| {
            for &v in &pieces[k].polygon {
                if !vertices.iter().any(|&w| key(w) == key(v)) {
                    vertices.push(v);
                }
            }
        };
        add_vertices(&mut vertices, seed);
        // Per piece of the group, the side of its plane that the group's vertices lie on (0
        // while they all lie in it).
        let mut sides = vec![0.0];
        let mut next = 0;
        while next < group.len() && group.len() <= MAX_SOLID_PIECES {
            let k = group[next];
            next += 1;
            for e in edges_of(k) {
                for &nb in &edges[&e] {
                    if group.contains(&nb)
                        || solid_of[nb].is_some()
                        || pieces[nb].normal() == DVec3::ZERO
                    {
                        continue;
                    }
                    // The group's vertices on one side of the piece's plane, and the piece's
                    // on the group's side of every plane of the group.
                    let Some(own_side) = side(&pieces[nb], &vertices, tol) else { continue };
                    let mut new_sides = sides.clone();
                    let convex = group.iter().zip(&mut new_sides).all(|(&g, s)| {
                        match side(&pieces[g], &pieces[nb].polygon, tol) {
                            Some(0.0) => true,
                            Some(t) if *s == 0.0 || *s == t => {
                                *s = t;
                                true
                            }
                            _ => false,
                        }
                    });
                    if convex {
                        group.push(nb);
                        new_sides.push(own_side);
                        sides = new_sides;
                        add_vertices(&mut vertices, nb);
                    }
                }
            }
        }
        if group.len() < 4 || group.len() > MAX_SOLID_PIECES {
            continue;
        }
        // Vertices off every plane of the group (not all in one plane).
        let solid_volume = sides.iter().all(|&s| s != 0.0);
        let Some(open) = open_edges(&group, pieces, &edges) else { continue };
        if !solid_volume || !(open.is_empty() || is_capped(&open, &vertices, &mut scene, tol)) {
            continue;
        }
        let mut faces: Vec<usize> =
            group.iter().flat_map(|&k| pieces[k].faces.iter().copied()).collect();
        faces.sort_unstable();
        faces.dedup();
        // The group's vertices lie on side `s` of piece g's plane: its outward normal is -s n.
        let planes = group
            .iter()
            .zip(&sides)
            .map(|(&g, &s)| {
                let n = -s * pieces[g].normal();
                (n, n.dot(pieces[g].polygon[0]))
            })
            .collect();
        let index = |v: DVec3| vertices.iter().position(|&w| key(w) == key(v));
        // Each piece's sides with the piece's plane (its place in the group); an edge is the
        // side of one piece (on the cap) or of two.
        let mut sides_with_planes: Vec<((usize, usize), usize)> = group
            .iter()
            .enumerate()
            .flat_map(|(plane, &k)| {
                let polygon = &pieces[k].polygon;
                let m = polygon.len();
                (0..m).map(move |l| (polygon[l], polygon[(l + 1) % m], plane))
            })
            .filter_map(|(u, v, plane)| {
                let (a, b) = (index(u)?, index(v)?);
                (a != b).then_some(((a.min(b), a.max(b)), plane))
            })
            .collect();
        sides_with_planes.sort_unstable();
        let (mut solid_edges, mut edge_planes) = (Vec::new(), Vec::new());
        for (edge, plane) in sides_with_planes {
            if solid_edges.last() == Some(&edge) {
                if let Some((_, other @ None)) = edge_planes.last_mut() {
                    *other = Some(plane);
                }
            } else {
                solid_edges.push(edge);
                edge_planes.push((plane, None));
            }
        }
        for &k in &group {
            solid_of[k] = Some(solids.len());
        }
        let (lo, hi) = crate::geometry::bounding_box_3d(&vertices);
        let size = (hi - lo).length();
        let centre = vertices.iter().sum::<DVec3>() / vertices.len() as f64;
        solids.push(Solid {
            faces,
            vertices,
            edges: solid_edges,
            edge_planes,
            planes,
            size,
            centre,
        });
    }
    (solids, solid_of)
}

/// A vertex by its bits: faces of one scene file or mesh share vertices to the bit.
type VertexKey = [u64; 3];

fn vertex_key(v: DVec3) -> VertexKey {
    v.to_array().map(f64::to_bits)
}

/// An edge by its two vertices, in either direction.
fn edge_key(a: DVec3, b: DVec3) -> (VertexKey, VertexKey) {
    let (a, b) = (vertex_key(a), vertex_key(b));
    if a <= b { (a, b) } else { (b, a) }
}

/// The edges of `group` that bound one of its pieces, or `None` when an edge bounds more than
/// two (each must bound one or two).
fn open_edges(
    group: &[usize],
    pieces: &[Occluder],
    edges: &HashMap<(VertexKey, VertexKey), Vec<usize>>,
) -> Option<Vec<(DVec3, DVec3)>> {
    let mut open = Vec::new();
    for &k in group {
        let polygon = &pieces[k].polygon;
        let m = polygon.len();
        for l in 0..m {
            let (u, v) = (polygon[l], polygon[(l + 1) % m]);
            match edges[&edge_key(u, v)].iter().filter(|g| group.contains(g)).count() {
                1 => open.push((u, v)),
                2 => {}
                _ => return None,
            }
        }
    }
    Some(open)
}

/// The side of `piece`'s plane that `points` lie on: 1 or -1, 0 where all lie in it (within
/// `tol`), `None` where they lie on both sides.
fn side(piece: &Occluder, points: &[DVec3], tol: f64) -> Option<f64> {
    let (n, origin) = (piece.normal(), piece.polygon[0]);
    let (mut above, mut below) = (false, false);
    for &v in points {
        let h = n.dot(v - origin);
        above |= h > tol;
        below |= h < -tol;
    }
    match (above, below) {
        (true, true) => None,
        (true, false) => Some(1.0),
        (false, true) => Some(-1.0),
        (false, false) => Some(0.0),
    }
}

/// Largest group of pieces grown into a solid (a flat floor of many tiles stops there; each
/// piece seeds a group of its own).
const MAX_SOLID_PIECES: usize = 16;

/// Every vertex of the scene, and the extent of their projections on the directions asked so
/// far: the caps of a city's buildings all lie in the ground's plane, so one pass over the
/// scene answers all of them (a pass per cap made the solids quadratic in the faces).
struct SceneVertices {
    all: Vec<DVec3>,
    size: f64,
    /// Per unit normal (by its bits), the least and greatest `n·v` over `all`.
    extents: HashMap<VertexKey, (f64, f64)>,
}

impl SceneVertices {
    fn new(pieces: &[Occluder]) -> Self {
        let all: Vec<DVec3> = pieces.iter().flat_map(|p| p.polygon.iter().copied()).collect();
        let (lo, hi) = crate::geometry::bounding_box_3d(&all);
        Self { size: (hi - lo).length(), all, extents: HashMap::new() }
    }

    /// Whether every vertex `v` has `n·(v - origin)`, times `sign`, at least `-tol`.
    fn on_side(&mut self, n: DVec3, origin: DVec3, sign: f64, tol: f64) -> bool {
        let all = &self.all;
        let (least, greatest) = *self.extents.entry(vertex_key(n)).or_insert_with(|| {
            all.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
                let h = n.dot(v);
                (a.min(h), b.max(h))
            })
        });
        let h = if sign > 0.0 { least - n.dot(origin) } else { n.dot(origin) - greatest };
        // `n·v - n·origin` and `n·(v - origin)` differ by rounding only: decide by the extent
        // away from the boundary, and by the vertices themselves within rounding of it.
        let rounding = 1e-14 * (self.size + origin.abs().max_element());
        if h >= -tol + rounding {
            true
        } else if h < -tol - rounding {
            false
        } else {
            all.iter().all(|&v| n.dot(v - origin) * sign >= -tol)
        }
    }
}

/// Whether the open edges of a group (with vertices `vertices`) form one loop in a plane that
/// has the group and every vertex of the scene on one side.
fn is_capped(
    open: &[(DVec3, DVec3)],
    vertices: &[DVec3],
    scene: &mut SceneVertices,
    tol: f64,
) -> bool {
    // One loop: every vertex of the open edges ends exactly two of them (pieces need not agree
    // on their orientation), and walking from the first edge visits them all.
    let ends = |p: DVec3| open.iter().filter(|e| e.0 == p || e.1 == p).count();
    if open.iter().any(|e| ends(e.0) != 2 || ends(e.1) != 2) {
        return false;
    }
    let mut loop_points = vec![open[0].0];
    let (mut previous, mut at) = (0, open[0].1);
    while at != open[0].0 {
        loop_points.push(at);
        let Some(k) =
            (0..open.len()).find(|&k| k != previous && (open[k].0 == at || open[k].1 == at))
        else {
            return false;
        };
        at = if open[k].0 == at { open[k].1 } else { open[k].0 };
        previous = k;
        if loop_points.len() > open.len() {
            return false;
        }
    }
    if loop_points.len() != open.len() {
        return false;
    }
    let normal = (1..loop_points.len() - 1)
        .map(|k| (loop_points[k] - loop_points[0]).cross(loop_points[k + 1] - loop_points[0]))
        .sum::<DVec3>();
    let Some(n) = normal.try_normalize() else { return false };
    let h = |v: DVec3| n.dot(v - loop_points[0]);
    let planar = loop_points.iter().all(|&v| h(v).abs() <= tol);
    let up =
        vertices.iter().map(|&v| h(v)).fold(0.0, |a: f64, x| if x.abs() > a.abs() { x } else { a });
    planar && up != 0.0 && scene.on_side(n, loop_points[0], up.signum(), tol)
}
