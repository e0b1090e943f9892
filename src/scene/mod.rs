//! Scenes: planar polygonal faces with their radiating side, reflectivity and emissivity
//! (paper sec. 1: S = S_1 ∪ ... ∪ S_J, each S_j a closed polygon).

mod builtin;
mod city;
mod face;
mod file;
pub mod generated;
mod merge;

pub use builtin::{BuiltinScene, SurfaceParameters, baffled_box, cube, five_piece, four_piece};
pub use city::{city, lit_city};
pub use face::{
    BandSet, CHANNELS, COPLANAR_DISTANCE, Colour, Diagonal, Face, MIN_RELATIVE_AREA, parse_bands,
};
pub use file::{
    Coplanar, Duplicates, IMPORT_RHO, ImportOptions, NonPlanar, Side, from_triangles,
    is_scene_file, load, load_with, parse_toml, stl_triangles,
};
pub use merge::{Merged, merge_coplanar};

use glam::{DVec2, DVec3};
use rstar::primitives::{GeomWithData, Rectangle};
use rstar::{AABB, RTree};

use crate::error::{Error, Result};
use crate::geometry::{HalfPlane, clip_convex, signed_area, triangulate};

/// A set of faces. Every face is opaque to light crossing it (an occluder), and radiates and
/// receives on the side its normal points to.
#[derive(Clone, Debug)]
pub struct Scene {
    /// Name, for reports.
    pub name: String,
    /// The faces, in the scene's local frame: the user's coordinates minus [`Scene::origin`].
    pub faces: Vec<Face>,
    /// Where the local frame's origin lies in the user's coordinates (zero unless the scene lies
    /// far from the origin for its size; [`local_origin`]).
    pub origin: DVec3,
    /// What the loader repaired in the file (non-planar polygons split, duplicates dropped), one
    /// line per kind, for the user.
    pub notes: Vec<String>,
    /// The sun and the sky the scene file gives (`[sun]`, `[sky]`), for `sun` runs.
    pub daylight: Option<Daylight>,
}

/// The sun and the sky of a scene file, as its `[sun]` and `[sky]` tables give them (checked
/// by the `sun` module, which takes them as its sources).
#[derive(Clone, Copy, Debug, PartialEq, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Daylight {
    /// `[sun] zenith`, degrees from the zenith.
    pub zenith: f64,
    /// `[sun] azimuth`, compass degrees clockwise from north.
    pub azimuth: f64,
    /// `[sun] x_azimuth`, the compass direction of +x (default 90: east).
    pub x_azimuth: Option<f64>,
    /// `[sun] direct_normal`, the direct normal irradiance.
    pub direct_normal: f64,
    /// `[sky] diffuse_horizontal` (0 without a `[sky]` table).
    #[serde(skip)]
    pub diffuse_horizontal: f64,
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
        let mut names = std::collections::HashSet::new();
        for f in &faces {
            if !names.insert(f.name.as_str()) {
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
        let origin = local_origin(&faces);
        let faces = if origin == DVec3::ZERO {
            faces
        } else {
            faces.iter().map(|f| f.moved_by(origin)).collect()
        };
        let scene = Self { name, faces, origin, notes: Vec::new(), daylight: None };
        scene.check_no_overlap()?;
        Ok(scene)
    }

    /// Two faces in one plane facing the same way must not overlap: a node would see the shared
    /// area twice. (Facing opposite ways they are the two sides of a plate, as S2 and S3.)
    fn check_no_overlap(&self) -> Result<()> {
        match self.coplanar_overlaps().into_iter().find(|o| o.same_facing) {
            Some(o) => Err(Error::OverlappingFaces {
                first: self.faces[o.first].name.clone(),
                second: self.faces[o.second].name.clone(),
                area: o.area,
            }),
            None => Ok(()),
        }
    }

    /// Faces that lie on one another facing each other but are not the two sides of one plate (a
    /// lid lying on a floor): every pair between them is skipped, which is right for a plate, whose
    /// two faces cover each other exactly, and a modelling mistake otherwise. Returns the two names
    /// and the area they share.
    pub fn faces_in_contact(&self) -> Vec<(String, String, f64)> {
        let covers = |area: f64, face: usize| area >= (1.0 - 1e-9) * self.faces[face].area();
        self.coplanar_overlaps()
            .into_iter()
            .filter(|o| !o.same_facing)
            .filter(|o| !(covers(o.area, o.first) && covers(o.area, o.second)))
            .map(|o| (self.faces[o.first].name.clone(), self.faces[o.second].name.clone(), o.area))
            .collect()
    }

    /// Pairs of faces in one plane that overlap, either orientation.
    fn coplanar_overlaps(&self) -> Vec<CoplanarOverlap> {
        // Only faces whose bounding boxes touch can overlap: an R*-tree finds those pairs.
        let boxes: Vec<(DVec3, DVec3)> = self.faces.iter().map(Face::bounding_box).collect();
        let tree = RTree::bulk_load(
            boxes
                .iter()
                .enumerate()
                .map(|(k, (lo, hi))| {
                    GeomWithData::new(Rectangle::from_corners(lo.to_array(), hi.to_array()), k)
                })
                .collect::<Vec<_>>(),
        );
        let mut overlaps = Vec::new();
        for (a, (lo, hi)) in boxes.iter().enumerate() {
            let pad = DVec3::splat(1e-9 * self.faces[a].size());
            let near = AABB::from_corners((*lo - pad).to_array(), (*hi + pad).to_array());
            for b in tree.locate_in_envelope_intersecting(near).map(|g| g.data).filter(|&b| b > a) {
                let (fa, fb) = (&self.faces[a], &self.faces[b]);
                if !self.coplanar(a, b) {
                    continue;
                }
                let pa = fa.local_polygon();
                let mut pb: Vec<DVec2> =
                    fb.vertices.iter().map(|&v| fa.frame.to_plane(v)).collect();
                let same_facing = fa.frame.normal.dot(fb.frame.normal) > 0.0;
                if !same_facing {
                    // Counter-clockwise in a's plane, as the overlap's triangulation needs.
                    pb.reverse();
                }
                let area = overlap_area(&pa, &pb);
                if area > 1e-9 * fa.area().min(fb.area()) {
                    overlaps.push(CoplanarOverlap { first: a, second: b, area, same_facing });
                }
            }
        }
        overlaps
    }

    /// Index of the face with this name.
    pub fn face_index(&self, name: &str) -> Option<usize> {
        self.faces.iter().position(|f| f.name == name)
    }

    /// Whether faces `a` and `b` lie in one plane (either orientation), up to the planarity
    /// tolerance of a face (1e-9 of the larger size) and a 1e-6 angle between their normals.
    /// Faces that close are in contact: a node on one sees the other edge-on or not at all, and
    /// the integrals between them have no accurate digits, so the pair plan skips them (fuzzing
    /// found a face 1e-22 in front of another, tilted 1e-9, counted as filling a hemisphere).
    pub fn coplanar(&self, a: usize, b: usize) -> bool {
        self.faces[a].is_coplanar_with(&self.faces[b])
    }

    /// Total area.
    pub fn area(&self) -> f64 {
        self.faces.iter().map(Face::area).sum()
    }
}

/// Why triangulating a face's polygon cannot fail: [`Face::new`] refuses faces without a
/// triangulation.
pub(crate) const TRIANGULABLE: &str = "a valid face triangulates (checked in Face::new)";

/// Area common to two simple counter-clockwise polygons (triangulated, then clipped pairwise).
fn overlap_area(a: &[DVec2], b: &[DVec2]) -> f64 {
    let triangles = |p: &[DVec2]| -> Vec<[DVec2; 3]> {
        triangulate(p).expect(TRIANGULABLE).iter().map(|t| [p[t[0]], p[t[1]], p[t[2]]]).collect()
    };
    let (ta, tb) = (triangles(a), triangles(b));
    let mut area = 0.0;
    for s in &ta {
        for t in &tb {
            let mut piece = Some(s.to_vec());
            for k in 0..3 {
                let edge = HalfPlane::left_of(t[k], t[(k + 1) % 3]);
                piece = piece.and_then(|p| clip_convex(&p, &edge));
            }
            area += piece.map_or(0.0, |p| signed_area(&p).abs());
        }
    }
    area
}

/// Two faces of a scene in one plane that overlap.
struct CoplanarOverlap {
    first: usize,
    second: usize,
    area: f64,
    same_facing: bool,
}

/// A scene farther than this many of its sizes from the origin is moved to a local frame.
const FAR_FROM_ORIGIN: f64 = 16.0;

/// The origin of a scene's local frame. Survey and city models arrive in projected coordinates
/// (eastings of 5e5 m, northings of 1e7 m) where every difference of coordinates and every plane
/// offset carries a rounding error of ε |offset|, enough to flip the pair plan's visibility and
/// coplanarity tests. Computing in a frame centred on the scene makes the errors relative to its
/// size again. Per axis on which the scene lies farther than [`FAR_FROM_ORIGIN`] sizes from 0, the
/// origin is the bounding box's centre rounded to a multiple of a power of two `s` at least the
/// scene's size; every coordinate x on that axis then lies within `s` of the origin c, closer than
/// x to 0, and both are multiples of x's last bit, so `x - c` is exact and the moved scene is the
/// same scene. Other axes, and scenes near the origin (the paper's, the examples), stay put.
fn local_origin(faces: &[Face]) -> DVec3 {
    let points = faces.iter().flat_map(|f| f.vertices.iter());
    let (lo, hi) =
        points.fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(lo, hi), v| (lo.min(*v), hi.max(*v)));
    let size = (hi - lo).max_element();
    if size.is_nan() || size <= 0.0 {
        return DVec3::ZERO;
    }
    let step = 2f64.powi(size.log2().ceil() as i32);
    let axis = |lo: f64, hi: f64| {
        if lo.abs().max(hi.abs()) <= FAR_FROM_ORIGIN * size {
            0.0
        } else {
            ((lo + hi) * 0.5 / step).round() * step
        }
    };
    DVec3::new(axis(lo.x, hi.x), axis(lo.y, hi.y), axis(lo.z, hi.z))
}

#[cfg(test)]
mod tests {
    use glam::DVec3;

    use super::*;

    fn square(name: &str, x0: f64, flip: bool) -> Face {
        let mut v = vec![
            DVec3::new(x0, 0.0, 0.0),
            DVec3::new(x0 + 1.0, 0.0, 0.0),
            DVec3::new(x0 + 1.0, 1.0, 0.0),
            DVec3::new(x0, 1.0, 0.0),
        ];
        if flip {
            v.reverse();
        }
        Face::new(name, v, 0.5).unwrap()
    }

    #[test]
    fn overlapping_faces_in_one_plane_are_refused_unless_they_are_a_plate() {
        // Found by fuzzing: two coplanar faces facing the same way, seen twice by every node.
        let e = Scene::new("s", vec![square("a", 0.0, false), square("b", 0.5, false)]);
        let e = e.unwrap_err().to_string();
        assert!(e.contains("'a' and 'b'") && e.contains("5e-1"), "{e}");
        // Side by side, or the two sides of one plate: fine.
        assert!(Scene::new("s", vec![square("a", 0.0, false), square("b", 1.0, false)]).is_ok());
        assert!(Scene::new("s", vec![square("a", 0.0, false), square("b", 0.0, true)]).is_ok());
    }

    #[test]
    fn scenes_far_from_the_origin_move_to_a_local_frame_exactly() {
        for offset in [DVec3::new(-3e7, 0.3, 2e3), DVec3::new(5e5 + 0.1, 4.2e6, 100.3)] {
            let faces: Vec<Face> = [square("a", 0.0, false), square("b", 0.0, true)]
                .into_iter()
                .map(|f| {
                    Face::new(f.name.clone(), f.vertices.iter().map(|v| *v + offset).collect(), 0.5)
                        .unwrap()
                })
                .collect();
            let scene = Scene::new("far", faces.clone()).unwrap();
            assert!(scene.origin.length() > 1e2, "{offset}: origin {}", scene.origin);
            for (moved, original) in scene.faces.iter().zip(&faces) {
                for (m, o) in moved.vertices.iter().zip(&original.vertices) {
                    assert!(m.abs().max_element() <= 2.0, "{m}: not local");
                    assert_eq!(*m + scene.origin, *o, "the move must be exact");
                }
            }
        }
        // Near the origin nothing moves.
        assert_eq!(Scene::new("near", vec![square("a", 3.0, false)]).unwrap().origin, DVec3::ZERO);
    }
}
