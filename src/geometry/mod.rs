//! Geometry: plane frames, 2-D convex polygons (clipping, subtraction) and 3-D polygon clipping.
//!
//! Everything the pair plan and the kernels need to describe "the part of an element a node can see"
//! lives here, in plain f64 arithmetic with no snapping, so that visible pieces are exact up to
//! rounding (paper sec. 2.7: an O(h) error in a partially visible element destroys the rates).

mod frame;
mod polygon;

pub use frame::PlaneFrame;
pub use polygon::{
    HalfPlane, bounding_box, clip_convex, clip_polygon_3d, convex_contains, distance_to_convex,
    signed_area, subtract_convex, triangulate,
};

/// Vectors used throughout: glam's f64 vectors.
pub use glam::{DVec2, DVec3};
