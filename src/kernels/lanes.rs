//! The centroid method's closed form ([`super::exact::constant_weight`], eqs. 4.5 and 4.7 in edge
//! form) for [`LANES`] (node, triangle) pairs at once. The pairs are laid out as structure of
//! arrays and every step is a loop over the lanes without branches, so the compiler turns each
//! into vector instructions (AVX2 and FMA when the CPU has them, chosen at run time). The one
//! transcendental function, the arctangent of each edge's term, is our own branch-free one (the
//! reduction and polynomial of `shaders/math_f64.wgsl`, 1-2 ulp, its reduction folded into one
//! division). The edge terms are the scalar form's with the edge's length left in (one square
//! root and two divisions per edge instead of two and four), so the two agree to what rounding
//! moves either by: a few ulps of π, more for a node just above an edge's line close to the
//! plane, where K itself is ill-conditioned (tests below and in `assembly`). The scalar form stays
//! the reference.

use glam::DVec2;

use super::Observer;
use super::lane_math::atan2_positive_y;

/// Pairs evaluated together: two AVX2 registers per step, whose independent chains overlap
/// (faster than four lanes, and than eight in one AVX-512 register; docs/performance.md,
/// "What was tried and did not pay").
pub const LANES: usize = 8;

/// `∫_T G(P, Q) dS_Q` for each lane's observer and triangle (counter-clockwise, the observer's
/// local coordinates, height `z > 0`).
pub fn constant_weight(obs: &[Observer; LANES], tris: &[[DVec2; 3]; LANES]) -> [f64; LANES] {
    let mut pairs = PairLanes::default();
    for l in 0..LANES {
        pairs.set(l, &obs[l], &tris[l]);
    }
    pairs.constant_weight()
}

/// [`LANES`] (node, triangle) pairs as structure of arrays: what the kernel reads, written one
/// scalar at a time as the pairs come (a pair's observer, just computed, is read back field by
/// field, which the store buffer forwards; a 16-byte read of two 8-byte writes it cannot, and
/// would stall every batch).
#[derive(Clone, Copy, Debug, Default)]
struct PairLanes {
    /// The observers' positions (x, y, z) and normals (i, j, k).
    position: [Lanes; 3],
    normal: [Lanes; 3],
    /// The triangles' vertices: `vertex[c][k]` is coordinate c of vertex k.
    vertex: [[Lanes; 3]; 2],
}

impl PairLanes {
    #[inline(always)]
    fn set(&mut self, l: usize, obs: &Observer, tri: &[DVec2; 3]) {
        for c in 0..3 {
            self.position[c][l] = obs.position[c];
            self.normal[c][l] = obs.normal[c];
        }
        for (k, v) in tri.iter().enumerate() {
            (self.vertex[0][k][l], self.vertex[1][k][l]) = (v.x, v.y);
        }
    }

    /// Copies lane 0 into lanes `from..`.
    fn repeat_first(&mut self, from: usize) {
        let rows = self
            .position
            .iter_mut()
            .chain(&mut self.normal)
            .chain(self.vertex.iter_mut().flatten());
        for row in rows {
            for l in from..LANES {
                row[l] = row[0];
            }
        }
    }

    /// `∫_T G(P, Q) dS_Q` for each lane.
    fn constant_weight(&self) -> Lanes {
        #[cfg(target_arch = "x86_64")]
        if std::arch::is_x86_feature_detected!("avx2") && std::arch::is_x86_feature_detected!("fma")
        {
            // SAFETY: AVX2 and FMA were detected at run time just above.
            return unsafe { constant_weight_avx2(self) };
        }
        constant_weight_portable::<false>(self)
    }
}

/// Pairs waiting to be evaluated together, each with a tag `T` (where its value goes: a column,
/// a weight); every full batch and the last partial one give `(tag, value)` to a sink.
#[derive(Default)]
pub struct Batch<T> {
    len: usize,
    tags: [T; LANES],
    pairs: PairLanes,
}

impl<T: Copy> Batch<T> {
    /// Adds a pair; when the batch is full it is evaluated into `sink`.
    #[inline(always)]
    pub fn push(&mut self, tag: T, obs: Observer, tri: [DVec2; 3], sink: impl FnMut(T, f64)) {
        self.tags[self.len] = tag;
        self.pairs.set(self.len, &obs, &tri);
        self.len += 1;
        if self.len == LANES {
            self.flush(sink);
        }
    }

    /// Evaluates the waiting pairs into `sink` (the empty lanes repeat the first).
    pub fn flush(&mut self, mut sink: impl FnMut(T, f64)) {
        if self.len == 0 {
            return;
        }
        self.pairs.repeat_first(self.len);
        let values = self.pairs.constant_weight();
        for (&tag, v) in self.tags[..self.len].iter().zip(values) {
            sink(tag, v);
        }
        self.len = 0;
    }
}

/// [`PairLanes::constant_weight`] compiled for AVX2 and FMA (the arctangent's polynomial fused).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
fn constant_weight_avx2(pairs: &PairLanes) -> Lanes {
    constant_weight_portable::<true>(pairs)
}

type Lanes = [f64; LANES];

#[inline(always)]
fn lanes(f: impl Fn(usize) -> f64) -> Lanes {
    std::array::from_fn(f)
}

#[inline(always)]
fn constant_weight_portable<const FUSED: bool>(pairs: &PairLanes) -> Lanes {
    let [x, y, z] = pairs.position;
    let [vx, vy] = pairs.vertex;
    let z2 = lanes(|l| z[l] * z[l]);
    let (mut m00, mut m10, mut m01) = ([0.0; LANES], [0.0; LANES], [0.0; LANES]);
    for k in 0..3 {
        // Edge k from p to q, relative to the projection O of the observer.
        let px = lanes(|l| vx[k][l] - x[l]);
        let py = lanes(|l| vy[k][l] - y[l]);
        let qx = lanes(|l| vx[(k + 1) % 3][l] - x[l]);
        let qy = lanes(|l| vy[(k + 1) % 3][l] - y[l]);
        let (dx, dy) = (lanes(|l| qx[l] - px[l]), lanes(|l| qy[l] - py[l]));
        // The scalar form's terms with the edge's length L left in: H = h L, T_a = t_a L,
        // T_b = t_b L, R = S L = (H² + z² L²)^(1/2). Its arctangent is that of (S L, S² + t_a t_b),
        // both scaled by L², and A_e = angle / S: one square root and two divisions per edge
        // instead of two and four. A zero-length edge adds nothing.
        let l2 = lanes(|l| dx[l] * dx[l] + dy[l] * dy[l]);
        let hl = lanes(|l| 0.5 * ((px[l] + qx[l]) * dy[l] - (py[l] + qy[l]) * dx[l]));
        let ta = lanes(|l| px[l] * dx[l] + py[l] * dy[l]);
        let tb = lanes(|l| qx[l] * dx[l] + qy[l] * dy[l]);
        let r2 = lanes(|l| hl[l] * hl[l] + z2[l] * l2[l]);
        let r = lanes(|l| r2[l].sqrt());
        let angle = atan2_positive_y::<LANES, FUSED>(
            lanes(|l| r[l] * l2[l]),
            lanes(|l| r2[l] + ta[l] * tb[l]),
        );
        for l in 0..LANES {
            let a = if l2[l] > 0.0 { angle[l] / r[l] } else { 0.0 };
            m00[l] += 0.5 * hl[l] * a;
            m10[l] -= 0.5 * z[l] * dy[l] * a;
            m01[l] += 0.5 * z[l] * dx[l] * a;
        }
    }
    let [nx, ny, nz] = pairs.normal;
    lanes(|l| -nz[l] * m00[l] + nx[l] * m10[l] + ny[l] * m01[l])
}

#[cfg(test)]
mod tests {
    use glam::DVec3;
    use rand::{Rng, SeedableRng};

    use super::*;
    use crate::kernels::exact;

    /// What rounding alone may move the closed form by: the edge terms are angles of order 1
    /// whatever the value (which cancels to O(z) near the plane), so a few ulps of π; and the
    /// distance h of an edge's line from the node's foot, whatever the formula, carries an error
    /// of an ulp of the vertices' distances |p| + |q|, which moves that edge's term h A by about
    /// as much over S = (h² + z²)^(1/2) (large for a node just above the line, close to the plane,
    /// where K changes by O(1) as the node crosses the line).
    fn rounding_scale(obs: &Observer, tri: &[DVec2; 3]) -> f64 {
        let foot = obs.position.truncate();
        let conditioning: f64 = (0..3)
            .map(|k| {
                let (p, q) = (tri[k] - foot, tri[(k + 1) % 3] - foot);
                let e = (q - p).normalize_or_zero();
                let h = p.perp_dot(e);
                (p.length() + q.length()) / h.hypot(obs.position.z)
            })
            .sum();
        f64::EPSILON * (1.0 + conditioning)
    }

    #[test]
    fn lanes_agree_with_the_scalar_closed_form() {
        let mut rng = rand::rngs::StdRng::seed_from_u64(11);
        let mut worst = 0.0f64;
        for _ in 0..20_000 {
            let mut obs = [Observer { position: DVec3::Z, normal: DVec3::Z }; LANES];
            let mut tris = [[DVec2::ZERO; 3]; LANES];
            for l in 0..LANES {
                let v = |rng: &mut rand::rngs::StdRng| {
                    DVec2::new(rng.random_range(-1.0..1.0), rng.random_range(-1.0..1.0))
                };
                let mut t = [v(&mut rng), v(&mut rng), v(&mut rng)];
                if (t[1] - t[0]).perp_dot(t[2] - t[0]) < 0.0 {
                    t.swap(1, 2);
                }
                // Heights from far above down to 1e-6 of the triangle's size, anywhere around.
                let z = 10f64.powf(rng.random_range(-6.0..1.5));
                let position =
                    DVec3::new(rng.random_range(-3.0..3.0), rng.random_range(-3.0..3.0), z);
                let normal = DVec3::new(
                    rng.random_range(-1.0..1.0),
                    rng.random_range(-1.0..1.0),
                    rng.random_range(-1.0..1.0),
                )
                .normalize();
                (obs[l], tris[l]) = (Observer { position, normal }, t);
            }
            let got = constant_weight(&obs, &tris);
            // And the portable form (no fused multiply-adds), whatever this CPU runs.
            let mut pairs = PairLanes::default();
            for l in 0..LANES {
                pairs.set(l, &obs[l], &tris[l]);
            }
            let portable = constant_weight_portable::<false>(&pairs);
            for l in 0..LANES {
                let want = exact::constant_weight(&obs[l], [&tris[l][..]]);
                let scale = rounding_scale(&obs[l], &tris[l]);
                worst = worst.max((got[l] - want).abs().max((portable[l] - want).abs()) / scale);
            }
        }
        // Measured: 0.29 at most.
        assert!(worst < 1.0, "{worst} times the rounding scale");
    }
}
