//! Orthonormal frames of planes: local coordinates (X, Y, height) used by every kernel (paper sec. 4.1,
//! where the element lies in the xy-plane and P = (x, y, z) with z > 0).

use glam::{DVec2, DVec3};

/// A right-handed orthonormal frame attached to a plane: `normal = e1 × e2`.
///
/// Local coordinates of a point are `((p - origin)·e1, (p - origin)·e2, (p - origin)·normal)`; the
/// third one is the signed height above the plane, positive on the side the normal points to.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PlaneFrame {
    /// A point of the plane, the origin of the local coordinates.
    pub origin: DVec3,
    /// First in-plane unit axis.
    pub e1: DVec3,
    /// Second in-plane unit axis, `normal × e1`.
    pub e2: DVec3,
    /// Unit normal.
    pub normal: DVec3,
}

impl PlaneFrame {
    /// Builds a frame from a point, a unit normal and a direction (not parallel to the normal) that
    /// fixes the first axis. Panics if the direction is parallel to the normal (a programmer error).
    pub fn new(origin: DVec3, normal: DVec3, e1_hint: DVec3) -> Self {
        let e1 = (e1_hint - normal * e1_hint.dot(normal)).normalize();
        assert!(e1.is_finite(), "PlaneFrame::new: axis hint parallel to the normal");
        let e2 = normal.cross(e1);
        Self { origin, e1, e2, normal }
    }

    /// The same plane and axes with another origin.
    pub fn with_origin(&self, origin: DVec3) -> Self {
        Self { origin, ..*self }
    }

    /// Local coordinates (X, Y, height) of a point.
    pub fn to_local(&self, p: DVec3) -> DVec3 {
        let d = p - self.origin;
        DVec3::new(d.dot(self.e1), d.dot(self.e2), d.dot(self.normal))
    }

    /// Local components of a direction.
    pub fn dir_to_local(&self, v: DVec3) -> DVec3 {
        DVec3::new(v.dot(self.e1), v.dot(self.e2), v.dot(self.normal))
    }

    /// In-plane coordinates of a point (its projection onto the plane).
    pub fn to_plane(&self, p: DVec3) -> DVec2 {
        let d = p - self.origin;
        DVec2::new(d.dot(self.e1), d.dot(self.e2))
    }

    /// The point of the plane with in-plane coordinates `q`.
    pub fn to_global(&self, q: DVec2) -> DVec3 {
        self.origin + self.e1 * q.x + self.e2 * q.y
    }

    /// Signed height of a point above the plane.
    pub fn height(&self, p: DVec3) -> f64 {
        (p - self.origin).dot(self.normal)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn local_coordinates_round_trip_and_are_right_handed() {
        let n = DVec3::new(1.0, 2.0, -2.0).normalize();
        let f = PlaneFrame::new(DVec3::new(0.5, -1.0, 3.0), n, DVec3::X);
        assert!((f.e1.cross(f.e2) - f.normal).length() < 1e-15);
        let p = DVec3::new(2.0, 0.25, -7.0);
        let l = f.to_local(p);
        let back = f.to_global(DVec2::new(l.x, l.y)) + f.normal * l.z;
        assert!((back - p).length() < 1e-14, "{back} vs {p}");
        assert_eq!(f.height(p), l.z);
    }
}
