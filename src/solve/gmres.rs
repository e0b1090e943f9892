//! Restarted GMRES (Saad and Schultz 1986) for `(I - K_RR) u = b`, chosen over BiCGSTAB because it
//! cannot break down: each step minimises the residual over the Krylov space, so the residual never
//! grows, and an exhausted space (h_{j+1,j} = 0) means the exact solution has been reached in it.
//! BiCGSTAB's shadow residual can become orthogonal to the residual (a scene whose emitters
//! reflect nothing does this at the first step, see [`super::system`]) and then it stalls.
//!
//! Every restart recomputes the residual from scratch with compensated dot products, so the
//! restarts act as iterative refinement and the stopping test is on the true residual, not on
//! the recurrence. A cycle that does not halve the residual is stagnation: the solver stops there
//! and says how far it got, instead of running to an iteration limit.

use super::system::{ReducedSystem, dot};
use crate::error::{Error, IterationFailure, Result};

/// Krylov vectors kept per cycle (memory: `(RESTART + 1) n` values).
pub const RESTART: usize = 30;

/// Most matrix-vector products in all cycles together.
pub const MAX_ITERATIONS: usize = 1000;

/// A cycle must reduce the residual by at least this factor, or the solve has stagnated.
const STAGNATION_FACTOR: f64 = 0.5;

/// A system `A x = b` that GMRES solves through products with `A` alone.
pub trait KrylovSystem: Sync {
    /// Number of unknowns.
    fn dim(&self) -> usize;
    /// `A x`.
    fn apply(&self, x: &[f64]) -> Vec<f64>;
    /// `b - A x`, as accurately as the system can give it (restarts stop on it).
    fn residual(&self, x: &[f64], b: &[f64]) -> Vec<f64>;
}

/// The dense system without its zero rows; restarts use its compensated residual.
impl KrylovSystem for ReducedSystem<'_> {
    fn dim(&self) -> usize {
        ReducedSystem::dim(self)
    }

    fn apply(&self, x: &[f64]) -> Vec<f64> {
        ReducedSystem::apply(self, x)
    }

    fn residual(&self, x: &[f64], b: &[f64]) -> Vec<f64> {
        self.compensated_residual(x, b)
    }
}

/// A GMRES solution.
#[derive(Clone, Debug)]
pub struct GmresSolution {
    /// The reduced solution.
    pub x: Vec<f64>,
    /// Matrix-vector products (Krylov steps).
    pub iterations: usize,
}

/// Solves `sys x = b` to `||b - A x||_2 <= tolerance ||b||_2`, starting from `x = b` (the first
/// term of the Neumann series of `(I - K)^-1`).
pub fn gmres(sys: &impl KrylovSystem, b: &[f64], tolerance: f64) -> Result<GmresSolution> {
    let n = sys.dim();
    let b_norm = norm(b);
    if b_norm == 0.0 {
        return Ok(GmresSolution { x: vec![0.0; n], iterations: 0 });
    }
    let target = tolerance * b_norm;
    let mut x = b.to_vec();
    // The start needs no extra precision: every restart recomputes the residual compensated.
    let mut r: Vec<f64> = sys.apply(&x).iter().zip(b).map(|(ax, bi)| bi - ax).collect();
    let mut r_norm = norm(&r);
    let mut iterations = 0;
    while r_norm > target {
        if iterations >= MAX_ITERATIONS {
            return Err(failure(IterationFailure::IterationLimit, r_norm / b_norm, iterations));
        }
        let steps = cycle(sys, &mut x, &r, r_norm, target, MAX_ITERATIONS - iterations);
        iterations += steps;
        r = sys.residual(&x, b);
        let new_norm = norm(&r);
        if !new_norm.is_finite() {
            return Err(failure(IterationFailure::NotFinite, new_norm, iterations));
        }
        if new_norm > target && new_norm > STAGNATION_FACTOR * r_norm {
            return Err(failure(IterationFailure::Stagnation, new_norm / b_norm, iterations));
        }
        r_norm = new_norm;
    }
    Ok(GmresSolution { x, iterations })
}

fn failure(reason: IterationFailure, residual: f64, iterations: usize) -> Error {
    Error::NotConverged { reason, residual, iterations }
}

/// One GMRES cycle from residual `r` (norm `r_norm`): at most [`RESTART`] and `budget` Arnoldi
/// steps, stopping early once the recurrence's residual is below `target`; adds the correction to
/// `x` and returns the number of steps.
fn cycle(
    sys: &impl KrylovSystem,
    x: &mut [f64],
    r: &[f64],
    r_norm: f64,
    target: f64,
    budget: usize,
) -> usize {
    let m = RESTART.min(budget).max(1);
    let mut basis: Vec<Vec<f64>> = vec![r.iter().map(|v| v / r_norm).collect()];
    // Hessenberg columns, already rotated to upper triangular form.
    let mut h: Vec<Vec<f64>> = Vec::with_capacity(m);
    let mut rotations: Vec<(f64, f64)> = Vec::with_capacity(m);
    let mut g = vec![r_norm];
    for j in 0..m {
        let mut w = sys.apply(&basis[j]);
        let w_norm_before = norm(&w);
        let mut column = vec![0.0; j + 2];
        // Modified Gram–Schmidt, twice ("twice is enough": Giraud, Langou, Rozložník 2005).
        for _ in 0..2 {
            for (i, v) in basis.iter().enumerate() {
                let hij = dot(&w, v);
                column[i] += hij;
                w.iter_mut().zip(v).for_each(|(wk, vk)| *wk -= hij * vk);
            }
        }
        let w_norm = norm(&w);
        column[j + 1] = w_norm;
        for (i, &(c, s)) in rotations.iter().enumerate() {
            let (a, b) = (column[i], column[i + 1]);
            column[i] = c * a + s * b;
            column[i + 1] = -s * a + c * b;
        }
        let (a, b) = (column[j], column[j + 1]);
        let d = a.hypot(b);
        let (c, s) = if d == 0.0 { (1.0, 0.0) } else { (a / d, b / d) };
        column[j] = d;
        column[j + 1] = 0.0;
        rotations.push((c, s));
        let gj = g[j];
        g[j] = c * gj;
        g.push(-s * gj);
        column.truncate(j + 1);
        h.push(column);
        // An invariant Krylov space (to rounding): the solution in it is exact, nothing to add.
        let exhausted = w_norm <= f64::EPSILON * w_norm_before;
        if exhausted || g[j + 1].abs() <= target || j + 1 == m {
            break;
        }
        basis.push(w.iter().map(|v| v / w_norm).collect());
    }
    // Back substitution: R y = g.
    let k = h.len();
    let mut y = vec![0.0; k];
    for i in (0..k).rev() {
        let s: f64 = (i + 1..k).map(|l| h[l][i] * y[l]).sum();
        y[i] = if h[i][i] == 0.0 { 0.0 } else { (g[i] - s) / h[i][i] };
    }
    for (yi, v) in y.iter().zip(&basis) {
        x.iter_mut().zip(v).for_each(|(xk, vk)| *xk += yi * vk);
    }
    k
}

fn norm(a: &[f64]) -> f64 {
    // Scaled so that neither large nor tiny entries over- or underflow.
    let scale = a.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    if scale == 0.0 || !scale.is_finite() {
        return scale;
    }
    scale * a.iter().map(|v| (v / scale).powi(2)).sum::<f64>().sqrt()
}
