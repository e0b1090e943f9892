//! Adaptive cross approximation with partial pivoting (Bebendorf 2000; Bebendorf and Rjasanow
//! 2003): a block M (m × c), known only through its rows and columns, as `U V^T` of rank k, built
//! from k rows and k columns of M, to a relative tolerance in the Frobenius norm.
//!
//! The classical stopping rule `|u_k| |v_k| <= eps |S_k|_F` looks at the last cross only and can
//! stop early on a block whose remainder lives in rows not yet visited. Before accepting, a row
//! and a column not used so far (chosen at random) are compared with the approximation; a
//! remainder above the tolerance there becomes the next pivot instead. That is the "reliable
//! stopping rule" asked for: every accepted block has passed a test on entries it was not built
//! from.

use faer::Mat;
use rand::{Rng, SeedableRng};

/// `U V^T`: `u` is m × k and `v` is c × k, both row-major.
#[derive(Clone, Debug, PartialEq)]
pub struct LowRank {
    /// Rows.
    pub m: usize,
    /// Columns.
    pub c: usize,
    /// Rank.
    pub k: usize,
    /// m × k.
    pub u: Vec<f64>,
    /// c × k.
    pub v: Vec<f64>,
}

impl LowRank {
    /// `y += U V^T x`.
    pub fn apply_add(&self, x: &[f64], y: &mut [f64]) {
        let mut t = vec![0.0; self.k];
        for (j, xj) in x.iter().enumerate() {
            let row = &self.v[j * self.k..(j + 1) * self.k];
            t.iter_mut().zip(row).for_each(|(t, v)| *t += v * xj);
        }
        for (yi, row) in y.iter_mut().zip(self.u.chunks_exact(self.k.max(1))) {
            *yi += dot(row, &t);
        }
    }

    /// Entry (i, j).
    pub fn get(&self, i: usize, j: usize) -> f64 {
        (0..self.k).map(|l| self.u[i * self.k + l] * self.v[j * self.k + l]).sum()
    }

    /// Stored values.
    pub fn len(&self) -> usize {
        self.u.len() + self.v.len()
    }

    /// Whether nothing is stored (rank 0).
    pub fn is_empty(&self) -> bool {
        self.k == 0
    }
}

/// Builds `U V^T` with `|M - U V^T|_F <= tolerance |M|_F` (estimated), from `row(i)` and
/// `col(j)`, or `None` when the rank would reach `max_rank` (the block is then cheaper dense).
pub fn aca(
    m: usize,
    c: usize,
    row: impl Fn(usize) -> Vec<f64>,
    col: impl Fn(usize) -> Vec<f64>,
    tolerance: f64,
    max_rank: usize,
) -> Option<LowRank> {
    let mut cross = Aca::new(m, c, tolerance, max_rank);
    while let Some(request) = cross.request() {
        let values = match request {
            Request::Row(i) => row(i),
            Request::Column(j) => col(j),
        };
        cross.supply(values);
    }
    cross.finish()
}

/// What a cross approximation needs next: a row (`c` values) or a column (`m` values) of M.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Request {
    /// Row i.
    Row(usize),
    /// Column j.
    Column(usize),
}

/// [`aca`] as a state machine: it asks for one row or column at a time ([`Aca::request`]) and
/// resumes when given it ([`Aca::supply`]), so that many blocks can be approximated in lockstep,
/// their rows and columns evaluated together in one batch (the GPU's pair kernel).
#[derive(Clone, Debug)]
pub struct Aca {
    m: usize,
    c: usize,
    tolerance: f64,
    max_rank: usize,
    us: Vec<Vec<f64>>,
    vs: Vec<Vec<f64>>,
    /// |U V^T|_F², updated with every cross.
    norm2: f64,
    used_rows: Vec<bool>,
    used_cols: Vec<bool>,
    rng: rand::rngs::StdRng,
    state: State,
}

#[derive(Clone, Debug)]
enum State {
    /// The pivot row i.
    PivotRow(usize),
    /// The column of the pivot j, with the new cross's row part v.
    PivotColumn { j: usize, v: Vec<f64> },
    /// A row not used, to check the approximation before accepting it.
    CheckRow(usize),
    /// A column not used, likewise.
    CheckColumn(usize),
    /// Done: accepted, or refused at the rank limit.
    Finished { accepted: bool },
}

impl Aca {
    /// A cross approximation of an m × c block to `tolerance`, refused at rank `max_rank`.
    pub fn new(m: usize, c: usize, tolerance: f64, max_rank: usize) -> Self {
        let mut cross = Self {
            m,
            c,
            tolerance,
            max_rank,
            us: Vec::new(),
            vs: Vec::new(),
            norm2: 0.0,
            used_rows: vec![false; m],
            used_cols: vec![false; c],
            // Deterministic: the same block always gets the same approximation.
            rng: rand::rngs::StdRng::seed_from_u64((m as u64) << 32 | c as u64),
            state: State::Finished { accepted: true },
        };
        cross.start_row(0, None);
        cross
    }

    /// The row or column needed next, or `None` when finished.
    pub fn request(&self) -> Option<Request> {
        match self.state {
            State::PivotRow(i) | State::CheckRow(i) => Some(Request::Row(i)),
            State::PivotColumn { j, .. } | State::CheckColumn(j) => Some(Request::Column(j)),
            State::Finished { .. } => None,
        }
    }

    /// Gives the values of the row or column last requested.
    pub fn supply(&mut self, values: Vec<f64>) {
        match std::mem::replace(&mut self.state, State::Finished { accepted: false }) {
            State::PivotRow(i) => {
                let r = self.residual_row(i, values);
                self.pivot_row(r);
            }
            State::PivotColumn { j, v } => {
                let u = self.residual_col(j, values);
                // |S_k|_F² = |S_{k-1}|_F² + 2 Σ_l (u·u_l)(v·v_l) + |u|² |v|².
                let cross: f64 =
                    self.us.iter().zip(&self.vs).map(|(ul, vl)| dot(&u, ul) * dot(&v, vl)).sum();
                let (nu, nv) = (dot(&u, &u), dot(&v, &v));
                let grown = (self.norm2 + 2.0 * cross + nu * nv).max(0.0);
                // A cross below the tolerance is left out: it would change the block by less
                // than the tolerance (and a block of rank r keeps rank r).
                let small = (nu * nv).sqrt() <= self.tolerance * grown.sqrt();
                let next_row = argmax_abs(&u, &self.used_rows);
                if !small {
                    self.norm2 = grown;
                    self.us.push(u);
                    self.vs.push(v);
                }
                self.after_cross(small, next_row);
            }
            State::CheckRow(i) => {
                let r = self.residual_row(i, values);
                if norm(&r) * (self.m as f64).sqrt() > self.limit() {
                    self.start_row(i, Some(r));
                } else {
                    self.check_column();
                }
            }
            State::CheckColumn(j) => {
                let r = self.residual_col(j, values);
                let next_row = (norm(&r) * (self.c as f64).sqrt() > self.limit())
                    .then(|| argmax_abs(&r, &self.used_rows))
                    .flatten();
                match next_row {
                    // Restart from the row where that column's remainder is largest.
                    Some(i) => self.start_row(i, None),
                    None => self.state = State::Finished { accepted: true },
                }
            }
            State::Finished { accepted } => {
                panic!("a finished cross approximation (accepted: {accepted}) was given values")
            }
        }
    }

    /// The approximation, or `None` when it was refused at the rank limit.
    pub fn finish(self) -> Option<LowRank> {
        match self.state {
            State::Finished { accepted: true } => {}
            State::Finished { accepted: false } => return None,
            _ => panic!("cross approximation not finished"),
        }
        Some(recompressed(self.m, self.c, self.us, self.vs, RECOMPRESSION_SHARE * self.tolerance))
    }

    /// Takes row i as the next pivot row; `residual` when its remainder is known already.
    fn start_row(&mut self, i: usize, residual: Option<Vec<f64>>) {
        if self.us.len() >= self.max_rank {
            self.state = State::Finished { accepted: false };
            return;
        }
        self.used_rows[i] = true;
        match residual {
            Some(r) => self.pivot_row(r),
            None => self.state = State::PivotRow(i),
        }
    }

    /// With the remainder r of the pivot row: the pivot column, or the next row when the row is
    /// represented already (or the columns are exhausted).
    fn pivot_row(&mut self, r: Vec<f64>) {
        match argmax_abs(&r, &self.used_cols) {
            Some(j) => {
                self.used_cols[j] = true;
                let v = r.iter().map(|x| x / r[j]).collect();
                self.state = State::PivotColumn { j, v };
            }
            None => {
                let from = self.rng.random_range(0..self.m.max(1));
                let next_row = first_unused(&self.used_rows, from);
                self.after_cross(self.norm2 == 0.0 && next_row.is_none(), next_row);
            }
        }
    }

    fn after_cross(&mut self, converged: bool, next_row: Option<usize>) {
        match next_row {
            Some(i) if !converged => self.start_row(i, None),
            _ => {
                // Check a row and a column not used; the larger remainder decides.
                let from = self.rng.random_range(0..self.m.max(1));
                match first_unused(&self.used_rows, from) {
                    Some(i) => self.state = State::CheckRow(i),
                    None => self.check_column(),
                }
            }
        }
    }

    fn check_column(&mut self) {
        let from = self.rng.random_range(0..self.c.max(1));
        self.state = match first_unused(&self.used_cols, from) {
            Some(j) => State::CheckColumn(j),
            None => State::Finished { accepted: true },
        };
    }

    fn limit(&self) -> f64 {
        self.tolerance * self.norm2.sqrt()
    }

    fn residual_row(&self, i: usize, mut r: Vec<f64>) -> Vec<f64> {
        assert_eq!(r.len(), self.c, "a row of the block has {} values", self.c);
        for (u, v) in self.us.iter().zip(&self.vs) {
            r.iter_mut().zip(v).for_each(|(r, v)| *r -= u[i] * v);
        }
        r
    }

    fn residual_col(&self, j: usize, mut r: Vec<f64>) -> Vec<f64> {
        assert_eq!(r.len(), self.m, "a column of the block has {} values", self.m);
        for (u, v) in self.us.iter().zip(&self.vs) {
            r.iter_mut().zip(u).for_each(|(r, u)| *r -= v[j] * u);
        }
        r
    }
}

/// The share of the tolerance that recompression may add to a block's error: ACA's rank
/// overshoots the numerical rank (each cross is one row and one column of the remainder, not
/// its best rank-one part), and truncating the SVD of its factors at half the tolerance drops
/// the excess, so that the block meets 1.5 × the tolerance in all.
const RECOMPRESSION_SHARE: f64 = 0.5;

/// The crosses `us[l] vs[l]^T` (m and c values each) summed into one [`LowRank`], recompressed
/// (Bebendorf 2008, sec. 2.6): U = Q_u R_u and V = Q_v R_v, the SVD W S Z^T of the small core
/// R_u R_v^T, and the singular values whose tail stays within `tail` of |S|_F left out, so that
/// U = Q_u W S and V = Q_v Z with the rank that is left.
///
/// The crosses are taken, and each copy is dropped as soon as the next one exists: a block of
/// a face against a face (131 072 by 65 536 at rank 36, 57 MB of factors) would otherwise hold
/// the crosses, their matrices, their QR factors and the new factors at once.
fn recompressed(m: usize, c: usize, us: Vec<Vec<f64>>, vs: Vec<Vec<f64>>, tail: f64) -> LowRank {
    let k = us.len();
    let u = Mat::from_fn(m, k, |i, l| us[l][i]);
    drop(us);
    let v = Mat::from_fn(c, k, |j, l| vs[l][j]);
    drop(vs);
    let plain = |u: &Mat<f64>, v: &Mat<f64>| LowRank {
        m,
        c,
        k,
        u: by_rows(u, |_| 1.0),
        v: by_rows(v, |_| 1.0),
    };
    if k < 2 || m < k || c < k {
        return plain(&u, &v);
    }
    let (qr_u, qr_v) = (u.qr(), v.qr());
    let core = qr_u.thin_R() * qr_v.thin_R().transpose();
    let Ok(svd) = core.thin_svd() else { return plain(&u, &v) };
    let s = svd.S().column_vector();
    let total: f64 = (0..k).map(|l| s[l] * s[l]).sum();
    // The smallest rank whose left-out tail is within `tail`.
    let (mut rank, mut left_out) = (k, 0.0);
    while rank > 1 && left_out + s[rank - 1] * s[rank - 1] <= tail * tail * total {
        left_out += s[rank - 1] * s[rank - 1];
        rank -= 1;
    }
    if rank == k {
        drop((qr_u, qr_v));
        return plain(&u, &v);
    }
    drop((u, v));
    let u = {
        let q = qr_u.compute_thin_Q();
        drop(qr_u);
        by_rows(&(q * svd.U().subcols(0, rank)), |l| s[l])
    };
    let v = {
        let q = qr_v.compute_thin_Q();
        drop(qr_v);
        by_rows(&(q * svd.V().subcols(0, rank)), |_| 1.0)
    };
    LowRank { m, c, k: rank, u, v }
}

/// `a`'s entries row by row, column l times `scale(l)`.
fn by_rows(a: &Mat<f64>, scale: impl Fn(usize) -> f64) -> Vec<f64> {
    let rank = a.ncols();
    (0..a.nrows() * rank).map(|x| a[(x / rank, x % rank)] * scale(x % rank)).collect()
}

/// `a · b` in four interleaved partial sums, which the compiler keeps in vector registers (a
/// single running sum is a chain of dependent additions); the order of the additions is fixed,
/// so the result is the same on every run. `a` may be stored in f32 (taken to f64 as read).
pub(super) fn dot<T: Copy + Into<f64>>(a: &[T], b: &[f64]) -> f64 {
    let n = a.len().min(b.len());
    let (a4, b4) = (a[..n].chunks_exact(4), b[..n].chunks_exact(4));
    let tail: f64 = a4.remainder().iter().zip(b4.remainder()).map(|(&x, y)| x.into() * y).sum();
    let mut s = [0.0; 4];
    for (x, y) in a4.zip(b4) {
        for l in 0..4 {
            s[l] += x[l].into() * y[l];
        }
    }
    (s[0] + s[2]) + (s[1] + s[3]) + tail
}

fn norm(a: &[f64]) -> f64 {
    dot(a, a).sqrt()
}

/// Entries within this relative distance of the largest count as tied for the pivot.
const PIVOT_TIE: f64 = 1e-9;

/// Index of the largest |x_i| among those not `used`, if any is non-zero; among entries tied
/// with it (within [`PIVOT_TIE`]) the first. Symmetric meshes give many entries equal in exact
/// arithmetic, which the CPU and the GPU round differently: the first of the near-largest is the
/// same pivot for both, so their approximations agree to rounding, not just to the tolerance.
fn argmax_abs(x: &[f64], used: &[bool]) -> Option<usize> {
    let largest = x.iter().zip(used).filter(|(_, u)| !**u).fold(0.0f64, |m, (v, _)| m.max(v.abs()));
    if largest == 0.0 {
        return None;
    }
    let threshold = largest * (1.0 - PIVOT_TIE);
    x.iter().zip(used).position(|(v, u)| !u && v.abs() >= threshold)
}

/// The first index at or after `from` (cyclically) not `used`.
fn first_unused(used: &[bool], from: usize) -> Option<usize> {
    let n = used.len();
    (0..n).map(|d| (from + d) % n).find(|&i| !used[i])
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A block of exact rank `r`: sum of r separable terms.
    fn rank_r(m: usize, c: usize, r: usize) -> impl Fn(usize, usize) -> f64 {
        move |i, j| {
            (0..r)
                .map(|l| {
                    let x = (i as f64 + 0.5) / m as f64;
                    let y = (j as f64 + 0.3) / c as f64;
                    (1.0 + l as f64) * x.powi(l as i32) * (1.0 - y).powi(2 * l as i32 + 1)
                })
                .sum()
        }
    }

    #[test]
    fn a_block_of_known_rank_compresses_to_that_rank_exactly() {
        for r in [1, 3, 5] {
            let (m, c) = (40, 60);
            let f = rank_r(m, c, r);
            let lr = aca(
                m,
                c,
                |i| (0..c).map(|j| f(i, j)).collect(),
                |j| (0..m).map(|i| f(i, j)).collect(),
                1e-12,
                30,
            )
            .expect("compressible");
            assert_eq!(lr.k, r, "rank {r}");
            let worst = (0..m)
                .flat_map(|i| (0..c).map(move |j| (i, j)))
                .map(|(i, j)| (lr.get(i, j) - f(i, j)).abs())
                .fold(0.0, f64::max);
            assert!(worst < 1e-12, "rank {r}: {worst}");
        }
    }

    #[test]
    fn a_smooth_kernel_meets_the_tolerance_and_a_block_without_structure_is_refused() {
        // 1/|x - y|² between two separated clusters of points on a line.
        let (m, c) = (50, 70);
        let f = |i: usize, j: usize| {
            let x = i as f64 / m as f64;
            let y = 3.0 + j as f64 / c as f64;
            1.0 / ((x - y) * (x - y))
        };
        for tol in [1e-4, 1e-8, 1e-12] {
            let lr = aca(
                m,
                c,
                |i| (0..c).map(|j| f(i, j)).collect(),
                |j| (0..m).map(|i| f(i, j)).collect(),
                tol,
                40,
            )
            .expect("smooth");
            let (mut err, mut norm) = (0.0, 0.0);
            for i in 0..m {
                for j in 0..c {
                    err += (lr.get(i, j) - f(i, j)).powi(2);
                    norm += f(i, j).powi(2);
                }
            }
            assert!((err / norm).sqrt() <= tol, "tol {tol}: {}", (err / norm).sqrt());
            assert!(lr.k < 15, "tol {tol}: rank {}", lr.k);
        }
        // The identity has full rank: refused at the rank limit.
        let id = |i: usize, j: usize| if i == j { 1.0 } else { 0.0 };
        let refused = aca(
            20,
            20,
            |i| (0..20).map(|j| id(i, j)).collect(),
            |j| (0..20).map(|i| id(i, j)).collect(),
            1e-6,
            10,
        );
        assert!(refused.is_none());
    }

    #[test]
    fn recompression_keeps_the_rank_the_crosses_span_and_their_product() {
        let (m, c) = (30, 20);
        let wave = |n: usize, f: f64, g: f64| -> Vec<f64> {
            (0..n).map(|i| (f * i as f64 + g).sin()).collect()
        };
        let mix = |a: &[f64], b: &[f64], x: f64, y: f64| -> Vec<f64> {
            a.iter().zip(b).map(|(a, b)| x * a + y * b).collect()
        };
        let (a, b) = (wave(m, 0.3, 0.1), wave(m, 0.7, 1.0));
        let (p, q) = (wave(c, 0.2, 0.5), wave(c, 1.1, 0.2));
        // Four crosses in two directions on each side: rank 2.
        let us = vec![a.clone(), b.clone(), mix(&a, &b, 1.0, 1.0), mix(&a, &b, 1.0, -2.0)];
        let vs = vec![p.clone(), q.clone(), mix(&p, &q, 1.0, -1.0), mix(&p, &q, 2.0, 1.0)];
        let product = |i: usize, j: usize| -> f64 { (0..4).map(|l| us[l][i] * vs[l][j]).sum() };
        let lr = recompressed(m, c, us.clone(), vs.clone(), 1e-12);
        assert_eq!(lr.k, 2);
        let scale = (0..m).flat_map(|i| (0..c).map(move |j| (i, j)));
        let largest = scale.clone().map(|(i, j)| product(i, j).abs()).fold(0.0, f64::max);
        let worst = scale.map(|(i, j)| (lr.get(i, j) - product(i, j)).abs()).fold(0.0, f64::max);
        assert!(worst <= 1e-13 * largest, "{worst} of {largest}");
        // Independent crosses keep their rank.
        let independent = recompressed(m, c, us[..2].to_vec(), vs[..2].to_vec(), 1e-12);
        assert_eq!(independent.k, 2);
    }
}
