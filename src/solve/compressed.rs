//! Solving `(I - K) u = E` with K the compressed operator ([`crate::operator`]): GMRES on
//! products alone, since no matrix is there to factor.

use super::gmres::{self, KrylovSystem};
use super::{
    CLOSED_ROW_TOLERANCE, SolveOutcome, SolverOptions, check_tolerance, reject_unit_row_sums,
};
use crate::error::Result;
use crate::operator::CompressedOperator;

/// `I - diag(s) K` with K compressed (s = 1 but for a colour band's rows).
struct CompressedSystem<'a> {
    k: &'a CompressedOperator,
    row_scale: Option<Vec<f64>>,
}

impl KrylovSystem for CompressedSystem<'_> {
    fn dim(&self) -> usize {
        self.k.dof()
    }

    fn apply(&self, x: &[f64]) -> Vec<f64> {
        let mut kx = self.k.apply(x);
        if let Some(scale) = &self.row_scale {
            kx.iter_mut().zip(scale).for_each(|(v, s)| *v *= s);
        }
        x.iter().zip(kx).map(|(a, b)| a - b).collect()
    }

    /// In plain arithmetic: the compression's tolerance is far above its rounding.
    fn residual(&self, x: &[f64], b: &[f64]) -> Vec<f64> {
        self.apply(x).iter().zip(b).map(|(ax, bi)| bi - ax).collect()
    }
}

/// Solves `(I - K) u = rhs` by GMRES to `options.tolerance`, which must not be below what the
/// compression keeps (the products are exact only to `compression_tolerance`). `rho` is each
/// node's reflectivity, that of the operator's rows or, for a colour band, the band's: the
/// rows are then scaled by it over `operator_rho` (K holds rho/π per row; rho = 0 only where
/// every band's is), as the dense path scales its matrix. Nodes that reflect nothing get u = E
/// exactly. A closed surface with rho = 1 everywhere is refused as singular, as by
/// [`super::solve`].
pub fn solve_compressed(
    k: &CompressedOperator,
    rhs: &[f64],
    (rho, operator_rho): (&[f64], &[f64]),
    options: SolverOptions,
    compression_tolerance: f64,
) -> Result<SolveOutcome> {
    check_tolerance(options.tolerance)?;
    let row_scale = (rho != operator_rho).then(|| {
        rho.iter().zip(operator_rho).map(|(&b, &g)| if g == 0.0 { 0.0 } else { b / g }).collect()
    });
    let sys = CompressedSystem { k, row_scale };
    if !rho.is_empty() && rho.iter().all(|&r| r == 1.0) {
        let ones = vec![1.0; k.dof()];
        let mut sums = k.apply(&ones);
        if let Some(scale) = &sys.row_scale {
            sums.iter_mut().zip(scale).for_each(|(v, s)| *v *= s);
        }
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
