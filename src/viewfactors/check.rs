//! What a view factor computation promises, checked against a reference computed with a tighter
//! tolerance: every entry within the reported estimate (the run's and the reference's), and,
//! where both directions were integrated, reciprocity within the areas times the estimate.

use serde::Serialize;

use super::matrix::ViewFactors;

/// How far a run of view factors is from a reference, in units of what its estimate promises.
#[derive(Clone, Copy, Debug, Serialize)]
pub struct EstimateCheck {
    /// max |F_ij - F_ref,ij| over every entry of either.
    pub largest_error: f64,
    /// `largest_error` over the sum of the run's and the reference's estimates: at most 1
    /// where the estimate holds.
    pub error_ratio: f64,
    /// max |A_i F_ij - A_j F_ji| / ((A_i + A_j) · estimate) over the pairs: at most 1 where the
    /// estimate holds (both directions integrated; otherwise reciprocity holds by construction).
    pub reciprocity_ratio: f64,
    /// The entry (i, j) where `error_ratio` is reached.
    pub worst_entry: (usize, usize),
    /// Entries below zero in the run.
    pub negative: usize,
}

impl EstimateCheck {
    /// Whether every promise holds: errors and reciprocity within the estimate, no negative
    /// entry.
    pub fn holds(&self) -> bool {
        self.error_ratio <= 1.0 && self.reciprocity_ratio <= 1.0 && self.negative == 0
    }
}

impl ViewFactors {
    /// These view factors against `reference`, computed on the same mesh with a tighter
    /// tolerance.
    ///
    /// # Panics
    /// Where the two have different numbers of elements.
    pub fn check_against(&self, reference: &ViewFactors) -> EstimateCheck {
        assert_eq!(self.len(), reference.len(), "a reference on the same mesh");
        let allowed = self.error_estimate + reference.error_estimate;
        let (mut largest_error, mut worst_entry) = (0.0f64, (0, 0));
        let mut reciprocity_ratio = 0.0f64;
        for i in 0..self.len() {
            // Both rows' columns, merged: an entry that one of the two leaves out is 0 there.
            let (columns, values) = self.row(i);
            let (ref_columns, ref_values) = reference.row(i);
            let mut k = 0;
            for (&j, &want) in ref_columns.iter().zip(ref_values) {
                while k < columns.len() && columns[k] < j {
                    (largest_error, worst_entry) =
                        worse((largest_error, worst_entry), values[k].abs(), (i, columns[k]));
                    k += 1;
                }
                let got = if k < columns.len() && columns[k] == j {
                    k += 1;
                    values[k - 1]
                } else {
                    0.0
                };
                (largest_error, worst_entry) =
                    worse((largest_error, worst_entry), (got - want).abs(), (i, j));
            }
            for k in k..columns.len() {
                (largest_error, worst_entry) =
                    worse((largest_error, worst_entry), values[k].abs(), (i, columns[k]));
            }
            if self.each_direction {
                for (&j, &v) in columns.iter().zip(values) {
                    let j = j as usize;
                    let gap = (self.areas[i] * v - self.areas[j] * self.get(j, i)).abs();
                    let promised = (self.areas[i] + self.areas[j]) * self.error_estimate;
                    reciprocity_ratio = reciprocity_ratio.max(ratio(gap, promised));
                }
            }
        }
        EstimateCheck {
            largest_error,
            error_ratio: ratio(largest_error, allowed),
            reciprocity_ratio,
            worst_entry,
            negative: self.values.iter().filter(|&&v| v < 0.0).count(),
        }
    }
}

/// The larger of an error found so far and a new one, with its entry.
fn worse(found: (f64, (usize, usize)), error: f64, at: (usize, u32)) -> (f64, (usize, usize)) {
    if error > found.0 { (error, (at.0, at.1 as usize)) } else { found }
}

/// `error / allowed`, 0 where both are 0 and infinite where only `allowed` is.
fn ratio(error: f64, allowed: f64) -> f64 {
    if error == 0.0 { 0.0 } else { error / allowed }
}
