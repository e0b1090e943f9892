//! Triangle meshes of a scene (paper sec. 2.1): initial triangles per face, refined n -> 4n by
//! joining side midpoints; uniform and discontinuity meshes (sec. 3.1).
//!
//! Elements are stored face by face, so the elements of one face form a contiguous range; each
//! element keeps its face's orientation (vertices counter-clockwise about the face's normal).

mod constrained;
mod graded;
mod grid;
mod shadow_lines;

pub use graded::Grading;
pub use grid::{GridCuts, S5Diagonals, paper_discontinuity_cuts};
pub use shadow_lines::{LineExtent, Segment, Sources, shadow_lines};

use std::ops::Range;
use std::sync::Arc;

use glam::DVec3;

use crate::error::{Error, Result};
use crate::scene::{Diagonal, MIN_RELATIVE_AREA, Scene};

/// A triangle of the mesh.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Element {
    /// Index of the face it lies on.
    pub face: usize,
    /// Vertices, counter-clockwise about the face's normal.
    pub vertices: [DVec3; 3],
}

impl Element {
    /// Centroid (paper (2.5)).
    pub fn centroid(&self) -> DVec3 {
        (self.vertices[0] + self.vertices[1] + self.vertices[2]) / 3.0
    }

    /// Area.
    pub fn area(&self) -> f64 {
        let [a, b, c] = self.vertices;
        0.5 * (b - a).cross(c - a).length()
    }

    /// Diameter (longest side).
    pub fn diameter(&self) -> f64 {
        let [a, b, c] = self.vertices;
        (b - a).length().max((c - b).length()).max((a - c).length())
    }

    /// The four children of midpoint refinement, with the parent's orientation.
    pub fn refine(&self) -> [Element; 4] {
        let [a, b, c] = self.vertices;
        let (ab, bc, ca) = ((a + b) * 0.5, (b + c) * 0.5, (c + a) * 0.5);
        let face = self.face;
        [[a, ab, ca], [ab, b, bc], [ca, bc, c], [ab, bc, ca]]
            .map(|vertices| Element { face, vertices })
    }
}

/// How the initial triangles of each face are made.
#[derive(Clone, Debug, PartialEq)]
pub enum MeshKind {
    /// Each quadrilateral face split by its diagonal, other faces triangulated (paper's "uniform mesh").
    Uniform,
    /// Faces cut along given lines first (paper's "discontinuity mesh", Fig. 3.3).
    Discontinuity(Vec<GridCuts>),
    /// Each face triangulated (constrained Delaunay) so that no element crosses the given
    /// segments, one list per face in face coordinates ([`shadow_lines`]).
    Constrained(Vec<Vec<Segment>>),
}

/// A triangulation of a scene.
#[derive(Clone, Debug)]
pub struct Mesh {
    /// Shared with the discretizations made from it ([`Mesh::shared_elements`]).
    elements: Arc<[Element]>,
    face_ranges: Vec<Range<usize>>,
}

impl Mesh {
    /// The initial triangulation of every face, then `refine` rounds of midpoint refinement.
    pub fn new(scene: &Scene, kind: &MeshKind, refine: u32) -> Result<Self> {
        if refine > 12 {
            return Err(Error::InvalidParameter {
                name: "refine",
                value: refine.to_string(),
                reason: "at most 12 refinement levels (each multiplies the elements by 4)".into(),
            });
        }
        let mut per_face: Vec<Vec<Element>> = Vec::with_capacity(scene.faces.len());
        for (k, face) in scene.faces.iter().enumerate() {
            let cuts = match kind {
                MeshKind::Discontinuity(cuts) => cuts.iter().find(|c| c.face == k),
                MeshKind::Uniform | MeshKind::Constrained(_) => None,
            };
            let tris = match (cuts, kind) {
                (Some(c), _) => grid::cut_quadrilateral(face, c)?,
                (None, MeshKind::Constrained(lines)) if !lines[k].is_empty() => {
                    constrained::triangulate_with_segments(face, &lines[k])?
                }
                _ => initial_triangles(face)?,
            };
            for tri in &tris {
                let size = (0..3).map(|i| (tri[i] - tri[(i + 1) % 3]).length()).fold(0.0, f64::max);
                let area = 0.5 * (tri[1] - tri[0]).cross(tri[2] - tri[0]).length();
                // The face's own checks allow vertices that are collinear only with a diagonal;
                // such a triangle has no usable basis functions and defeats every quadrature.
                if area.is_nan() || area <= MIN_RELATIVE_AREA * size * size {
                    return Err(Error::DegenerateElement { face: face.name.clone(), area, size });
                }
            }
            per_face.push(tris.into_iter().map(|vertices| Element { face: k, vertices }).collect());
        }
        for _ in 0..refine {
            for tris in &mut per_face {
                *tris = tris.iter().flat_map(Element::refine).collect();
            }
        }
        let mut elements = Vec::new();
        let mut face_ranges = Vec::new();
        for tris in per_face {
            let start = elements.len();
            elements.extend(tris);
            face_ranges.push(start..elements.len());
        }
        Ok(Self { elements: elements.into(), face_ranges })
    }

    /// All elements, face by face.
    pub fn elements(&self) -> &[Element] {
        &self.elements
    }

    /// The elements, shared rather than copied (a discretization keeps them to place its
    /// elements).
    pub(crate) fn shared_elements(&self) -> Arc<[Element]> {
        Arc::clone(&self.elements)
    }

    /// Number of elements n.
    pub fn len(&self) -> usize {
        self.elements.len()
    }

    /// Whether the mesh has no elements.
    pub fn is_empty(&self) -> bool {
        self.elements.is_empty()
    }

    /// The elements of face `f`, as a range of element indices.
    pub fn face_range(&self, f: usize) -> Range<usize> {
        self.face_ranges[f].clone()
    }

    /// Number of faces.
    pub fn face_count(&self) -> usize {
        self.face_ranges.len()
    }

    /// Largest element diameter h.
    pub fn mesh_size(&self) -> f64 {
        self.elements.iter().map(Element::diameter).fold(0.0, f64::max)
    }
}

/// Initial triangles of a face: those it was merged from, if any; else quadrilaterals by their
/// diagonal, other convex polygons by a fan from vertex 0, non-convex polygons by ear clipping.
fn initial_triangles(face: &crate::scene::Face) -> Result<Vec<[DVec3; 3]>> {
    if !face.triangles.is_empty() {
        return Ok(face.triangles.clone());
    }
    let v = &face.vertices;
    if v.len() == 4 && face.is_convex() {
        return Ok(match face.diagonal {
            Diagonal::FromFirst => vec![[v[0], v[1], v[2]], [v[0], v[2], v[3]]],
            Diagonal::FromSecond => vec![[v[0], v[1], v[3]], [v[1], v[2], v[3]]],
        });
    }
    if face.is_convex() {
        return Ok((1..v.len() - 1).map(|k| [v[0], v[k], v[k + 1]]).collect());
    }
    let local = face.local_polygon();
    let tris = crate::geometry::triangulate(&local).ok_or_else(|| Error::DegenerateFace {
        face: face.name.clone(),
        area: face.area(),
        size: face.size(),
    })?;
    Ok(tris.into_iter().map(|[a, b, c]| [v[a], v[b], v[c]]).collect())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::{SurfaceParameters, five_piece, four_piece};

    #[test]
    fn uniform_meshes_have_the_paper_sizes() {
        let p = SurfaceParameters::default();
        for (refine, n4, n5) in [(0, 8, 10), (1, 32, 40), (2, 128, 160), (4, 2048, 2560)] {
            assert_eq!(
                Mesh::new(&four_piece(p).unwrap(), &MeshKind::Uniform, refine).unwrap().len(),
                n4
            );
            assert_eq!(
                Mesh::new(&five_piece(p).unwrap(), &MeshKind::Uniform, refine).unwrap().len(),
                n5
            );
        }
    }

    #[test]
    fn refinement_preserves_area_and_orientation() {
        let scene = five_piece(SurfaceParameters::default()).unwrap();
        let mesh = Mesh::new(&scene, &MeshKind::Uniform, 3).unwrap();
        for f in 0..scene.faces.len() {
            let area: f64 = mesh.elements()[mesh.face_range(f)].iter().map(Element::area).sum();
            assert!((area - scene.faces[f].area()).abs() < 1e-12, "face {f}");
            for e in &mesh.elements()[mesh.face_range(f)] {
                let [a, b, c] = e.vertices;
                assert!((b - a).cross(c - a).dot(scene.faces[f].frame.normal) > 0.0);
            }
        }
        assert!((mesh.mesh_size() - 5.0 * 2f64.sqrt() / 8.0).abs() < 1e-12);
    }

    #[test]
    fn s5_is_split_by_the_diagonal_from_a_a_0() {
        let scene = five_piece(SurfaceParameters::default()).unwrap();
        let mesh = Mesh::new(&scene, &MeshKind::Uniform, 0).unwrap();
        let s5 = &mesh.elements()[mesh.face_range(4)];
        let diag = [DVec3::new(5.0, 5.0, 0.0), DVec3::new(0.0, 5.0, 1.0)];
        for e in s5 {
            assert!(diag.iter().all(|d| e.vertices.contains(d)), "{e:?}");
        }
    }

    #[test]
    fn too_many_refinements_are_refused() {
        let scene = four_piece(SurfaceParameters::default()).unwrap();
        assert!(Mesh::new(&scene, &MeshKind::Uniform, 13).is_err());
    }
}
