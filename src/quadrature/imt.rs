//! The IMT (Iri–Moriguti–Takasawa) rule on [0, 1] (paper sec. 4.1 after (4.14); Atkinson [2, p. 307]).
//!
//! The substitution `x = φ(τ) = (1/Q) ∫_0^τ exp(-1/s - 1/(1-s)) ds` makes every derivative of the
//! integrand vanish at both ends, after which the trapezoidal rule in τ converges faster than any
//! power of the step, also for integrands with end-point singularities. The paper uses 128 nodes.

use super::GaussLegendre;

/// Nodes per group in [`ImtRule::lanes`].
pub const IMT_LANES: usize = 8;

/// The N-point IMT rule on [0, 1]: nodes `φ(k/N)` and weights `φ'(k/N)/N`, k = 1 .. N-1 (the end
/// points have weight zero).
#[derive(Clone, Debug, PartialEq)]
pub struct ImtRule {
    nodes: Vec<f64>,
    weights: Vec<f64>,
    /// The nodes and weights in groups of [`IMT_LANES`], the last padded with the middle node at
    /// weight zero.
    lanes: Vec<([f64; IMT_LANES], [f64; IMT_LANES])>,
}

fn imt_density(s: f64) -> f64 {
    if s <= 0.0 || s >= 1.0 { 0.0 } else { (-1.0 / s - 1.0 / (1.0 - s)).exp() }
}

impl ImtRule {
    /// The paper's choice of 128 nodes.
    pub const PAPER_NODES: usize = 128;

    /// The rule with `n >= 2` subintervals (n - 1 nodes with nonzero weight).
    pub fn new(n: usize) -> Self {
        assert!(n >= 2, "the IMT rule needs at least two subintervals");
        // φ(k/n) by cumulative 20-point Gauss–Legendre over each subinterval: the density is
        // analytic inside (0, 1), so this is exact to rounding.
        let gl = GaussLegendre::new(20);
        let h = 1.0 / n as f64;
        // Neumaier-compensated running sum: plain summation over N/2 panels would leave errors of
        // order N·ε in the middle nodes.
        let mut cumulative = vec![0.0; n + 1];
        let (mut sum, mut carry) = (0.0_f64, 0.0_f64);
        for k in 0..n {
            let a = k as f64 * h;
            let term = gl.integrate(a, a + h, imt_density);
            let t = sum + term;
            carry += if sum.abs() >= term.abs() { (sum - t) + term } else { (term - t) + sum };
            sum = t;
            cumulative[k + 1] = sum + carry;
        }
        let q = cumulative[n];
        let mut nodes = Vec::with_capacity(n - 1);
        let mut weights = Vec::with_capacity(n - 1);
        for (k, &c) in cumulative.iter().enumerate().take(n).skip(1) {
            // Use the symmetry φ(1-τ) = 1 - φ(τ) so both halves are equally accurate.
            let x = if 2 * k <= n { c / q } else { 1.0 - cumulative[n - k] / q };
            nodes.push(x);
            weights.push(imt_density(k as f64 * h) / q * h);
        }
        let lanes = nodes
            .chunks(IMT_LANES)
            .zip(weights.chunks(IMT_LANES))
            .map(|(x, w)| {
                let x = std::array::from_fn(|l| x.get(l).copied().unwrap_or(0.5));
                (x, std::array::from_fn(|l| w.get(l).copied().unwrap_or(0.0)))
            })
            .collect();
        Self { nodes, weights, lanes }
    }

    /// Nodes in (0, 1), increasing.
    pub fn nodes(&self) -> &[f64] {
        &self.nodes
    }

    /// Weights matching [`Self::nodes`].
    pub fn weights(&self) -> &[f64] {
        &self.weights
    }

    /// Number of subintervals N.
    pub fn subintervals(&self) -> usize {
        self.nodes.len() + 1
    }

    /// Integral of `f` over `[a, b]`.
    pub fn integrate(&self, a: f64, b: f64, mut f: impl FnMut(f64) -> f64) -> f64 {
        let len = b - a;
        len * self.nodes.iter().zip(&self.weights).map(|(&x, &w)| w * f(a + len * x)).sum::<f64>()
    }

    /// The nodes and weights in groups of [`IMT_LANES`], for vectorised integrands; the last
    /// group is padded with the middle node at weight zero.
    pub fn lanes(&self) -> &[([f64; IMT_LANES], [f64; IMT_LANES])] {
        &self.lanes
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn weights_sum_to_one_and_nodes_are_symmetric() {
        let rule = ImtRule::new(128);
        assert!((rule.weights().iter().sum::<f64>() - 1.0).abs() < 1e-15);
        let (x, w) = (rule.nodes(), rule.weights());
        let n = x.len();
        for k in 0..n {
            assert!((x[k] + x[n - 1 - k] - 1.0).abs() <= 2.0 * f64::EPSILON);
            assert!((w[k] - w[n - 1 - k]).abs() <= 1e-16 * w[k].max(1e-300));
        }
    }

    #[test]
    fn end_point_singularities_converge_to_rounding() {
        let rule = ImtRule::new(128);
        // ∫_0^1 x^(-1/2) dx = 2 and ∫_0^1 ln x dx = -1: both singular at an end point.
        let s = rule.integrate(0.0, 1.0, |x| x.powf(-0.5));
        assert!((s - 2.0).abs() < 1e-9, "{s}");
        let l = rule.integrate(0.0, 1.0, f64::ln);
        assert!((l + 1.0).abs() < 1e-12, "{l}");
        // A smooth integrand: e^x.
        let e = rule.integrate(0.0, 2.0, f64::exp);
        assert!((e - (2f64.exp() - 1.0)).abs() < 1e-14, "{e}");
        let lanes: f64 = rule
            .lanes()
            .iter()
            .flat_map(|(x, w)| x.iter().zip(w).map(|(x, w)| 2.0 * w * (2.0 * x).exp()))
            .sum();
        assert!((lanes - e).abs() < 4.0 * f64::EPSILON * e, "{lanes} vs {e}");
    }
}
