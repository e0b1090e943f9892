//! Property tests: the kernels and the pair plan on random input never panic, return finite
//! values, and agree with independent truth (adaptive quadrature; a node sees at most its
//! hemisphere, and inside a closed surface all of it, so the row sums of K/rho are 1 whatever
//! occludes what).

use glam::{DVec2, DVec3};
use proptest::prelude::*;

use radiosity::assembly::{AssemblyOptions, Problem, assemble};
use radiosity::discretization::{Discretization, Method};
use radiosity::kernels::reference::{integral, integral_of};
use radiosity::kernels::{Affine2, Observer, exact};
use radiosity::mesh::{Mesh, MeshKind};
use radiosity::quadrature::{ImtRule, Tolerance};
use radiosity::scene::{Face, Scene};

fn point2() -> impl Strategy<Value = DVec2> {
    (-1.0..1.0f64, -1.0..1.0f64).prop_map(|(x, y)| DVec2::new(x, y))
}

fn point3(lo: f64, hi: f64) -> impl Strategy<Value = DVec3> {
    (lo..hi, lo..hi, lo..hi).prop_map(|(x, y, z)| DVec3::new(x, y, z))
}

/// A counter-clockwise triangle that is not too thin (the thin ones have their own tests).
fn triangle() -> impl Strategy<Value = [DVec2; 3]> {
    (point2(), point2(), point2())
        .prop_map(|(a, b, c)| if (b - a).perp_dot(c - a) >= 0.0 { [a, b, c] } else { [a, c, b] })
        .prop_filter("area", |t| {
            let area = 0.5 * (t[1] - t[0]).perp_dot(t[2] - t[0]);
            let d2 = (0..3).map(|k| (t[k] - t[(k + 1) % 3]).length_squared()).fold(0.0, f64::max);
            area > 0.02 * d2 && area > 1e-3
        })
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    #[test]
    fn closed_forms_are_finite_and_agree_with_adaptive_quadrature(
        tri in triangle(),
        foot in (-2.0..2.0f64, -2.0..2.0f64),
        z in 1e-3..2.0f64,
        tilt in (-0.7..0.7f64, -0.7..0.7f64),
        w in (-1.0..1.0f64, -1.0..1.0f64, -1.0..1.0f64),
    ) {
        let normal = DVec3::new(tilt.0, tilt.1, -1.0).normalize();
        let obs = Observer { position: DVec3::new(foot.0, foot.1, z), normal };
        // Only the part in front of the node's tangent plane counts; keep configurations where
        // the whole element is in front, so the integrand has one sign.
        let in_front = tri.iter().all(|q| (q.extend(0.0) - obs.position).dot(normal) > 0.0);
        prop_assume!(in_front);
        let weight = Affine2 { c0: w.0, cx: w.1, cy: w.2 };
        let tol = Tolerance { absolute: 1e-300, relative: 1e-13, max_intervals: 4000 };
        let c = exact::constant_weight(&obs, [&tri[..]]);
        let a = exact::affine_weights(&obs, [&tri[..]], &[weight], &ImtRule::new(128))[0];
        prop_assert!(c.is_finite() && a.is_finite());
        let want_c = integral(&obs, &tri, |_| 1.0, tol);
        let scale = integral(&obs, &tri, |q| weight.eval(q).abs(), tol);
        let want_a = integral(&obs, &tri, |q| weight.eval(q), tol);
        // The closed form is a sum of edge terms about as large as the kernel with the node
        // facing the element, z / r³: seen from just above the plane and far away (z = 1e-3,
        // 2.5 away from a triangle of 0.5) the entry is 4e-4 of that scale, and the rounding
        // of the terms is 1e-8 of the entry but 1e-11 of the scale. Both bounds matter: the
        // relative one where the entry is as large as its terms, the scale one where it is not.
        let terms = integral_of(&tri, |q| {
            let d = q.extend(0.0) - obs.position;
            z / d.length().powi(3)
        }, tol);
        prop_assert!(
            (c - want_c).abs() <= 1e-11 * want_c + 1e-10 * terms,
            "constant: {} vs {} (terms {})", c, want_c, terms
        );
        // The same for the weight's three parts (c0, cx X, cy Y), each integrated apart.
        let weight_terms = integral_of(&tri, |q| {
            let d = q.extend(0.0) - obs.position;
            (weight.c0.abs() + (weight.cx * q.x).abs() + (weight.cy * q.y).abs()) * z
                / d.length().powi(3)
        }, tol);
        prop_assert!(
            (a - want_a).abs() <= 1e-10 * scale + 1e-10 * weight_terms,
            "affine: {} vs {} (terms {})", a, want_a, weight_terms
        );
    }

    #[test]
    fn random_plates_in_a_closed_box_keep_every_row_sum_at_1(
        plates in proptest::collection::vec((point3(-1.0, 1.0), point3(-0.6, 0.6), point3(-0.6, 0.6)), 1..4),
        linear in any::<bool>(),
    ) {
        // A closed box (half-size 2.5) and random double-sided plates inside it: whatever they
        // hide, every ray from a node hits exactly one surface, so every row of K/rho sums to 1
        // (Lemma 2.1) -- only if the pair plan's visible pieces are exact, with no overlap or gap.
        let quad = |o: DVec3, a: DVec3, b: DVec3| vec![o, o + a, o + a + b, o + b];
        let (lo, s) = (DVec3::splat(-2.5), 5.0);
        let (x, y, z) = (DVec3::X * s, DVec3::Y * s, DVec3::Z * s);
        let mut faces = vec![
            Face::new("bottom", quad(lo, x, y), 1.0),
            Face::new("top", quad(lo + z, y, x), 1.0),
            Face::new("front", quad(lo, z, x), 1.0),
            Face::new("back", quad(lo + y, x, z), 1.0),
            Face::new("left", quad(lo, y, z), 1.0),
            Face::new("right", quad(lo + x, z, y), 1.0),
        ];
        for (k, (o, a, b)) in plates.iter().enumerate() {
            faces.push(Face::new(format!("plate {k} up"), quad(*o, *a, *b), 1.0));
            faces.push(Face::new(format!("plate {k} down"), quad(*o, *b, *a), 1.0));
        }
        // Degenerate random plates are rejected with an error, never a panic.
        let faces: Vec<Face> = faces.into_iter().filter_map(|f| f.ok()).collect();
        let scene = Scene::new("random", faces).unwrap();
        let mesh = Mesh::new(&scene, &MeshKind::Uniform, 1).unwrap();
        let method = if linear { Method::Linear { alpha: 1.0 / 6.0 } } else { Method::Centroid };
        let disc = Discretization::new(&scene, &mesh, method).unwrap();
        let problem = Problem::new(scene.clone(), mesh.clone(), disc.clone());
        let a = assemble(&problem, &AssemblyOptions::default(), &radiosity::progress::Silent).unwrap();
        for i in 0..disc.dof() {
            let row = a.matrix.row(i);
            prop_assert!(row.iter().all(|v| v.is_finite()));
            if !linear {
                // Piecewise constant: every entry is a visible solid-angle share.
                prop_assert!(row.iter().all(|&v| v >= -1e-15), "row {}: negative entry", i);
            }
            let sum: f64 = row.iter().sum();
            prop_assert!((sum - 1.0).abs() <= 1e-9, "row {} ({:?}): K/rho sums to {}", i, disc.node(i).position, sum);
        }
    }

    #[test]
    fn the_matrix_does_not_depend_on_the_unit_of_length(exponent in -49i32..50, linear in any::<bool>()) {
        // G dS is dimensionless: scaling the scene by 10^k changes no entry beyond rounding,
        // from 1e-49 to 1e49 (the fuzzer found NaN entries at 1e-115 before every pair was
        // integrated in units of its element).
        let matrix = |scale: f64| {
            let scene = radiosity::scene::baffled_box().unwrap();
            let faces = scene
                .faces
                .iter()
                .map(|f| Face::new(f.name.clone(), f.vertices.iter().map(|v| *v * scale).collect(), f.rho).unwrap())
                .collect();
            let scene = Scene::new("scaled", faces).unwrap();
            let mesh = Mesh::new(&scene, &MeshKind::Uniform, 0).unwrap();
            let method = if linear { Method::Linear { alpha: 1.0 / 6.0 } } else { Method::Centroid };
            let disc = Discretization::new(&scene, &mesh, method).unwrap();
            let problem = Problem::new(scene.clone(), mesh.clone(), disc.clone());
            assemble(&problem, &AssemblyOptions::default(), &radiosity::progress::Silent).unwrap().matrix
        };
        let (one, scaled) = (matrix(1.0), matrix(10f64.powi(exponent)));
        for (a, b) in one.as_slice().iter().zip(scaled.as_slice()) {
            prop_assert!(b.is_finite() && (a - b).abs() <= 1e-12, "{} vs {}", a, b);
        }
    }
}

#[test]
fn scenes_spanning_more_than_60_orders_of_magnitude_are_refused() {
    // Found by the fuzzer (there with coordinates up to 2e52, now refused for that alone): a tiny
    // triangle beside a huge quadrilateral.
    let small = Face::new(
        "small",
        vec![
            DVec3::new(0.0, 7e-20, 0.0),
            DVec3::new(0.0, 0.0, 7e-20),
            DVec3::new(7e-20, 7e-20, 7e-20),
        ],
        0.5,
    )
    .unwrap();
    let huge = Face::new(
        "huge",
        vec![DVec3::ZERO, DVec3::new(2e45, 0.0, 0.0), DVec3::new(2e45, 2e45, 0.0)],
        0.5,
    )
    .unwrap();
    let err = Scene::new("fuzz", vec![small, huge]).unwrap_err().to_string();
    assert!(err.contains("'small'") && err.contains("1e60"), "{err}");
    let err = Face::new("far", vec![DVec3::ZERO, DVec3::X * 1e60, DVec3::Y], 0.5).unwrap_err();
    assert!(err.to_string().contains("1e50"), "{err}");
}
