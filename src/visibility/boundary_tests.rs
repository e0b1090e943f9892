//! The occluder pieces that bound the scene (its ground, its sky, a room's walls), which the
//! trees leave out: which pieces they are, and that the views without them are those of a
//! scan over every piece.

use super::occluders::{ViewVolume, boundary_pieces};
use super::*;
use crate::mesh::{Mesh, MeshKind};
use crate::scene::{Scene, generated, lit_city};

/// Whether every vertex of every face of `scene` lies on one side of `piece`'s plane (on it or
/// beyond by at most a billionth of the scene's size): the definition, tested point by point.
fn scene_on_one_side(scene: &Scene, piece: &Occluder) -> bool {
    let origin = piece.polygon[0];
    let points = || scene.faces.iter().flat_map(|f| f.vertices.iter());
    let size = points().map(|p| p.abs().max_element()).fold(1.0, f64::max);
    let heights: Vec<f64> = points().map(|&p| piece.normal().dot(p - origin)).collect();
    heights.iter().all(|&h| h >= -1e-9 * size) || heights.iter().all(|&h| h <= 1e-9 * size)
}

#[test]
fn the_pieces_that_bound_a_scene_are_its_ground_its_sky_and_a_room_s_walls() {
    let flagged = |scene: &Scene| {
        let planner = PairPlanner::new(scene);
        let pieces = planner.occluders();
        let flags = boundary_pieces(pieces);
        for (piece, &flag) in pieces.iter().zip(&flags) {
            // Only pieces with the whole scene on one side; on these scenes, every such piece.
            assert_eq!(flag, scene_on_one_side(scene, piece), "{}: {piece:?}", scene.name);
        }
        // The units' tree, searched with a volume that holds everything, gives every solid and
        // every other piece but those.
        let everywhere = ViewVolume::default();
        let units: Vec<OccluderUnit> = planner
            .occluders
            .units_reaching(&everywhere)
            .expect("the trees")
            .map(|(unit, _, _)| unit)
            .collect();
        for (k, &flag) in flags.iter().enumerate() {
            let alone = planner.occluders.solid_of_piece(k).is_none();
            let listed = units.contains(&OccluderUnit::Piece(k));
            assert_eq!(listed, alone && !flag, "{}: piece {k}", scene.name);
        }
        let names = |k: usize| pieces[k].faces.iter().map(|&f| scene.faces[f].name.clone());
        (0..pieces.len()).filter(|&k| flags[k]).flat_map(names).collect::<Vec<String>>()
    };
    // The lit city: the ground between the houses (7 x 5 cells less the 3 x 2 houses) and the
    // sky; no wall and no roof.
    let city = flagged(&lit_city(3, 2).unwrap());
    assert_eq!(city.len(), 7 * 5 - 6 + 1, "{city:?}");
    assert!(city.iter().all(|name| name.starts_with("ground") || name == "sky"), "{city:?}");
    // A closed room: its six walls, none of the boxes floating in it.
    for seed in 0..3 {
        let room = flagged(&generated::room_with_boxes(seed));
        assert_eq!(room.len(), 6, "{room:?}");
        assert!(room.iter().all(|name| name.starts_with("room")), "{room:?}");
    }
    // A generated city far from the origin, its houses turned: the ground, and the roof of
    // the highest house (nothing above it), which bounds a solid and stays in the trees.
    let city = flagged(&generated::city(1));
    assert_eq!(city, ["ground", "b2-roof"]);
}

/// Each element of each face seen from every `step`-th node of `scene` (refined `refine` times),
/// through
/// the trees (which leave the pieces that bound the scene out) and through a scan of every
/// piece: the same class, and the same visible area to rounding. Returns the pairs seen in
/// part.
fn views_agree_with_a_scan_of_every_piece(scene: &Scene, refine: u32, step: usize) -> usize {
    let tree = PairPlanner::new(scene);
    let scan = PairPlanner::with_acceleration(scene, Acceleration::Scan);
    let mesh = Mesh::new(scene, &MeshKind::Uniform, refine).unwrap();
    let in_face = |j: usize| {
        let frame = &scene.faces[mesh.elements()[j].face].frame;
        mesh.elements()[j].vertices.map(|v| frame.to_plane(v))
    };
    let area = |visibility: &Visibility, element: &[glam::DVec2]| match visibility {
        Visibility::Skip(_) => 0.0,
        Visibility::Full => crate::geometry::signed_area(element),
        Visibility::Partial(pieces) => pieces.iter().map(|p| crate::geometry::signed_area(p)).sum(),
    };
    let mut partial = 0;
    for node in mesh.elements().iter().step_by(step) {
        let (p, normal) = (node.centroid(), scene.faces[node.face].frame.normal);
        for b in 0..scene.faces.len() {
            let (a, b_view) =
                (tree.face_view(p, normal, node.face, b), scan.face_view(p, normal, node.face, b));
            for j in mesh.face_range(b) {
                let element = in_face(j);
                let (found, expected) =
                    (tree.visible(&a, &element), scan.visible(&b_view, &element));
                let (x, y) = (area(&found, &element), area(&expected, &element));
                let whole = crate::geometry::signed_area(&element);
                assert!(
                    (x - y).abs() <= 1e-12 * whole,
                    "{}: face {b} element {j} from {p}: area {x} through the trees, {y} scanned",
                    scene.name
                );
                assert_eq!(
                    matches!(found, Visibility::Skip(_)),
                    matches!(expected, Visibility::Skip(_)),
                    "{}: face {b} element {j} from {p}",
                    scene.name
                );
                partial += usize::from(matches!(found, Visibility::Partial(_)));
            }
        }
    }
    partial
}

#[test]
fn views_without_the_pieces_that_bound_the_scene_see_what_a_scan_of_every_piece_sees() {
    // Scenes of more than 512 faces search the trees (smaller ones a table of each pair's
    // occluders, from the pieces' tree as well): the lit city, and small scenes whose walls,
    // ground and boxes shadow each other.
    let mut partial = views_agree_with_a_scan_of_every_piece(&lit_city(10, 10).unwrap(), 0, 13);
    for seed in 0..2 {
        partial += views_agree_with_a_scan_of_every_piece(&generated::room_with_boxes(seed), 1, 1);
        partial += views_agree_with_a_scan_of_every_piece(&generated::city(seed), 1, 1);
    }
    assert!(partial > 1000, "{partial} pairs seen in part");
}

#[test]
fn the_pieces_that_bound_a_scene_hide_none_of_it_from_its_points() {
    // Drawn into a node's occlusion cube, they hide neither a face nor a face's box; the other
    // pieces do (so the walks that find the faces in sight need not draw them).
    let scenes = [lit_city(4, 3).unwrap(), generated::city(0), generated::room_with_boxes(1)];
    for scene in &scenes {
        let planner = PairPlanner::new(scene);
        let flags = boundary_pieces(planner.occluders());
        let mesh = Mesh::new(scene, &MeshKind::Uniform, 1).unwrap();
        let mut cube = OcclusionCube::default();
        let (mut tested, mut hidden_by_all) = (0, 0);
        for node in mesh.elements().iter().step_by(3) {
            let (p, normal) = (node.centroid(), scene.faces[node.face].frame.normal);
            let drawn = |cube: &mut OcclusionCube, boundary: bool| {
                cube.reset(p, normal);
                for (piece, &flag) in planner.occluders().iter().zip(&flags) {
                    if flag == boundary && !piece.faces.contains(&node.face) {
                        cube.draw(&piece.polygon);
                    }
                }
            };
            let in_front = scene.faces.iter().enumerate().filter(|(b, face)| {
                *b != node.face && face.vertices.iter().any(|&v| normal.dot(v - p) > 1e-9)
            });
            drawn(&mut cube, true);
            for (b, face) in in_front.clone() {
                let (lo, hi) = face.bounding_box();
                assert!(!cube.hides_polygon(&face.vertices, lo, hi), "{}: face {b}", scene.name);
                assert!(!cube.hides_box(lo, hi), "{}: box of face {b}", scene.name);
                tested += 1;
            }
            drawn(&mut cube, false);
            for (_, face) in in_front {
                let (lo, hi) = face.bounding_box();
                hidden_by_all += usize::from(cube.hides_polygon(&face.vertices, lo, hi));
            }
        }
        assert!(tested > 200 && hidden_by_all > 0, "{}: {tested}, {hidden_by_all}", scene.name);
    }
}
