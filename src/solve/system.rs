//! The system (I - K) u = E with the unknowns that need no solve taken out. A zero row of K (a
//! node on a face that reflects nothing, rho = 0, as a lamp usually is, or a node that sees
//! nothing) gives u_i = E_i exactly; its column moves to the right-hand side and the rest is
//! solved on the remaining rows: (I - K_RR) u_R = E_R + K_RF E_F.
//!
//! Besides saving work, this is what keeps Krylov solvers alive on such scenes: when E lives only
//! on zero rows, BiCGSTAB's shadow residual E is orthogonal to every later residual and the
//! iteration breaks down at its first step.

use faer::Mat;
use rayon::prelude::*;

use crate::assembly::CollocationMatrix;

/// `I - K` restricted to the rows and columns still unknown.
#[derive(Debug)]
pub struct ReducedSystem<'a> {
    k: &'a CollocationMatrix,
    /// The unknown rows in increasing order, or `None` when no row was taken out.
    free: Option<Vec<usize>>,
}

impl<'a> ReducedSystem<'a> {
    /// The whole system, nothing taken out.
    pub fn full(k: &'a CollocationMatrix) -> Self {
        Self { k, free: None }
    }

    /// The system without the zero rows of K (and their columns).
    pub fn without_zero_rows(k: &'a CollocationMatrix) -> Self {
        let free: Vec<usize> =
            (0..k.dof()).into_par_iter().filter(|&i| k.row(i).iter().any(|&v| v != 0.0)).collect();
        if free.len() == k.dof() { Self::full(k) } else { Self { k, free: Some(free) } }
    }

    /// Number of unknowns left.
    pub fn dim(&self) -> usize {
        self.free.as_ref().map_or(self.k.dof(), Vec::len)
    }

    /// Number of unknowns taken out (known without solving).
    pub fn eliminated(&self) -> usize {
        self.k.dof() - self.dim()
    }

    /// The right-hand side of the reduced system, `E_R + K_RF E_F`, from the full `E`.
    pub fn reduce_rhs(&self, rhs: &[f64]) -> Vec<f64> {
        match &self.free {
            None => rhs.to_vec(),
            Some(free) => {
                // Zero at the free positions: K_R(full) * that = K_RF E_F.
                let mut fixed = rhs.to_vec();
                free.iter().for_each(|&i| fixed[i] = 0.0);
                free.par_iter().map(|&i| rhs[i] + dot(self.k.row(i), &fixed)).collect()
            }
        }
    }

    /// The full solution from the reduced one: `u_F = E_F`.
    pub fn expand(&self, x: &[f64], rhs: &[f64]) -> Vec<f64> {
        match &self.free {
            None => x.to_vec(),
            Some(free) => {
                let mut u = rhs.to_vec();
                free.iter().zip(x).for_each(|(&i, &v)| u[i] = v);
                u
            }
        }
    }

    /// A reduced vector scattered to full length, zero at the eliminated positions.
    fn scatter(&self, x: &[f64]) -> Vec<f64> {
        match &self.free {
            None => x.to_vec(),
            Some(free) => {
                let mut full = vec![0.0; self.k.dof()];
                free.iter().zip(x).for_each(|(&i, &v)| full[i] = v);
                full
            }
        }
    }

    /// The row of K behind reduced row `a`.
    fn row(&self, a: usize) -> &[f64] {
        match &self.free {
            None => self.k.row(a),
            Some(free) => self.k.row(free[a]),
        }
    }

    /// `(I - K_RR) x`.
    pub fn apply(&self, x: &[f64]) -> Vec<f64> {
        let full = self.scatter(x);
        (0..self.dim()).into_par_iter().map(|a| x[a] - dot(self.row(a), &full)).collect()
    }

    /// `rhs - (I - K_RR) x`, each entry a compensated dot product (error-free TwoSum/TwoProduct
    /// accumulation, Ogita–Rump–Oishi Dot2), i.e. as if computed in twice the working precision
    /// and rounded once: residuals below plain f64 rounding, so that refinement and restarts
    /// gain digits beyond it.
    pub fn compensated_residual(&self, x: &[f64], rhs: &[f64]) -> Vec<f64> {
        let full = self.scatter(x);
        (0..self.dim())
            .into_par_iter()
            .map(|a| {
                let (mut s, mut c) = two_sum(rhs[a], -x[a]);
                for (kij, uj) in self.row(a).iter().zip(&full) {
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

    /// The dense matrix `I - K_RR`.
    pub fn matrix(&self) -> Mat<f64> {
        let n = self.dim();
        match &self.free {
            None => self.k.system_matrix(),
            Some(free) => Mat::from_fn(n, n, |a, b| {
                let k = self.k.get(free[a], free[b]);
                if a == b { 1.0 - k } else { -k }
            }),
        }
    }
}

/// `a · b`.
pub(super) fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// Knuth's error-free sum: `a + b = s + e` exactly.
fn two_sum(a: f64, b: f64) -> (f64, f64) {
    let s = a + b;
    let bb = s - a;
    (s, (a - (s - bb)) + (b - bb))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn zero_rows_are_taken_out_and_their_columns_move_to_the_right_hand_side() {
        // Row 1 is zero: u_1 = E_1 = 2; rows 0 and 2 see it through K_01 = 0.25, K_21 = 0.5.
        let k = CollocationMatrix::from_rows(3, vec![0.0, 0.25, 0.1, 0.0, 0.0, 0.0, 0.2, 0.5, 0.0]);
        let s = ReducedSystem::without_zero_rows(&k);
        assert_eq!((s.dim(), s.eliminated()), (2, 1));
        let rhs = [1.0, 2.0, 3.0];
        assert_eq!(s.reduce_rhs(&rhs), vec![1.0 + 0.5, 3.0 + 1.0]);
        let m = s.matrix();
        assert_eq!([m[(0, 0)], m[(0, 1)], m[(1, 0)], m[(1, 1)]], [1.0, -0.1, -0.2, 1.0]);
        assert_eq!(s.apply(&[1.0, 1.0]), vec![0.9, 0.8]);
        assert_eq!(s.expand(&[7.0, 8.0], &rhs), vec![7.0, 2.0, 8.0]);
        // Without a zero row nothing is taken out.
        let k = CollocationMatrix::from_rows(2, vec![0.0, 0.5, 0.5, 0.0]);
        assert_eq!(ReducedSystem::without_zero_rows(&k).eliminated(), 0);
    }
}
