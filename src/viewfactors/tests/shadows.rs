//! Shadows: occluders found once per face, inclusion and exclusion of shadows, openings in a
//! partition or a plate, and the vector lanes of shadowed points against the scalar closed
//! forms they replace.

use std::f64::consts::PI;

use glam::DVec3;

use super::super::compute::view_factors;
use super::super::opening::Opening;
use super::super::options::ViewFactorOptions;
use super::super::outer_rules::OuterRules;
use super::super::patch::{GaussRules, Patch};
use super::super::row::{Between, Tally};
use super::super::sight::{Among, INCLUSION_EXCLUSION, PointView, Sight};
use super::Fixture;
use super::references::brute_force_pair;
use crate::geometry::{SmallPolygon, clip_polygon_3d};
use crate::mesh::Element;
use crate::scene::{Face, Scene};
use crate::visibility::FaceView;

/// Each row's occluders found once per face (the units that each pair's shaft is searched
/// among, or the face hidden whole by a building) give every entry of city:3x2 exactly as
/// each pair's own search of the scene (close pairs checked by reciprocity alike).
#[test]
fn occluders_found_once_per_face_give_each_pair_s_entry() {
    let fixture = Fixture::new(crate::scene::city(3, 2).unwrap());
    let options = ViewFactorOptions { tolerance: 1e-6, ..Default::default() };
    let f = fixture.view_factors(&options);
    let (context, rules) = (fixture.context(&options), OuterRules::new(&options));
    let areas: Vec<f64> = fixture.mesh.elements().iter().map(Element::area).collect();
    let (mut tally, mut kinds) = (Tally::default(), [0; 3]);
    for i in 0..f.len() {
        for j in (0..f.len()).filter(|&j| areas[i].total_cmp(&areas[j]).then(i.cmp(&j)).is_lt()) {
            let mut own = Tally::default();
            let mut searched = context.pair(i, j, &mut Some(Between::Search), &rules, &mut own);
            if searched > 0.0 && context.close(i, j) {
                searched = context.reconciled((i, j), (searched, own.error), &rules, &mut tally).0;
            }
            assert_eq!(f.get(i, j), searched, "({i}, {j})");
            match context.between(i, fixture.mesh.elements()[j].face) {
                Between::Hidden => kinds[0] += 1,
                Between::Among(_) => kinds[1] += 1,
                _ => kinds[2] += 1,
            }
        }
    }
    assert!(kinds[0] > 0 && kinds[1] > 0, "hidden, among, other: {kinds:?}");
}

/// A point's view of T_j integrated by inclusion and exclusion of up to four shadows equals
/// the integral over the pieces that subtracting them leaves, on the occluded box (a cube,
/// a tilted plate and an L plate between the walls), to rounding.
#[test]
fn inclusion_and_exclusion_of_shadows_equals_the_subtracted_pieces() {
    let fixture = Fixture::example("occluded-box.toml");
    let options = ViewFactorOptions::default();
    let context = fixture.context(&options);
    let Fixture { scene, mesh, planner, disc, integrator } = &fixture;
    let mut shadows_seen = [0usize; INCLUSION_EXCLUSION + 1];
    for (i, ei) in mesh.elements().iter().enumerate() {
        for (j, ej) in mesh.elements().iter().enumerate() {
            let among = planner.candidates(ei.face, ej.face);
            if among.is_empty() {
                continue;
            }
            let normal = scene.faces[ei.face].frame.normal;
            let part = disc.in_face(j);
            let among = planner.casters(ei.face, ej.face, &among);
            // Points on a grid over T_i, inside it.
            let grid = (1..7).flat_map(|a| (1..7 - a).map(move |b| (a, b)));
            for (u, v) in grid.map(|(a, b)| (a as f64 / 7.0, b as f64 / 7.0)) {
                let [a, b, c] = ei.vertices;
                let p = a + (b - a) * u + (c - a) * v;
                let got =
                    context.point_to_element(i, j, p, Sight::PerPoint(Among::occluders(&among)));
                let view = planner.part_view_among(p, normal, ei.face, ej.face, &part, &among);
                if let FaceView::Visible { shadows, .. } = &view {
                    if let Some(seen) = shadows_seen.get_mut(shadows.len()) {
                        *seen += 1;
                    }
                }
                let vis = planner.visible(&view, &part);
                let want =
                    integrator.integrate(&disc.placed(j), disc.basis(j), p, normal, &vis)[0] / PI;
                assert!((got - want).abs() <= 1e-14, "{i} -> {j} at {p}: {got} vs {want}");
            }
        }
    }
    assert!(shadows_seen.iter().all(|&k| k > 20), "{shadows_seen:?}");
}

/// Through the opening that the louvre room's partition leaves around its louvre, a point's view
/// of an element equals its view shadowed by the partition's pieces themselves, to rounding,
/// on the side of the partition where the point is and beyond it (the slats still shadow both).
#[test]
fn a_partition_is_seen_through_its_opening() {
    let fixture = Fixture::example("louvre-room.toml");
    let options = ViewFactorOptions::default();
    let context = fixture.context(&options);
    let Fixture { mesh, planner, .. } = &fixture;
    let (mut openings, mut seen_through) = (0, 0);
    for (i, ei) in mesh.elements().iter().enumerate() {
        // The part of T_i west of the partition's plane x = 2.
        let mut west = SmallPolygon::new();
        if !clip_polygon_3d(&ei.vertices, DVec3::NEG_X, 2.0, &mut west) {
            continue;
        }
        for (j, ej) in mesh.elements().iter().enumerate() {
            let among = planner.candidates(ei.face, ej.face);
            if among.is_empty() || planner.same_plane(ei.face, ej.face) {
                continue;
            }
            let Some(opening) = Opening::find(&west, &ej.vertices, &among, planner) else {
                continue;
            };
            openings += 1;
            let on_partition =
                |o: &usize| planner.occluders()[*o].polygon.iter().all(|v| v.x == 2.0);
            assert!(opening.pieces.iter().all(on_partition), "{i} -> {j}: the partition's pieces");
            let others: Vec<usize> =
                among.iter().copied().filter(|o| !opening.pieces.contains(o)).collect();
            let (among, others) = (
                planner.casters(ei.face, ej.face, &among),
                planner.casters(ei.face, ej.face, &others),
            );
            let through = Among { occluders: &among, opening: Some((&opening, &others)) };
            // Points inside the western part: irrational barycentric weights in each triangle
            // of its fan, so that none lies on an occluder's plane.
            const W: [f64; 3] = [0.659027622374092, 0.231933368553031, 0.109039009072877];
            for k in 1..west.len() - 1 {
                let (a, b, c) = (west[0], west[k], west[k + 1]);
                for [x, y, z] in [[0, 1, 2], [1, 2, 0], [2, 0, 1]] {
                    let p = a * W[x] + b * W[y] + c * W[z];
                    let got = context.point_to_element(i, j, p, Sight::PerPoint(through));
                    let want = context.point_to_element(
                        i,
                        j,
                        p,
                        Sight::PerPoint(Among::occluders(&among)),
                    );
                    assert!((got - want).abs() <= 1e-14, "{i} -> {j} at {p}: {got} vs {want}");
                    seen_through +=
                        usize::from(ej.vertices.iter().any(|v| v.x > 2.0) && want > 0.0);
                }
            }
        }
    }
    assert!(openings > 100 && seen_through > 500, "{openings} openings, {seen_through} seen");
}

/// Two squares face each other across a plate of two rectangles that closes the plane between
/// them: each point of one sees nothing of the other, exactly (no entry is stored), while each
/// still sees the plate; with a square hole in the plate's middle (four rectangles around it),
/// each entry equals the one integrated with the plate's pieces as shadows.
#[test]
fn a_closed_plate_hides_and_a_holed_one_shows_its_opening() {
    let square = |z: f64, up: bool| {
        let mut v: Vec<DVec3> = [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)]
            .iter()
            .map(|&(x, y)| DVec3::new(x, y, z))
            .collect();
        if !up {
            v.reverse();
        }
        v
    };
    let rectangle = |(x0, y0): (f64, f64), (x1, y1): (f64, f64)| {
        // Facing down, towards the bottom square.
        vec![
            DVec3::new(x0, y0, 1.0),
            DVec3::new(x0, y1, 1.0),
            DVec3::new(x1, y1, 1.0),
            DVec3::new(x1, y0, 1.0),
        ]
    };
    let scene_with = |plate: Vec<Vec<DVec3>>| {
        let mut faces = vec![
            Face::new("bottom", square(0.0, true), 0.5).unwrap(),
            Face::new("top", square(2.0, false), 0.5).unwrap(),
        ];
        for (k, polygon) in plate.into_iter().enumerate() {
            faces.push(Face::new(format!("plate-{k}"), polygon, 0.5).unwrap());
        }
        Scene::new("plate", faces).unwrap()
    };
    let tolerance = 1e-8;
    let options = ViewFactorOptions { tolerance, ..Default::default() };
    // Closed: two rectangles meeting at x = 0.4.
    let closed =
        scene_with(vec![rectangle((-2.0, -2.0), (0.4, 3.0)), rectangle((0.4, -2.0), (3.0, 3.0))]);
    let fixture = Fixture::new(closed);
    let f = view_factors(
        &fixture.scene,
        &fixture.mesh,
        &fixture.planner,
        &options,
        &crate::progress::Silent,
    )
    .unwrap();
    for i in 0..2 {
        for j in 2..4 {
            assert_eq!(f.get(i, j), 0.0, "bottom {i} -> top {j}");
            assert_eq!(f.get(j, i), 0.0);
        }
        assert!(f.row(i).1.iter().sum::<f64>() > 0.5, "the plate is seen");
    }
    // Holed: the opening [0.3, 0.7] x [0.2, 0.9].
    let holed = scene_with(vec![
        rectangle((-2.0, -2.0), (0.3, 3.0)),
        rectangle((0.7, -2.0), (3.0, 3.0)),
        rectangle((0.3, -2.0), (0.7, 0.2)),
        rectangle((0.3, 0.9), (0.7, 3.0)),
    ]);
    let fixture = Fixture::new(holed);
    let context = fixture.context(&options);
    let rules = OuterRules::new(&options);
    let (mut checked, mut openings) = (0, 0);
    for i in 0..2 {
        let ei = &fixture.mesh.elements()[i];
        for j in 2..4 {
            let ej = &fixture.mesh.elements()[j];
            let among = fixture.planner.candidates(ei.face, ej.face);
            let opening = Opening::find(&ei.vertices, &ej.vertices, &among, &fixture.planner);
            openings += usize::from(opening.is_some_and(|o| o.pieces.len() == 4));
            let mut tally = Tally::default();
            let got = context.pair(i, j, &mut Some(Between::Search), &rules, &mut tally);
            let want = brute_force_pair(&fixture, &context, (i, j), 64);
            assert!(got > 0.0 && (got - want).abs() <= 1e-5, "{i} -> {j}: {got} against {want}");
            checked += 1;
        }
    }
    assert_eq!((checked, openings), (4, 4));
}

/// The weighted sums over the points of a patch, whose visible pieces are integrated eight
/// at a time in vector lanes, equal the scalar closed forms point by point, on the occluded
/// box's shadowed pairs.
#[test]
fn shadowed_points_in_lanes_equal_the_scalar_closed_forms() {
    let fixture = Fixture::example("occluded-box.toml");
    let options = ViewFactorOptions::default();
    let context = fixture.context(&options);
    let Fixture { mesh, planner, .. } = &fixture;
    let rules = GaussRules::new(6);
    let (mut pairs, mut partial) = (0, 0);
    for (i, ei) in mesh.elements().iter().enumerate() {
        for j in 0..mesh.len() {
            let among = planner.candidates(ei.face, mesh.elements()[j].face);
            if among.is_empty() || planner.same_plane(ei.face, mesh.elements()[j].face) {
                continue;
            }
            let among = planner.casters(ei.face, mesh.elements()[j].face, &among);
            let sight = Sight::PerPoint(Among::occluders(&among));
            let points = Patch::Triangle(ei.vertices).gauss_points(&rules, 6);
            let got = context.weighted_sum(i, j, sight, &points).0;
            let want: f64 =
                points.iter().map(|&(p, w)| w * context.point_to_element(i, j, p, sight)).sum();
            let scale: f64 = points.iter().map(|&(_, w)| w.abs()).sum();
            assert!((got - want).abs() <= 1e-14 * scale, "{i} -> {j}: {got} vs {want}");
            pairs += 1;
            let sees = |&(p, _): &(DVec3, f64)| {
                matches!(
                    context.point_view(i, j, p, Among::occluders(&among)),
                    PointView::Signed { .. }
                )
            };
            partial += usize::from(points.iter().any(sees));
        }
    }
    assert!(pairs > 100 && partial > 100, "{pairs} pairs, {partial} partly visible");
}
