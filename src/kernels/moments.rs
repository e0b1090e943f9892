//! Moments of the kernel's denominator over a polygon, in edge form (paper sec. 4.1).
//!
//! With coordinates (X, Y) centred at the projection O of P and D = X² + Y² + z², every collocation
//! integral over a polygon is a combination of `M_ab = ∫ X^a Y^b / D² dA` (a + b <= 2) and
//! `N_00 = ∫ 1 / D dA`. The paper evaluates them over right triangles (eqs. 4.5–4.10) and adds six
//! of those per triangle (4.11); here the same closed forms appear as one term per edge:
//!
//! - fan from O over each edge, integrated radially: `z² M_00 = Σ_e (h_e / 2) A_e`, which is the
//!   signed sum of (4.10) over the two right triangles at the foot of the perpendicular from O
//!   (the decomposition (4.11));
//! - divergence theorem, `∇(1/D) = -2 (X, Y)/D²`: `(M_10, M_01) = -(1/2) Σ_e ν_e A_e`, the
//!   integrals (4.5);
//! - `∂_X (X/D) = 1/D - 2X²/D²` and its twins: `M_20 = (N_00 - ∮ X ν_X / D)/2`,
//!   `M_02 = (N_00 - ∮ Y ν_Y / D)/2`, `M_11 = -(1/2) ∮ X ν_Y / D`, the integrals (4.6), (4.8), (4.9);
//! - `N_00` is not elementary; per edge it is the 1-D integral
//!   `(h/2) ∫ ln(1 + (h² + t²)/z²) / (h² + t²) dt` (equivalent to the paper's (4.13)), evaluated by
//!   the IMT rule after `t = S sinh w`, which removes the length scale `S = (h² + z²)^(1/2)` and
//!   leaves an integrand analytic at unit scale.
//!
//! Edge quantities: unit tangent e, outward normal ν, signed distance `h = a·ν` of the edge's line
//! from O (positive when O is on the inner side), tangential end coordinates t_a, t_b,
//! `A_e = ∫ dt/(S² + t²) = [atan(t_b/S) - atan(t_a/S)]/S` (one atan2) and
//! `B_e = ∫ t dt/(S² + t²) = ln(r_b/r_a)` (one log1p), r the distance from P to the end points.
//!
//! Every moment is returned multiplied by the power of z that the kernel G carries, so nothing is
//! divided by z and the limit z -> 0 is harmless.

use glam::DVec2;

use super::lane_math;
use crate::quadrature::{IMT_LANES, ImtRule};

/// Scaled moments of a polygon seen from P = (x, y, z): see the module documentation.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Moments {
    /// `z² M_00`.
    pub m00: f64,
    /// `z M_10`.
    pub m10: f64,
    /// `z M_01`.
    pub m01: f64,
    /// `z ∮ X ν_X / D ds`, the boundary part of `z M_20`.
    pub bxx: f64,
    /// `z ∮ X ν_Y / D ds`, so `z M_11 = -bxy / 2`.
    pub bxy: f64,
    /// `z ∮ Y ν_Y / D ds`, the boundary part of `z M_02`.
    pub byy: f64,
    /// `z N_00`, when it was asked for.
    pub zn00: Option<f64>,
}

/// One polygon edge seen from O, with its closed-form line integrals.
#[derive(Clone, Copy, Debug)]
pub(crate) struct EdgeTerms {
    /// Signed distance of the edge's line from O along the outward normal.
    pub h: f64,
    /// Outward unit normal.
    pub nu: DVec2,
    /// Unit tangent.
    pub e: DVec2,
    /// Tangential coordinate of the start (from the foot of the perpendicular).
    pub ta: f64,
    /// Tangential coordinate of the end.
    pub tb: f64,
    /// `S² = h² + z²`.
    pub s2: f64,
    /// `∫ dt / (S² + t²)` over the edge.
    pub a: f64,
    /// `∫ t dt / (S² + t²)` over the edge (zero unless asked for: the constant weight needs no log).
    pub b: f64,
}

impl EdgeTerms {
    /// Terms of the edge from `p` to `q` (coordinates relative to O), or `None` for a zero-length
    /// edge; `b` only when `with_log`.
    pub fn new(p: DVec2, q: DVec2, z2: f64, with_log: bool) -> Option<Self> {
        let d = q - p;
        let len = d.length();
        if len == 0.0 {
            return None;
        }
        let e = d / len;
        let nu = DVec2::new(e.y, -e.x);
        let h = 0.5 * (p + q).dot(nu);
        let (ta, tb) = (p.dot(e), q.dot(e));
        let s2 = h * h + z2;
        let s = s2.sqrt();
        // atan(tb/S) - atan(ta/S) as a single atan2: exact quadrant, no cancellation.
        let a = (s * len).atan2(s2 + ta * tb) / s;
        let b = if with_log { half_log_ratio(s2, ta, tb, len) } else { 0.0 };
        Some(Self { h, nu, e, ta, tb, s2, a, b })
    }

    /// `∫ X / D dt` and `∫ Y / D dt` along the edge (X = h ν_X + t e_X on the edge).
    pub fn first_boundary(&self) -> DVec2 {
        self.nu * (self.h * self.a) + self.e * self.b
    }
}

/// `ln(r_b / r_a) = (1/2) ln((S² + t_b²)/(S² + t_a²))`, accurate for every ratio: near 1 through
/// log1p of the difference `r_b² - r_a² = len (t_a + t_b)` (no cancellation), otherwise as the log
/// of the ratio (log1p of a difference near -1 would lose the digits of the small radius).
pub(crate) fn half_log_ratio(s2: f64, ta: f64, tb: f64, len: f64) -> f64 {
    let (ra2, rb2) = (s2 + ta * ta, s2 + tb * tb);
    let ratio = rb2 / ra2;
    if (0.5..=2.0).contains(&ratio) {
        0.5 * (len * (ta + tb) / ra2).ln_1p()
    } else {
        0.5 * ratio.ln()
    }
}

/// Widest interval in `w` one application of the IMT rule covers. The span `asinh(t_b/S) -
/// asinh(t_a/S)` grows like `2 ln(L/S)` as the node nears both the element's plane and an edge's
/// line; one 128-node rule over it lost digits (8.3e-14 relative at S/L = 1e-4 in the test below). Wider spans are cut
/// into equal panels, each integrated by the rule, so the work grows with `ln(L/S)` and the error
/// stays at rounding level (test below, against 40-digit values). Spans within it, the common
/// case, are integrated as before.
pub const LOG_PANEL_WIDTH: f64 = 8.0;

/// What both forms of the log moment take from an edge: `S`, `h²`, the span `[w_a, w_b]` of
/// `w = asinh(t/S)` and its panels of at most [`LOG_PANEL_WIDTH`].
struct LogSpan {
    s: f64,
    h2: f64,
    wa: f64,
    wb: f64,
    panels: usize,
    width: f64,
}

impl LogSpan {
    /// `None` for an edge whose line passes through the node's foot (h = 0: no share).
    fn new(edge: &EdgeTerms) -> Option<Self> {
        if edge.h == 0.0 {
            return None;
        }
        let s = edge.s2.sqrt();
        let (wa, wb) = ((edge.ta / s).asinh(), (edge.tb / s).asinh());
        let panels = ((wb - wa) / LOG_PANEL_WIDTH) as usize + 1;
        let width = (wb - wa) / panels as f64;
        Some(Self { s, h2: edge.h * edge.h, wa, wb, panels, width })
    }
}

/// `z L_e` for the edge from `p` to `q` (coordinates relative to the node's foot) seen from the
/// height `z`: its share of `z N_00`, in vector lanes (what the kernels use) or by the scalar
/// reference; zero for a zero-length edge. For benches.
pub fn edge_log_moment(p: DVec2, q: DVec2, z: f64, imt: &ImtRule, in_lanes: bool) -> f64 {
    match EdgeTerms::new(p, q, z * z, true) {
        Some(edge) if in_lanes => log_integral(&edge, z, imt),
        Some(edge) => log_integral_scalar(&edge, z, imt),
        None => 0.0,
    }
}

/// `z L_e`: this edge's share of `z N_00`, as [`log_integral_scalar`] computes it, with the IMT
/// nodes evaluated [`IMT_LANES`] at a time (in AVX2 registers when the CPU has them): the
/// exponential and log1p of [`lane_math`], within 2 ulp of the library's, so the result is the
/// scalar form's to rounding (test below). Spans beyond the lanes' exponential
/// ([`lane_math::EXP_LIMIT`]) take the scalar form.
pub(crate) fn log_integral(edge: &EdgeTerms, z: f64, imt: &ImtRule) -> f64 {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx2") && std::arch::is_x86_feature_detected!("fma") {
        // SAFETY: AVX2 and FMA were detected at run time just above.
        return unsafe { log_integral_avx2(edge, z, imt) };
    }
    log_integral_lanes::<false>(edge, z, imt)
}

/// [`log_integral_lanes`] compiled for AVX2 and FMA (the polynomials of [`lane_math`] fuse their
/// steps).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
fn log_integral_avx2(edge: &EdgeTerms, z: f64, imt: &ImtRule) -> f64 {
    log_integral_lanes::<true>(edge, z, imt)
}

type ImtLanes = [f64; IMT_LANES];

#[inline(always)]
fn lanes(f: impl Fn(usize) -> f64) -> ImtLanes {
    std::array::from_fn(f)
}

/// The integrand and panels of [`log_integral_scalar`], every step a loop over the lanes.
#[inline(always)]
fn log_integral_lanes<const FUSED: bool>(edge: &EdgeTerms, z: f64, imt: &ImtRule) -> f64 {
    let Some(LogSpan { s, h2, wa, wb, panels, width }) = LogSpan::new(edge) else {
        return 0.0;
    };
    // Spans beyond the lanes' exponential, and heights so small that 1/z² overflows.
    if wa.abs().max(wb.abs()) > lane_math::EXP_LIMIT || z < 1e-150 {
        return log_integral_scalar(edge, z, imt);
    }
    let inv_z2 = 1.0 / (z * z);
    let log_s_over_z = (s / z).ln();
    // Loops, not iterators or closures: those become functions of their own, compiled without
    // the caller's AVX2.
    let mut integral = 0.0;
    for k in 0..panels {
        let a = wa + width * k as f64;
        let mut sums = [0.0; IMT_LANES];
        for (x, weight) in imt.lanes() {
            let w = lanes(|l| a + width * x[l]);
            let (e, inv) = lane_math::exp_and_reciprocal::<IMT_LANES, FUSED>(w);
            let t = lanes(|l| 0.5 * s * (e[l] - inv[l]));
            let r = lanes(|l| 0.5 * s * (e[l] + inv[l]));
            let q = lanes(|l| (h2 + t[l] * t[l]) * inv_z2);
            // One log1p per node, of q below 1 and of m² = e^-2|w| above (see the scalar form).
            let m = lanes(|l| e[l].min(inv[l]));
            let log = lane_math::ln_1p_unit::<IMT_LANES, FUSED>(lanes(|l| {
                if q[l] < 1.0 { q[l] } else { m[l] * m[l] }
            }));
            // ln(1 + q)/q, every branch of the scalar form computed and one kept (selects,
            // not jumps).
            let near = lanes(|l| 1.0 - q[l] * (0.5 - q[l] * (1.0 / 3.0)));
            let above =
                lanes(|l| 2.0 * (log_s_over_z + w[l].abs() - std::f64::consts::LN_2 + log[l]));
            let ratio = lanes(|l| (if q[l] < 1.0 { log[l] } else { above[l] }) / q[l]);
            for l in 0..IMT_LANES {
                let ratio = if q[l] < 1e-8 { near[l] } else { ratio[l] };
                sums[l] += weight[l] * (ratio * r[l]);
            }
        }
        let mut panel = 0.0;
        for sum in sums {
            panel += sum;
        }
        integral += width * panel;
    }
    0.5 * edge.h * integral / z
}

/// `z L_e`: this edge's share of `z N_00`, by the IMT rule in `w` with `t = S sinh w`, on panels of
/// at most [`LOG_PANEL_WIDTH`]. The scalar reference of [`log_integral`].
pub(crate) fn log_integral_scalar(edge: &EdgeTerms, z: f64, imt: &ImtRule) -> f64 {
    let Some(LogSpan { s, h2, wa, panels, width, .. }) = LogSpan::new(edge) else {
        return 0.0;
    };
    let z2 = z * z;
    // Integrand in w: [ln(1 + q)/q] r / z² with q = (h² + t²)/z² and r = (S² + t²)^(1/2) = dt/dw.
    // One exponential gives t = S sinh w and r = S cosh w. Since 1 + q = r²/z², for q >= 1
    // ln(1 + q) = 2 ln(r/z) = 2 [ln(S/z) + |w| - ln 2 + ln(1 + m²)], m = e^-|w| <= 1: one log per
    // edge and a log1p of an argument in [0, 1] per node (below q = 1 the log1p of q keeps its digits).
    let log_s_over_z = (s / z).ln();
    let integrand = |w: f64| {
        let e = w.exp();
        let inv = 1.0 / e;
        let (t, r) = (0.5 * s * (e - inv), 0.5 * s * (e + inv));
        let q = (h2 + t * t) / z2;
        let ratio = if q < 1e-8 {
            1.0 - q * (0.5 - q / 3.0)
        } else if q < 1.0 {
            q.ln_1p() / q
        } else {
            let m = e.min(inv);
            2.0 * (log_s_over_z + w.abs() - std::f64::consts::LN_2 + (m * m).ln_1p()) / q
        };
        ratio * r
    };
    let integral: f64 = (0..panels)
        .map(|k| {
            let a = wa + width * k as f64;
            imt.integrate(a, a + width, integrand)
        })
        .sum();
    0.5 * edge.h * integral / z
}

impl Moments {
    /// Moments of the region bounded by `loops` seen from `P = (o, z)`, `z > 0` (`o` in the same
    /// in-plane coordinates as the loops). Only `m00`, `m10`, `m01` unless `second_order`; `N_00`
    /// only when `imt` is given.
    pub fn new<'a>(
        loops: impl IntoIterator<Item = &'a [DVec2]>,
        o: DVec2,
        z: f64,
        second_order: bool,
        imt: Option<&ImtRule>,
    ) -> Self {
        let z2 = z * z;
        let mut m = Moments { zn00: imt.map(|_| 0.0), ..Default::default() };
        for poly in loops {
            let n = poly.len();
            for k in 0..n {
                let Some(edge) =
                    EdgeTerms::new(poly[k] - o, poly[(k + 1) % n] - o, z2, second_order)
                else {
                    continue;
                };
                m.m00 += 0.5 * edge.h * edge.a;
                m.m10 -= 0.5 * z * edge.nu.x * edge.a;
                m.m01 -= 0.5 * z * edge.nu.y * edge.a;
                if !second_order {
                    continue;
                }
                let xy = edge.first_boundary();
                m.bxx += z * edge.nu.x * xy.x;
                m.bxy += z * edge.nu.y * xy.x;
                m.byy += z * edge.nu.y * xy.y;
                if let (Some(rule), Some(acc)) = (imt, m.zn00.as_mut()) {
                    *acc += log_integral(&edge, z, rule);
                }
            }
        }
        m
    }
}

/// `z M_ab` for `a + b <= 3` (and `z² M_ab` through [`ThirdOrderMoments::z2m`]), for the integral of
/// G against a quadratic (the emissivity of a polynomial true solution). Besides the relations in
/// the module documentation this uses `∂_X (X^(a+1) Y^b / D) = (a+1) X^a Y^b / D - 2 X^(a+2) Y^b / D²`
/// and `N_10 = (1/2) ∮ ln D ν_X` (from `∇ ln D = 2 (X, Y) / D`), elementary along each edge.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ThirdOrderMoments {
    /// `z M_ab` at `[a][b]`, `a + b <= 3` (entries with a + b > 3 are zero).
    pub zm: [[f64; 4]; 4],
    /// `z² M_00`.
    pub m00: f64,
    /// Height z.
    pub z: f64,
}

impl ThirdOrderMoments {
    /// Moments of the region bounded by `loops` seen from `P = (o, z)`, `z > 0`.
    pub fn new<'a>(
        loops: impl IntoIterator<Item = &'a [DVec2]>,
        o: DVec2,
        z: f64,
        imt: &ImtRule,
    ) -> Self {
        let z2 = z * z;
        // Boundary integrals ∮ p ν_c / D ds for monomials p of degree <= 2, and ∮ ln D ν ds.
        let (mut m00, mut zn00) = (0.0, 0.0);
        let mut first = DVec2::ZERO; // Σ ν A
        let mut xx = DVec2::ZERO; // ∮ X² ν / D
        let mut xy = DVec2::ZERO; // ∮ X Y ν / D
        let mut yy = DVec2::ZERO; // ∮ Y² ν / D
        let mut x1 = DVec2::ZERO; // ∮ X ν / D
        let mut y1 = DVec2::ZERO; // ∮ Y ν / D
        let mut log = DVec2::ZERO; // ∮ ln D ν
        for poly in loops {
            let n = poly.len();
            for k in 0..n {
                let (p, q) = (poly[k] - o, poly[(k + 1) % n] - o);
                let Some(edge) = EdgeTerms::new(p, q, z2, true) else {
                    continue;
                };
                let len = (q - p).length();
                let (h, nu, e) = (edge.h, edge.nu, edge.e);
                let (i0, i1, i2) = (edge.a, edge.b, len - edge.s2 * edge.a);
                m00 += 0.5 * h * i0;
                zn00 += log_integral(&edge, z, imt);
                first += nu * i0;
                let fx = h * nu.x * i0 + e.x * i1;
                let fy = h * nu.y * i0 + e.y * i1;
                x1 += nu * fx;
                y1 += nu * fy;
                let quad = |ca: f64, cb: f64, da: f64, db: f64| {
                    // ∫ (h ca + t da)(h cb + t db) / (S² + t²) dt
                    h * h * ca * cb * i0 + h * (ca * db + cb * da) * i1 + da * db * i2
                };
                xx += nu * quad(nu.x, nu.x, e.x, e.x);
                xy += nu * quad(nu.x, nu.y, e.x, e.y);
                yy += nu * quad(nu.y, nu.y, e.y, e.y);
                let (ra2, rb2) = (edge.s2 + edge.ta * edge.ta, edge.s2 + edge.tb * edge.tb);
                let log_edge =
                    edge.tb * rb2.ln() - edge.ta * ra2.ln() - 2.0 * len + 2.0 * edge.s2 * i0;
                log += nu * log_edge;
            }
        }
        let hz = 0.5 * z;
        let (n10, n01) = (0.5 * log.x, 0.5 * log.y);
        let mut zm = [[0.0; 4]; 4];
        zm[0][0] = m00 / z;
        zm[1][0] = -hz * first.x;
        zm[0][1] = -hz * first.y;
        zm[2][0] = hz * (zn00 / z - x1.x);
        zm[0][2] = hz * (zn00 / z - y1.y);
        zm[1][1] = -hz * x1.y;
        zm[3][0] = hz * (2.0 * n10 - xx.x);
        zm[2][1] = hz * (n01 - xy.x);
        zm[1][2] = hz * (n10 - xy.y);
        zm[0][3] = hz * (2.0 * n01 - yy.y);
        Self { zm, m00, z }
    }

    /// `z² M_ab` for `a + b <= 2`.
    pub fn z2m(&self, a: usize, b: usize) -> f64 {
        if a == 0 && b == 0 { self.m00 } else { self.z * self.zm[a][b] }
    }
}

#[cfg(test)]
mod tests {
    use rand::{Rng, SeedableRng};

    use super::*;

    #[test]
    fn lanes_give_the_scalar_log_moment_to_rounding() {
        let imt = ImtRule::new(ImtRule::PAPER_NODES);
        let mut rng = rand::rngs::StdRng::seed_from_u64(17);
        let mut worst = 0.0f64;
        for _ in 0..20_000 {
            let v = |rng: &mut rand::rngs::StdRng| {
                DVec2::new(rng.random_range(-2.0..2.0), rng.random_range(-2.0..2.0))
            };
            // Heights from well above to 1e-9 of the edge's length and edges passing right under
            // the node, so that every branch of the integrand (q below 1e-8, below 1, above)
            // and long spans in w are met.
            let z = 10f64.powf(rng.random_range(-9.0..1.0));
            let (mut p, mut q) = (v(&mut rng), v(&mut rng));
            if rng.random_bool(0.25) {
                // The edge's line within 1e-6 .. 1 heights of the node's foot.
                let h = z * 10f64.powf(rng.random_range(-6.0..0.0));
                (p, q) = (DVec2::new(p.x, h), DVec2::new(q.x, h));
            }
            let Some(edge) = EdgeTerms::new(p, q, z * z, true) else {
                continue;
            };
            let want = log_integral_scalar(&edge, z, &imt);
            // The form this CPU runs, and the portable one (no fused multiply-adds).
            for got in [log_integral(&edge, z, &imt), log_integral_lanes::<false>(&edge, z, &imt)] {
                worst = worst.max(((got - want) / want).abs());
            }
        }
        println!("worst {worst:e}");
        assert!(worst < 2e-15, "worst relative difference {worst:e}");
    }

    /// `z L_e` for the edge t in [-0.4, 1] at distance h = 0.6 S from the node's foot, the node
    /// z = 0.8 S above the plane (S² = h² + z²): near both the element's plane and the edge's line
    /// as S → 0. Reference values by mpmath (40 digits, tanh-sinh with break points at 0, ±h, ±z
    /// and a geometric grid toward 0; its error estimate below 1e-41):
    /// (h/2z) ∫ ln(1 + q)/q dt, q = (h² + t²)/z². The digits are kept as mpmath printed them.
    #[allow(clippy::excessive_precision)]
    const REFERENCE: [(f64, f64); 6] = [
        (1e-2, 0.016_551_514_782_715_998_484_597_64),
        (1e-4, 0.000_174_042_600_183_879_185_954_961_3),
        (1e-6, 0.000_001_742_044_706_852_856_377_141_698),
        (1e-8, 1.742_068_553_222_122_326_411_964e-8),
        (1e-10, 1.742_068_868_279_005_519_374_666e-10),
        (1e-12, 1.742_068_872_195_506_256_637_832e-12),
    ];

    #[test]
    fn the_log_moment_is_accurate_near_the_plane_and_the_edge_line() {
        let imt = ImtRule::new(ImtRule::PAPER_NODES);
        for (s, want) in REFERENCE {
            let (h, z) = (0.6 * s, 0.8 * s);
            let p = DVec2::new(-0.4, -h);
            let q = DVec2::new(1.0, -h);
            let edge = EdgeTerms::new(p, q, z * z, true).unwrap();
            assert!((edge.h - h).abs() <= 1e-15 * h && edge.ta == -0.4 && edge.tb == 1.0);
            let got = log_integral_scalar(&edge, z, &imt);
            let error = ((got - want) / want).abs();
            let lanes = log_integral(&edge, z, &imt);
            assert!(((lanes - got) / got).abs() <= 1e-15, "S/L = {s:e}: lanes {lanes} vs {got}");
            println!("S/L = {s:e}: relative error {error:.2e}");
            assert!(error <= 1e-14, "S/L = {s:e}: {got} vs {want}: relative error {error:.2e}");
        }
    }
}
