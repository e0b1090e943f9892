//! `[∫ G, ∫ G X, ∫ G Y]` over a triangle by a fixed rule, [`LANES`] points per step: the far-field
//! rule of the linear method and the paper's graded rules (sec. 4.2). The rule's points come in
//! lanes ([`PointLanes`]). Where the CPU has AVX2 and FMA (chosen at run time), one group of
//! points fills one register and the sums of products are fused, which rounds differently from
//! the scalar form by about an ulp of the integral of G's size `|Q - P| z / r⁴` per group of
//! points (test below: 1.2 at most); elsewhere the portable form does the
//! operations of [`TriangleRule::moments`] with [`Observer::kernel`] in the same order, to the
//! last bit. That scalar form stays the reference.

use glam::{DVec2, DVec3};

use super::Observer;
use crate::quadrature::{PointLanes, RULE_LANES as LANES, TriangleRule};

/// The moments `[∫ G, ∫ G X, ∫ G Y]` of the kernel over `tri` (any orientation) by `rule`.
pub fn kernel_moments(obs: &Observer, rule: &TriangleRule, tri: &[DVec2; 3]) -> [f64; 3] {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx2") && std::arch::is_x86_feature_detected!("fma") {
        // SAFETY: AVX2 and FMA were detected at run time just above.
        return unsafe { kernel_moments_avx2(obs, rule.lanes(), tri) };
    }
    kernel_moments_portable(obs, rule.lanes(), tri)
}

/// What both forms take from the observer and the triangle `a, b, c`: the map
/// `Q = a + (b - a) u + (c - a) v` and its Jacobian, and the height component `0 - z` of `Q - P`
/// (Q in the plane), which enters as its square and its product with the normal's height
/// component, the same for every point.
struct Setup {
    a: DVec2,
    ab: DVec2,
    ac: DVec2,
    p: DVec3,
    n: DVec3,
    dz2: f64,
    dznz: f64,
    jacobian: f64,
}

impl Setup {
    #[inline(always)]
    fn new(obs: &Observer, tri: &[DVec2; 3]) -> Self {
        let [a, b, c] = *tri;
        let (p, n) = (obs.position, obs.normal);
        let dz = 0.0 - p.z;
        Self {
            a,
            ab: b - a,
            ac: c - a,
            p,
            n,
            dz2: dz * dz,
            dznz: dz * n.z,
            jacobian: (b - a).perp_dot(c - a).abs(),
        }
    }
}

/// [`kernel_moments`] in AVX2 registers, one group of [`LANES`] points per register, with fused
/// multiply-adds: written out with intrinsics because the compiler kept the portable form in
/// two-lane registers.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
fn kernel_moments_avx2(obs: &Observer, rule: &[PointLanes], tri: &[DVec2; 3]) -> [f64; 3] {
    use std::arch::x86_64::*;
    let Setup { a, ab, ac, p, n, dz2, dznz, jacobian } = Setup::new(obs, tri);
    let splat = _mm256_set1_pd;
    let load = |x: &[f64; LANES]| _mm256_set_pd(x[3], x[2], x[1], x[0]);
    let (ax, ay, abx, aby, acx, acy) =
        (splat(a.x), splat(a.y), splat(ab.x), splat(ab.y), splat(ac.x), splat(ac.y));
    let (px, py, pz, nx, ny) = (splat(p.x), splat(p.y), splat(p.z), splat(n.x), splat(n.y));
    let (dz2, dznz) = (splat(dz2), splat(dznz));
    let (mut s0, mut s1, mut s2) = (splat(0.0), splat(0.0), splat(0.0));
    for group in rule {
        let (u, v, w) = (load(&group.u), load(&group.v), load(&group.w));
        let qx = _mm256_fmadd_pd(acx, v, _mm256_fmadd_pd(abx, u, ax));
        let qy = _mm256_fmadd_pd(acy, v, _mm256_fmadd_pd(aby, u, ay));
        let (dx, dy) = (_mm256_sub_pd(qx, px), _mm256_sub_pd(qy, py));
        let r2 = _mm256_fmadd_pd(dy, dy, _mm256_fmadd_pd(dx, dx, dz2));
        let dot = _mm256_fmadd_pd(dy, ny, _mm256_fmadd_pd(dx, nx, dznz));
        let kernel = _mm256_div_pd(_mm256_mul_pd(dot, pz), _mm256_mul_pd(r2, r2));
        let g = _mm256_mul_pd(w, kernel);
        s0 = _mm256_add_pd(s0, g);
        s1 = _mm256_fmadd_pd(g, qx, s1);
        s2 = _mm256_fmadd_pd(g, qy, s2);
    }
    [s0, s1, s2].map(|s| {
        let mut l = [0.0; LANES];
        // SAFETY: `l` holds four f64, the width of the register stored.
        unsafe { _mm256_storeu_pd(l.as_mut_ptr(), s) };
        jacobian * ((l[0] + l[1]) + (l[2] + l[3]))
    })
}

#[inline(always)]
fn lanes(f: impl Fn(usize) -> f64) -> [f64; LANES] {
    std::array::from_fn(f)
}

#[inline(always)]
fn kernel_moments_portable(obs: &Observer, rule: &[PointLanes], tri: &[DVec2; 3]) -> [f64; 3] {
    let Setup { a, ab, ac, p, n, dz2, dznz, jacobian } = Setup::new(obs, tri);
    let mut sums = [[0.0f64; LANES]; 3];
    for group in rule {
        let (u, v) = (&group.u, &group.v);
        let qx = lanes(|l| (a.x + ab.x * u[l]) + ac.x * v[l]);
        let qy = lanes(|l| (a.y + ab.y * u[l]) + ac.y * v[l]);
        let (dx, dy) = (lanes(|l| qx[l] - p.x), lanes(|l| qy[l] - p.y));
        let r2 = lanes(|l| (dx[l] * dx[l] + dy[l] * dy[l]) + dz2);
        let g = lanes(|l| {
            let kernel = ((dx[l] * n.x + dy[l] * n.y) + dznz) * p.z / (r2[l] * r2[l]);
            group.w[l] * kernel
        });
        for l in 0..LANES {
            sums[0][l] += g[l];
            sums[1][l] += g[l] * qx[l];
            sums[2][l] += g[l] * qy[l];
        }
    }
    sums.map(|s| jacobian * ((s[0] + s[1]) + (s[2] + s[3])))
}

#[cfg(test)]
mod tests {
    use glam::DVec3;
    use rand::{Rng, SeedableRng};

    use super::*;

    #[test]
    fn lanes_give_the_scalar_rule() {
        let mut rng = rand::rngs::StdRng::seed_from_u64(13);
        let mut worst = 0.0f64;
        // Every point count modulo LANES, so that padding is exercised.
        let rules = [
            TriangleRule::stroud_t2_5_1(),
            TriangleRule::stroud_t2_5_1().composite(2),
            TriangleRule::collapsed_gauss(5),
            TriangleRule::collapsed_gauss(6),
            TriangleRule::collapsed_gauss(11),
        ];
        for _ in 0..2000 {
            let v = |rng: &mut rand::rngs::StdRng| {
                DVec2::new(rng.random_range(-1.0..1.0), rng.random_range(-1.0..1.0))
            };
            let tri = [v(&mut rng), v(&mut rng), v(&mut rng)];
            // Where fixed rules are used: the node at least a radius and a half from the
            // triangle's centroid (closer, G's gradient times the rounding of a point's
            // coordinates outgrows G itself, in either form), down to 1e-3 above its plane.
            let centroid = (tri[0] + tri[1] + tri[2]) / 3.0;
            let radius = tri.iter().map(|v| v.distance(centroid)).fold(0.0, f64::max);
            let direction = DVec2::from_angle(rng.random_range(0.0..std::f64::consts::TAU));
            let distance = radius * rng.random_range(1.5..20.0);
            let z = distance * 10f64.powf(rng.random_range(-3.0..0.0));
            let position = (centroid + direction * (distance * distance - z * z).sqrt()).extend(z);
            let normal = DVec3::new(
                rng.random_range(-1.0..1.0),
                rng.random_range(-1.0..1.0),
                rng.random_range(-1.0..1.0),
            )
            .normalize();
            let obs = Observer { position, normal };
            for rule in &rules {
                let want = rule.moments(&tri, |q| obs.kernel(q));
                assert_eq!(kernel_moments_portable(&obs, rule.lanes(), &tri), want);
                // Fused multiply-adds round differently. Measured against the integral of the
                // kernel's size |Q - P| z / r⁴ (G and its moments may cancel far below it), times
                // the largest coordinate for the first moments.
                let size = |q: DVec2| {
                    let d = q.extend(0.0) - obs.position;
                    d.length() * obs.position.z / (d.length_squared() * d.length_squared())
                };
                let scale = rule.moments(&tri, size)[0]
                    * tri.iter().map(|v| v.abs().max_element()).fold(1.0, f64::max);
                let got = kernel_moments(&obs, rule, &tri);
                // Both sum each lane's points in turn, so the rounding may grow with their number
                // (measured: 1.2 ulps per step at most).
                let steps = rule.lanes().len() as f64;
                for k in 0..3 {
                    worst = worst.max((got[k] - want[k]).abs() / (scale * steps * f64::EPSILON));
                }
            }
        }
        assert!(worst < 2.0, "worst difference {worst} ulps of the integral of |G| per step");
    }
}
