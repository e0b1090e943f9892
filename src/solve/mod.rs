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
    /// Estimated 1-norm condition number of I - K (LU only).
    pub condition_estimate: Option<f64>,
    /// Steps of iterative refinement with a compensated residual (LU only).
    pub refinement_steps: usize,
}

/// Largest estimated condition number accepted: beyond it fewer than two digits of the solution
/// could be trusted (κ ε > 1e-2), so the system is reported as singular instead.
pub const CONDITION_LIMIT: f64 = 1e-2 / f64::EPSILON;

/// Solves `(I - K) u = rhs`. A closed surface with rho = 1 everywhere (every row of K sums to 1,
/// so I - K annihilates constants) and, for LU, an estimated condition number above
/// [`CONDITION_LIMIT`] are reported as [`Error::SingularSystem`].
pub fn solve(k: &CollocationMatrix, rhs: &[f64], choice: SolverChoice) -> Result<SolveOutcome> {
    reject_constant_null_vector(k)?;
    let use_lu = match choice {
        SolverChoice::Lu => true,
        SolverChoice::Iterative => false,
        SolverChoice::Auto => k.dof() <= LU_LIMIT,
    };
    let outcome = if use_lu {
        let lu = LuSolution::new(k, rhs, REFINEMENT_STEPS)?;
        SolveOutcome {
            residual: relative_residual(k, &lu.u, rhs),
            u: lu.u,
            solver: "lu",
            iterations: 0,
            condition_estimate: Some(lu.condition),
            refinement_steps: lu.refinement_steps,
        }
    } else {
        let (u, iterations) = solve_bicgstab(k, rhs)?;
        SolveOutcome {
            residual: relative_residual(k, &u, rhs),
            u,
            solver: "bicgstab",
            iterations,
            condition_estimate: None,
            refinement_steps: 0,
        }
    };
    clear_upper_vector_state();
    Ok(outcome)
}

/// How far a row sum of K may be from 1 for the row to count as "closed with rho = 1".
const CLOSED_ROW_TOLERANCE: f64 = 1e-10;

/// Lemma 2.1: inside a closed surface every row of K/rho sums to 1, so with rho = 1 everywhere
/// (I - K) 1 = 0 and the system is singular; caught here before any factorisation, for both solvers.
fn reject_constant_null_vector(k: &CollocationMatrix) -> Result<()> {
    let n = k.dof();
    let closed =
        n > 0 && (0..n).all(|i| (k.row(i).iter().sum::<f64>() - 1.0).abs() <= CLOSED_ROW_TOLERANCE);
    if closed {
        return Err(Error::SingularSystem {
            condition: f64::INFINITY,
            reason: "every row of K sums to 1, so I - K maps constants to 0".into(),
        });
    }
    Ok(())
}

/// Most refinement steps [`solve`] takes.
pub const REFINEMENT_STEPS: usize = 3;

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

/// An LU solution of `(I - K) u = rhs` with its condition estimate.
#[derive(Clone, Debug)]
pub struct LuSolution {
    /// The solution.
    pub u: Vec<f64>,
    /// Estimated 1-norm condition number of I - K.
    pub condition: f64,
    /// Refinement steps taken.
    pub refinement_steps: usize,
}

impl LuSolution {
    /// LU with partial pivoting, the condition estimate (Hager–Higham), then up to `max_steps`
    /// steps of iterative refinement whose residual is computed with compensated dot products
    /// (Ogita–Rump–Oishi Dot2), so that refinement gains digits beyond plain f64 and the forward
    /// error approaches ε instead of κ ε. Fails with [`Error::SingularSystem`] above
    /// [`CONDITION_LIMIT`].
    pub fn new(k: &CollocationMatrix, rhs: &[f64], max_steps: usize) -> Result<Self> {
        let a = k.system_matrix();
        let lu = a.partial_piv_lu();
        let n = rhs.len();
        let solve = |b: &[f64], transpose: bool| -> Vec<f64> {
            let b = Col::from_fn(n, |i| b[i]);
            let x = if transpose { lu.solve_transpose(&b) } else { lu.solve(&b) };
            (0..n).map(|i| x[i]).collect()
        };
        let norm_a =
            (0..n).map(|j| (0..n).map(|i| a[(i, j)].abs()).sum::<f64>()).fold(0.0, f64::max);
        let condition = norm_a * inverse_norm_1_estimate(n, &solve);
        if condition.is_nan() || condition > CONDITION_LIMIT {
            return Err(Error::SingularSystem {
                condition,
                reason: format!("LU condition estimate above {CONDITION_LIMIT:.1e}"),
            });
        }
        let mut u = solve(rhs, false);
        let mut refinement_steps = 0;
        for _ in 0..max_steps {
            let r = compensated_residual(k, &u, rhs);
            let d = solve(&r, false);
            let (dn, un) = (max_abs(&d), max_abs(&u));
            u.iter_mut().zip(&d).for_each(|(x, dx)| *x += dx);
            refinement_steps += 1;
            if dn <= f64::EPSILON * un {
                break;
            }
        }
        if u.iter().any(|v| !v.is_finite()) {
            return Err(Error::SingularSystem {
                condition: f64::INFINITY,
                reason: "the LU solution is not finite".into(),
            });
        }
        Ok(Self { u, condition, refinement_steps })
    }
}

/// Solves `(I - K) u = rhs` by LU with partial pivoting (no refinement); see [`LuSolution`].
pub fn solve_lu(k: &CollocationMatrix, rhs: &[f64]) -> Result<Vec<f64>> {
    Ok(LuSolution::new(k, rhs, 0)?.u)
}

fn max_abs(v: &[f64]) -> f64 {
    v.iter().fold(0.0f64, |m, x| m.max(x.abs()))
}

/// Estimate of `||A⁻¹||₁` from solves with A and Aᵀ (Hager 1984 with Higham's 1988 safeguards:
/// at most five sign vectors, and the alternating test vector whose estimate catches the cases
/// Hager's iteration misses). A lower bound, usually within a factor 3 of the truth.
pub fn inverse_norm_1_estimate(n: usize, solve: &dyn Fn(&[f64], bool) -> Vec<f64>) -> f64 {
    if n == 0 {
        return 0.0;
    }
    let mut x = vec![1.0 / n as f64; n];
    let mut estimate = 0.0f64;
    let mut last_j = usize::MAX;
    for _ in 0..5 {
        let y = solve(&x, false);
        let norm_y: f64 = y.iter().map(|v| v.abs()).sum();
        if !norm_y.is_finite() {
            return f64::INFINITY;
        }
        if norm_y <= estimate {
            break;
        }
        estimate = norm_y;
        let signs: Vec<f64> = y.iter().map(|v| if *v >= 0.0 { 1.0 } else { -1.0 }).collect();
        let z = solve(&signs, true);
        let (j, zmax) = z.iter().enumerate().fold((0, 0.0f64), |(bj, bm), (j, v)| {
            if v.abs() > bm { (j, v.abs()) } else { (bj, bm) }
        });
        let ztx: f64 = z.iter().zip(&x).map(|(a, b)| a * b).sum();
        if zmax <= ztx || j == last_j {
            break;
        }
        last_j = j;
        x = vec![0.0; n];
        x[j] = 1.0;
    }
    let alternating: Vec<f64> = (0..n)
        .map(|i| {
            let s = if i % 2 == 0 { 1.0 } else { -1.0 };
            s * (1.0 + i as f64 / (n.max(2) - 1) as f64)
        })
        .collect();
    let y = solve(&alternating, false);
    let alt = 2.0 * y.iter().map(|v| v.abs()).sum::<f64>() / (3.0 * n as f64);
    estimate.max(alt)
}

/// `rhs - (I - K) u`, each entry a compensated dot product (error-free TwoSum/TwoProduct
/// accumulation), i.e. as if computed in twice the working precision and rounded once.
pub fn compensated_residual(k: &CollocationMatrix, u: &[f64], rhs: &[f64]) -> Vec<f64> {
    use rayon::prelude::*;
    (0..u.len())
        .into_par_iter()
        .map(|i| {
            let (mut s, mut c) = two_sum(rhs[i], -u[i]);
            for (kij, uj) in k.row(i).iter().zip(u) {
                let p = kij * uj;
                let pe = kij.mul_add(*uj, -p);
                let (t, e) = two_sum(s, p);
                s = t;
                c += e + pe;
            }
            s + c
        })
        .collect()
}

/// Knuth's error-free sum: `a + b = s + e` exactly.
fn two_sum(a: f64, b: f64) -> (f64, f64) {
    let s = a + b;
    let bb = s - a;
    (s, (a - (s - bb)) + (b - bb))
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

    /// K = rho J / n with J all ones off the diagonal, scaled per row to sum to rho: a closed
    /// "enclosure" whose I - K has the eigenvalue 1 - rho on constants.
    fn enclosure(n: usize, rho: f64) -> CollocationMatrix {
        let data =
            (0..n * n).map(|k| if k % (n + 1) == 0 { 0.0 } else { rho / (n - 1) as f64 }).collect();
        CollocationMatrix::from_rows(n, data)
    }

    #[test]
    fn the_condition_estimate_matches_the_exact_1_norm_condition() {
        for (n, rho) in [(5, 0.9), (40, 0.999), (64, 0.5)] {
            let k = enclosure(n, rho);
            let a = k.system_matrix();
            // Exact: ||A||_1 ||A^-1||_1 from the explicit inverse.
            let inv = a.partial_piv_lu().solve(Mat::<f64>::identity(n, n));
            let norm1 = |m: &Mat<f64>| {
                (0..n).map(|j| (0..n).map(|i| m[(i, j)].abs()).sum::<f64>()).fold(0.0, f64::max)
            };
            let exact = norm1(&a) * norm1(&inv);
            let s = LuSolution::new(&k, &vec![1.0; n], 0).unwrap();
            assert!(
                s.condition <= exact * (1.0 + 1e-12) && s.condition >= exact / 3.0,
                "n {n}, rho {rho}: estimate {} vs exact {exact}",
                s.condition
            );
        }
    }

    #[test]
    fn a_closed_enclosure_with_rho_1_is_refused_by_both_solvers() {
        let k = enclosure(30, 1.0);
        for choice in [SolverChoice::Lu, SolverChoice::Iterative, SolverChoice::Auto] {
            match solve(&k, &vec![1.0; 30], choice) {
                Err(Error::SingularSystem { condition, .. }) => assert!(condition.is_infinite()),
                other => panic!("{choice:?}: expected a singular system, got {other:?}"),
            }
        }
        // Just below 1, LU alone refuses past the condition limit.
        let k = enclosure(30, 1.0 - 1e-15);
        assert!(matches!(
            LuSolution::new(&k, &vec![1.0; 30], 0),
            Err(Error::SingularSystem { .. })
        ));
    }

    #[test]
    fn compensated_residuals_make_refinement_recover_the_digits_lu_loses() {
        // rho = 1 - 2^-30: condition ~ 4e9, and plain LU loses about 9 digits. With 65 nodes,
        // entries (1 - 2^-30)/64 and an integer solution, the right-hand side is exact, so
        // refinement with compensated residuals must recover nearly all of them.
        let n = 65;
        let k = enclosure(n, 1.0 - 2f64.powi(-30));
        let exact: Vec<f64> = (0..n).map(|i| ((i * 37) % 11) as f64 - 5.0).collect();
        let rhs: Vec<f64> =
            compensated_residual(&k, &exact, &vec![0.0; n]).iter().map(|v| -v).collect();
        let err =
            |u: &[f64]| u.iter().zip(&exact).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max) / 5.0;
        let plain = LuSolution::new(&k, &rhs, 0).unwrap();
        let refined = LuSolution::new(&k, &rhs, REFINEMENT_STEPS).unwrap();
        assert!(refined.refinement_steps >= 1);
        assert!(err(&refined.u) < 1e-14, "refined error {}", err(&refined.u));
        assert!(
            err(&plain.u) > 100.0 * err(&refined.u),
            "{} vs {}",
            err(&plain.u),
            err(&refined.u)
        );
    }

    #[test]
    fn the_compensated_residual_is_exact_where_plain_arithmetic_cancels() {
        // rhs - (I - K) u with terms of size 1e16 that cancel to 1.
        let k = CollocationMatrix::from_rows(2, vec![0.0, 1.0, 0.0, 0.0]);
        let u = [1e16, 1e16 + 2.0];
        let r = compensated_residual(&k, &u, &[1.0, 0.0]);
        // Row 0: 1 - (1e16 - (1e16 + 2)) = 3.
        assert_eq!(r[0], 3.0);
    }
}
