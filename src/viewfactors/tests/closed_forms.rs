//! Whole matrices against closed forms: Howell's catalogue (C-11, C-14) and the five-piece
//! scene's parallel and perpendicular rectangles and its published reference.

use std::f64::consts::PI;

use glam::DVec3;

use super::fixture::compute;
use crate::scene::{Face, Scene};

fn square(name: &str, z: f64, up: bool, x0: f64) -> Face {
    let mut v = vec![
        DVec3::new(x0, 0.0, z),
        DVec3::new(x0 + 1.0, 0.0, z),
        DVec3::new(x0 + 1.0, 1.0, z),
        DVec3::new(x0, 1.0, z),
    ];
    if !up {
        v.reverse();
    }
    Face::new(name, v, 0.5).unwrap()
}

#[test]
fn howell_c11_parallel_unit_squares() {
    // Howell's catalogue C-11: directly opposed unit squares at distance 1.
    let scene =
        Scene::new("c11", vec![square("a", 0.0, true, 0.0), square("b", 1.0, false, 0.0)]).unwrap();
    for refine in [0, 1] {
        let (mesh, f) = compute(&scene, refine);
        let faces = f.by_face(&mesh);
        let want = 0.199_824_895_698_387_46;
        assert!((faces[0][1] - want).abs() < 1e-10, "refine {refine}: {}", faces[0][1]);
        assert!((faces[1][0] - want).abs() < 1e-10);
        assert!(f.reciprocity_error() < 1e-10);
    }
}

#[test]
fn howell_c14_perpendicular_squares_with_a_common_edge() {
    // C-14 with W = H = 1; the inner integral has d log d behaviour at the common edge.
    let wall = Face::new(
        "wall",
        vec![DVec3::ZERO, DVec3::Y, DVec3::new(0.0, 1.0, 1.0), DVec3::new(0.0, 0.0, 1.0)],
        0.5,
    )
    .unwrap();
    let scene = Scene::new("c14", vec![square("floor", 0.0, true, 0.0), wall]).unwrap();
    let want = common_edge(1.0, 1.0);
    for refine in [0, 2] {
        let (mesh, f) = compute(&scene, refine);
        let got = f.by_face(&mesh)[0][1];
        assert!((got - want).abs() < 1e-9, "refine {refine}: {got} vs {want}");
        assert!(f.reciprocity_error() < 1e-9, "{}", f.reciprocity_error());
    }
}

#[test]
fn five_piece_face_factors_match_closed_forms_and_the_reference() {
    // S1 -> S2: parallel squares [0,5]² and [0,2]² a distance 1 apart (the parallel-rectangle
    // formula); S1 -> S4 past the square: the paper's reference to its printed digits;
    // reciprocity from accuracy alone.
    let scene = crate::scene::five_piece(Default::default()).unwrap();
    let (mesh, f) = compute(&scene, 2);
    let faces = f.by_face(&mesh);
    let a1 = 25.0;
    let s1_s2 = parallel_rectangles(0.0, 5.0, 0.0, 5.0, 0.0, 2.0, 0.0, 2.0, 1.0) / a1;
    assert!((faces[0][1] - s1_s2).abs() < 1e-8, "{} vs {s1_s2}", faces[0][1]);
    // S1 -> S5: perpendicular, sharing S1's edge y = 5 (length 5; S1 5 wide, S5 1 high).
    let s1_s5 = common_edge(1.0, 0.2);
    assert!((faces[0][4] - s1_s5).abs() < 1e-8, "{} vs {s1_s5}", faces[0][4]);
    assert!((faces[0][3] - 0.00171932).abs() < 5e-9, "{}", faces[0][3]);
    assert!(f.reciprocity_error() < 1e-9, "{}", f.reciprocity_error());
}

/// Howell's C-14: F from a rectangle of width `w` to a perpendicular one of height `h`
/// sharing its whole edge, both in units of that edge's length.
fn common_edge(w: f64, h: f64) -> f64 {
    let (w2, h2) = (w * w, h * h);
    let s = (h2 + w2).sqrt();
    let log_term = ((1.0 + w2) * (1.0 + h2) / (1.0 + w2 + h2)).ln()
        + w2 * (w2 * (1.0 + w2 + h2) / ((1.0 + w2) * (w2 + h2))).ln()
        + h2 * (h2 * (1.0 + h2 + w2) / ((1.0 + h2) * (h2 + w2))).ln();
    (w * (1.0 / w).atan() + h * (1.0 / h).atan() - s * (1.0 / s).atan() + 0.25 * log_term)
        / (PI * w)
}

/// A_1 F_12 between the parallel rectangles [x1,x2]×[y1,y2] and [ξ1,ξ2]×[η1,η2] a distance
/// `c` apart (the standard double-sum closed form).
#[allow(clippy::too_many_arguments)]
fn parallel_rectangles(
    x1: f64,
    x2: f64,
    y1: f64,
    y2: f64,
    xi1: f64,
    xi2: f64,
    eta1: f64,
    eta2: f64,
    c: f64,
) -> f64 {
    let g = |x: f64, y: f64| {
        let (x2, y2, c2) = (x * x, y * y, c * c);
        0.5 * x * (y2 + c2).sqrt() * (x / (y2 + c2).sqrt()).atan()
            + 0.5 * y * (x2 + c2).sqrt() * (y / (x2 + c2).sqrt()).atan()
            - 0.25 * c2 * (x2 + y2 + c2).ln()
    };
    let mut sum = 0.0;
    for (i, x) in [x1, x2].into_iter().enumerate() {
        for (j, y) in [y1, y2].into_iter().enumerate() {
            for (k, xi) in [xi1, xi2].into_iter().enumerate() {
                for (l, eta) in [eta1, eta2].into_iter().enumerate() {
                    let sign = if (i + j + k + l) % 2 == 0 { 1.0 } else { -1.0 };
                    sum += sign * g(xi - x, eta - y);
                }
            }
        }
    }
    sum / PI
}
