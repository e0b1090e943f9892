//! Small analyses of study results: observed convergence rates and Pareto fronts.

/// The rate p of `E = O(h^p)` fitted by least squares to `(n, E)` on log-log axes, with the mesh
/// size h proportional to n^(-1/2); `None` with fewer than two points or a non-positive error.
pub fn fit_rate(points: &[(usize, f64)]) -> Option<f64> {
    if points.len() < 2 || points.iter().any(|&(n, e)| n == 0 || e.is_nan() || e <= 0.0) {
        return None;
    }
    let xs: Vec<f64> = points.iter().map(|&(n, _)| (n as f64).ln()).collect();
    let ys: Vec<f64> = points.iter().map(|&(_, e)| e.ln()).collect();
    let count = xs.len() as f64;
    let (mx, my) = (xs.iter().sum::<f64>() / count, ys.iter().sum::<f64>() / count);
    let sxx: f64 = xs.iter().map(|x| (x - mx) * (x - mx)).sum();
    let sxy: f64 = xs.iter().zip(&ys).map(|(x, y)| (x - mx) * (y - my)).sum();
    (sxx > 0.0).then(|| -2.0 * sxy / sxx)
}

/// Which of the `(time, error)` points are on the Pareto front: no other point is at least as fast
/// and at least as accurate, and strictly better in one of the two.
pub fn pareto_front(points: &[(f64, f64)]) -> Vec<bool> {
    points
        .iter()
        .map(|&(t, e)| !points.iter().any(|&(s, f)| s <= t && f <= e && (s < t || f < e)))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rates_of_exact_power_laws() {
        // E = n^-1 = h^2.
        let points: Vec<(usize, f64)> =
            [10, 40, 160, 640].iter().map(|&n| (n, 3.0 / n as f64)).collect();
        assert!((fit_rate(&points).unwrap() - 2.0).abs() < 1e-12);
        assert_eq!(fit_rate(&points[..1]), None);
        assert_eq!(fit_rate(&[(10, 1.0), (40, 0.0)]), None);
    }

    #[test]
    fn the_front_keeps_the_undominated_points() {
        let points = [(1.0, 5.0), (2.0, 3.0), (2.5, 4.0), (3.0, 1.0), (3.0, 1.0), (0.5, 9.0)];
        assert_eq!(pareto_front(&points), [true, true, false, true, true, true]);
    }
}
