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
use crate::distributed::Collective;
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
    let mut solver = Gmres::new(b, tolerance);
    loop {
        let given = match solver.need() {
            None => return solver.finish(),
            Some(Need::Product(x)) => sys.apply(x),
            Some(Need::Residual(x)) => sys.residual(x, b),
        };
        solver.give(given);
    }
}

/// What a [`Gmres`] solve needs next from its system.
#[derive(Debug)]
pub enum Need<'a> {
    /// `A x`.
    Product(&'a [f64]),
    /// `b - A x`, as accurately as the system can give it.
    Residual(&'a [f64]),
}

/// Where a GMRES solve's vectors are: whole in this process, or each rank holding its own rows
/// ([`crate::distributed`]), so that the Krylov basis is divided among the ranks. The sums
/// over a vector (dot products, norms) add the ranks' partial sums in rank order, the same
/// on every rank, so every rank's solve takes the same steps; on one rank they are the plain
/// sums.
#[derive(Clone, Copy, Debug, Default)]
pub struct Rows<'a> {
    ranks: Option<&'a dyn Collective>,
}

impl<'a> Rows<'a> {
    /// Vectors whole in this process.
    pub fn whole() -> Self {
        Self { ranks: None }
    }

    /// Each rank of `ranks` holding its own rows.
    pub fn over(ranks: &'a dyn Collective) -> Self {
        Self { ranks: Some(ranks) }
    }

    /// Each of `values` combined over the ranks by `combine`, in rank order from `start`.
    fn over_ranks(&self, values: &[f64], start: f64, combine: fn(f64, f64) -> f64) -> Vec<f64> {
        match self.ranks {
            None => values.to_vec(),
            Some(ranks) => {
                let parts = ranks.gather_f64(values);
                (0..values.len())
                    .map(|k| parts.iter().fold(start, |a, p| combine(a, p[k])))
                    .collect()
            }
        }
    }

    /// The sum over the ranks of each of `values`, in rank order.
    pub(super) fn summed(&self, values: &[f64]) -> Vec<f64> {
        self.over_ranks(values, 0.0, |a, b| a + b)
    }

    /// The largest over the ranks of each of `values`.
    pub(super) fn largest(&self, values: &[f64]) -> Vec<f64> {
        self.over_ranks(values, 0.0, f64::max)
    }

    fn dot(&self, a: &[f64], b: &[f64]) -> f64 {
        self.summed(&[dot(a, b)])[0]
    }

    fn norm(&self, a: &[f64]) -> f64 {
        // Scaled so that neither large nor tiny entries over- or underflow; the scale is the
        // largest entry of all the ranks' rows.
        let scale = self.largest(&[a.iter().fold(0.0f64, |m, v| m.max(v.abs()))])[0];
        if scale == 0.0 || !scale.is_finite() {
            return scale;
        }
        let squares: f64 = a.iter().map(|v| (v / scale).powi(2)).sum();
        scale * self.summed(&[squares])[0].sqrt()
    }
}

/// One GMRES solve as a sequence of requests ([`Gmres::need`], answered by [`Gmres::give`]), so
/// that many solves on one operator can have their products computed together, each matrix
/// entry read once for all of them. Its vectors are those of its [`Rows`]: the products it asks
/// for and is given are of its rows only.
#[derive(Debug)]
pub struct Gmres<'a> {
    rows: Rows<'a>,
    b_norm: f64,
    target: f64,
    x: Vec<f64>,
    /// Norm of the residual at the start of the current cycle.
    r_norm: f64,
    iterations: usize,
    state: State,
}

#[derive(Debug)]
enum State {
    /// Waiting for `A x` of the start `x = b` (its residual starts the first cycle).
    Start { b: Vec<f64> },
    /// Waiting for the product with the cycle's newest basis vector.
    Arnoldi(Cycle),
    /// Waiting for the residual of `x` after a cycle.
    Restart,
    /// Finished: the error, if it failed.
    Done(Option<Error>),
}

impl<'a> Gmres<'a> {
    /// A solve of `A x = b` to `||b - A x||_2 <= tolerance ||b||_2`, from `x = b`, its vectors
    /// whole.
    pub fn new(b: &[f64], tolerance: f64) -> Self {
        Self::over_rows(b, tolerance, Rows::whole())
    }

    /// As [`Gmres::new`], `b` being this process's rows of the right-hand side as `rows` holds
    /// them.
    pub fn over_rows(b: &[f64], tolerance: f64, rows: Rows<'a>) -> Self {
        let b_norm = rows.norm(b);
        let mut solver = Self {
            rows,
            b_norm,
            target: tolerance * b_norm,
            x: b.to_vec(),
            r_norm: 0.0,
            iterations: 0,
            state: State::Start { b: b.to_vec() },
        };
        if b_norm == 0.0 {
            solver.x.iter_mut().for_each(|v| *v = 0.0);
            solver.state = State::Done(None);
        }
        solver
    }

    /// What the solve needs next, or `None` once it has finished.
    pub fn need(&self) -> Option<Need<'_>> {
        match &self.state {
            // The start needs no extra precision: every restart recomputes the residual
            // compensated.
            State::Start { .. } => Some(Need::Product(&self.x)),
            State::Arnoldi(cycle) => Some(Need::Product(cycle.basis.last().expect("a vector"))),
            State::Restart => Some(Need::Residual(&self.x)),
            State::Done(_) => None,
        }
    }

    /// Gives what [`Gmres::need`] asked for.
    pub fn give(&mut self, given: Vec<f64>) {
        match std::mem::replace(&mut self.state, State::Done(None)) {
            State::Start { b } => {
                let r: Vec<f64> = given.iter().zip(&b).map(|(ax, bi)| bi - ax).collect();
                self.r_norm = self.rows.norm(&r);
                self.state = self.next_cycle(r);
            }
            State::Arnoldi(mut cycle) => {
                self.state = match cycle.step(given, self.target, self.rows) {
                    false => State::Arnoldi(cycle),
                    true => {
                        self.iterations += cycle.finish(&mut self.x);
                        State::Restart
                    }
                };
            }
            State::Restart => {
                let new_norm = self.rows.norm(&given);
                let (b_norm, iterations) = (self.b_norm, self.iterations);
                self.state = if !new_norm.is_finite() {
                    State::Done(Some(failure(IterationFailure::NotFinite, new_norm, iterations)))
                } else if new_norm > self.target && new_norm > STAGNATION_FACTOR * self.r_norm {
                    let residual = new_norm / b_norm;
                    State::Done(Some(failure(IterationFailure::Stagnation, residual, iterations)))
                } else {
                    self.r_norm = new_norm;
                    self.next_cycle(given)
                };
            }
            State::Done(_) => panic!("a finished GMRES solve was given a vector"),
        }
    }

    /// A cycle from residual `r` (norm `self.r_norm`), or the end where it is small enough or
    /// the iterations are spent.
    fn next_cycle(&self, r: Vec<f64>) -> State {
        if self.r_norm <= self.target {
            State::Done(None)
        } else if self.iterations >= MAX_ITERATIONS {
            let residual = self.r_norm / self.b_norm;
            State::Done(Some(failure(IterationFailure::IterationLimit, residual, self.iterations)))
        } else {
            State::Arnoldi(Cycle::new(r, self.r_norm, MAX_ITERATIONS - self.iterations))
        }
    }

    /// The solution, or why the solve stopped short.
    pub fn finish(self) -> Result<GmresSolution> {
        match self.state {
            State::Done(None) => Ok(GmresSolution { x: self.x, iterations: self.iterations }),
            State::Done(Some(e)) => Err(e),
            _ => panic!("GMRES finished before it was done"),
        }
    }
}

fn failure(reason: IterationFailure, residual: f64, iterations: usize) -> Error {
    Error::NotConverged { reason, residual, iterations }
}

/// One GMRES cycle: at most [`RESTART`] (and the iterations left) Arnoldi steps from a
/// residual, stopping early once the recurrence's residual is below the target.
#[derive(Debug)]
struct Cycle {
    /// Most steps.
    m: usize,
    basis: Vec<Vec<f64>>,
    /// Hessenberg columns, already rotated to upper triangular form.
    h: Vec<Vec<f64>>,
    rotations: Vec<(f64, f64)>,
    g: Vec<f64>,
}

impl Cycle {
    fn new(r: Vec<f64>, r_norm: f64, budget: usize) -> Self {
        let m = RESTART.min(budget).max(1);
        Self {
            m,
            basis: vec![r.iter().map(|v| v / r_norm).collect()],
            h: Vec::with_capacity(m),
            rotations: Vec::with_capacity(m),
            g: vec![r_norm],
        }
    }

    /// One Arnoldi step with `w` = A times the newest basis vector; whether the cycle ends.
    fn step(&mut self, mut w: Vec<f64>, target: f64, rows: Rows) -> bool {
        let j = self.h.len();
        let w_norm_before = rows.norm(&w);
        let mut column = vec![0.0; j + 2];
        // Modified Gram–Schmidt, twice ("twice is enough": Giraud, Langou, Rozložník 2005).
        for _ in 0..2 {
            for (i, v) in self.basis.iter().enumerate() {
                let hij = rows.dot(&w, v);
                column[i] += hij;
                w.iter_mut().zip(v).for_each(|(wk, vk)| *wk -= hij * vk);
            }
        }
        let w_norm = rows.norm(&w);
        column[j + 1] = w_norm;
        for (i, &(c, s)) in self.rotations.iter().enumerate() {
            let (a, b) = (column[i], column[i + 1]);
            column[i] = c * a + s * b;
            column[i + 1] = -s * a + c * b;
        }
        let (a, b) = (column[j], column[j + 1]);
        let d = a.hypot(b);
        let (c, s) = if d == 0.0 { (1.0, 0.0) } else { (a / d, b / d) };
        column[j] = d;
        column[j + 1] = 0.0;
        self.rotations.push((c, s));
        let gj = self.g[j];
        self.g[j] = c * gj;
        self.g.push(-s * gj);
        column.truncate(j + 1);
        self.h.push(column);
        // An invariant Krylov space (to rounding): the solution in it is exact, nothing to add.
        let exhausted = w_norm <= f64::EPSILON * w_norm_before;
        if exhausted || self.g[j + 1].abs() <= target || j + 1 == self.m {
            return true;
        }
        self.basis.push(w.iter().map(|v| v / w_norm).collect());
        false
    }

    /// Adds the cycle's correction to `x` (back substitution, R y = g); the steps taken.
    fn finish(&self, x: &mut [f64]) -> usize {
        let (h, g) = (&self.h, &self.g);
        let k = h.len();
        let mut y = vec![0.0; k];
        for i in (0..k).rev() {
            let s: f64 = (i + 1..k).map(|l| h[l][i] * y[l]).sum();
            y[i] = if h[i][i] == 0.0 { 0.0 } else { (g[i] - s) / h[i][i] };
        }
        for (yi, v) in y.iter().zip(&self.basis) {
            x.iter_mut().zip(v).for_each(|(xk, vk)| *xk += yi * vk);
        }
        k
    }
}
