//! Coplanar triangles of an imported mesh joined into planar polygons.
//!
//! STL files, and most OBJ exports, describe a floor or a wall as many triangles. Every face
//! is an occluder and a target of the pair plan, which costs a view per (node, face): a wall of
//! two triangles costs two views, a ground of ten thousand costs ten thousand. Joined into
//! polygons, the faces are the surfaces the user meant; the triangles stay the face's initial
//! elements, so the discretization is the one the file gave.
//!
//! A region grows from a seed triangle across edges that exactly two faces share (by the bits
//! of their vertices, as a mesh file's triangles share them), taking in triangles of the same
//! properties and orientation that lie within the planarity tolerance of a face
//! ([`PLANARITY`] of the region's size) of the seed's plane, and only while the region stays a
//! disk: a triangle that would close a ring around a hole, or touch the region at a vertex
//! only, waits until a neighbour fills the gap, or starts another region. A region stops
//! growing at [`MAX_OUTLINE`] outline vertices, so that a view of a face stays cheap.

use std::collections::{HashMap, VecDeque};

use glam::DVec3;

use super::face::{Face, MIN_RELATIVE_AREA, PLANARITY};

/// Largest number of outline vertices a region grows to (the outline is tested for
/// self-intersection in quadratic time, and views clip against it).
const MAX_OUTLINE: usize = 64;

/// A vertex by its bits.
type Key = [u64; 3];

fn key(v: DVec3) -> Key {
    v.to_array().map(f64::to_bits)
}

fn edge(a: Key, b: Key) -> (Key, Key) {
    if a <= b { (a, b) } else { (b, a) }
}

/// What merging did: the faces before and after.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Merged {
    /// Faces given.
    pub from: usize,
    /// Faces returned.
    pub to: usize,
}

/// `faces` with the coplanar, edge-connected triangles among those marked `mergeable` joined
/// into polygons (each placed where its first triangle was, named after it with `+K` for the
/// K triangles it took in); the other faces as they were.
pub fn merge_coplanar(faces: Vec<Face>, mergeable: &[bool]) -> (Vec<Face>, Merged) {
    let from = faces.len();
    let candidate: Vec<bool> = faces
        .iter()
        .zip(mergeable)
        .map(|(f, &m)| m && f.vertices.len() == 3 && f.triangles.is_empty())
        .collect();
    let mut users: HashMap<(Key, Key), Vec<usize>> = HashMap::new();
    for (k, face) in faces.iter().enumerate() {
        let v = &face.vertices;
        for l in 0..v.len() {
            users.entry(edge(key(v[l]), key(v[(l + 1) % v.len()]))).or_default().push(k);
        }
    }
    let mut taken = vec![false; faces.len()];
    let mut replaced: Vec<Option<Face>> = vec![None; faces.len()];
    let mut absorbed = vec![false; faces.len()];
    for seed in 0..faces.len() {
        if !candidate[seed] || taken[seed] {
            continue;
        }
        let region = Region::grow(seed, &faces, &candidate, &users, &mut taken);
        if region.members.len() < 2 {
            continue;
        }
        // An outline that is no valid face (rounding across a long region) leaves the
        // triangles faces of their own, which is always right.
        if let Some(face) = region.face(&faces) {
            for &m in &region.members[1..] {
                absorbed[m] = true;
            }
            replaced[seed] = Some(face);
        }
    }
    let merged: Vec<Face> = faces
        .into_iter()
        .zip(replaced)
        .zip(absorbed)
        .filter(|(_, absorbed)| !absorbed)
        .map(|((face, replacement), _)| replacement.unwrap_or(face))
        .collect();
    let to = merged.len();
    (merged, Merged { from, to })
}

/// A disk of coplanar triangles: its outline as a doubly linked loop of vertices
/// (counter-clockwise about the seed's normal), and every vertex it has.
struct Region {
    members: Vec<usize>,
    next: HashMap<Key, Key>,
    prev: HashMap<Key, Key>,
    /// Every vertex it has, inside or on the outline.
    position: HashMap<Key, DVec3>,
    lo: DVec3,
    hi: DVec3,
}

impl Region {
    /// The region grown from `seed` (marking its members `taken`).
    fn grow(
        seed: usize,
        faces: &[Face],
        candidate: &[bool],
        users: &HashMap<(Key, Key), Vec<usize>>,
        taken: &mut [bool],
    ) -> Self {
        let v = &faces[seed].vertices;
        let mut region = Region {
            members: vec![seed],
            next: HashMap::new(),
            prev: HashMap::new(),
            position: HashMap::new(),
            lo: v[0].min(v[1]).min(v[2]),
            hi: v[0].max(v[1]).max(v[2]),
        };
        for l in 0..3 {
            let (a, b) = (key(v[l]), key(v[(l + 1) % 3]));
            region.next.insert(a, b);
            region.prev.insert(b, a);
            region.position.insert(a, v[l]);
        }
        taken[seed] = true;
        let fits = |k: usize, region: &Region| -> bool {
            let (f, s) = (&faces[k], &faces[seed]);
            if f.rho.to_bits() != s.rho.to_bits()
                || f.emission.to_bits() != s.emission.to_bits()
                || f.colour != s.colour
                || f.frame.normal.dot(s.frame.normal) <= 0.0
            {
                return false;
            }
            let (lo, hi) = f
                .vertices
                .iter()
                .fold((region.lo, region.hi), |(lo, hi), &p| (lo.min(p), hi.max(p)));
            let tolerance = PLANARITY * (hi - lo).length();
            f.vertices.iter().all(|&p| s.frame.height(p).abs() <= tolerance)
        };
        let neighbours = |k: usize| {
            let v = &faces[k].vertices;
            (0..3).filter_map(move |l| {
                let shared = &users[&edge(key(v[l]), key(v[(l + 1) % 3]))];
                // An edge of three or more faces (a T of walls) is no place to join.
                (shared.len() == 2).then(|| if shared[0] == k { shared[1] } else { shared[0] })
            })
        };
        let mut queue: VecDeque<usize> = neighbours(seed).collect();
        while let Some(k) = queue.pop_front() {
            if region.next.len() >= MAX_OUTLINE {
                break;
            }
            if taken[k] || !candidate[k] || !fits(k, &region) || !region.take_in(&faces[k]) {
                continue;
            }
            taken[k] = true;
            region.members.push(k);
            // A triangle turned away may fit once this one has filled the gap beside it.
            queue.extend(neighbours(k).filter(|&n| !taken[n]));
        }
        region
    }

    /// Adds the triangle if it shares an outline edge and the region stays a disk.
    fn take_in(&mut self, face: &Face) -> bool {
        let v = &face.vertices;
        let keys = [key(v[0]), key(v[1]), key(v[2])];
        // The triangle runs b -> a along an outline edge a -> b; c is its third vertex.
        let Some(l) = (0..3).find(|&l| self.next.get(&keys[(l + 1) % 3]) == Some(&keys[l])) else {
            return false;
        };
        let (b, a, c) = (keys[l], keys[(l + 1) % 3], keys[(l + 2) % 3]);
        if !self.position.contains_key(&c) {
            // A new vertex between a and b.
            self.link(a, c);
            self.link(c, b);
            self.position.insert(c, v[(l + 2) % 3]);
        } else if self.prev.get(&a) == Some(&c) && self.next.len() > 3 {
            // It fills the notch c -> a -> b: a goes inside.
            self.unlink(a);
            self.link(c, b);
        } else if self.next.get(&b) == Some(&c) && self.next.len() > 3 {
            // It fills the notch a -> b -> c: b goes inside.
            self.unlink(b);
            self.link(a, c);
        } else {
            return false;
        }
        self.lo = self.lo.min(v[0]).min(v[1]).min(v[2]);
        self.hi = self.hi.max(v[0]).max(v[1]).max(v[2]);
        true
    }

    fn link(&mut self, from: Key, to: Key) {
        self.next.insert(from, to);
        self.prev.insert(to, from);
    }

    fn unlink(&mut self, vertex: Key) {
        self.next.remove(&vertex);
        self.prev.remove(&vertex);
    }

    /// The region as one face: its outline without the vertices that lie on the line through
    /// their neighbours (as a face must be), its members' triangles as the elements; `None`
    /// where that outline is no valid face.
    fn face(&self, faces: &[Face]) -> Option<Face> {
        let start = *self.next.keys().min()?;
        let mut outline = vec![self.position[&start]];
        let mut at = self.next[&start];
        while at != start {
            outline.push(self.position[&at]);
            at = self.next[&at];
        }
        let size = (self.hi - self.lo).length();
        // Twice the largest corner area that Face::new calls collinear, with room for rounding.
        let straight = 4.0 * MIN_RELATIVE_AREA * size * size;
        let mut k = 0;
        while k < outline.len() && outline.len() > 3 {
            let n = outline.len();
            let (a, b, c) = (outline[(k + n - 1) % n], outline[k], outline[(k + 1) % n]);
            if (b - a).cross(c - b).length() <= straight {
                outline.remove(k);
                k = k.saturating_sub(1);
            } else {
                k += 1;
            }
        }
        let seed = &faces[self.members[0]];
        let name = format!("{}+{}", seed.name, self.members.len() - 1);
        let triangles =
            self.members.iter().map(|&m| <[DVec3; 3]>::try_from(faces[m].vertices.as_slice()));
        let triangles: Vec<[DVec3; 3]> = triangles.collect::<Result<_, _>>().ok()?;
        let face = Face::new(name, outline, seed.rho)
            .and_then(|f| f.with_emission(seed.emission))
            .and_then(|f| f.with_colour(seed.colour))
            .ok()?;
        // The outline must enclose the triangles' area (an outline that crossed itself within
        // rounding of the tolerance would not).
        let area: f64 =
            triangles.iter().map(|t| 0.5 * (t[1] - t[0]).cross(t[2] - t[0]).length()).sum();
        ((area - face.area()).abs() <= 1e-9 * area).then(|| face.with_triangles(triangles))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The triangles of an `nx` x `ny` grid of unit cells in the plane z = 0, facing up, but for
    /// the cells that `hole` names.
    fn grid(
        nx: usize,
        ny: usize,
        rho: impl Fn(usize) -> f64,
        hole: impl Fn(usize, usize) -> bool,
    ) -> Vec<Face> {
        let mut faces = Vec::new();
        let p = |a: usize, b: usize| DVec3::new(a as f64, b as f64, 0.0);
        for i in 0..nx {
            for j in 0..ny {
                if hole(i, j) {
                    continue;
                }
                let (a, b, c, d) = (p(i, j), p(i + 1, j), p(i + 1, j + 1), p(i, j + 1));
                for t in [[a, b, c], [a, c, d]] {
                    let name = format!("t{}", faces.len());
                    faces.push(Face::new(name, t.to_vec(), rho(i)).unwrap());
                }
            }
        }
        faces
    }

    fn merged(given: &[Face]) -> (Vec<Face>, Merged) {
        merge_coplanar(given.to_vec(), &vec![true; given.len()])
    }

    /// Every triangle given is an element of exactly one face returned, and the faces cover
    /// the area of the triangles.
    fn keeps_every_triangle(given: &[Face], faces: &[Face]) {
        let bits = |t: &[DVec3]| -> Vec<Key> { t.iter().map(|&v| key(v)).collect() };
        let mut before: Vec<Vec<Key>> = given.iter().map(|f| bits(&f.vertices)).collect();
        let mut after: Vec<Vec<Key>> = faces
            .iter()
            .flat_map(|f| match f.triangles.is_empty() {
                true => vec![bits(&f.vertices)],
                false => f.triangles.iter().map(|t| bits(t)).collect(),
            })
            .collect();
        before.sort();
        after.sort();
        assert_eq!(before, after);
        let area = |faces: &[Face]| faces.iter().map(Face::area).sum::<f64>();
        assert!((area(given) - area(faces)).abs() <= 1e-12 * area(given));
    }

    #[test]
    fn a_tessellated_rectangle_becomes_one_face_of_its_four_corners() {
        let given = grid(3, 2, |_| 0.5, |_, _| false);
        let (faces, m) = merged(&given);
        assert_eq!(m, Merged { from: 12, to: 1 });
        assert_eq!(faces[0].name, "t0+11");
        assert_eq!(faces[0].vertices.len(), 4, "{:?}", faces[0].vertices);
        assert_eq!(faces[0].triangles.len(), 12);
        keeps_every_triangle(&given, &faces);
    }

    #[test]
    fn a_ring_around_a_hole_becomes_faces_without_holes() {
        let given = grid(3, 3, |_| 0.5, |i, j| i == 1 && j == 1);
        let (faces, m) = merged(&given);
        assert!(m.to >= 2 && m.to <= 4, "{m:?}");
        keeps_every_triangle(&given, &faces);
    }

    #[test]
    fn properties_orientation_and_edges_of_three_faces_keep_triangles_apart() {
        // Two columns of different rho: two faces.
        let given = grid(2, 2, |i| [0.5, 0.7][i], |_, _| false);
        let (faces, m) = merged(&given);
        assert_eq!(m.to, 2);
        keeps_every_triangle(&given, &faces);
        // A triangle facing down beside the grid stays alone.
        let mut given = grid(1, 1, |_| 0.5, |_, _| false);
        let down = vec![DVec3::X, DVec3::new(1.0, 1.0, 0.0), DVec3::new(2.0, 0.5, 0.0)];
        given.push(Face::new("down", down, 0.5).unwrap());
        assert_eq!(merged(&given).1.to, 2);
        // A fin standing on the edge between two cells: the cells do not join across it.
        let mut given = grid(2, 1, |_| 0.5, |_, _| false);
        let fin = vec![DVec3::X, DVec3::new(1.0, 1.0, 0.0), DVec3::new(1.0, 0.5, 1.0)];
        given.push(Face::new("fin", fin, 0.5).unwrap());
        let (faces, m) = merged(&given);
        assert_eq!(m.to, 3);
        keeps_every_triangle(&given, &faces);
        // Faces not marked mergeable stay as they are.
        let given = grid(2, 2, |_| 0.5, |_, _| false);
        let (faces, m) = merge_coplanar(given.clone(), &vec![false; given.len()]);
        assert_eq!(m.to, 8);
        assert!(
            faces.iter().zip(&given).all(|(a, b)| a.vertices == b.vertices && a.name == b.name)
        );
    }

    #[test]
    fn a_large_grid_becomes_faces_of_bounded_outline() {
        let given = grid(40, 40, |_| 0.5, |i, j| (i * 7 + j * 3) % 11 == 0);
        let (faces, m) = merged(&given);
        assert!(m.to * 10 < m.from, "{m:?}");
        assert!(faces.iter().all(|f| f.vertices.len() <= MAX_OUTLINE));
        keeps_every_triangle(&given, &faces);
    }
}
