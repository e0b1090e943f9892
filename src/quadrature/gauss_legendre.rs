//! Gauss–Legendre rules on [-1, 1], computed by Newton's method on the three-term recurrence.

/// An n-point Gauss–Legendre rule on [-1, 1] (exact for polynomials of degree 2n - 1).
#[derive(Clone, Debug)]
pub struct GaussLegendre {
    nodes: Vec<f64>,
    weights: Vec<f64>,
}

impl GaussLegendre {
    /// The n-point rule; `n >= 1`.
    pub fn new(n: usize) -> Self {
        assert!(n >= 1, "a Gauss–Legendre rule needs at least one node");
        let mut nodes = vec![0.0; n];
        let mut weights = vec![0.0; n];
        let nf = n as f64;
        for k in 0..n.div_ceil(2) {
            // Tricomi's initial guess, then Newton on P_n.
            let mut x = (std::f64::consts::PI * (k as f64 + 0.75) / (nf + 0.5)).cos();
            let mut dp = 0.0;
            for _ in 0..100 {
                let (p, d) = legendre_and_derivative(n, x);
                dp = d;
                let dx = p / d;
                x -= dx;
                if dx.abs() <= 1e-16 * x.abs().max(1e-300) {
                    break;
                }
            }
            let (_, d) = legendre_and_derivative(n, x);
            dp = if d != 0.0 { d } else { dp };
            let w = 2.0 / ((1.0 - x * x) * dp * dp);
            nodes[k] = -x;
            nodes[n - 1 - k] = x;
            weights[k] = w;
            weights[n - 1 - k] = w;
        }
        if n % 2 == 1 {
            nodes[n / 2] = 0.0;
        }
        Self { nodes, weights }
    }

    /// Nodes in increasing order.
    pub fn nodes(&self) -> &[f64] {
        &self.nodes
    }

    /// Weights, matching [`Self::nodes`].
    pub fn weights(&self) -> &[f64] {
        &self.weights
    }

    /// Integral of `f` over `[a, b]`.
    pub fn integrate(&self, a: f64, b: f64, mut f: impl FnMut(f64) -> f64) -> f64 {
        let half = 0.5 * (b - a);
        let mid = 0.5 * (a + b);
        half * self
            .nodes
            .iter()
            .zip(&self.weights)
            .map(|(&x, &w)| w * f(mid + half * x))
            .sum::<f64>()
    }
}

/// `(P_n(x), P_n'(x))` by the recurrence `(k+1) P_{k+1} = (2k+1) x P_k - k P_{k-1}`.
fn legendre_and_derivative(n: usize, x: f64) -> (f64, f64) {
    let (mut p0, mut p1) = (1.0, x);
    for k in 1..n {
        let kf = k as f64;
        let p2 = ((2.0 * kf + 1.0) * x * p1 - kf * p0) / (kf + 1.0);
        p0 = p1;
        p1 = p2;
    }
    let p = if n == 0 { p0 } else { p1 };
    let pm1 = if n == 0 { 0.0 } else { p0 };
    (p, n as f64 * (x * p - pm1) / (x * x - 1.0))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rules_integrate_polynomials_of_degree_2n_minus_1_exactly() {
        for n in [1, 2, 3, 7, 16, 64] {
            let rule = GaussLegendre::new(n);
            assert!((rule.weights().iter().sum::<f64>() - 2.0).abs() < 1e-14);
            for deg in 0..(2 * n) {
                let got = rule.integrate(0.0, 1.0, |x| x.powi(deg as i32));
                let want = 1.0 / (deg as f64 + 1.0);
                assert!((got - want).abs() < 2e-15, "n={n} deg={deg}: {got} vs {want}");
            }
        }
    }

    #[test]
    fn nodes_are_sorted_and_symmetric() {
        let rule = GaussLegendre::new(9);
        let x = rule.nodes();
        assert!(x.windows(2).all(|w| w[0] < w[1]));
        for k in 0..9 {
            assert_eq!(x[k], -x[8 - k]);
        }
    }
}
