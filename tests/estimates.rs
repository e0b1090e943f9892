//! The view factors' error estimate is a promise: on scenes generated from seeds (slivers touching
//! walls at a corner, rooms with boxes, louvres, small cities of rotated buildings), every entry
//! lies within the reported estimate of a run with a much tighter tolerance, reciprocity holds
//! within the areas times the estimate when both directions are integrated, and no entry is
//! negative.

use glam::DVec3;
use radiosity::mesh::{Mesh, MeshKind};
use radiosity::progress::Silent;
use radiosity::scene::{Face, Scene};
use radiosity::viewfactors::{ViewFactorOptions, ViewFactors, view_factors};
use radiosity::visibility::PairPlanner;
use rand::rngs::StdRng;
use rand::{Rng, SeedableRng};

/// The reference's tolerance: far below every tolerance checked.
const REFERENCE: f64 = 1e-11;

fn compute(scene: &Scene, mesh: &Mesh, tolerance: f64, each_direction: bool) -> ViewFactors {
    let planner = PairPlanner::new(scene);
    let options =
        ViewFactorOptions { tolerance, each_direction, max_depth: 0, ..Default::default() };
    view_factors(scene, mesh, &planner, &options, &Silent).unwrap()
}

/// Every promise of the view factors of `scene` at `refine`, at each tolerance, both ways.
fn assert_estimates_hold(scene: &Scene, refine: u32, tolerances: &[f64]) {
    let mesh = Mesh::new(scene, &MeshKind::Uniform, refine).unwrap();
    let reference = compute(scene, &mesh, REFERENCE, false);
    for &tolerance in tolerances {
        for each_direction in [false, true] {
            let f = compute(scene, &mesh, tolerance, each_direction);
            let check = f.check_against(&reference);
            assert!(
                check.holds(),
                "{} (refine {refine}) at {tolerance:e}, each direction {each_direction}: \
                 estimate {:.2e} (reference {:.2e}) and {check:?}",
                scene.name,
                f.error_estimate,
                reference.error_estimate,
            );
        }
    }
}

fn face(name: String, vertices: Vec<DVec3>) -> Face {
    Face::new(name, vertices, 0.5).unwrap()
}

/// The pair of a public urban mesh whose estimate was 2 200 times too small: a 1 m x 25 m ground
/// sliver facing up and a wall triangle in the plane x = 30 that touches it at one corner, the
/// wall's foot leaving that corner 2.3 degrees off the sliver's long side.
fn sliver_and_wall() -> Scene {
    let v = |x, y, z| DVec3::new(x, y, z);
    let sliver =
        face("sliver".into(), vec![v(31.0, 31.0, 0.0), v(31.0, 56.0, 0.0), v(30.0, 56.0, 0.0)]);
    let wall =
        face("wall".into(), vec![v(30.0, 56.0, 0.0), v(30.0, 51.0, 10.0), v(30.0, 51.0, 0.0)]);
    Scene::new("sliver-and-wall", vec![sliver, wall]).unwrap()
}

#[test]
fn the_sliver_touching_a_wall_at_a_corner_meets_its_tolerance() {
    let scene = sliver_and_wall();
    let mesh = Mesh::new(&scene, &MeshKind::Uniform, 0).unwrap();
    // The converged value (tolerance 1e-10, and 1e-8 within 1e-11 of it; Monte Carlo with 8e5
    // rays gave 0.13807 +- 0.00055).
    let converged = 0.138_127_685_6;
    let f = compute(&scene, &mesh, 1e-6, true);
    let got = f.get(0, 1);
    assert!((got - converged).abs() <= 1e-6, "F(sliver -> wall) = {got}, not {converged}");
    assert!(f.error_estimate <= 1e-6);
    assert_estimates_hold(&scene, 0, &[1e-4, 1e-6, 1e-8]);
}

/// Ground slivers (aspect 10 to 60) each touched at a corner by a wall triangle whose foot leaves
/// the corner 1 to 10 degrees off the sliver's long side, in random directions and far from the
/// origin.
fn slivers_touching_walls(seed: u64) -> Scene {
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
        .unwrap()
}

#[test]
fn slivers_touching_walls_at_a_corner_keep_their_estimates() {
    // At 1e-8 one of these pairs is 1.0e-11 off under an estimate of 7e-12: not yet held.
    for seed in 0..6 {
        assert_estimates_hold(&slivers_touching_walls(seed), 0, &[1e-4, 1e-6]);
    }
}

/// An axis-aligned box's faces from `lo` to `hi`, facing out (or in, for a room).
fn box_faces(prefix: &str, lo: DVec3, hi: DVec3, inward: bool) -> Vec<Face> {
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
fn room_with_boxes(seed: u64) -> Scene {
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
    Scene::new(format!("room-{seed}"), faces).unwrap()
}

#[test]
fn rooms_with_random_boxes_keep_their_estimates_and_close() {
    for seed in 0..3 {
        let scene = room_with_boxes(seed);
        assert_estimates_hold(&scene, 0, &[1e-4, 1e-6]);
        // Closed: every row of F sums to 1 within the estimates of its entries.
        let mesh = Mesh::new(&scene, &MeshKind::Uniform, 0).unwrap();
        let f = compute(&scene, &mesh, 1e-8, false);
        let (lo, hi) = f.row_sum_range();
        assert!(
            (lo - 1.0).abs() < 1e-6 && (hi - 1.0).abs() < 1e-6,
            "{}: rows {lo}..{hi}",
            scene.name
        );
    }
}

/// A louvre of two-sided slats (a random count and tilt) between two facing walls.
fn louvre(seed: u64) -> Scene {
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
    Scene::new(format!("louvre-{seed}"), faces).unwrap()
}

#[test]
fn louvres_with_random_slats_keep_their_estimates() {
    for seed in 0..3 {
        assert_estimates_hold(&louvre(seed), 0, &[1e-4, 1e-6]);
    }
}

/// Buildings (boxes without bottoms, random heights, footprints and rotations) on a ground
/// square, far from the origin.
fn city(seed: u64) -> Scene {
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
    Scene::new(format!("city-{seed}"), faces).unwrap()
}

#[test]
fn small_cities_of_rotated_buildings_keep_their_estimates() {
    for seed in 0..2 {
        assert_estimates_hold(&city(seed), 0, &[1e-4, 1e-6]);
    }
}

#[test]
fn the_generated_city_keeps_its_estimates() {
    // Facing walls across a street, 6 m apart with elements 35 m across: the certified rule's
    // order from the ellipse through a point beyond a side's end left an entry 2.1e-6 off at
    // 1e-6 with each direction integrated. At 1e-8 entries of walls touching ground triangles
    // at a corner are still up to 15 times their estimate: not yet held.
    assert_estimates_hold(&radiosity::scene::city(4, 4).unwrap(), 0, &[1e-4, 1e-6]);
}

#[test]
fn a_wall_touching_a_small_ground_triangle_at_a_corner_keeps_its_estimate() {
    // Integrated over the wall (each direction), its triangles' tanh-sinh levels met 1e-8 while
    // 1.5e-7 off: the integrand changes its scale at the ground triangle's size, far inside.
    let v = |x, y, z| DVec3::new(x, y, z);
    let wall =
        vec![v(38.0, 64.0, 0.0), v(38.0, 54.0, 0.0), v(38.0, 54.0, 33.0), v(38.0, 64.0, 33.0)];
    let ground = vec![v(32.0, 64.0, 0.0), v(38.0, 64.0, 0.0), v(38.0, 70.0, 0.0)];
    let scene = Scene::new(
        "wall-and-ground",
        vec![face("wall".into(), wall), face("ground".into(), ground)],
    )
    .unwrap();
    assert_estimates_hold(&scene, 0, &[1e-6, 1e-8]);
}
