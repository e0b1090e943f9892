//! The exact collocation integrals (paper sec. 4.1, the "exact method" of sec. 4.2): closed forms for
//! the constant weight of the centroid method, closed forms plus one IMT quadrature per edge for the
//! affine weights of piecewise linear collocation.

use glam::DVec2;

use super::{Affine2, Moments, Observer, Quadratic2, ThirdOrderMoments};
use crate::quadrature::ImtRule;

/// `∫_region G(P, Q) dS_Q` in closed form (eqs. 4.5 and 4.7 in edge form).
pub fn constant_weight<'a>(obs: &Observer, loops: impl IntoIterator<Item = &'a [DVec2]>) -> f64 {
    let o = obs.position.truncate();
    let m = Moments::new(loops, o, obs.position.z, false, None);
    let n = obs.normal;
    -n.z * m.m00 + n.x * m.m10 + n.y * m.m01
}

/// `∫_region G(P, Q) φ_l(Q) dS_Q` for affine weights φ_l (eqs. 4.5–4.9). The single non-elementary
/// moment `N_00` (the paper's (4.13)) is evaluated with `imt`, and only when some weight needs it:
/// it enters with the factor `i c_x + j c_y`, which vanishes when the node's face is parallel to the
/// element.
pub fn affine_weights<'a, const L: usize>(
    obs: &Observer,
    loops: impl IntoIterator<Item = &'a [DVec2]>,
    weights: &[Affine2; L],
    imt: &ImtRule,
) -> [f64; L] {
    let (o, z) = (obs.position.truncate(), obs.position.z);
    let (i, j, k) = (obs.normal.x, obs.normal.y, obs.normal.z);
    let needs_log = weights.iter().any(|w| i * w.cx + j * w.cy != 0.0);
    let m = Moments::new(loops, o, z, true, needs_log.then_some(imt));
    let zn00 = m.zn00.unwrap_or(0.0);
    let (zm20, zm11, zm02) = (0.5 * (zn00 - m.bxx), -0.5 * m.bxy, 0.5 * (zn00 - m.byy));
    weights.map(|w| {
        let d0 = w.eval(o);
        -k * d0 * m.m00
            + (i * d0 - z * k * w.cx) * m.m10
            + (j * d0 - z * k * w.cy) * m.m01
            + i * w.cx * zm20
            + (i * w.cy + j * w.cx) * zm11
            + j * w.cy * zm02
    })
}

/// `∫_region G(P, Q) u(Q) dS_Q` for a quadratic u (moments up to third order; one IMT quadrature
/// per edge). Used for the emissivity of polynomial true solutions such as (3.2).
pub fn quadratic_weight<'a>(
    obs: &Observer,
    loops: impl IntoIterator<Item = &'a [DVec2]>,
    u: &Quadratic2,
    imt: &ImtRule,
) -> f64 {
    let (o, z) = (obs.position.truncate(), obs.position.z);
    let (i, j, k) = (obs.normal.x, obs.normal.y, obs.normal.z);
    let m = ThirdOrderMoments::new(loops, o, z, imt);
    let q = u.shifted(o);
    let mut total = 0.0;
    for a in 0..3 {
        for b in 0..3 - a {
            total += q.c[a][b] * (i * m.zm[a + 1][b] + j * m.zm[a][b + 1] - k * m.z2m(a, b));
        }
    }
    total
}

#[cfg(test)]
mod tests {
    use super::super::far_field::{self, FarFieldRule};
    use super::super::{lambert, paper_closed_form, reference};
    use super::*;
    use crate::quadrature::Tolerance;
    use glam::DVec3;
    use rand::{Rng, SeedableRng, rngs::StdRng};

    fn random_unit(rng: &mut StdRng) -> DVec3 {
        loop {
            let v = DVec3::new(
                rng.random_range(-1.0..1.0),
                rng.random_range(-1.0..1.0),
                rng.random_range(-1.0..1.0),
            );
            if v.length() > 0.2 && v.length() < 1.0 {
                return v.normalize();
            }
        }
    }

    fn random_triangle(rng: &mut StdRng) -> [DVec2; 3] {
        loop {
            let t = [(); 3]
                .map(|_| DVec2::new(rng.random_range(-1.0..1.0), rng.random_range(-1.0..1.0)));
            let area = 0.5 * (t[1] - t[0]).perp_dot(t[2] - t[0]);
            if area > 0.05 {
                return t;
            }
        }
    }

    /// `w` in coordinates centred at `c`.
    fn shifted(w: Affine2, c: DVec2) -> Affine2 {
        Affine2 { c0: w.eval(c), ..w }
    }

    /// Linear-collocation basis (α = 1/6) of a triangle, as affine functions.
    fn basis(t: &[DVec2; 3]) -> [Affine2; 3] {
        let alpha = 1.0 / 6.0;
        let area2 = (t[1] - t[0]).perp_dot(t[2] - t[0]);
        [0, 1, 2].map(|k| {
            let (p, q) = (t[(k + 1) % 3], t[(k + 2) % 3]);
            // Barycentric λ_k(X) = (q - p) × (X - p) / (2 area).
            let d = q - p;
            let lam = Affine2 { c0: d.perp_dot(-p) / area2, cx: -d.y / area2, cy: d.x / area2 };
            Affine2 {
                c0: (lam.c0 - alpha) / (1.0 - 3.0 * alpha),
                cx: lam.cx / (1.0 - 3.0 * alpha),
                cy: lam.cy / (1.0 - 3.0 * alpha),
            }
        })
    }

    struct Case {
        obs: Observer,
        tri: [DVec2; 3],
    }

    /// Checks the edge form, Lambert and the linear weights to `tol` relative to `∫ |G|`, and the
    /// paper's literal right-triangle formula to `paper_tol`: that formula first changes
    /// coordinates to the two right triangles, a perturbation of order ε·size of the node's
    /// position, and where the node is δ above the element's plane next to a vertex the integral
    /// changes by about (ε/δ) times itself under such a perturbation.
    fn check(case: &Case, tol: f64, paper_tol: f64, label: &str) {
        let imt = ImtRule::new(ImtRule::PAPER_NODES);
        let loops = [&case.tri[..]];
        let t = Tolerance { relative: 2e-14, ..Tolerance::default() };
        // Errors are measured relative to ∫ |G| (the integral itself may cancel to near zero).
        let scale = reference::integral_of(&case.tri, |q| case.obs.kernel(q).abs(), t);
        let want = reference::integral(&case.obs, &case.tri, |_| 1.0, t);
        let constant = [
            ("edge form", constant_weight(&case.obs, loops)),
            ("Lambert", lambert::constant_weight(&case.obs, loops)),
            ("paper (4.5)+(4.11)", paper_closed_form::constant_weight(&case.obs, &case.tri)),
        ];
        for (name, got) in constant {
            let err = (got - want).abs() / scale;
            let tol = if name.starts_with("paper") { paper_tol } else { tol };
            assert!(err < tol, "{label}: {name}: got {got:e}, want {want:e}, rel err {err:e}");
        }
        // The linear weights as the program evaluates them: closed forms within 3 radii of the
        // element, the far-field rule beyond (where the closed forms' edge terms cancel; see
        // closed_forms_lose_digits_far_from_thin_elements).
        let phi = basis(&case.tri);
        let centroid = (case.tri[0] + case.tri[1] + case.tri[2]) / 3.0;
        let local = case.tri.map(|v| v - centroid);
        let local_obs = Observer { position: case.obs.position - centroid.extend(0.0), ..case.obs };
        let rule = FarFieldRule::standard();
        let got = match rule.band(&local_obs, far_field::radius(&local)) {
            Some(band) => {
                local_obs.integrate_by_rule(&band.rule, &local, &phi.map(|w| shifted(w, centroid)))
            }
            None => affine_weights(&case.obs, loops, &phi, &imt),
        };
        for (l, w) in phi.iter().enumerate() {
            let want = reference::integral(&case.obs, &case.tri, |q| w.eval(q), t);
            let err = (got[l] - want).abs() / scale;
            assert!(
                err < tol,
                "{label}: linear basis {l}: got {:e}, want {want:e}, rel err {err:e}",
                got[l]
            );
        }
    }

    #[test]
    fn closed_forms_match_adaptive_quadrature_on_random_configurations() {
        let mut rng = StdRng::seed_from_u64(20001106);
        for n in 0..60 {
            let tri = random_triangle(&mut rng);
            let position = DVec3::new(
                rng.random_range(-2.0..2.0),
                rng.random_range(-2.0..2.0),
                rng.random_range(0.05..2.0),
            );
            let case = Case { obs: Observer { position, normal: random_unit(&mut rng) }, tri };
            check(&case, 1e-11, 1e-11, &format!("random case {n}"));
        }
    }

    #[test]
    fn closed_forms_lose_digits_far_from_thin_elements() {
        // The affine-weight closed forms sum edge terms that cancel when the node is many element
        // sizes away: for this thin triangle (aspect about 7, radius 0.5) they err by 1e-13 to
        // 2.2e-12 relative to ∫|G| at 4 to 20 radii (measured), the far-field rule that replaces
        // them there by at most 2e-16.
        let tri = [DVec2::new(-0.5, -0.05), DVec2::new(0.5, -0.05), DVec2::new(0.0, 0.1)];
        let imt = ImtRule::new(ImtRule::PAPER_NODES);
        let phi = basis(&tri);
        let centroid = (tri[0] + tri[1] + tri[2]) / 3.0;
        let t = Tolerance { relative: 1e-15, ..Tolerance::default() };
        for distance in [2.0, 5.0, 10.0] {
            let obs = Observer {
                position: DVec3::new(0.3, distance, 0.4 * distance),
                normal: DVec3::new(0.2, -0.9, -0.3).normalize(),
            };
            let scale = reference::integral_of(&tri, |q| obs.kernel(q).abs(), t);
            let got = affine_weights(&obs, [&tri[..]], &phi, &imt);
            let local = tri.map(|v| v - centroid);
            let local_obs = Observer { position: obs.position - centroid.extend(0.0), ..obs };
            let far_field = FarFieldRule::standard();
            let band = far_field.band(&local_obs, far_field::radius(&local)).expect("far");
            let rule =
                local_obs.integrate_by_rule(&band.rule, &local, &phi.map(|w| shifted(w, centroid)));
            for l in 0..3 {
                let want = reference::integral(&obs, &tri, |q| phi[l].eval(q), t);
                let closed = (got[l] - want).abs() / scale;
                let far = (rule[l] - want).abs() / scale;
                assert!(closed < 1e-11, "distance {distance}: closed form error {closed:e}");
                assert!(far < 1e-15, "distance {distance}: far-field rule error {far:e}");
            }
        }
    }

    #[test]
    fn closed_forms_match_adaptive_quadrature_near_a_shared_edge() {
        // A node on a perpendicular neighbouring face, a distance δ from the element's edge on the
        // line Y = 0 (paper Fig. 4.1 in miniature), and just beyond the edge's ends.
        let tri = [DVec2::new(0.0, 0.0), DVec2::new(1.0, 0.0), DVec2::new(0.2, 0.9)];
        for delta in [1e-2, 1e-4, 1e-6] {
            for x in [0.3, 0.0, 1.0 + 1e-3, -0.5] {
                let obs = Observer { position: DVec3::new(x, 0.0, delta), normal: DVec3::Y };
                let paper_tol = 1e-11f64.max(1e-16 / delta);
                check(&Case { obs, tri }, 1e-11, paper_tol, &format!("δ = {delta:e}, x = {x}"));
            }
        }
    }

    #[test]
    fn closed_forms_match_the_paper_figure_4_1_configuration() {
        // Paper Fig. 4.1: P = (4.7917, 5.0, 0.0208) on S5 (normal -y), the element of S1 with vertices
        // (4.375, 5), (5, 4.375), (5, 5); max G ≈ 750.
        let tri = [DVec2::new(4.375, 5.0), DVec2::new(5.0, 4.375), DVec2::new(5.0, 5.0)];
        let obs = Observer { position: DVec3::new(4.7917, 5.0, 0.0208), normal: -DVec3::Y };
        check(&Case { obs, tri }, 1e-11, 1e-11, "Fig. 4.1");
    }

    #[test]
    fn projection_inside_the_element_and_very_close_to_its_plane() {
        let tri = [DVec2::new(0.0, 0.0), DVec2::new(1.0, 0.0), DVec2::new(0.0, 1.0)];
        for z in [1e-1, 1e-3] {
            let obs = Observer {
                position: DVec3::new(0.25, 0.3, z),
                normal: DVec3::new(0.3, -0.2, -1.0).normalize(),
            };
            check(&Case { obs, tri }, 1e-11, 1e-11, &format!("inside, z = {z}"));
        }
    }

    #[test]
    fn quadratic_weights_match_adaptive_quadrature() {
        let mut rng = StdRng::seed_from_u64(33);
        let imt = ImtRule::new(ImtRule::PAPER_NODES);
        let t = Tolerance { relative: 2e-14, ..Tolerance::default() };
        for n in 0..20 {
            let tri = random_triangle(&mut rng);
            let position = DVec3::new(
                rng.random_range(-1.5..1.5),
                rng.random_range(-1.5..1.5),
                if n < 4 { 1e-3 } else { rng.random_range(0.05..1.5) },
            );
            let obs = Observer { position, normal: random_unit(&mut rng) };
            let mut u = Quadratic2::default();
            for a in 0..3 {
                for b in 0..3 - a {
                    u.c[a][b] = rng.random_range(-1.0..1.0);
                }
            }
            let got = quadratic_weight(&obs, [&tri[..]], &u, &imt);
            let want = reference::integral(&obs, &tri, |q| u.eval(q), t);
            let scale = reference::integral_of(&tri, |q| (obs.kernel(q) * u.eval(q)).abs(), t);
            let err = (got - want).abs() / scale;
            assert!(err < 1e-11, "case {n}: got {got:e}, want {want:e}, rel err {err:e}");
        }
    }

    #[test]
    fn third_order_moments_match_direct_quadrature() {
        let tri = [DVec2::new(-0.3, -0.2), DVec2::new(0.9, 0.1), DVec2::new(0.2, 0.8)];
        let imt = ImtRule::new(ImtRule::PAPER_NODES);
        let z = 0.4;
        let m = ThirdOrderMoments::new([&tri[..]], DVec2::ZERO, z, &imt);
        let t = Tolerance { relative: 1e-14, ..Tolerance::default() };
        let direct = |a: i32, b: i32| {
            z * reference::integral_of(
                &tri,
                |q| {
                    let d = q.length_squared() + z * z;
                    q.x.powi(a) * q.y.powi(b) / (d * d)
                },
                t,
            )
        };
        for (a, b) in [(3, 0), (2, 1), (1, 2), (0, 3), (2, 0), (1, 1), (0, 2)] {
            let want = direct(a as i32, b as i32);
            assert!((m.zm[a][b] - want).abs() < 1e-13, "zM_{a}{b}: {} vs {want}", m.zm[a][b]);
        }
    }

    #[test]
    fn howell_b3_differential_element_to_a_parallel_rectangle() {
        // Howell B-3 with a = b = c = 1: the normal through a corner of the unit square.
        let square = [
            DVec2::new(0.0, 0.0),
            DVec2::new(1.0, 0.0),
            DVec2::new(1.0, 1.0),
            DVec2::new(0.0, 1.0),
        ];
        let obs = Observer { position: DVec3::new(0.0, 0.0, 1.0), normal: -DVec3::Z };
        let want = 0.138_531_605_994_892_98;
        let edge = constant_weight(&obs, [&square[..]]) / std::f64::consts::PI;
        let lam = lambert::constant_weight(&obs, [&square[..]]) / std::f64::consts::PI;
        assert!((edge - want).abs() < 1e-14, "edge form {edge} vs {want}");
        assert!((lam - want).abs() < 1e-14, "Lambert {lam} vs {want}");
    }

    #[test]
    fn howell_b4_perpendicular_rectangle() {
        // B-4: element at the origin with normal +z; rectangle in the plane y = d, x in [0, w],
        // z in [0, h]. In the rectangle's frame (normal -y towards the element): X = x, Y = z.
        for ((w, h, d), want) in [
            ((1.0, 1.0, 1.0), 0.055_734_197_002_553_51),
            ((3.0, 0.5, 2.0), 0.006_842_703_753_210_53),
        ] {
            // Rectangle frame: normal -y (towards the element), e1 = +x, e2 = normal × e1 = +z.
            let rect =
                [DVec2::new(0.0, 0.0), DVec2::new(w, 0.0), DVec2::new(w, h), DVec2::new(0.0, h)];
            let obs =
                Observer { position: DVec3::new(0.0, 0.0, d), normal: DVec3::new(0.0, 1.0, 0.0) };
            let got = constant_weight(&obs, [&rect[..]]) / std::f64::consts::PI;
            assert!((got - want).abs() < 1e-14, "B-4 ({w}, {h}, {d}): {got} vs {want}");
        }
    }
}
