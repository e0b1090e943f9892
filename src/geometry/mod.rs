//! Geometry: plane frames, 2-D convex polygons (clipping, subtraction), 3-D polygon clipping and
//! distances.
//!
//! Everything the pair plan and the kernels need to describe "the part of an element a node can see"
//! lives here, in plain f64 arithmetic with no snapping, so that visible pieces are exact up to
//! rounding (paper sec. 2.7: an O(h) error in a partially visible element destroys the rates).

mod distance;
mod frame;
mod polygon;
#[cfg(test)]
pub(crate) use polygon::ON_LINE;

pub use distance::convex_polygons_distance;
pub use frame::PlaneFrame;
pub use polygon::{
    HalfPlane, SmallPolygon, bounding_box, bounding_box_3d, box_corners, boxes_overlap,
    clip_convex, clip_convex_into, clip_polygon_3d, clip_to_convex, clip_to_half_planes,
    convex_apart, convex_contains, convex_hull, convex_partition, distance_to_convex,
    polygon_contains, signed_area, subtract_convex, triangulate, wholly_inside_3d,
};

/// Vectors used throughout: glam's f64 vectors.
pub use glam::{DVec2, DVec3};

/// `2^-e` for the binary exponent `e` of `length`, so that `length * unit` lies in [1, 2): a unit
/// of length by which coordinates can be scaled exactly (1 for zero, subnormal or non-finite
/// lengths).
pub fn power_of_two_unit(length: f64) -> f64 {
    let exponent = ((length.to_bits() >> 52) & 0x7ff) as i64 - 1023;
    if (-1000..=1000).contains(&exponent) {
        f64::from_bits(((1023 - exponent) as u64) << 52)
    } else {
        1.0
    }
}

#[cfg(test)]
mod unit_tests {
    use super::power_of_two_unit;

    #[test]
    fn the_unit_scales_a_length_into_1_to_2_exactly() {
        for length in [1.0, 1.5, 3.0, 1e-115, 7.3e99, 0.75] {
            let scaled = length * power_of_two_unit(length);
            assert!((1.0..2.0).contains(&scaled), "{length}: {scaled}");
            assert_eq!(scaled / power_of_two_unit(length), length, "exact");
        }
        assert_eq!(power_of_two_unit(0.0), 1.0);
        assert_eq!(power_of_two_unit(f64::INFINITY), 1.0);
    }
}
