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
        for (i, yi) in y.iter_mut().enumerate() {
            let row = &self.u[i * self.k..(i + 1) * self.k];
            *yi += row.iter().zip(&t).map(|(u, t)| u * t).sum::<f64>();
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
    let mut us: Vec<Vec<f64>> = Vec::new();
    let mut vs: Vec<Vec<f64>> = Vec::new();
    let mut norm2 = 0.0f64;
    let mut used_rows = vec![false; m];
    let mut used_cols = vec![false; c];
    // Deterministic: the same block always gets the same approximation.
    let mut rng = rand::rngs::StdRng::seed_from_u64((m as u64) << 32 | c as u64);
    let residual_row = |i: usize, us: &[Vec<f64>], vs: &[Vec<f64>]| {
        let mut r = row(i);
        for (u, v) in us.iter().zip(vs) {
            r.iter_mut().zip(v).for_each(|(r, v)| *r -= u[i] * v);
        }
        r
    };
    let residual_col = |j: usize, us: &[Vec<f64>], vs: &[Vec<f64>]| {
        let mut r = col(j);
        for (u, v) in us.iter().zip(vs) {
            r.iter_mut().zip(u).for_each(|(r, u)| *r -= v[j] * u);
        }
        r
    };
    let mut next_row = Some(0);
    let mut pending: Option<Vec<f64>> = None;
    while let Some(i) = next_row {
        if us.len() >= max_rank {
            return None;
        }
        used_rows[i] = true;
        let r = pending.take().unwrap_or_else(|| residual_row(i, &us, &vs));
        let pivot = argmax_abs(&r, &used_cols);
        let converged = match pivot {
            Some(j) if r[j] != 0.0 => {
                used_cols[j] = true;
                let v: Vec<f64> = r.iter().map(|x| x / r[j]).collect();
                let u = residual_col(j, &us, &vs);
                // |S_k|_F² = |S_{k-1}|_F² + 2 Σ_l (u·u_l)(v·v_l) + |u|² |v|².
                let cross: f64 = us.iter().zip(&vs).map(|(ul, vl)| dot(&u, ul) * dot(&v, vl)).sum();
                let (nu, nv) = (dot(&u, &u), dot(&v, &v));
                let grown = (norm2 + 2.0 * cross + nu * nv).max(0.0);
                // A cross below the tolerance is left out: it would change the block by less
                // than the tolerance (and a block of rank r keeps rank r).
                let small = (nu * nv).sqrt() <= tolerance * grown.sqrt();
                next_row = argmax_abs(&u, &used_rows);
                if !small {
                    norm2 = grown;
                    us.push(u);
                    vs.push(v);
                }
                small
            }
            // The row is represented already (or the columns are exhausted).
            _ => {
                next_row = first_unused(&used_rows, rng.random_range(0..m.max(1)));
                norm2 == 0.0 && next_row.is_none()
            }
        };
        if converged || next_row.is_none() {
            // Check a row and a column not used; the larger remainder decides.
            let limit = tolerance * norm2.sqrt();
            let check_row = first_unused(&used_rows, rng.random_range(0..m.max(1)));
            if let Some(ci) = check_row {
                let r = residual_row(ci, &us, &vs);
                if norm(&r) * (m as f64).sqrt() > limit {
                    next_row = Some(ci);
                    pending = Some(r);
                    continue;
                }
            }
            let check_col = first_unused(&used_cols, rng.random_range(0..c.max(1)));
            if let Some(cj) = check_col {
                let r = residual_col(cj, &us, &vs);
                if norm(&r) * (c as f64).sqrt() > limit {
                    // Restart from the row where that column's remainder is largest.
                    next_row = argmax_abs(&r, &used_rows);
                    if next_row.is_some() {
                        continue;
                    }
                }
            }
            break;
        }
    }
    let k = us.len();
    let mut u = vec![0.0; m * k];
    let mut v = vec![0.0; c * k];
    for l in 0..k {
        (0..m).for_each(|i| u[i * k + l] = us[l][i]);
        (0..c).for_each(|j| v[j * k + l] = vs[l][j]);
    }
    Some(LowRank { m, c, k, u, v })
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

fn norm(a: &[f64]) -> f64 {
    dot(a, a).sqrt()
}

/// Index of the largest |x_i| among those not `used`, if any is non-zero.
fn argmax_abs(x: &[f64], used: &[bool]) -> Option<usize> {
    let mut best: Option<(usize, f64)> = None;
    for (i, (&v, &u)) in x.iter().zip(used).enumerate() {
        if !u && v != 0.0 && best.is_none_or(|(_, b)| v.abs() > b) {
            best = Some((i, v.abs()));
        }
    }
    best.map(|(i, _)| i)
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
}
