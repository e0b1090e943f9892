//! The nested tensor tanh-sinh rule over a triangle that touches T_j, where Gauss rules fail (d log
//! d behaviour beside a common edge), with Bailey's error estimate from its last levels.

use glam::DVec3;

use super::options::ViewFactorOptions;
use super::patch::triangle_quarters;
use crate::quadrature::TanhSinh;

/// The adaptive outer integral of a row over one element.
pub(super) struct Outer<'a, F: FnMut(&[DVec3], &mut [f64])> {
    pub(super) rule: &'a TanhSinh,
    pub(super) options: &'a ViewFactorOptions,
    /// The integrand at each of a list of points, all at once (so that they share the lanes).
    pub(super) integrand: F,
    pub(super) evaluations: u64,
}

/// How a touching triangle's rule is checked.
#[derive(Clone, Copy, PartialEq, Eq)]
pub(super) enum Check {
    /// By its levels alone.
    Levels,
    /// By its four quarters' rules against the rule over the whole.
    Quarters,
    /// By its quarters, every level of each rule taken: where the integrand changes its scale
    /// far from the contact the rule is collapsed at (a narrow contact, a triangle much larger
    /// than T_j), the first three levels of the whole and of the quarters can agree by chance
    /// at a loose tolerance (a ground sliver touching a wall at 1e-4: 9.7e-6 estimated, 2.1e-5
    /// off).
    QuartersEveryLevel,
}

impl<F: FnMut(&[DVec3], &mut [f64])> Outer<'_, F> {
    /// `(1/A) ∫_T g dA` for the triangle `t`, and the estimated error, checked as `check` says.
    /// The levels of one rule can agree to 5e-7 while missing the integral by 2.2e-6 (a
    /// partition's element touching a floor element at one corner, the floor partly behind the
    /// partition's plane); the quarters, collapsed at other corners, do not share that miss
    /// (they met the integral to 1e-10 there).
    pub(super) fn integrate(&mut self, t: [DVec3; 3], check: Check) -> (f64, f64) {
        let early = check != Check::QuartersEveryLevel;
        let whole = self.levels(t, 0, early);
        if check == Check::Levels {
            return whole;
        }
        let whole = whole.0;
        let (mut sum, mut error) = (0.0, 0.0);
        for child in triangle_quarters(t) {
            let (v, e) = self.levels(child, 0, early);
            sum += 0.25 * v;
            error += 0.25 * e;
        }
        (sum, error.max((sum - whole).abs()))
    }

    /// `(1/A) ∫_T g dA` by the rule's levels (split into quarters at most `max_depth - depth`
    /// times where the finest levels disagree), and the estimated error; where `early`, taken
    /// from the first three levels whose estimate meets the tolerance.
    fn levels(&mut self, t: [DVec3; 3], depth: u32, early: bool) -> (f64, f64) {
        let [a, b, c] = t;
        // P(u, v) = c + u (a - c) + u v (b - a); dA = 2 A u du dv. The integrand at the finest
        // grid's points, by their positions in the rule: each level adds the points between
        // the last level's.
        let points = &self.rule.points;
        let n = points.len();
        // The rule is truncated in the plane as on each axis: a point whose weight per unit
        // step, 2 u w_u w_v, is below the tail is left out (for an integrand bounded by 1 they
        // change the integral by about the tail), not only those beyond the axes' truncation:
        // a fifth fewer points at levels 2 and 3.
        let weight = |ku: usize, kv: usize| 2.0 * points[ku].1 * points[ku].3 * points[kv].3;
        let in_rule = |&(ku, kv): &(usize, usize)| weight(ku, kv) >= self.rule.tail;
        let mut cache: Vec<Option<f64>> = vec![None; n * n];
        let (mut previous, mut before): (Option<f64>, Option<f64>) = (None, None);
        for level in 0..=self.rule.max_level {
            let stride = 1i64 << (self.rule.max_level - level);
            let on_level: Vec<usize> = (0..n).filter(|&k| points[k].0 % stride == 0).collect();
            let grid: Vec<(usize, usize)> = on_level
                .iter()
                .flat_map(|&ku| on_level.iter().map(move |&kv| (ku, kv)))
                .filter(in_rule)
                .collect();
            let new: Vec<usize> = grid
                .iter()
                .map(|&(ku, kv)| ku * n + kv)
                .filter(|&slot| cache[slot].is_none())
                .collect();
            let at: Vec<DVec3> = new
                .iter()
                .map(|&slot| {
                    let (u, v) = (points[slot / n].1, points[slot % n].1);
                    c + (a - c) * u + (b - a) * (u * v)
                })
                .collect();
            let mut found = vec![0.0; at.len()];
            (self.integrand)(&at, &mut found);
            self.evaluations += at.len() as u64;
            for (&slot, g) in new.iter().zip(found) {
                cache[slot] = Some(g);
            }
            let step = (-(level as f64)).exp2();
            let (mut value, mut total_weight) = (0.0, 0.0);
            for &(ku, kv) in &grid {
                let g = cache[ku * n + kv].expect("every point of the level is evaluated");
                let w = weight(ku, kv) * step * step;
                total_weight += w;
                value += w * g;
            }
            // The rule integrates 1 to within its truncation (1e-11 at the coarsest level);
            // dividing by its sum makes it exact for constants (closure to rounding). The
            // points left out then move the value by at most their weight (the integrand lies
            // in [0, 1]), which the estimate counts.
            value /= total_weight;
            let truncated = (1.0 - total_weight).abs();
            if let Some(prev) = previous {
                let diff = (value - prev).abs();
                // Two levels alone can agree by chance: on city:4x4 at --tolerance 1e-5 a
                // ground triangle at a wall's foot had levels 0 and 1 (5 and 11 points a side)
                // agree to 6.5e-6 and miss by 2.9e-5. A value is taken on the estimate of
                // three levels, whose digits double per level once the rule converges: that
                // may already meet the tolerance, and stopping there saves the next, finer
                // level (on the louvre room level 2 to 3 differed by 1e-10 where level 1 to 2
                // differed by 3e-6).
                let kept = kept_error(value, before, diff) + truncated;
                if early && before.is_some() && kept <= self.options.tolerance {
                    return (value, kept);
                }
                if level == self.rule.max_level && depth < self.options.max_depth {
                    let (mut sum, mut error) = (0.0, 0.0);
                    for child in triangle_quarters(t) {
                        let (v, e) = self.levels(child, depth + 1, early);
                        sum += 0.25 * v;
                        error += 0.25 * e;
                    }
                    return (sum, error);
                }
                if level == self.rule.max_level {
                    return (value, kept);
                }
            }
            before = previous.replace(value);
        }
        (previous.unwrap_or(0.0), f64::INFINITY)
    }
}

/// The error of the finest of three tanh-sinh levels, `value`, whose difference from the one
/// before is `diff` and which follows `before`: Bailey's estimate 10^max(d1²/d2, 2 d1), d1 and
/// d2 the decimal logs of the differences from the last two levels relative to the value (the
/// digits double per level once the rule converges), but no less than twice what is left if the
/// levels' differences go on shrinking at the rate they did (diff² over the difference before),
/// as they do before the rule converges; kept between a hundredth of `diff` and `diff`.
/// Bailey's alone trusted levels that agreed early: in the furnished room without its furniture
/// it estimated 1e-10 where F_ij was 1e-9 off; with the floor, reciprocity 6.6e-11 (9.6e-11
/// with a thousandth).
/// On a ground triangle whose corner touches a wall's foot (tessellated city, --tolerance 1e-6)
/// the levels' differences fell 1.9e-3, 4.5e-5, 1.4e-6: Bailey's estimate after the second was
/// 3e-8, the hundredth 4.5e-7 and the error 1.4e-6, where the rate says 1.1e-6: the rate's
/// floor catches such early agreement, and costs little where the levels converge, since
/// their differences then shrink far faster than the rate.
fn kept_error(value: f64, before: Option<f64>, diff: f64) -> f64 {
    let Some(before) = before else { return diff };
    let (scale, far) = (value.abs(), (value - before).abs());
    if scale == 0.0 || diff == 0.0 || far >= scale {
        return diff;
    }
    let (d1, d2) = ((diff / scale).log10(), (far / scale).log10());
    let digits = (d1 * d1 / d2).max(2.0 * d1);
    let geometric = 2.0 * diff * diff / far;
    (10f64.powf(digits) * scale).max(geometric).max(diff * 0.01).min(diff)
}

#[cfg(test)]
mod tests {
    use super::kept_error;

    /// The levels of a touching triangle that converge slowly at first (a ground triangle whose
    /// corner touches a wall's foot): after the third level the estimate is above the error
    /// left, 1.38e-6 from the converged value, where Bailey's alone said 3e-8.
    #[test]
    fn levels_that_converge_slowly_are_not_trusted_early() {
        let levels: [f64; 3] = [0.09472575017965218, 0.0965990781551397, 0.09655382425929668];
        let converged = 0.09655520673084433;
        let diff = (levels[2] - levels[1]).abs();
        let estimate = kept_error(levels[2], Some(levels[0]), diff);
        let error = (levels[2] - converged).abs();
        assert!(estimate >= error && estimate <= diff, "{estimate} against {error}");
        // Levels that do double their digits keep a small estimate: 1e-3, 1e-6, 1e-12.
        let (value, before) = (0.5, 0.5 + 1e-3);
        assert!(kept_error(value, Some(before), 1e-6) <= 1e-8);
    }
}
