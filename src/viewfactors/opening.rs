//! Openings: coplanar occluders that close their plane between a piece of T_i and T_j but for one
//! convex opening (a partition with a door, a wall with a window, a louvre's frame). From a point
//! of the piece, the part of T_j beyond that plane is then seen only inside the cone through the
//! opening: one convex clip per point, where each piece of the plate cast a shadow of its own.

use glam::{DVec2, DVec3};

use crate::geometry::{
    HalfPlane, PlaneFrame, SmallPolygon, clip_convex_into, clip_polygon_3d, clip_to_half_planes,
    convex_hull, signed_area, subtract_convex,
};
use crate::visibility::PairPlanner;

/// A plate of coplanar occluder pieces between a piece of T_i and T_j, and the convex opening it
/// leaves in the shaft between them (none where it closes it).
pub(super) struct Opening {
    /// The plate's plane `normal·x = offset`, the normal towards the piece of T_i.
    normal: DVec3,
    offset: f64,
    /// The opening's corners in space (convex, in order; none where the plate is closed), and
    /// their centroid.
    corners: Vec<DVec3>,
    centroid: DVec3,
    /// The occluder pieces of the plate, which the opening stands for.
    pub(super) pieces: Vec<usize>,
}

/// Relative size (of the coordinates) under which a height over a plane is rounding.
const HEIGHT_ROUNDING: f64 = 1e-12;

/// Relative size (of an area against the shaft's cross-section, or of a side against its
/// square root) under which what the plate leaves open is rounding.
const ROUNDING: f64 = 1e-9;

impl Opening {
    /// The opening left by the `occluders` (of the shaft from `viewer`, a piece of T_i, to
    /// `target`) that lie in one plane with the viewer on one side and part of the target on the
    /// other, where they leave at most one convex opening between the two: of the planes with the
    /// most such occluders, the first.
    pub(super) fn find(
        viewer: &[DVec3],
        target: &[DVec3; 3],
        occluders: &[usize],
        planner: &PairPlanner,
    ) -> Option<Opening> {
        if occluders.len() < 2 {
            return None;
        }
        let pieces = planner.occluders();
        let scale = viewer.iter().chain(target).fold(0.0f64, |m, v| m.max(v.abs().max_element()));
        let tol = HEIGHT_ROUNDING * scale.max(f64::MIN_POSITIVE);
        // The occluders by plane: (unit normal, offset, members).
        let mut planes: Vec<(DVec3, f64, Vec<usize>)> = Vec::new();
        for &o in occluders {
            let polygon = &pieces[o].polygon;
            let normal = pieces[o].normal();
            let coplanar = |(n, d, _): &&mut (DVec3, f64, Vec<usize>)| {
                n.dot(normal).abs() > 1.0 - 1e-12
                    && polygon.iter().all(|v| (n.dot(*v) - *d).abs() <= tol)
            };
            match planes.iter_mut().find(coplanar) {
                Some((_, _, members)) => members.push(o),
                None => planes.push((normal, normal.dot(polygon[0]), vec![o])),
            }
        }
        planes.sort_by_key(|(_, _, members)| std::cmp::Reverse(members.len()));
        planes.into_iter().take_while(|(_, _, members)| members.len() >= 2).find_map(
            |(normal, offset, members)| {
                Self::in_plane(viewer, target, normal, offset, members, planner, tol)
            },
        )
    }

    /// The opening left by the occluders `members` in the plane `normal·x = offset`.
    fn in_plane(
        viewer: &[DVec3],
        target: &[DVec3; 3],
        normal: DVec3,
        offset: f64,
        members: Vec<usize>,
        planner: &PairPlanner,
        tol: f64,
    ) -> Option<Opening> {
        // The viewer on the positive side (touching the plane at most).
        let heights: Vec<f64> = viewer.iter().map(|&v| normal.dot(v) - offset).collect();
        let (normal, offset) = if heights.iter().all(|&h| h >= -tol) {
            (normal, offset)
        } else if heights.iter().all(|&h| h <= tol) {
            (-normal, -offset)
        } else {
            return None;
        };
        let height = |v: DVec3| normal.dot(v) - offset;
        if viewer.iter().all(|&v| height(v) <= tol) {
            return None;
        }
        // The part of the target beyond the plane.
        let mut beyond = SmallPolygon::new();
        if !clip_polygon_3d(target, -normal, offset, &mut beyond) {
            return None;
        }
        let frame = PlaneFrame::new(normal * offset, normal, any_perpendicular(normal));
        // The shaft's cross-section: where the segments between the corners cross the plane.
        let mut crossings: Vec<DVec2> = Vec::with_capacity(viewer.len() * beyond.len());
        for &a in viewer {
            let ha = height(a).max(0.0);
            for &b in &beyond {
                let hb = height(b).min(0.0);
                let x = if ha - hb <= tol { a } else { a + (b - a) * (ha / (ha - hb)) };
                crossings.push(frame.to_plane(x));
            }
        }
        let section = convex_hull(&crossings);
        let section_area = signed_area(&section);
        if section.len() < 3 || section_area <= 0.0 {
            return None;
        }
        // What the plate's pieces leave open of it.
        let mut open = vec![section.into_vec()];
        for &o in &members {
            let mut hole: Vec<DVec2> =
                planner.occluders()[o].polygon.iter().map(|&v| frame.to_plane(v)).collect();
            if signed_area(&hole) < 0.0 {
                hole.reverse();
            }
            open = open.iter().flat_map(|piece| subtract_convex(piece, &hole)).collect();
        }
        let open_area: f64 = open.iter().map(|p| signed_area(p)).sum();
        let corners: Vec<DVec3> = if open_area <= ROUNDING * section_area {
            Vec::new()
        } else {
            // One convex opening: the pieces left fill their hull.
            let points: Vec<DVec2> = open.iter().flatten().copied().collect();
            let mut hull = convex_hull(&points);
            if signed_area(&hull) - open_area > ROUNDING * section_area {
                return None;
            }
            // Corners that rounding set apart (where the plate's pieces and the section cross)
            // would make sides without a direction, and planes through them at random.
            let apart = ROUNDING * section_area.sqrt();
            hull.dedup_by(|a, b| a.distance(*b) <= apart);
            while hull.len() > 1 && hull[0].distance(hull[hull.len() - 1]) <= apart {
                hull.pop();
            }
            if hull.len() < 3 {
                return None;
            }
            hull.iter().map(|&q| frame.to_global(q)).collect()
        };
        let centroid = corners.iter().sum::<DVec3>() / corners.len().max(1) as f64;
        Some(Opening { normal, offset, corners, centroid, pieces: members })
    }

    /// The parts of the convex polygon `window` of T_j's plane (coordinates of `frame`) that the
    /// point `p` may see past the plate: the part on its own side of the plate's plane, and
    /// the part beyond it inside the cone through the opening (each `None` where nothing with
    /// area is left). `None` for a point on the plate's plane, which needs the plate's pieces.
    pub(super) fn windows(
        &self,
        p: DVec3,
        frame: &PlaneFrame,
        window: &[DVec2],
    ) -> Option<[Option<SmallPolygon<DVec2>>; 2]> {
        let h = self.normal.dot(p) - self.offset;
        if h <= 0.0 {
            return None;
        }
        // normal·X - offset >= 0 for X = origin + u e1 + v e2 of T_j's plane.
        let near = HalfPlane {
            normal: DVec2::new(self.normal.dot(frame.e1), self.normal.dot(frame.e2)),
            offset: self.normal.dot(frame.origin) - self.offset,
        };
        let mut here = SmallPolygon::new();
        let here = clip_convex_into(window, &near, &mut here).then_some(here);
        if self.corners.is_empty() {
            return Some([here, None]);
        }
        // Beyond the plane, and inside each plane through `p` and a side of the opening on the
        // side of its centroid: side·(X - p) >= 0 on T_j's plane.
        let m = self.corners.len();
        let cone = (0..m).map(|k| {
            let (a, b) = (self.corners[k], self.corners[(k + 1) % m]);
            let side = (a - p).cross(b - p);
            let side = if side.dot(self.centroid - p) < 0.0 { -side } else { side };
            HalfPlane {
                normal: DVec2::new(side.dot(frame.e1), side.dot(frame.e2)),
                offset: side.dot(frame.origin - p),
            }
        });
        let through = clip_to_half_planes(window, std::iter::once(near.flipped()).chain(cone));
        Some([here, through])
    }
}

/// A unit vector perpendicular to the unit vector `n`.
fn any_perpendicular(n: DVec3) -> DVec3 {
    let axis = if n.x.abs() < 0.9 { DVec3::X } else { DVec3::Y };
    n.cross(axis).normalize()
}
