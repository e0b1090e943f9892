//! Visibility against brute-force ray casting on random occluder configurations.

use glam::{DVec2, DVec3};
use rand::{Rng, SeedableRng, rngs::StdRng};

use super::projection::ShadowSet;
use super::*;
use crate::geometry::{PlaneFrame, SmallPolygon, signed_area, triangulate};
use crate::mesh::{Mesh, MeshKind};
use crate::scene::{Face, Scene};

/// Whether the open segment from p to q crosses the (possibly non-convex) planar polygon.
fn segment_hits(p: DVec3, q: DVec3, polygon: &[DVec3]) -> bool {
    let e1 = polygon[1] - polygon[0];
    let n: DVec3 = (0..polygon.len())
        .map(|k| (polygon[k] - polygon[0]).cross(polygon[(k + 1) % polygon.len()] - polygon[0]))
        .sum::<DVec3>()
        .normalize();
    let frame = PlaneFrame::new(polygon[0], n, e1);
    let (hp, hq) = (frame.height(p), frame.height(q));
    if hp * hq >= 0.0 {
        return false;
    }
    let s = hp / (hp - hq);
    let x = frame.to_plane(p + (q - p) * s);
    let local: Vec<DVec2> = polygon.iter().map(|&v| frame.to_plane(v)).collect();
    triangulate(&local).unwrap().iter().any(|t| {
        let t = t.map(|k| local[k]);
        (0..3).all(|k| (t[(k + 1) % 3] - t[k]).perp_dot(x - t[k]) > 0.0)
    })
}

fn inside_any(pieces: &[Vec<DVec2>], x: DVec2) -> bool {
    pieces.iter().any(|p| {
        let n = p.len();
        (0..n).all(|k| (p[(k + 1) % n] - p[k]).perp_dot(x - p[k]) > 0.0)
    })
}

/// A random polygon in the plane through `centre` with normal `n`: convex (regular-ish) or a
/// non-convex star.
fn random_polygon(rng: &mut StdRng, centre: DVec3, n: DVec3, convex: bool) -> Vec<DVec3> {
    let frame = PlaneFrame::new(centre, n, DVec3::new(0.3, 0.7, 0.1));
    let m = rng.random_range(3..8);
    let phase: f64 = rng.random_range(0.0..1.0);
    (0..m)
        .map(|k| {
            let angle = std::f64::consts::TAU * (k as f64 + phase) / m as f64;
            let r = if convex || k % 2 == 0 { 0.35 } else { 0.12 };
            frame.to_global(DVec2::new(angle.cos(), angle.sin()) * r * rng.random_range(0.8..1.2))
        })
        .collect()
}

/// The unit square at z = 0 facing up, and the square [lo, hi]² at z = 1.5 facing down.
fn receiver_and_source(lo: f64, hi: f64) -> Vec<Face> {
    let receiver = Face::new(
        "receiver",
        vec![DVec3::ZERO, DVec3::X, DVec3::new(1.0, 1.0, 0.0), DVec3::Y],
        0.5,
    )
    .unwrap();
    let source = Face::new(
        "source",
        vec![
            DVec3::new(lo, lo, 1.5),
            DVec3::new(lo, hi, 1.5),
            DVec3::new(hi, hi, 1.5),
            DVec3::new(hi, lo, 1.5),
        ],
        0.5,
    )
    .unwrap();
    vec![receiver, source]
}

/// Checks `vis`, the visible part of the triangle `tri` of the receiver (face 0, `frame`) from
/// `p` with normal `normal`, against ray casting to the occluders (faces 2 and on) at `samples`
/// random points of the triangle.
fn assert_agrees_with_ray_casting(
    rng: &mut StdRng,
    scene: &Scene,
    (p, normal): (DVec3, DVec3),
    tri: &[DVec2],
    vis: &Visibility,
    samples: usize,
) {
    let frame = scene.faces[0].frame;
    for _ in 0..samples {
        let (a, b): (f64, f64) = (rng.random_range(0.0..1.0), rng.random_range(0.0..1.0));
        let (a, b) = if a + b > 1.0 { (1.0 - a, 1.0 - b) } else { (a, b) };
        let x = tri[0] + (tri[1] - tri[0]) * a + (tri[2] - tri[0]) * b;
        let q = frame.to_global(x);
        let in_front = normal.dot(q - p) > 0.0;
        let blocked = scene.faces[2..].iter().any(|f| segment_hits(p, q, &f.vertices));
        let truth = in_front && !blocked;
        let planned = match vis {
            Visibility::Skip(_) => false,
            Visibility::Full => true,
            Visibility::Partial(pieces) => inside_any(pieces, x),
        };
        assert_eq!(planned, truth, "{}, p {p}, q {q}: {vis:?}", scene.name);
    }
}

#[test]
fn visible_pieces_agree_with_ray_casting() {
    let mut rng = StdRng::seed_from_u64(7);
    let mut checked = 0;
    for case in 0..12 {
        let mut faces = receiver_and_source(0.2, 0.8);
        for k in 0..3 {
            let centre = DVec3::new(
                rng.random_range(0.2..0.8),
                rng.random_range(0.2..0.8),
                rng.random_range(0.3..1.2),
            );
            let tilt = DVec3::new(rng.random_range(-0.5..0.5), rng.random_range(-0.5..0.5), 1.0);
            let convex = (case + k) % 2 == 0;
            let poly = random_polygon(&mut rng, centre, tilt.normalize(), convex);
            faces.push(Face::new(format!("occluder{k}"), poly, 0.5).unwrap());
        }
        let scene = Scene::new(format!("random {case}"), faces).unwrap();
        let planner = PairPlanner::new(&scene);
        assert!(planner.has_occlusion());
        let mesh = Mesh::new(&scene, &MeshKind::Uniform, 2).unwrap();
        let frame = scene.faces[0].frame;
        for _ in 0..4 {
            let p = DVec3::new(rng.random_range(0.25..0.75), rng.random_range(0.25..0.75), 1.5);
            // A tilted normal makes the node's tangent plane cut the receiver in some cases.
            let normal = DVec3::new(rng.random_range(-1.0..1.0), 0.0, -1.0).normalize();
            let view = planner.face_view(p, normal, 1, 0);
            for e in &mesh.elements()[mesh.face_range(0)] {
                let tri: Vec<DVec2> = e.vertices.iter().map(|&v| frame.to_plane(v)).collect();
                let vis = planner.visible(&view, &tri);
                assert_agrees_with_ray_casting(&mut rng, &scene, (p, normal), &tri, &vis, 40);
                checked += 40;
            }
        }
    }
    assert!(checked > 10_000);
}

#[test]
fn the_paper_surfaces_need_occlusion_only_between_s1_or_s5_and_s4() {
    use crate::scene::{SurfaceParameters, five_piece, four_piece};
    let s = five_piece(SurfaceParameters::default()).unwrap();
    let planner = PairPlanner::new(&s);
    for a in 0..5 {
        for b in 0..5 {
            let expect = matches!((a, b), (0, 3) | (3, 0) | (4, 3) | (3, 4));
            assert_eq!(!planner.candidates(a, b).is_empty(), expect, "S{} -> S{}", a + 1, b + 1);
        }
    }
    // S2 and S3 are one occluder.
    assert_eq!(planner.occluders().len(), 4);
    let four = PairPlanner::new(&four_piece(SurfaceParameters::default()).unwrap());
    assert!(four.has_occlusion());
    let cube = PairPlanner::new(&crate::scene::cube().unwrap());
    assert!(!cube.has_occlusion(), "a convex enclosure has no occluders");
}

#[test]
fn shadow_of_the_square_from_a_corner_of_s4_is_exact() {
    use crate::scene::{SurfaceParameters, four_piece};
    let s = four_piece(SurfaceParameters::default()).unwrap();
    let planner = PairPlanner::new(&s);
    // From P = (px, py, 2) the square [0,2]² at z = 1 casts [0, 4 - px] x [0, 4 - py] on S1.
    let p = DVec3::new(0.25, 0.75, 2.0);
    let view = planner.face_view(p, -DVec3::Z, 3, 0);
    let FaceView::Visible { clip: None, shadows } = &view else { panic!("{view:?}") };
    assert_eq!(shadows.len(), 1);
    let area = signed_area(&shadows[0]);
    assert!((area - 3.75 * 3.25).abs() < 1e-12, "{area}");
    let visible: f64 = planner.visible_part_of_face(&view, 0).iter().map(|p| signed_area(p)).sum();
    assert!((visible - (25.0 - 3.75 * 3.25)).abs() < 1e-12);
}

#[test]
fn views_among_a_polygons_shaft_occluders_equal_the_searched_views_there() {
    // The occluded box: a floating cube and two plates between the walls; a city, whose
    // buildings hide each other's walls (pieces a solid hides from the whole sub-triangle are
    // left out of its shaft). For element pairs with occluders between them, the shaft of a
    // sub-triangle of T_i and T_j keeps some of the pair's occluders; from points of that
    // sub-triangle, the view among those alone must leave the same visible part of T_j as the
    // full search (also when the shadows are clipped to T_j instead of its face), and a shaft
    // found hidden must leave nothing.
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/occluded-box.toml");
    let (compared, hidden_shafts, fewer) =
        compare_views_among_shafts(&crate::scene::load(&path).unwrap(), 5);
    assert!(
        compared > 1000 && hidden_shafts > 0 && fewer > 100,
        "{compared} {hidden_shafts} {fewer}"
    );
    let (compared, hidden_shafts, fewer) =
        compare_views_among_shafts(&crate::scene::city(3, 3).unwrap(), 6);
    assert!(
        compared > 10_000 && hidden_shafts > 1000 && fewer > 3000,
        "{compared} {hidden_shafts} {fewer}"
    );
}

/// Compares, for the element pairs of `scene` (refine 0) with occluders between them and a
/// random sub-triangle of T_i, the views among the sub-triangle's shaft occluders with the
/// searched views; returns the views compared, the shafts found hidden and those that kept
/// fewer occluders than the pair.
fn compare_views_among_shafts(scene: &Scene, seed: u64) -> (usize, usize, usize) {
    let mesh = Mesh::new(scene, &MeshKind::Uniform, 0).unwrap();
    let planner = PairPlanner::new(scene);
    let mut rng = StdRng::seed_from_u64(seed);
    let area = |pieces: &[Vec<DVec2>]| pieces.iter().map(|p| signed_area(p)).sum::<f64>();
    let (mut compared, mut hidden_shafts, mut fewer) = (0, 0, 0);
    for ei in mesh.elements() {
        for ej in mesh.elements() {
            let (a, b) = (ei.face, ej.face);
            let all = planner.candidates(a, b);
            if all.is_empty() {
                continue;
            }
            // A random sub-triangle of T_i.
            let point = |rng: &mut StdRng| {
                let (u, v): (f64, f64) = (rng.random_range(0.0..1.0), rng.random_range(0.0..1.0));
                let (u, v) = if u + v > 1.0 { (1.0 - u, 1.0 - v) } else { (u, v) };
                ei.vertices[0]
                    + (ei.vertices[1] - ei.vertices[0]) * u
                    + (ei.vertices[2] - ei.vertices[0]) * v
            };
            let corner = ei.vertices[rng.random_range(0..3)];
            let scale = rng.random_range(0.05..0.5);
            let sub: Vec<DVec3> =
                (0..3).map(|_| corner + (point(&mut rng) - corner) * scale).collect();
            let (among, hidden) = planner.polygon_shaft(a, b, &sub, &ej.vertices, &all);
            fewer += usize::from(among.len() < all.len());
            hidden_shafts += usize::from(hidden);
            let among = planner.casters(a, b, &among);
            let normal = scene.faces[a].frame.normal;
            let target: Vec<DVec2> =
                ej.vertices.iter().map(|&v| scene.faces[b].frame.to_plane(v)).collect();
            let visible = |view: &FaceView| match planner.visible(view, &target) {
                Visibility::Skip(_) => Vec::new(),
                Visibility::Full => vec![target.clone()],
                Visibility::Partial(pieces) => pieces,
            };
            for _ in 0..4 {
                // Interior points of the sub-triangle.
                let w: [f64; 3] = std::array::from_fn(|_| rng.random_range(0.05..1.0));
                let p = (sub[0] * w[0] + sub[1] * w[1] + sub[2] * w[2]) / (w[0] + w[1] + w[2]);
                let searched = area(&visible(&planner.face_view(p, normal, a, b)));
                if hidden {
                    assert!(searched.abs() <= 1e-12, "hidden shaft, yet {searched} seen");
                    continue;
                }
                let hull = &planner.faces[b].hull;
                let got = area(&visible(&planner.part_view_among(p, normal, a, b, hull, &among)));
                let part_view = planner.part_view_among(p, normal, a, b, &target, &among);
                let of_part = area(&visible(&part_view));
                for got in [got, of_part] {
                    assert!(
                        (got - searched).abs() <= 1e-12 * signed_area(&target),
                        "{} -> {}: {got} vs {searched}",
                        scene.faces[a].name,
                        scene.faces[b].name
                    );
                }
                compared += 1;
            }
        }
    }
    (compared, hidden_shafts, fewer)
}

#[test]
fn a_shadow_set_keeps_no_shadow_that_another_holds() {
    let square = |lo: f64, hi: f64| -> Vec<DVec2> {
        vec![DVec2::new(lo, lo), DVec2::new(hi, lo), DVec2::new(hi, hi), DVec2::new(lo, hi)]
    };
    let mut set = ShadowSet::default();
    set.add(None, square(0.0, 1.0));
    set.add(None, square(0.25, 0.75)); // inside the first
    set.add(None, square(0.5, 1.5)); // overlaps it only
    assert_eq!(set.casts.len(), 2);
    // A shadow whose occluder's whole projection holds both earlier ones replaces them, though
    // the shadow itself (cut by its window) holds neither.
    let outline: SmallPolygon<DVec2> = square(-1.0, 2.0).into_iter().collect();
    set.add(Some(outline), square(-1.0, 0.1));
    assert_eq!(set.into_shadows().into_polygons(), vec![square(-1.0, 0.1)]);
}

/// In a city, most shadows on a face lie inside another's (a building's far side behind its near
/// side): the views keep far fewer shadows than the core solver's plan, which lists every one,
/// and leave the same visible area ([`crate::bench::bench_plan`] compares the areas).
#[test]
fn views_keep_only_the_shadows_that_no_other_holds() {
    let scene = crate::scene::city(6, 6).unwrap();
    let (tree, every) =
        (PairPlanner::new(&scene), PairPlanner::with_acceleration(&scene, Acceleration::BoxScan));
    let (mut kept, mut listed) = (0, 0);
    for (a, f) in scene.faces.iter().enumerate().step_by(7) {
        let centre = f.vertices.iter().sum::<DVec3>() / f.vertices.len() as f64;
        for b in 0..scene.faces.len() {
            let count =
                |planner: &PairPlanner| match planner.face_view(centre, f.frame.normal, a, b) {
                    FaceView::Visible { shadows, .. } => shadows.len(),
                    FaceView::Skip(_) => 0,
                };
            let (k, l) = (count(&tree), count(&every));
            if k > 0 {
                kept += k;
                listed += l;
            }
        }
    }
    assert!(listed > 500 && 2 * kept < listed, "kept {kept} of {listed}");
}

/// The six faces of the box with centre `centre`, half-sides `half` along the axes of the rotation
/// `axes`, each counter-clockwise seen from outside.
fn box_faces(name: &str, centre: DVec3, axes: [DVec3; 3], half: DVec3) -> Vec<Face> {
    let corner = |s: [f64; 3]| {
        centre + axes[0] * (s[0] * half.x) + axes[1] * (s[1] * half.y) + axes[2] * (s[2] * half.z)
    };
    let quads = [
        [[-1., -1., -1.], [-1., 1., -1.], [1., 1., -1.], [1., -1., -1.]],
        [[-1., -1., 1.], [1., -1., 1.], [1., 1., 1.], [-1., 1., 1.]],
        [[-1., -1., -1.], [1., -1., -1.], [1., -1., 1.], [-1., -1., 1.]],
        [[-1., 1., -1.], [-1., 1., 1.], [1., 1., 1.], [1., 1., -1.]],
        [[-1., -1., -1.], [-1., -1., 1.], [-1., 1., 1.], [-1., 1., -1.]],
        [[1., -1., -1.], [1., 1., -1.], [1., 1., 1.], [1., -1., 1.]],
    ];
    quads
        .iter()
        .enumerate()
        .map(|(k, q)| Face::new(format!("{name}{k}"), q.map(corner).to_vec(), 0.5).unwrap())
        .collect()
}

/// The faces of a box named "box" standing upright (its third axis vertical) about `centre`,
/// its first axis the horizontal unit vector `x`, with half-sides `half` along its axes.
fn upright_box(centre: DVec3, x: DVec3, half: DVec3) -> Vec<Face> {
    box_faces("box", centre, [x, DVec3::Z.cross(x), DVec3::Z], half)
}

/// A random horizontal unit vector.
fn horizontal_direction(rng: &mut StdRng) -> DVec3 {
    DVec3::new(rng.random_range(-1.0..1.0), rng.random_range(-1.0..1.0), 0.0).normalize()
}

/// A closed convex solid, or one standing open on the receiver, casts one shadow, the
/// receiver's part in the cone from the point over it, in place of its faces' shadows: the
/// visible parts agree with ray casting, with the core plan (which shadows face by face) to
/// rounding, and the views hold fewer shadows.
#[test]
fn a_closed_box_casts_one_shadow_that_ray_casting_confirms() {
    let mut rng = StdRng::seed_from_u64(11);
    let (mut checked, mut fewer) = (0, 0);
    for case in 0..8 {
        let a = DVec3::new(rng.random_range(-1.0..1.0), rng.random_range(-1.0..1.0), 1.0);
        let x = a.normalize();
        let y = x.any_orthonormal_vector();
        let centre = DVec3::new(rng.random_range(0.3..0.7), rng.random_range(0.3..0.7), 0.75);
        let half = DVec3::new(
            rng.random_range(0.05..0.2),
            rng.random_range(0.05..0.2),
            rng.random_range(0.05..0.2),
        );
        let mut faces = receiver_and_source(0.0, 1.0);
        // Every other box stands on the receiver without a bottom face, upright (a building on
        // the ground): a solid capped by the receiver's plane.
        let standing = case % 2 == 1;
        if standing {
            let x = DVec3::new(x.x, x.y, 0.0).normalize();
            let centre = DVec3::new(centre.x, centre.y, half.z);
            faces.extend(upright_box(centre, x, half));
            faces.remove(2);
        } else {
            faces.extend(box_faces("box", centre, [x, y, x.cross(y)], half));
        }
        let scene = Scene::new(format!("boxed {case}"), faces).unwrap();
        let (solid, core) = (
            PairPlanner::new(&scene),
            PairPlanner::with_acceleration(&scene, Acceleration::BoxScan),
        );
        assert_eq!(solid.occluders.solids.len(), 1, "case {case}");
        let box_faces: Vec<usize> = (2..scene.faces.len()).collect();
        assert_eq!(solid.occluders.solids[0].faces, box_faces, "case {case}");
        let mesh = Mesh::new(&scene, &MeshKind::Uniform, 1).unwrap();
        for _ in 0..6 {
            let p = DVec3::new(rng.random_range(0.0..1.0), rng.random_range(0.0..1.0), 1.5);
            let (with_solids, face_by_face) =
                compare_views_with_solids(&mut rng, &scene, (&solid, &core), &mesh, p);
            fewer += usize::from(with_solids < face_by_face);
            checked += 30 * mesh.face_range(0).len();
        }
    }
    assert!(checked > 5_000 && fewer > 20, "{checked} points, {fewer} views with fewer shadows");
}

/// A convex solid that reaches above the viewing point (a building taller than the point on a
/// wall that sees the ground past it) cannot be projected whole, but its cone from the point
/// casts its one shadow: the visible parts agree with ray casting and with the core plan (face
/// by face) to rounding, and every view holds at most one shadow.
#[test]
fn a_solid_taller_than_the_viewing_point_casts_one_shadow_that_ray_casting_confirms() {
    let mut rng = StdRng::seed_from_u64(12);
    let (mut checked, mut fewer) = (0, 0);
    for case in 0..8 {
        let x = horizontal_direction(&mut rng);
        let half = DVec3::new(rng.random_range(0.05..0.15), rng.random_range(0.05..0.15), 0.0);
        let centre = DVec3::new(rng.random_range(0.5..0.65), rng.random_range(0.5..0.65), 0.0);
        // The viewing points lie at height 1.5 over the receiver's corner at the origin; a
        // standing box (no bottom face, on the receiver) or a floating one reaches above
        // 0.9 of that height, from below it or from the receiver.
        let standing = case % 2 == 1;
        let (bottom, top) = if standing { (0.0, rng.random_range(1.4..2.5)) } else { (0.3, 2.0) };
        let half = DVec3::new(half.x, half.y, 0.5 * (top - bottom));
        let centre = DVec3::new(centre.x, centre.y, 0.5 * (top + bottom));
        let mut faces = receiver_and_source(0.0, 0.25);
        faces.extend(upright_box(centre, x, half));
        if standing {
            faces.remove(2);
        }
        let scene = Scene::new(format!("tall box {case}"), faces).unwrap();
        let (c, f) = views_of_one_solid(&mut rng, &scene, |rng| {
            DVec3::new(rng.random_range(0.0..0.25), rng.random_range(0.0..0.25), 1.5)
        });
        checked += c;
        fewer += f;
    }
    assert!(checked > 5_000 && fewer > 30, "{checked} points, {fewer} views with fewer shadows");
}

/// A convex solid that reaches behind the receiver's plane (beside it, a box sunk into the
/// ground past the receiver's edge) has no cone from the point whose part in front of the
/// receiver is its shadow: the part of it in the pyramid over the window casts the one
/// shadow, and the visible parts agree with ray casting and with the core plan to rounding.
#[test]
fn a_solid_reaching_behind_the_receiver_s_plane_casts_one_shadow_that_ray_casting_confirms() {
    let mut rng = StdRng::seed_from_u64(13);
    let (mut checked, mut fewer) = (0, 0);
    for case in 0..6 {
        let x = horizontal_direction(&mut rng);
        let (bottom, top) = (rng.random_range(-0.4..-0.1), rng.random_range(0.6..1.2));
        let half = DVec3::new(0.1, 0.1, 0.5 * (top - bottom));
        let centre = DVec3::new(1.25, 1.25, 0.5 * (top + bottom));
        // The source lies over the far side of the box from the receiver.
        let mut faces = receiver_and_source(1.8, 2.2);
        faces.extend(upright_box(centre, x, half));
        let scene = Scene::new(format!("sunk box {case}"), faces).unwrap();
        let (c, f) = views_of_one_solid(&mut rng, &scene, |rng| {
            DVec3::new(rng.random_range(1.8..2.2), rng.random_range(1.8..2.2), 1.5)
        });
        checked += c;
        fewer += f;
    }
    assert!(checked > 5_000 && fewer > 20, "{checked} points, {fewer} views with fewer shadows");
}

/// The receiver's views from 8 points of the source drawn by `point`, in `scene`, whose faces
/// past the first two make one solid, compared with solids cast whole and face by face
/// ([`compare_views_with_solids`]), each holding at most one shadow: the element points
/// checked, and the views with fewer shadows than face by face.
fn views_of_one_solid(
    rng: &mut StdRng,
    scene: &Scene,
    point: impl Fn(&mut StdRng) -> DVec3,
) -> (usize, usize) {
    let (solid, core) =
        (PairPlanner::new(scene), PairPlanner::with_acceleration(scene, Acceleration::BoxScan));
    assert_eq!(solid.occluders.solids.len(), 1, "{}", scene.name);
    let mesh = Mesh::new(scene, &MeshKind::Uniform, 1).unwrap();
    let (mut checked, mut fewer) = (0, 0);
    for _ in 0..8 {
        let p = point(rng);
        let (with_solids, face_by_face) =
            compare_views_with_solids(rng, scene, (&solid, &core), &mesh, p);
        assert!(with_solids <= 1, "{}, p {p}: {with_solids} shadows", scene.name);
        fewer += usize::from(with_solids < face_by_face);
        checked += 30 * mesh.face_range(0).len();
    }
    (checked, fewer)
}

/// The receiver (face 0) seen from `p` on the source (face 1) with solids cast whole
/// (`solid`) and face by face (`core`): each element's visible area agrees between the two to
/// rounding, and with ray casting at 30 points. Returns the two views' numbers of shadows.
fn compare_views_with_solids(
    rng: &mut StdRng,
    scene: &Scene,
    (solid, core): (&PairPlanner, &PairPlanner),
    mesh: &Mesh,
    p: DVec3,
) -> (usize, usize) {
    let view = solid.face_view(p, -DVec3::Z, 1, 0);
    let core_view = core.face_view(p, -DVec3::Z, 1, 0);
    let frame = scene.faces[0].frame;
    for e in &mesh.elements()[mesh.face_range(0)] {
        let tri: Vec<DVec2> = e.vertices.iter().map(|&v| frame.to_plane(v)).collect();
        let (vis, core_vis) = (solid.visible(&view, &tri), core.visible(&core_view, &tri));
        let area = |vis: &Visibility| match vis {
            Visibility::Skip(_) => 0.0,
            Visibility::Full => signed_area(&tri),
            Visibility::Partial(pieces) => pieces.iter().map(|p| signed_area(p)).sum(),
        };
        let (got, want) = (area(&vis), area(&core_vis));
        assert!((got - want).abs() <= 1e-13, "{}, p {p}: {got} vs {want}", scene.name);
        assert_agrees_with_ray_casting(rng, scene, (p, -DVec3::Z), &tri, &vis, 30);
    }
    let count = |view: &FaceView| match view {
        FaceView::Visible { shadows, .. } => shadows.len(),
        FaceView::Skip(_) => 0,
    };
    (count(&view), count(&core_view))
}

/// Only convex groups of pieces closed, or capped by a plane that the whole scene lies on one
/// side of, are solids: the occluded box's cube and its walls, not its plates; a city's
/// buildings (capped by the ground), not its ground; a box without its lid alone, but not with
/// a plate over it, nor a box with one corner pushed in.
#[test]
fn only_closed_or_capped_convex_groups_of_pieces_are_solids() {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/occluded-box.toml");
    let scene = crate::scene::load(&path).unwrap();
    let solids = &PairPlanner::new(&scene).occluders.solids;
    let names = |s: &solids::Solid| -> Vec<String> {
        s.faces.iter().map(|&f| scene.faces[f].name.clone()).collect()
    };
    assert_eq!(solids.len(), 2);
    assert!(names(&solids[0]).iter().all(|n| n.starts_with("box-")), "{:?}", names(&solids[0]));
    assert!(names(&solids[1]).iter().all(|n| n.starts_with("cube-")), "{:?}", names(&solids[1]));
    assert!(solids.iter().all(|s| s.faces.len() == 6 && s.vertices.len() == 8));
    let city = crate::scene::city(5, 6).unwrap();
    let solids = &PairPlanner::new(&city).occluders.solids;
    assert_eq!(solids.len(), 30);
    assert!(solids.iter().all(|s| s.faces.len() == 5 && s.vertices.len() == 8));
    let axes = [DVec3::X, DVec3::Y, DVec3::Z];
    let mut open = box_faces("open", DVec3::splat(0.5), axes, DVec3::splat(0.2));
    open.remove(1);
    let alone = Scene::new("open", open.clone()).unwrap();
    assert_eq!(PairPlanner::new(&alone).occluders.solids.len(), 1);
    let lid = |z: f64| {
        let corners = [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)];
        Face::new("plate", corners.map(|(x, y)| DVec3::new(x, y, z)).to_vec(), 0.5).unwrap()
    };
    open.push(lid(1.0));
    let mut dented = box_faces("dented", DVec3::splat(0.5), axes, DVec3::splat(0.2));
    // Moving the corner (0.7, 0.7, 0.7) inwards along the diagonal breaks the planes of the
    // three faces at it; they are split into triangles so that each piece stays planar.
    let corner = DVec3::splat(0.7);
    let pushed = DVec3::splat(0.62);
    dented = dented
        .into_iter()
        .flat_map(|f| {
            let v = f.vertices.clone();
            match v.iter().position(|&x| x == corner) {
                None => vec![f],
                Some(k) => {
                    let at = |i: usize| v[(k + i) % 4];
                    vec![
                        Face::new(format!("{}a", f.name), vec![pushed, at(1), at(2)], 0.5).unwrap(),
                        Face::new(format!("{}b", f.name), vec![pushed, at(2), at(3)], 0.5).unwrap(),
                    ]
                }
            }
        })
        .collect();
    // A closed step: an L in the x-z plane drawn out along y (the planes of its inner corner's
    // two faces have vertices on both sides).
    let l = [(0.0, 0.0), (2.0, 0.0), (2.0, 1.0), (1.0, 1.0), (1.0, 2.0), (0.0, 2.0)];
    let side = |y: f64| l.iter().map(|&(x, z)| DVec3::new(x, y, z)).collect::<Vec<_>>();
    let (front, mut back) = (side(0.0), side(1.0));
    back.reverse();
    let mut step = vec![
        Face::new("front", front.clone(), 0.5).unwrap(),
        Face::new("back", back, 0.5).unwrap(),
    ];
    for k in 0..l.len() {
        let (a, b) = (front[k], front[(k + 1) % l.len()]);
        let (c, d) = (b + DVec3::Y, a + DVec3::Y);
        step.push(Face::new(format!("side{k}"), vec![a, d, c, b], 0.5).unwrap());
    }
    for (name, faces) in [("open under a plate", open), ("dented", dented), ("step", step)] {
        let scene = Scene::new(name, faces).unwrap();
        assert!(PairPlanner::new(&scene).occluders.solids.is_empty(), "{name}");
    }
}

#[test]
fn a_shaft_tried_on_its_parent_s_candidates_finds_what_the_whole_scene_gives() {
    // Boxes on pairs of the city's faces, inside boxes of the whole faces: the pieces that the
    // outer shafts hand down give every inner shaft's answer.
    let city = crate::scene::city(4, 4).unwrap();
    let planner = PairPlanner::new(&city);
    let mut rng = StdRng::seed_from_u64(5);
    let mut point_on = |f: &Face| {
        let (u, v): (f64, f64) = (rng.random(), rng.random());
        let w = &f.vertices;
        w[0] + (w[1] - w[0]) * u + (w[3] - w[0]) * v
    };
    let (mut tested, mut partial, mut hidden) = (0, 0, 0);
    for a in 0..city.faces.len() {
        for b in (0..city.faces.len()).filter(|b| (b * 7 + a * 3) % 29 == 0 && *b != a) {
            let (fa, fb) = (&city.faces[a], &city.faces[b]);
            let outer = planner.shaft_candidates(fa.bounding_box(), fb.bounding_box(), None);
            let inner_box = |p: DVec3, q: DVec3| (p.min(q), p.max(q));
            let nodes = inner_box(point_on(fa), point_on(fa));
            let elements = inner_box(point_on(fb), point_on(fb));
            // As in the block tree: each box in front of the other face's plane.
            let in_front = |bounds: (DVec3, DVec3), f: &Face| {
                crate::geometry::box_corners(bounds).iter().all(|&c| f.frame.height(c) > 0.0)
            };
            if !in_front(nodes, fb) || !in_front(elements, fa) {
                continue;
            }
            let inner = planner.shaft_candidates(nodes, elements, Some(&outer));
            assert!(inner.iter().all(|o| outer.contains(o)));
            let whole = planner.shaft(a, b, nodes, elements, None);
            assert_eq!(planner.shaft(a, b, nodes, elements, Some(&inner)), whole);
            assert_eq!(planner.shaft(a, b, nodes, elements, Some(&outer)), whole);
            tested += 1;
            partial += usize::from(whole == Shaft::Partial);
            hidden += usize::from(whole == Shaft::Hidden);
        }
    }
    assert!(tested > 100 && partial > 10 && hidden > 10, "{tested} {partial} {hidden}");
}

#[test]
fn a_building_hides_what_no_single_wall_hides_and_ray_casting_confirms_it() {
    // Boxes on pairs of a city's faces: where the shaft says hidden, every sampled segment
    // between the boxes crosses a face; some of them are hidden only by a building as a whole
    // (no single piece crosses every segment: they enter through a wall and leave through the
    // roof, or pass behind two walls).
    let city = crate::scene::city(4, 4).unwrap();
    let planner = PairPlanner::new(&city);
    let mut rng = StdRng::seed_from_u64(11);
    let point_on = |f: &Face, rng: &mut StdRng| {
        let (u, v): (f64, f64) = (rng.random(), rng.random());
        let w = &f.vertices;
        w[0] + (w[1] - w[0]) * u + (w[3] - w[0]) * v
    };
    let (mut hidden, mut by_solid_only) = (0, 0);
    for a in 0..city.faces.len() {
        for b in (0..city.faces.len()).filter(|b| (b * 5 + a * 3) % 7 == 0 && *b != a) {
            let (fa, fb) = (&city.faces[a], &city.faces[b]);
            let (p0, p1) = (point_on(fa, &mut rng), point_on(fa, &mut rng));
            let (q0, q1) = (point_on(fb, &mut rng), point_on(fb, &mut rng));
            let (nodes, elements) = ((p0.min(p1), p0.max(p1)), (q0.min(q1), q0.max(q1)));
            if planner.shaft(a, b, nodes, elements, None) != Shaft::Hidden {
                continue;
            }
            hidden += 1;
            let (found, _) = planner.shaft_occluders(a, b, nodes, elements);
            let tol = planner.pair_tolerance(a, b);
            let corners = crate::geometry::box_corners;
            let (from, to) = (corners(nodes), corners(elements));
            let single = found
                .iter()
                .any(|&o| planner.occluders.pieces[o].crosses_every_segment(&from, &to, tol, tol));
            by_solid_only += usize::from(!single);
            for _ in 0..50 {
                let in_box = |(lo, hi): (DVec3, DVec3), rng: &mut StdRng| {
                    lo + (hi - lo) * DVec3::new(rng.random(), rng.random(), rng.random())
                };
                let (p, q) = (in_box(nodes, &mut rng), in_box(elements, &mut rng));
                let blocked = city
                    .faces
                    .iter()
                    .enumerate()
                    .any(|(k, f)| k != a && k != b && segment_hits(p, q, &f.vertices));
                assert!(blocked, "faces {a} and {b}: {p} to {q} crosses no face");
            }
        }
    }
    assert!(hidden > 50 && by_solid_only > 10, "{hidden} hidden, {by_solid_only} by a solid only");
}

#[test]
fn halves_of_a_face_seen_whole_or_not_at_all_leave_every_element_as_it_is_seen_alone() {
    // The louvre room at refine 3: from nodes all over it, the faces they see in part (shadowed
    // by the slats and the partition, or clipped by the node's plane). Each element must come
    // out of the tree of halves as it does classified alone, up to a sliver (an element that
    // one shadow holds, cut first by another, leaves pieces of rounding size), and a box the
    // view settles at once (seen whole, hidden, behind the node) must hold only elements so
    // seen. Both kinds of settled boxes must occur, or the comparison proves nothing.
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/louvre-room.toml");
    let scene = crate::scene::load(&path).unwrap();
    let mesh = Mesh::new(&scene, &MeshKind::Uniform, 3).unwrap();
    let planner = PairPlanner::new(&scene);
    let polygons: Vec<Vec<[DVec2; 3]>> = (0..mesh.face_count())
        .map(|face| {
            let frame = &scene.faces[face].frame;
            mesh.elements()[mesh.face_range(face)]
                .iter()
                .map(|el| el.vertices.map(|v| frame.to_plane(v)))
                .collect()
        })
        .collect();
    let trees: Vec<ElementBoxes> = polygons.iter().map(|p| ElementBoxes::new(p.clone())).collect();
    let class = |v: &Visibility| std::mem::discriminant(v);
    // A piece of rounding size where the other sees nothing.
    let sliver = |x: &Visibility, y: &Visibility, element: &[DVec2; 3]| match (x, y) {
        (Visibility::Partial(pieces), Visibility::Skip(_))
        | (Visibility::Skip(_), Visibility::Partial(pieces)) => {
            let seen: f64 = pieces.iter().map(|p| signed_area(p)).sum();
            seen.abs() <= 1e-12 * signed_area(element)
        }
        _ => false,
    };
    let mut rng = StdRng::seed_from_u64(7);
    let (mut compared, mut slivers, mut settled) = (0, 0, [0usize; 2]);
    for el in mesh.elements().iter().step_by(13) {
        let viewer = Viewer {
            position: el.centroid(),
            normal: scene.faces[el.face].frame.normal,
            face: el.face,
            rho: 0.5,
        };
        for face in 0..mesh.face_count() {
            let view = planner.face_view(viewer.position, viewer.normal, el.face, face);
            let FaceView::Visible { .. } = view else { continue };
            if view.is_unobstructed() {
                continue;
            }
            let alone: Vec<Visibility> =
                polygons[face].iter().map(|p| planner.visible(&view, p)).collect();
            // Runs of elements (the tree's halves and others), settled by their box or not.
            for _ in 0..8 {
                let n = polygons[face].len();
                let start = rng.random_range(0..n);
                let end = rng.random_range(start + 1..=n.min(start + 64));
                let run = &polygons[face][start..end];
                let bounds = crate::geometry::bounding_box(&run.concat());
                if let Some(v) = planner.visible_in_box(&view, bounds) {
                    settled[usize::from(matches!(v, Visibility::Full))] += 1;
                    for (a, element) in alone[start..end].iter().zip(run) {
                        assert!(
                            class(a) == class(&v) || sliver(a, &v, element),
                            "{a:?} in a box taken as {v:?}"
                        );
                    }
                }
            }
            let mut by_tree: Vec<Option<Visibility>> = vec![None; alone.len()];
            let faces = std::iter::once((face, 0..alone.len()));
            planner.walk_row(
                &viewer,
                faces,
                Views::Fresh(&mut RecentHiders::default()),
                |_, _, s| {
                    let FaceSight::Part(mut part) = s else { panic!("a face seen in part") };
                    part.elements(&trees[face], |k, v| by_tree[k] = Some(v));
                },
            );
            for ((a, b), element) in alone.iter().zip(&by_tree).zip(&polygons[face]) {
                let b = b.clone().expect("every element visited");
                match (a, &b) {
                    (Visibility::Skip(_), Visibility::Skip(_))
                    | (Visibility::Full, Visibility::Full) => {}
                    (Visibility::Partial(x), Visibility::Partial(y)) => assert_eq!(x, y),
                    _ => {
                        assert!(sliver(a, &b, element), "{a:?} alone, {b:?} by the tree");
                        slivers += 1;
                    }
                }
                compared += 1;
            }
        }
    }
    assert!(compared > 100_000 && settled[0] > 1000 && settled[1] > 1000, "{compared} {settled:?}");
    assert!(slivers * 10_000 < compared, "{slivers} slivers of {compared}");
}
