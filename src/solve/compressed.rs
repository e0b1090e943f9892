//! Solving `(I - K) u = E` with K the compressed operator ([`crate::operator`]): GMRES on
//! products alone, since no matrix is there to factor.

use super::gmres::{self, KrylovSystem};
use super::{
    CLOSED_ROW_TOLERANCE, SolveOutcome, SolverOptions, check_tolerance, reject_unit_row_sums,
};
use crate::error::Result;
use crate::operator::CompressedOperator;

/// `I - K` with K compressed.
struct CompressedSystem<'a> {
    k: &'a CompressedOperator,
}

impl KrylovSystem for CompressedSystem<'_> {
    fn dim(&self) -> usize {
        self.k.dof()
    }

    fn apply(&self, x: &[f64]) -> Vec<f64> {
        let kx = self.k.apply(x);
        x.iter().zip(kx).map(|(a, b)| a - b).collect()
    }

    /// In plain arithmetic: the compression's tolerance is far above its rounding.
    fn residual(&self, x: &[f64], b: &[f64]) -> Vec<f64> {
        self.apply(x).iter().zip(b).map(|(ax, bi)| bi - ax).collect()
    }
}

/// Solves `(I - K) u = rhs` by GMRES to `options.tolerance`, which must not be below what the
/// compression keeps (the products are exact only to `compression_tolerance`). Nodes that
/// reflect nothing get u = E exactly. A closed surface with rho = 1 everywhere is refused as
/// singular, as by [`super::solve`].
pub fn solve_compressed(
    k: &CompressedOperator,
    rhs: &[f64],
    rho: &[f64],
    options: SolverOptions,
    compression_tolerance: f64,
) -> Result<SolveOutcome> {
    check_tolerance(options.tolerance)?;
    let sys = CompressedSystem { k };
    if !rho.is_empty() && rho.iter().all(|&r| r == 1.0) {
        let ones = vec![1.0; k.dof()];
        let sums = k.apply(&ones);
        reject_unit_row_sums(&sums, CLOSED_ROW_TOLERANCE.max(10.0 * compression_tolerance))?;
    }
    let g = gmres::gmres(&sys, rhs, options.tolerance)?;
    let mut u = g.x;
    let mut fixed = 0;
    for ((ui, &r), &e) in u.iter_mut().zip(rho).zip(rhs) {
        if r == 0.0 {
            *ui = e;
            fixed += 1;
        }
    }
    let r = sys.residual(&u, rhs);
    let scale = rhs.iter().fold(0.0f64, |m, v| m.max(v.abs())).max(f64::MIN_POSITIVE);
    Ok(SolveOutcome {
        residual: r.iter().fold(0.0f64, |m, v| m.max(v.abs())) / scale,
        u,
        solver: "gmres",
        iterations: g.iterations,
        condition_estimate: None,
        refinement_steps: 0,
        rows_eliminated: fixed,
    })
}
