//! Graded meshes (paper sec. 2.4.1): elements shrink toward chosen edges of faces, where the
//! solution has the singular behaviour (2.31) of a common edge. A point at distance d from the
//! graded edge (within its face, D the largest such distance) moves to distance D (d/D)^q; lines
//! parallel to the edge stay parallel, so the refined lattice of a face keeps its orientation.

use std::sync::Arc;

use glam::DVec3;

use super::Mesh;
use crate::error::{Error, Result};
use crate::scene::{MIN_RELATIVE_AREA, Scene};

/// Grading toward edges: each `(face, k)` names the edge from vertex k to vertex k + 1.
#[derive(Clone, Debug, PartialEq)]
pub struct Grading {
    /// The graded edges, at most one per face.
    pub edges: Vec<(usize, usize)>,
    /// Exponent q >= 1 (1: uniform).
    pub exponent: f64,
}

impl Grading {
    /// Parses `FACE:K` entries against `scene`.
    pub fn parse(scene: &Scene, entries: &[String], exponent: f64) -> Result<Self> {
        if !(exponent.is_finite() && (1.0..=10.0).contains(&exponent)) {
            return Err(Error::InvalidParameter {
                name: "grading",
                value: exponent.to_string(),
                reason: "the grading exponent q must lie in [1, 10]".into(),
            });
        }
        let mut edges: Vec<(usize, usize)> = Vec::new();
        for entry in entries {
            let bad = |reason: String| Error::InvalidParameter {
                name: "grade",
                value: entry.clone(),
                reason,
            };
            let (name, k) = entry
                .rsplit_once(':')
                .ok_or_else(|| bad("expected FACE:EDGE, e.g. S1:2".into()))?;
            let face = scene.face_index(name).ok_or_else(|| bad(format!("no face '{name}'")))?;
            let count = scene.faces[face].vertices.len();
            let k: usize = k
                .parse()
                .ok()
                .filter(|&k| k < count)
                .ok_or_else(|| bad(format!("face '{name}' has edges 0 to {}", count - 1)))?;
            if edges.iter().any(|&(f, _)| f == face) {
                return Err(bad(format!("face '{name}' is graded toward one edge at most")));
            }
            edges.push((face, k));
        }
        Ok(Self { edges, exponent })
    }
}

impl Mesh {
    /// Moves the vertices of the graded faces' elements (see the module documentation).
    pub fn grade(&mut self, scene: &Scene, grading: &Grading) -> Result<()> {
        for &(f, k) in &grading.edges {
            let face = &scene.faces[f];
            let v = &face.vertices;
            let (a, b) = (v[k], v[(k + 1) % v.len()]);
            let along = (b - a).normalize();
            // Inward unit vector in the face's plane, perpendicular to the edge.
            let inward = face.frame.normal.cross(along);
            let depth = v.iter().map(|&x| (x - a).dot(inward)).fold(0.0, f64::max);
            let map = |x: DVec3| {
                let d = (x - a).dot(inward).max(0.0);
                x + inward * (depth * (d / depth).powf(grading.exponent) - d)
            };
            let size = face.size();
            for e in &mut Arc::make_mut(&mut self.elements)[self.face_ranges[f].clone()] {
                let before = (e.vertices[1] - e.vertices[0]).cross(e.vertices[2] - e.vertices[0]);
                e.vertices = e.vertices.map(map);
                let after = (e.vertices[1] - e.vertices[0]).cross(e.vertices[2] - e.vertices[0]);
                if after.dot(before) <= MIN_RELATIVE_AREA * size * size {
                    return Err(Error::InvalidParameter {
                        name: "grading",
                        value: format!("face '{}' edge {k}", face.name),
                        reason: "an element folds over; grade a face whose triangulation has \
                                 lines parallel to the edge (parallelograms, triangles by an edge)"
                            .into(),
                    });
                }
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::MeshKind;
    use crate::scene::{SurfaceParameters, five_piece};

    #[test]
    fn grading_toward_the_common_edge_keeps_area_and_clusters_elements() {
        let scene = five_piece(SurfaceParameters::default()).unwrap();
        let mut mesh = Mesh::new(&scene, &MeshKind::Uniform, 3).unwrap();
        let grading = Grading::parse(&scene, &["S1:2".into(), "S5:3".into()], 3.0).unwrap();
        mesh.grade(&scene, &grading).unwrap();
        for f in [0, 4] {
            let area: f64 = mesh.elements()[mesh.face_range(f)].iter().map(|e| e.area()).sum();
            assert!((area - scene.faces[f].area()).abs() < 1e-12, "face {f}");
        }
        // S1's lattice lines y = 5 - 5 (j/8) map to 5 - 5 (j/8)^3: the first row is 5/512 wide.
        let nearest = mesh.elements()[mesh.face_range(0)]
            .iter()
            .flat_map(|e| e.vertices)
            .map(|v| 5.0 - v.y)
            .filter(|&d| d > 1e-12)
            .fold(f64::INFINITY, f64::min);
        assert!((nearest - 5.0 / 512.0).abs() < 1e-12, "{nearest}");
        assert!(Grading::parse(&scene, &["S1:9".into()], 2.0).is_err());
        assert!(Grading::parse(&scene, &["S9:0".into()], 2.0).is_err());
        assert!(Grading::parse(&scene, &["S1:0".into(), "S1:1".into()], 2.0).is_err());
        assert!(Grading::parse(&scene, &["S1:0".into()], 0.5).is_err());
    }
}
