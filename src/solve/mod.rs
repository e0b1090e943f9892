//! Solving (I - K) u = E with faer: LU with partial pivoting for moderate sizes, BiCGSTAB (faer's,
//! over K applied row by row, so the matrix is never copied) for large ones. ||K|| < 1 for open
//! surfaces with rho < 1 (paper (2.17)), so the iteration converges in few steps.

use faer::dyn_stack::{MemBuffer, MemStack, StackReq};
use faer::matrix_free::{
    InitialGuessStatus, LinOp,
    bicgstab::{BicgParams, bicgstab, bicgstab_scratch},
};
use faer::prelude::*;
use faer::{MatMut, MatRef, Par};
use serde::Serialize;

use crate::assembly::CollocationMatrix;
use crate::error::{Error, Result};

/// Which solver to use.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum SolverChoice {
    /// LU up to [`LU_LIMIT`] unknowns, BiCGSTAB beyond.
    #[default]
    Auto,
    /// Dense LU with partial pivoting.
    Lu,
    /// BiCGSTAB.
    Iterative,
}

/// Largest system solved by LU under [`SolverChoice::Auto`]: LU costs (2/3) n³ flops and a second
/// dense copy of the matrix.
pub const LU_LIMIT: usize = 6000;

/// A solution and how it was found.
#[derive(Clone, Debug, Serialize)]
pub struct SolveOutcome {
    /// Nodal values.
    #[serde(skip)]
    pub u: Vec<f64>,
    /// `lu` or `bicgstab`.
    pub solver: &'static str,
    /// Iterations (0 for LU).
    pub iterations: usize,
    /// Relative residual `||(I - K) u - E||_∞ / ||E||_∞`.
    pub residual: f64,
}

/// Solves `(I - K) u = rhs`.
pub fn solve(k: &CollocationMatrix, rhs: &[f64], choice: SolverChoice) -> Result<SolveOutcome> {
    let use_lu = match choice {
        SolverChoice::Lu => true,
        SolverChoice::Iterative => false,
        SolverChoice::Auto => k.dof() <= LU_LIMIT,
    };
    let (u, solver, iterations) = if use_lu {
        (solve_lu(k, rhs)?, "lu", 0)
    } else {
        let (u, iterations) = solve_bicgstab(k, rhs)?;
        (u, "bicgstab", iterations)
    };
    let residual = relative_residual(k, &u, rhs);
    clear_upper_vector_state();
    Ok(SolveOutcome { u, solver, iterations, residual })
}

/// faer's AVX-512 kernels can leave the upper halves of the vector registers dirty on the threads
/// that ran them, and plain (SSE-encoded) code on those threads then pays a transition penalty on
/// every vector instruction: on the AMD EPYC machines we measured, the linear n = 640 assembly
/// after a small solve took 0.55 s instead of 0.18 s. `vzeroupper` on every worker thread and on
/// this one restores the speed.
fn clear_upper_vector_state() {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx") {
        #[target_feature(enable = "avx")]
        fn zero_upper() {
            std::arch::x86_64::_mm256_zeroupper();
        }
        // SAFETY: AVX was detected at run time just above.
        let clear = || unsafe { zero_upper() };
        rayon::broadcast(|_| clear());
        clear();
    }
}

/// Solves `(I - K) u = rhs` by LU with partial pivoting.
pub fn solve_lu(k: &CollocationMatrix, rhs: &[f64]) -> Result<Vec<f64>> {
    let a = k.system_matrix();
    let lu = a.partial_piv_lu();
    let b = Col::from_fn(rhs.len(), |i| rhs[i]);
    let x = lu.solve(&b);
    let u: Vec<f64> = (0..x.nrows()).map(|i| x[i]).collect();
    if u.iter().any(|v| !v.is_finite()) {
        return Err(Error::SingularSystem { condition: f64::INFINITY });
    }
    Ok(u)
}

/// `I - K` as a faer operator.
#[derive(Debug)]
struct SystemOperator<'a>(&'a CollocationMatrix);

impl LinOp<f64> for SystemOperator<'_> {
    fn apply_scratch(&self, _rhs_ncols: usize, _par: Par) -> StackReq {
        StackReq::EMPTY
    }
    fn nrows(&self) -> usize {
        self.0.dof()
    }
    fn ncols(&self) -> usize {
        self.0.dof()
    }
    fn apply(
        &self,
        mut out: MatMut<'_, f64>,
        rhs: MatRef<'_, f64>,
        _par: Par,
        _stack: &mut MemStack,
    ) {
        for c in 0..rhs.ncols() {
            let x: Vec<f64> = (0..rhs.nrows()).map(|i| rhs[(i, c)]).collect();
            let kx = self.0.apply(&x);
            for i in 0..x.len() {
                out[(i, c)] = x[i] - kx[i];
            }
        }
    }
    fn conj_apply(
        &self,
        out: MatMut<'_, f64>,
        rhs: MatRef<'_, f64>,
        par: Par,
        stack: &mut MemStack,
    ) {
        self.apply(out, rhs, par, stack)
    }
}

/// Most BiCGSTAB iterations before giving up.
const MAX_ITERATIONS: usize = 1000;

fn solve_bicgstab(k: &CollocationMatrix, rhs: &[f64]) -> Result<(Vec<f64>, usize)> {
    let n = k.dof();
    let op = SystemOperator(k);
    let identity = faer::matrix_free::IdentityPrecond { dim: n };
    let par = Par::Seq;
    let mut buffer = MemBuffer::new(bicgstab_scratch(identity, identity, &op, 1, par));
    let stack = MemStack::new(&mut buffer);
    let b = Mat::from_fn(n, 1, |i, _| rhs[i]);
    let mut x = Mat::<f64>::zeros(n, 1);
    // faer 0.24's bicgstab forms r = b - A x only for `MaybeNonZero` and leaves r uninitialised for
    // `Zero`, so the zero start vector is passed as "maybe non-zero".
    let params = BicgParams {
        initial_guess: InitialGuessStatus::MaybeNonZero,
        abs_tolerance: 0.0,
        rel_tolerance: 1e-14,
        max_iters: MAX_ITERATIONS,
        ..Default::default()
    };
    let result =
        bicgstab(x.as_mut(), identity, identity, &op, b.as_ref(), params, |_| {}, par, stack);
    match result {
        Ok(info) => Ok(((0..n).map(|i| x[(i, 0)]).collect(), info.iter_count)),
        Err(faer::matrix_free::bicgstab::BicgError::NoConvergence { rel_residual, .. }) => {
            Err(Error::NotConverged { residual: rel_residual, iterations: MAX_ITERATIONS })
        }
    }
}

/// Relative residual `||(I - K) u - rhs||_∞ / ||rhs||_∞`.
pub fn relative_residual(k: &CollocationMatrix, u: &[f64], rhs: &[f64]) -> f64 {
    let ku = k.apply(u);
    let r = ku.iter().zip(u).zip(rhs).map(|((kv, uv), b)| (uv - kv - b).abs()).fold(0.0, f64::max);
    let nb = rhs.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    r / nb.max(f64::MIN_POSITIVE)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn radiosity_like(n: usize) -> CollocationMatrix {
        let data: Vec<f64> = (0..n * n)
            .map(|k| {
                if k % (n + 1) == 0 {
                    0.0
                } else {
                    0.6 / (n as f64) * (1.0 + ((k * 7) % 5) as f64 * 0.1)
                }
            })
            .collect();
        CollocationMatrix::from_rows(n, data)
    }

    #[test]
    fn lu_and_bicgstab_agree_and_have_small_residuals() {
        for n in [1, 2, 3, 17, 64, 255, 256, 257] {
            let k = radiosity_like(n);
            let norm_k =
                (0..n).map(|i| k.row(i).iter().map(|v| v.abs()).sum::<f64>()).fold(0.0, f64::max);
            assert!(norm_k < 1.0);
            // ||(I - K)^-1||_inf <= 1/(1 - ||K||): LU's backward error is a modest multiple of
            // n eps, so its residual stays below 16 n eps / (1 - ||K||); BiCGSTAB stops at
            // ||r||_2 <= 1e-14 ||b||_2, so ||r||_inf <= 1e-14 sqrt(n) ||b||_inf.
            let lu_bound = 16.0 * n as f64 * f64::EPSILON / (1.0 - norm_k);
            let it_bound = 1e-14 * (n as f64).sqrt() + lu_bound;
            let rhs: Vec<f64> = (0..n).map(|i| 1.0 + i as f64).collect();
            let lu = solve(&k, &rhs, SolverChoice::Lu).unwrap();
            let it = solve(&k, &rhs, SolverChoice::Iterative).unwrap();
            assert!(lu.residual < lu_bound, "n {n}: LU residual {:e} > {lu_bound:e}", lu.residual);
            assert!(
                it.residual < it_bound,
                "n {n}: BiCGSTAB residual {:e} > {it_bound:e}",
                it.residual
            );
            let scale = lu.u.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            for (a, b) in lu.u.iter().zip(&it.u) {
                assert!((a - b).abs() < (it_bound + lu_bound) / (1.0 - norm_k) * scale);
            }
        }
    }
}
