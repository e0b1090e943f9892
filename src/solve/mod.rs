//! Solving (I - K) u = E with faer: LU with partial pivoting (faer's high-level API).

use faer::prelude::*;

use crate::assembly::CollocationMatrix;
use crate::error::{Error, Result};

/// Solves `(I - K) u = rhs` by LU with partial pivoting.
pub fn solve_lu(k: &CollocationMatrix, rhs: &[f64]) -> Result<Vec<f64>> {
    let a = k.system_matrix();
    let lu = a.partial_piv_lu();
    let b = Col::from_fn(rhs.len(), |i| rhs[i]);
    let x = lu.solve(&b);
    let u: Vec<f64> = (0..x.nrows()).map(|i| x[i]).collect();
    if u.iter().any(|v| !v.is_finite()) {
        return Err(Error::SingularSystem {
            condition: f64::INFINITY,
        });
    }
    Ok(u)
}

/// Relative residual `||(I - K) u - rhs||_∞ / ||rhs||_∞`.
pub fn relative_residual(k: &CollocationMatrix, u: &[f64], rhs: &[f64]) -> f64 {
    let ku = k.apply(u);
    let r = ku
        .iter()
        .zip(u)
        .zip(rhs)
        .map(|((kv, uv), b)| (uv - kv - b).abs())
        .fold(0.0, f64::max);
    let nb = rhs.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    r / nb.max(f64::MIN_POSITIVE)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lu_solves_a_small_system_to_rounding() {
        // K with rows summing below 1, like a radiosity operator.
        let n = 5;
        let data: Vec<f64> = (0..n * n)
            .map(|k| {
                if k % (n + 1) == 0 {
                    0.0
                } else {
                    0.1 + 0.01 * k as f64
                }
            })
            .collect();
        let k = CollocationMatrix::from_rows(n, data);
        let rhs: Vec<f64> = (0..n).map(|i| 1.0 + i as f64).collect();
        let u = solve_lu(&k, &rhs).unwrap();
        assert!(relative_residual(&k, &u, &rhs) < 1e-14);
    }
}
