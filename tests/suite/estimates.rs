//! The view factors' error estimate is a promise: on scenes generated from seeds (slivers touching
//! walls at a corner, rooms with boxes, louvres, small cities of rotated buildings, two triangles
//! touching in every way), every entry
//! lies within the reported estimate of a run with a much tighter tolerance, reciprocity holds
//! within the areas times the estimate when both directions are integrated, and no entry is
//! negative.

use glam::DVec3;
use radiosity::mesh::{Mesh, MeshKind};
use radiosity::progress::Silent;
use radiosity::scene::Scene;
use radiosity::scene::generated::{
    Contact, box_faces, city, contact, face, louvre, room_with_boxes, slivers_touching_walls,
};
use radiosity::viewfactors::{ViewFactorOptions, ViewFactors, view_factors};
use radiosity::visibility::PairPlanner;

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

#[test]
fn slivers_touching_walls_at_a_corner_keep_their_estimates() {
    // Seed 6 is a wall touching the sliver 5.4 degrees off its foot, which the collapsed rule
    // about the corner took with too small an estimate (seeds 4 and 5 too, at 1e-8): a narrow
    // contact is the tanh-sinh rule's, checked by its quarters.
    for seed in 0..8 {
        assert_estimates_hold(&slivers_touching_walls(seed), 0, &[1e-4, 1e-6, 1e-8]);
    }
}

/// Two triangles touching in every way two triangles can (a shared vertex, a vertex on an
/// edge's interior either way, a shared edge, overlapping edges, crossing edges, near misses
/// at 1e-9 to 1e-3 of the size), at random angles: each direction within its estimate at
/// 1e-4, 1e-6 and 1e-8. A vertex on a wall's foot broke the estimate by 19 times before close
/// pairs were checked by reciprocity.
#[test]
fn two_triangles_touching_in_every_way_keep_their_estimates() {
    for kind in Contact::ALL {
        for seed in 0..4 {
            assert_estimates_hold(&contact(kind, seed), 0, &[1e-4, 1e-6, 1e-8]);
        }
    }
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

#[test]
fn louvres_with_random_slats_keep_their_estimates() {
    for seed in 0..3 {
        assert_estimates_hold(&louvre(seed), 0, &[1e-4, 1e-6]);
    }
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
    // at a corner were up to 15 times their estimate. Pair (129, 226) at 1e-8: a patch across
    // two curved events (three mutually skew edges lined up: two roofs' and T_j's), whose
    // orders 3, 4 and 5 agreed to 8e-9 of F while 9e-9 off; the quarters' rule checks it.
    assert_estimates_hold(&radiosity::scene::city(4, 4).unwrap(), 0, &[1e-4, 1e-6, 1e-8]);
}

#[test]
fn a_band_that_no_gauss_point_sees_is_found_at_the_rim() {
    // From a tessellated city 3 x 3: a wall triangle above a lower building's roof, seeing a
    // wall triangle past a taller building's corner. A curved event (the lower roof's edge,
    // the taller building's vertical edge and T_j's slanted side lined up) leaves a band along
    // one side of a patch from which slivers of T_j are seen, while every Gauss point of the
    // patch saw nothing: F was 2.4e-8 off at 1e-8 under an estimate of 1e-19.
    let v = |x, y, z| DVec3::new(x, y, z);
    let mut faces = vec![
        face("viewer".into(), vec![v(6.0, 38.0, 15.0), v(11.0, 38.0, 20.0), v(6.0, 38.0, 20.0)]),
        face("target".into(), vec![v(38.0, 11.0, 10.0), v(38.0, 6.0, 10.0), v(38.0, 6.0, 15.0)]),
    ];
    faces.extend(box_faces("low", v(6.0, 22.0, 0.0), v(16.0, 32.0, 15.0), false));
    faces.extend(box_faces("tall", v(22.0, 6.0, 0.0), v(32.0, 16.0, 35.0), false));
    let scene = Scene::new("band-past-a-corner", faces).unwrap();
    assert_estimates_hold(&scene, 0, &[1e-6, 1e-8]);
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

#[test]
fn the_cube_keeps_its_estimates() {
    // Triangles of adjacent faces share a side; their tanh-sinh levels agreed at 1e-6 while
    // 7.3e-7 off (estimate 3.9e-7), so a contact along a side is checked by its quarters.
    assert_estimates_hold(&radiosity::scene::cube().unwrap(), 0, &[1e-4, 1e-6, 1e-8]);
}
