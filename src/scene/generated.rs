//! Scenes generated from seeds, for invariants checked on families nobody tuned for: slivers
//! touching walls, closed rooms with floating boxes, louvres, small cities of rotated buildings
//! and every kind of contact between two triangles (the tests' families, and `study estimates`').
//! The same seed gives the same scene.

use glam::DVec3;
use rand::rngs::StdRng;
use rand::{Rng, SeedableRng};

use super::{Face, Scene};

/// A face of rho 0.5.
pub fn face(name: String, vertices: Vec<DVec3>) -> Face {
    Face::new(name, vertices, 0.5).expect("a generated face is planar and not degenerate")
}

/// Ground slivers (aspect 10 to 60) each touched at a corner by a wall triangle whose foot leaves
/// the corner 1 to 10 degrees off the sliver's long side, in random directions and far from the
/// origin.
pub fn slivers_touching_walls(seed: u64) -> Scene {
    let mut rng = StdRng::seed_from_u64(seed);
    let origin = DVec3::new(rng.random_range(-1e4..1e4), rng.random_range(-1e4..1e4), 0.0);
    let heading: f64 = rng.random_range(0.0..std::f64::consts::TAU);
    let length = rng.random_range(5.0..40.0);
    let aspect = rng.random_range(10.0..60.0);
    let gap = rng.random_range(1.0f64..10.0).to_radians();
    let (along, across) = (
        DVec3::new(heading.cos(), heading.sin(), 0.0),
        DVec3::new(-heading.sin(), heading.cos(), 0.0),
    );
    // The sliver: corner at `origin`, long side along `along`, its width across it at the far end.
    let corner = origin;
    let far = corner + along * length;
    let sliver = vec![corner, far, far + across * (length / aspect)];
    // The wall's foot leaves the corner `gap` radians off the long side, on the other side of it.
    let foot_direction = (along * gap.cos() - across * gap.sin()).normalize();
    let foot = rng.random_range(0.1..0.8) * length;
    let height = rng.random_range(1.0..15.0);
    let foot_end = corner + foot_direction * foot;
    let top = foot_end + DVec3::Z * height;
    // Its normal faces the sliver's side (+across, roughly).
    let mut wall = vec![corner, top, foot_end];
    let normal = (wall[1] - wall[0]).cross(wall[2] - wall[0]);
    if normal.dot(across) < 0.0 {
        wall.reverse();
    }
    let name = |s: &str| format!("{s}-{seed}");
    Scene::new(name("slivers"), vec![face(name("sliver"), sliver), face(name("wall"), wall)])
        .expect("a generated scene is valid")
}

/// An axis-aligned box's faces from `lo` to `hi`, facing out (or in, for a room).
pub fn box_faces(prefix: &str, lo: DVec3, hi: DVec3, inward: bool) -> Vec<Face> {
    let c = |x: bool, y: bool, z: bool| {
        DVec3::new(
            if x { hi.x } else { lo.x },
            if y { hi.y } else { lo.y },
            if z { hi.z } else { lo.z },
        )
    };
    // Each face counter-clockwise seen from outside.
    let quads = [
        (
            "bottom",
            [
                c(false, false, false),
                c(false, true, false),
                c(true, true, false),
                c(true, false, false),
            ],
        ),
        (
            "top",
            [
                c(false, false, true),
                c(true, false, true),
                c(true, true, true),
                c(false, true, true),
            ],
        ),
        (
            "south",
            [
                c(false, false, false),
                c(true, false, false),
                c(true, false, true),
                c(false, false, true),
            ],
        ),
        (
            "north",
            [
                c(false, true, false),
                c(false, true, true),
                c(true, true, true),
                c(true, true, false),
            ],
        ),
        (
            "west",
            [
                c(false, false, false),
                c(false, false, true),
                c(false, true, true),
                c(false, true, false),
            ],
        ),
        (
            "east",
            [
                c(true, false, false),
                c(true, true, false),
                c(true, true, true),
                c(true, false, true),
            ],
        ),
    ];
    quads
        .into_iter()
        .map(|(name, q)| {
            let mut v = q.to_vec();
            if inward {
                v.reverse();
            }
            face(format!("{prefix}-{name}"), v)
        })
        .collect()
}

/// A closed room with one or two floating boxes at random places and sizes.
pub fn room_with_boxes(seed: u64) -> Scene {
    let mut rng = StdRng::seed_from_u64(seed);
    let room = DVec3::new(
        rng.random_range(3.0..6.0),
        rng.random_range(3.0..5.0),
        rng.random_range(2.4..3.2),
    );
    let mut faces = box_faces("room", DVec3::ZERO, room, true);
    for k in 0..rng.random_range(1..=2) {
        let size = DVec3::new(
            rng.random_range(0.3..1.2),
            rng.random_range(0.3..1.2),
            rng.random_range(0.3..1.0),
        );
        let lo = DVec3::new(
            rng.random_range(0.2..room.x - size.x - 0.2),
            rng.random_range(0.2..room.y - size.y - 0.2),
            rng.random_range(0.2..room.z - size.z - 0.2),
        );
        faces.extend(box_faces(&format!("box{k}"), lo, lo + size, false));
    }
    Scene::new(format!("room-{seed}"), faces).expect("a generated scene is valid")
}

/// A louvre of two-sided slats (a random count and tilt) between two facing walls.
pub fn louvre(seed: u64) -> Scene {
    let mut rng = StdRng::seed_from_u64(seed);
    let slats = rng.random_range(2..=5);
    let tilt = rng.random_range(15.0f64..75.0).to_radians();
    let (width, pitch) = (2.0, 0.4);
    let depth = rng.random_range(0.3..0.5);
    let v = DVec3::new;
    let mut faces = vec![
        face(
            "floor".into(),
            vec![v(-2.0, 0.0, -1.0), v(2.0, 0.0, -1.0), v(2.0, width, -1.0), v(-2.0, width, -1.0)],
        ),
        face(
            "west".into(),
            vec![v(-2.0, 0.0, -1.0), v(-2.0, width, -1.0), v(-2.0, width, 2.5), v(-2.0, 0.0, 2.5)],
        ),
    ];
    for k in 0..slats {
        let z = k as f64 * pitch;
        let (dx, dz) = (0.5 * depth * tilt.cos(), 0.5 * depth * tilt.sin());
        let top = vec![
            v(-dx, 0.0, z - dz),
            v(dx, 0.0, z + dz),
            v(dx, width, z + dz),
            v(-dx, width, z - dz),
        ];
        let bottom: Vec<DVec3> = top.iter().rev().copied().collect();
        faces.push(face(format!("slat{k}"), top));
        faces.push(face(format!("slat{k}.back"), bottom));
    }
    Scene::new(format!("louvre-{seed}"), faces).expect("a generated scene is valid")
}

/// Buildings (boxes without bottoms, random heights, footprints and rotations) on a ground
/// square, far from the origin.
pub fn city(seed: u64) -> Scene {
    let mut rng = StdRng::seed_from_u64(seed);
    let origin = DVec3::new(rng.random_range(-5e3..5e3), rng.random_range(-5e3..5e3), 0.0);
    let v = |x: f64, y: f64, z: f64| origin + DVec3::new(x, y, z);
    let mut faces = vec![face(
        "ground".into(),
        vec![v(0.0, 0.0, 0.0), v(40.0, 0.0, 0.0), v(40.0, 40.0, 0.0), v(0.0, 40.0, 0.0)],
    )];
    for (k, (cx, cy)) in [(12.0, 12.0), (28.0, 14.0), (18.0, 29.0)].into_iter().enumerate() {
        let (w, d, h) =
            (rng.random_range(4.0..8.0), rng.random_range(4.0..8.0), rng.random_range(5.0..25.0));
        let angle: f64 = rng.random_range(0.0..std::f64::consts::FRAC_PI_2);
        let corner = |sx: f64, sy: f64, z: f64| {
            let (x, y) = (sx * 0.5 * w, sy * 0.5 * d);
            v(cx + x * angle.cos() - y * angle.sin(), cy + x * angle.sin() + y * angle.cos(), z)
        };
        let ring = [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)];
        for s in 0..4 {
            let ((ax, ay), (bx, by)) = (ring[s], ring[(s + 1) % 4]);
            let wall = vec![
                corner(ax, ay, 0.0),
                corner(bx, by, 0.0),
                corner(bx, by, h),
                corner(ax, ay, h),
            ];
            faces.push(face(format!("b{k}-wall{s}"), wall));
        }
        faces
            .push(face(format!("b{k}-roof"), ring.iter().map(|&(x, y)| corner(x, y, h)).collect()));
    }
    Scene::new(format!("city-{seed}"), faces).expect("a generated scene is valid")
}

/// How two triangles of [`contact`] touch: every configuration of a contact between two
/// triangles in different planes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Contact {
    /// A vertex of each at one point.
    SharedVertex,
    /// A vertex of the first on the interior of an edge of the second that lies in the first's
    /// plane (a T-junction: a ground triangulation meeting a wall's foot).
    VertexOnEdge,
    /// A vertex of the second on the interior of an edge of the first.
    EdgeOnVertex,
    /// A whole edge of each.
    SharedEdge,
    /// Collinear edges that overlap over part of each.
    OverlappingEdges,
    /// An edge of the second in the first's plane, crossing an edge of the first: the second
    /// stands on the first (a partition on a floor element).
    CrossingEdges,
    /// A vertex on an edge's interior, either way, moved apart by 1e-9 to 1e-3 of the size.
    NearMiss,
}

impl Contact {
    /// Every kind, in the order of their families.
    pub const ALL: [Contact; 7] = [
        Contact::SharedVertex,
        Contact::VertexOnEdge,
        Contact::EdgeOnVertex,
        Contact::SharedEdge,
        Contact::OverlappingEdges,
        Contact::CrossingEdges,
        Contact::NearMiss,
    ];

    /// Its name in scene names, kebab-case.
    pub fn name(self) -> &'static str {
        match self {
            Contact::SharedVertex => "shared-vertex",
            Contact::VertexOnEdge => "vertex-on-edge",
            Contact::EdgeOnVertex => "edge-on-vertex",
            Contact::SharedEdge => "shared-edge",
            Contact::OverlappingEdges => "overlapping-edges",
            Contact::CrossingEdges => "crossing-edges",
            Contact::NearMiss => "near-miss",
        }
    }
}

/// Two triangles touching as `kind` says, facing each other, of random shapes and sizes (1 to 20
/// m), the second at a random angle of 20 to 160 degrees from the first's plane about the line
/// of the contact, turned at random in space and far from the origin.
pub fn contact(kind: Contact, seed: u64) -> Scene {
    let mut rng = StdRng::seed_from_u64(seed);
    let v = |x: f64, y: f64, z: f64| DVec3::new(x, y, z);
    // Locally the first lies in z = 0 on the side y < 0 of the x axis, the second in the plane
    // through the x axis that rises at `tilt` from +y.
    let size = rng.random_range(1.0..20.0);
    let mut length = || size * rng.random_range(0.3..1.0);
    let (p, q, r, s, t) = (length(), length(), length(), length(), length());
    let tilt: f64 = rng.random_range(20.0f64..160.0).to_radians();
    let up = v(0.0, tilt.cos(), tilt.sin());
    // Two directions into y < 0, at least 20 degrees apart.
    let mut below = |from: f64, to: f64| {
        let angle: f64 = rng.random_range(from..to).to_radians();
        v(angle.cos(), angle.sin(), 0.0)
    };
    let (low, high) = (below(200.0, 260.0), below(280.0, 340.0));
    let mut along = |lo: f64, hi: f64| rng.random_range(lo..hi);
    let (x1, x2) = (along(-1.0, 1.0) * size, along(-1.0, 1.0) * size);
    let kind_here = match kind {
        Contact::NearMiss if seed.is_multiple_of(2) => Contact::VertexOnEdge,
        Contact::NearMiss => Contact::EdgeOnVertex,
        other => other,
    };
    let apex = |x: f64, height: f64| DVec3::X * x + up * height;
    let (first, mut second) = match kind_here {
        Contact::SharedVertex => {
            (vec![DVec3::ZERO, low * p, high * q], vec![DVec3::ZERO, apex(x1, r), apex(x2, s)])
        }
        Contact::VertexOnEdge => (
            vec![DVec3::ZERO, low * p, high * q],
            vec![v(-r, 0.0, 0.0), v(s, 0.0, 0.0), apex(x1, t)],
        ),
        Contact::EdgeOnVertex => (
            vec![v(-p, 0.0, 0.0), v(q, 0.0, 0.0), low * r],
            vec![DVec3::ZERO, apex(x1, s), apex(x2, t)],
        ),
        Contact::SharedEdge => (
            vec![v(-p, 0.0, 0.0), v(q, 0.0, 0.0), low * r],
            vec![v(-p, 0.0, 0.0), v(q, 0.0, 0.0), apex(x1, s)],
        ),
        Contact::OverlappingEdges => {
            let start = along(-0.8, 0.8) * p.min(q);
            (
                vec![v(-p, 0.0, 0.0), v(q, 0.0, 0.0), low * r],
                vec![v(start, 0.0, 0.0), v(q + s, 0.0, 0.0), apex(x1, t)],
            )
        }
        Contact::CrossingEdges => {
            // The second's foot runs through the origin into the first, at 30 to 150 degrees
            // to its edge, and its apex leans either way.
            let heading: f64 = rng.random_range(30.0f64..150.0).to_radians();
            let foot = v(heading.cos(), -heading.sin(), 0.0);
            let lean = DVec3::Z.cross(foot) * tilt.cos() + DVec3::Z * tilt.sin();
            (
                vec![v(-p, 0.0, 0.0), v(q, 0.0, 0.0), low * r],
                vec![-foot * s, foot * t, foot * (x1 * 0.5) + lean * size],
            )
        }
        Contact::NearMiss => unreachable!("a near miss is built as another kind"),
    };
    if kind == Contact::NearMiss {
        let gap = size * 10f64.powf(-rng.random_range(3.0..9.0));
        second.iter_mut().for_each(|x| *x += up * gap);
    }
    // Facing each other: the first up (the second lies over z >= 0), the second towards the
    // first's centroid.
    let mut first = first;
    if (first[1] - first[0]).cross(first[2] - first[0]).z < 0.0 {
        first.reverse();
    }
    let centre = (first[0] + first[1] + first[2]) / 3.0;
    if (second[1] - second[0]).cross(second[2] - second[0]).dot(centre - second[0]) < 0.0 {
        second.reverse();
    }
    let turn = glam::DQuat::from_euler(
        glam::EulerRot::ZXZ,
        rng.random_range(0.0..std::f64::consts::TAU),
        rng.random_range(0.0..std::f64::consts::PI),
        rng.random_range(0.0..std::f64::consts::TAU),
    );
    let origin = v(rng.random_range(-1e3..1e3), rng.random_range(-1e3..1e3), 0.0);
    let place = |t: Vec<DVec3>| t.into_iter().map(|x| origin + turn * x).collect::<Vec<_>>();
    let name = format!("{}-{seed}", kind.name());
    let faces =
        vec![face(format!("{name}-a"), place(first)), face(format!("{name}-b"), place(second))];
    Scene::new(name, faces).expect("a generated scene is valid")
}
