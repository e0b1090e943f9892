//! The sunlit part of each element, exactly: a point of an element is in the sun when the ray
//! from it towards the sun meets no face. The points of an occluder that can hide part of an
//! element are those above the element's plane; moved along the sun's direction down to that
//! plane they make a convex shadow (a parallel projection keeps a convex polygon convex), and
//! the element minus its shadows is a set of disjoint convex pieces
//! ([`subtract_convex`]), exact up to the rounding of line intersections.
//!
//! The occluders are the scene's faces triangulated once (refine 0), found for each element in
//! an R*-tree of their boxes seen along the sun: an occluder can shadow an element only where
//! the two overlap seen from the sun.

use glam::{DVec2, DVec3};
use rayon::prelude::*;
use rstar::primitives::{GeomWithData, Rectangle};
use rstar::{AABB, RTree};
use serde::Serialize;
use smallvec::SmallVec;

use crate::error::Result;
use crate::geometry::{PlaneFrame, SmallPolygon, clip_polygon_3d, signed_area, subtract_convex};
use crate::mesh::{Element, Mesh, MeshKind};
use crate::scene::Scene;

/// What the sun gives one element (or, summed by [`Sunlit::by_face`], one face).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct Sunlit {
    /// Area.
    pub area: f64,
    /// Area of the part in the sun.
    pub lit_area: f64,
    /// Cosine of the sun's angle of incidence on the element's side that its normal points
    /// to; 0 where that side faces away from the sun (or the sun is below the horizon).
    pub cos_incidence: f64,
}

impl Sunlit {
    /// The share of the area in the sun.
    pub fn fraction(&self) -> f64 {
        if self.area > 0.0 { self.lit_area / self.area } else { 0.0 }
    }

    /// The direct irradiance averaged over the area, for a sun of `direct_normal` irradiance.
    pub fn irradiance(&self, direct_normal: f64) -> f64 {
        direct_normal * self.cos_incidence * self.fraction()
    }

    /// The elements' results summed over each face of `mesh` (a face is planar: one cosine).
    pub fn by_face(mesh: &Mesh, elements: &[Sunlit]) -> Vec<Sunlit> {
        (0..mesh.face_count())
            .map(|f| {
                let range = mesh.face_range(f);
                let cos_incidence = elements.get(range.start).map_or(0.0, |e| e.cos_incidence);
                let (area, lit_area) = elements[range]
                    .iter()
                    .fold((0.0, 0.0), |(a, l), e| (a + e.area, l + e.lit_area));
                Sunlit { area, lit_area, cos_incidence }
            })
            .collect()
    }
}

/// An occluder's box in the plane across the sun's direction, with its index.
type Boxed = GeomWithData<Rectangle<[f64; 2]>, usize>;

/// The sunlit part of each element of `mesh` under a sun in `direction` (a unit vector towards
/// the sun, [`super::Sun::direction`]), in the mesh's order.
pub fn sunlit(scene: &Scene, mesh: &Mesh, direction: DVec3) -> Result<Vec<Sunlit>> {
    let occluders = Mesh::new(scene, &MeshKind::Uniform, 0)?;
    let occluders = occluders.elements();
    let across = across(direction);
    let boxes = occluders
        .iter()
        .enumerate()
        .map(|(k, o)| {
            let (lo, hi) = seen_box(&across, &o.vertices);
            GeomWithData::new(Rectangle::from_corners(lo, hi), k)
        })
        .collect();
    let tree = RTree::bulk_load(boxes);
    Ok(mesh
        .elements()
        .par_iter()
        .map(|e| lit_part(scene, e, direction, &across, &tree, occluders))
        .collect())
}

/// A frame whose plane lies across `direction`: coordinates in it are what the sun sees.
fn across(direction: DVec3) -> PlaneFrame {
    let hint = if direction.z.abs() < 0.9 { DVec3::Z } else { DVec3::X };
    PlaneFrame::new(DVec3::ZERO, direction, hint)
}

/// The box of `points` as the sun sees them.
fn seen_box(across: &PlaneFrame, points: &[DVec3]) -> ([f64; 2], [f64; 2]) {
    let (mut lo, mut hi) = (DVec2::INFINITY, DVec2::NEG_INFINITY);
    for &p in points {
        let q = across.to_plane(p);
        (lo, hi) = (lo.min(q), hi.max(q));
    }
    (lo.into(), hi.into())
}

/// The sunlit part of element `e`.
fn lit_part(
    scene: &Scene,
    e: &Element,
    direction: DVec3,
    across: &PlaneFrame,
    tree: &RTree<Boxed>,
    occluders: &[Element],
) -> Sunlit {
    let frame = scene.faces[e.face].frame;
    // Counter-clockwise about the face's normal, so counter-clockwise in its frame.
    let triangle: Vec<DVec2> = e.vertices.iter().map(|&v| frame.to_plane(v)).collect();
    let area = signed_area(&triangle);
    let sun = frame.dir_to_local(direction);
    if sun.z <= 0.0 {
        return Sunlit { area, lit_area: 0.0, cos_incidence: 0.0 };
    }
    let (lo, hi) = seen_box(across, &e.vertices);
    let mut pieces = vec![triangle];
    let mut above = SmallPolygon::new();
    let offset = -frame.normal.dot(frame.origin);
    for o in tree.locate_in_envelope_intersecting(AABB::from_corners(lo, hi)) {
        let occluder = &occluders[o.data];
        // A planar face hides none of itself; what lies in the element's plane or below it
        // hides nothing of it.
        if occluder.face == e.face
            || !clip_polygon_3d(&occluder.vertices, frame.normal, offset, &mut above)
        {
            continue;
        }
        let Some(shadow) = shadow(&frame, sun, &above) else { continue };
        pieces = pieces.iter().flat_map(|piece| subtract_convex(piece, &shadow)).collect();
        if pieces.is_empty() {
            break;
        }
    }
    // From +0: an empty sum of f64 is -0.
    let lit_area = pieces.iter().fold(0.0, |sum, p| sum + signed_area(p));
    Sunlit { area, lit_area, cos_incidence: sun.z }
}

/// The shadow on the plane of `frame` of the convex polygon `above` (on or above that plane),
/// cast along `sun` (the direction towards the sun in the frame's coordinates, `sun.z > 0`),
/// counter-clockwise; `None` where it has no area (an occluder edge-on to the sun).
fn shadow(frame: &PlaneFrame, sun: DVec3, above: &[DVec3]) -> Option<Vec<DVec2>> {
    let mut cast: SmallVec<[DVec2; 8]> = above
        .iter()
        .map(|&p| {
            let local = frame.to_local(p);
            // Down along the sun's direction by the point's height over the plane.
            let t = local.z.max(0.0) / sun.z;
            DVec2::new(local.x - t * sun.x, local.y - t * sun.y)
        })
        .collect();
    let area = signed_area(&cast);
    let (lo, hi) = cast
        .iter()
        .fold((DVec2::INFINITY, DVec2::NEG_INFINITY), |(lo, hi), &p| (lo.min(p), hi.max(p)));
    let size2 = (hi - lo).length_squared();
    if area.abs() <= 1e-13 * size2 {
        return None;
    }
    if area < 0.0 {
        cast.reverse();
    }
    Some(cast.to_vec())
}
