//! Solving (I - K) u = E with faer: zero rows of K taken out first ([`system`]), then LU with
//! partial pivoting for moderate sizes ([`lu`]) or restarted GMRES over K applied row by row
//! ([`gmres`]) for large ones.
//!
//! What is guaranteed: for rho < 1 the continuous operator has ||K|| <= max rho < 1 (paper
//! (2.17)), and so has the centroid method's discrete K (non-negative entries, row sums <= rho).
//! The linear method's discrete K has negative entries and its norm can exceed 1, so nothing
//! bounds the iteration count a priori; GMRES still never breaks down and its residual never
//! grows. Either way a solution is accepted only on its true residual, which is computed again at
//! the end and reported.

mod gmres;
mod lu;
mod products;
mod system;

use serde::Serialize;

pub use gmres::{Gmres, GmresSolution, KrylovSystem, MAX_ITERATIONS, Need, RESTART, gmres};
pub use lu::{LuFactors, LuSolution, inverse_norm_1_estimate};
pub use products::{Products, solve_by_products, solve_by_products_many};
pub use system::ReducedSystem;

use crate::assembly::CollocationMatrix;
use crate::error::{Error, Result};

crate::vocabulary::named_options! {
    /// Which solver to use; `auto` is LU up to [`LU_LIMIT`] unknowns, GMRES beyond.
    #[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
    #[serde(rename_all = "lowercase")]
    pub enum SolverChoice as "solver" {
        /// Dense LU for small problems, GMRES beyond (and for a compressed operator)
        Auto = "auto" default,
        /// Dense LU with partial pivoting
        Lu = "lu",
        /// Restarted GMRES
        Iterative = "iterative",
    }
}

/// Largest system solved by LU under [`SolverChoice::Auto`]: LU costs (2/3) n³ flops and a second
/// dense copy of the matrix.
pub const LU_LIMIT: usize = 6000;

/// Default relative residual `||E - (I - K) u||_2 / ||E||_2` at which GMRES stops.
pub const DEFAULT_TOLERANCE: f64 = 1e-13;

/// How to solve.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct SolverOptions {
    /// Which solver.
    pub choice: SolverChoice,
    /// Relative residual (2-norm, of the system without its zero rows) at which GMRES stops.
    pub tolerance: f64,
}

impl Default for SolverOptions {
    fn default() -> Self {
        Self { choice: SolverChoice::Auto, tolerance: DEFAULT_TOLERANCE }
    }
}

impl SolverOptions {
    /// The given solver with the default tolerance.
    pub fn with(choice: SolverChoice) -> Self {
        Self { choice, ..Self::default() }
    }
}

/// A solution and how it was found.
#[derive(Clone, Debug, Serialize)]
pub struct SolveOutcome {
    /// Nodal values.
    #[serde(skip)]
    pub u: Vec<f64>,
    /// `lu` or `gmres`.
    pub solver: &'static str,
    /// Iterations (matrix-vector products; 0 for LU).
    pub iterations: usize,
    /// Relative residual `||(I - K) u - E||_∞ / ||E||_∞` of the whole system.
    pub residual: f64,
    /// Estimated 1-norm condition number of the system without its zero rows (LU only).
    pub condition_estimate: Option<f64>,
    /// Steps of iterative refinement with a compensated residual (LU only).
    pub refinement_steps: usize,
    /// Unknowns known without solving: zero rows of K (rho = 0, or nothing in view), u = E.
    pub rows_eliminated: usize,
}

/// Largest estimated condition number accepted: beyond it fewer than two digits of the solution
/// could be trusted (κ ε > 1e-2), so the system is reported as singular instead.
pub const CONDITION_LIMIT: f64 = 1e-2 / f64::EPSILON;

/// Solves `(I - K) u = rhs`. Zero rows of K are taken out first. A closed surface with rho = 1
/// everywhere (every row of K sums to 1, so I - K annihilates constants) and, for LU, an
/// estimated condition number above [`CONDITION_LIMIT`] are reported as
/// [`Error::SingularSystem`]; GMRES that stagnates or runs out of iterations as
/// [`Error::NotConverged`], with the residual it reached.
pub fn solve(k: &CollocationMatrix, rhs: &[f64], options: SolverOptions) -> Result<SolveOutcome> {
    let mut outcomes = solve_many(k, std::slice::from_ref(&rhs), options)?;
    Ok(outcomes.pop().expect("one outcome per right-hand side"))
}

/// Solves `(I - K) u = E` for each right-hand side in `rhs` on one matrix, as [`solve`] does
/// for one: the zero rows are taken out and LU factors once for all of them (GMRES runs per
/// right-hand side; its products are what it costs).
pub fn solve_many(
    k: &CollocationMatrix,
    rhs: &[&[f64]],
    options: SolverOptions,
) -> Result<Vec<SolveOutcome>> {
    reject_constant_null_vector(k)?;
    check_tolerance(options.tolerance)?;
    let sys = ReducedSystem::without_zero_rows(k);
    let use_lu = match options.choice {
        SolverChoice::Lu => true,
        SolverChoice::Iterative => false,
        SolverChoice::Auto => sys.dim() <= LU_LIMIT,
    };
    let factors = if use_lu { Some(LuFactors::of_system(&sys)?) } else { None };
    let outcome = |rhs: &[f64]| -> Result<SolveOutcome> {
        let reduced_rhs = sys.reduce_rhs(rhs);
        let (x, solver, iterations, condition_estimate, refinement_steps) = match &factors {
            Some(factors) => {
                let lu = factors.solve(&sys, &reduced_rhs, REFINEMENT_STEPS)?;
                (lu.u, SolverChoice::Lu.name(), 0, Some(lu.condition), lu.refinement_steps)
            }
            None => {
                let g = gmres::gmres(&sys, &reduced_rhs, options.tolerance)?;
                (g.x, "gmres", g.iterations, None, 0)
            }
        };
        let u = sys.expand(&x, rhs);
        Ok(SolveOutcome {
            residual: relative_residual(k, &u, rhs),
            u,
            solver,
            iterations,
            condition_estimate,
            refinement_steps,
            rows_eliminated: sys.eliminated(),
        })
    };
    rhs.iter().map(|rhs| outcome(rhs)).collect()
}

/// Refuses a residual tolerance outside (0, 1).
fn check_tolerance(tolerance: f64) -> Result<()> {
    if !(tolerance > 0.0 && tolerance < 1.0) {
        return Err(Error::InvalidParameter {
            name: "tolerance",
            value: tolerance.to_string(),
            reason: "the relative residual must lie in (0, 1)".into(),
        });
    }
    Ok(())
}

/// How far a row sum of K may be from 1 for the row to count as "closed with rho = 1".
const CLOSED_ROW_TOLERANCE: f64 = 1e-10;

/// Lemma 2.1: inside a closed surface every row of K/rho sums to 1, so with rho = 1 everywhere
/// (I - K) 1 = 0 and the system is singular; caught here before any factorisation, for both solvers.
fn reject_constant_null_vector(k: &CollocationMatrix) -> Result<()> {
    let sums: Vec<f64> = (0..k.dof()).map(|i| k.row(i).iter().sum()).collect();
    reject_unit_row_sums(&sums, CLOSED_ROW_TOLERANCE)
}

/// [`Error::SingularSystem`] when every row sum of K is 1 within `limit` (none given: fine).
fn reject_unit_row_sums(sums: &[f64], limit: f64) -> Result<()> {
    if !sums.is_empty() && sums.iter().all(|s| (s - 1.0).abs() <= limit) {
        return Err(Error::SingularSystem {
            condition: f64::INFINITY,
            reason: "every row of K sums to 1, so I - K maps constants to 0".into(),
        });
    }
    Ok(())
}

/// Most refinement steps [`solve`] takes.
pub const REFINEMENT_STEPS: usize = 3;

/// Solves `(I - K) u = rhs` by LU with partial pivoting (no refinement); see [`LuSolution`].
pub fn solve_lu(k: &CollocationMatrix, rhs: &[f64]) -> Result<Vec<f64>> {
    Ok(LuSolution::new(k, rhs, 0)?.u)
}

fn max_abs(v: &[f64]) -> f64 {
    v.iter().fold(0.0f64, |m, x| m.max(x.abs()))
}

/// `rhs - (I - K) u` computed with compensated dot products ([`ReducedSystem::compensated_residual`]).
pub fn compensated_residual(k: &CollocationMatrix, u: &[f64], rhs: &[f64]) -> Vec<f64> {
    ReducedSystem::full(k).compensated_residual(u, rhs)
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
    use faer::prelude::*;

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
    fn lu_and_gmres_agree_and_have_small_residuals() {
        for n in [1, 2, 3, 17, 64, 255, 256, 257] {
            let k = radiosity_like(n);
            let norm_k =
                (0..n).map(|i| k.row(i).iter().map(|v| v.abs()).sum::<f64>()).fold(0.0, f64::max);
            assert!(norm_k < 1.0);
            // ||(I - K)^-1||_inf <= 1/(1 - ||K||): LU's backward error is a modest multiple of
            // n eps, so its residual stays below 16 n eps / (1 - ||K||); GMRES stops at
            // ||r||_2 <= tol ||b||_2, so ||r||_inf <= tol sqrt(n) ||b||_inf.
            let lu_bound = 16.0 * n as f64 * f64::EPSILON / (1.0 - norm_k);
            let it_bound = DEFAULT_TOLERANCE * (n as f64).sqrt() + lu_bound;
            let rhs: Vec<f64> = (0..n).map(|i| 1.0 + i as f64).collect();
            let lu = solve(&k, &rhs, SolverOptions::with(SolverChoice::Lu)).unwrap();
            let it = solve(&k, &rhs, SolverOptions::with(SolverChoice::Iterative)).unwrap();
            assert!(lu.residual < lu_bound, "n {n}: LU residual {:e} > {lu_bound:e}", lu.residual);
            assert!(
                it.residual < it_bound,
                "n {n}: GMRES residual {:e} > {it_bound:e}",
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
            match solve(&k, &vec![1.0; 30], SolverOptions::with(choice)) {
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

    /// A lamp that reflects nothing: E lives only on zero rows of K. BiCGSTAB's shadow residual
    /// (E) is then orthogonal to every later residual; GMRES on the reduced system must agree
    /// with LU on the full one.
    #[test]
    fn a_black_emitter_is_taken_out_and_gmres_agrees_with_lu() {
        let n = 40;
        let mut k = radiosity_like(n);
        let lamp = 5..9;
        let mut data = k.as_slice().to_vec();
        for i in lamp.clone() {
            data[i * n..(i + 1) * n].fill(0.0);
        }
        k = CollocationMatrix::from_rows(n, data);
        let rhs: Vec<f64> = (0..n).map(|i| if lamp.contains(&i) { 1.0 } else { 0.0 }).collect();
        let full_lu = LuSolution::new(&k, &rhs, REFINEMENT_STEPS).unwrap().u;
        let scale = max_abs(&full_lu);
        for choice in [SolverChoice::Lu, SolverChoice::Iterative] {
            let s = solve(&k, &rhs, SolverOptions::with(choice)).unwrap();
            assert_eq!(s.rows_eliminated, lamp.len(), "{choice:?}");
            for i in lamp.clone() {
                assert_eq!(s.u[i], 1.0, "{choice:?}: u = E on the lamp");
            }
            let diff = s.u.iter().zip(&full_lu).fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
            assert!(diff <= 1e-12 * scale, "{choice:?}: differs from LU by {diff:e}");
            if choice == SolverChoice::Iterative {
                assert!(s.iterations < 30, "{} iterations", s.iterations);
            }
        }
    }

    #[test]
    fn gmres_stops_on_stagnation_and_says_how_far_it_got() {
        let k = radiosity_like(50);
        let rhs: Vec<f64> = (0..50).map(|i| 1.0 + i as f64).collect();
        // Far below rounding: no cycle can halve a residual already at the rounding level.
        let options = SolverOptions { choice: SolverChoice::Iterative, tolerance: 1e-30 };
        match solve(&k, &rhs, options) {
            Err(Error::NotConverged { reason, residual, iterations }) => {
                assert_eq!(reason, crate::error::IterationFailure::Stagnation);
                assert!(residual < 1e-14, "residual reached {residual:e}");
                assert!(iterations <= 3 * RESTART, "stopped only after {iterations} iterations");
            }
            other => panic!("expected stagnation, got {other:?}"),
        }
        // And the tolerance asked for is the one met.
        for tolerance in [1e-4, 1e-8, 1e-12] {
            let s = solve(&k, &rhs, SolverOptions { choice: SolverChoice::Iterative, tolerance })
                .unwrap();
            let r = compensated_residual(&k, &s.u, &rhs);
            let norm = |v: &[f64]| v.iter().map(|x| x * x).sum::<f64>().sqrt();
            assert!(norm(&r) <= tolerance * norm(&rhs), "tolerance {tolerance:e}");
            assert!(norm(&r) > 1e-6 * tolerance * norm(&rhs), "{tolerance:e}: solved far past it");
        }
    }
}
