//! Scenes: planar polygonal faces with their radiating side, reflectivity and emissivity
//! (paper sec. 1: S = S_1 ∪ ... ∪ S_J, each S_j a closed polygon).

mod builtin;
mod face;

pub use builtin::{BuiltinScene, SurfaceParameters, baffled_box, cube, five_piece, four_piece};
pub use face::{Diagonal, Face};

use crate::error::{Error, Result};

/// A set of faces. Every face is opaque to light crossing it (an occluder), and radiates and
/// receives on the side its normal points to.
#[derive(Clone, Debug)]
pub struct Scene {
    /// Name, for reports.
    pub name: String,
    /// The faces.
    pub faces: Vec<Face>,
}

/// Largest ratio of the scene's largest coordinate to its smallest face: beyond it, the kernels'
/// fourth powers of distances in units of an element could overflow.
pub const MAX_SCALE_RANGE: f64 = 1e60;

impl Scene {
    /// A scene from validated faces; face names must be unique.
    pub fn new(name: impl Into<String>, faces: Vec<Face>) -> Result<Self> {
        let name = name.into();
        if faces.is_empty() {
            return Err(Error::InvalidParameter {
                name: "faces",
                value: "0".into(),
                reason: format!("scene '{name}' has no faces"),
            });
        }
        for (k, f) in faces.iter().enumerate() {
            if faces[..k].iter().any(|g| g.name == f.name) {
                return Err(Error::InvalidParameter {
                    name: "face name",
                    value: f.name.clone(),
                    reason: "face names must be unique".into(),
                });
            }
        }
        let magnitude = faces
            .iter()
            .flat_map(|f| f.vertices.iter())
            .map(|v| v.abs().max_element())
            .fold(0.0, f64::max);
        if let Some(small) = faces.iter().min_by(|a, b| a.size().total_cmp(&b.size())) {
            if magnitude > MAX_SCALE_RANGE * small.size() {
                return Err(Error::ScaleRange {
                    scene: name,
                    face: small.name.clone(),
                    size: small.size(),
                    magnitude,
                    limit: MAX_SCALE_RANGE,
                });
            }
        }
        Ok(Self { name, faces })
    }

    /// Index of the face with this name.
    pub fn face_index(&self, name: &str) -> Option<usize> {
        self.faces.iter().position(|f| f.name == name)
    }

    /// Whether faces `a` and `b` lie in one plane (either orientation), up to a relative tolerance.
    pub fn coplanar(&self, a: usize, b: usize) -> bool {
        let (fa, fb) = (&self.faces[a], &self.faces[b]);
        let tol = 1e-10 * fa.size().max(fb.size());
        fa.frame.normal.cross(fb.frame.normal).length() < 1e-10
            && fb.vertices.iter().all(|&v| fa.frame.height(v).abs() <= tol)
    }

    /// Total area.
    pub fn area(&self) -> f64 {
        self.faces.iter().map(Face::area).sum()
    }
}
