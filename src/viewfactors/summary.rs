//! The summary of a view factor computation ([`ViewFactorSummary`]), what reports print and
//! serialize.

use serde::Serialize;

use super::closure::Closure;
use super::matrix::ViewFactors;

/// Summary of a view factor computation, for reports.
#[derive(Clone, Debug, Serialize)]
pub struct ViewFactorSummary {
    /// Scene name.
    pub surface: String,
    /// Number of elements.
    pub n: usize,
    /// Smallest and largest row sum of F (1 for every element of a closed scene).
    pub row_sum_min: f64,
    /// See `row_sum_min`.
    pub row_sum_max: f64,
    /// Smallest and largest sky view factor, 1 - Σ_j F_ij (0 for a closed scene).
    pub sky_view_factor_min: f64,
    /// See `sky_view_factor_min`.
    pub sky_view_factor_max: f64,
    /// max |A_i F_ij - A_j F_ji| / max(A_i F_ij).
    pub reciprocity_error: f64,
    /// Largest estimated quadrature error of an entry.
    pub error_estimate: f64,
    /// Point-to-element integrals evaluated.
    pub evaluations: u64,
    /// Whether F_ij and F_ji were integrated each, so that `reciprocity_error` measures the
    /// accuracy; otherwise each pair once, and reciprocity holds by construction.
    pub each_direction: bool,
    /// Entries F_ij that are not zero (what a sparse output stores).
    pub nonzeros: usize,
    /// Entries that came out below zero by rounding and were stored as zero.
    pub clamped_negative: usize,
    /// What closure changed, where asked ([`ViewFactors::close`]): `conditioning` and
    /// `dropped`.
    #[serde(flatten)]
    pub closure: Closure,
    /// Wall time.
    pub seconds: f64,
}

impl ViewFactors {
    /// The summary of these view factors of scene `surface`, computed in `seconds`.
    pub fn summary(&self, surface: &str, seconds: f64) -> ViewFactorSummary {
        let (row_sum_min, row_sum_max) = self.row_sum_range();
        ViewFactorSummary {
            surface: surface.to_string(),
            n: self.len(),
            row_sum_min,
            row_sum_max,
            sky_view_factor_min: 1.0 - row_sum_max,
            sky_view_factor_max: 1.0 - row_sum_min,
            reciprocity_error: self.reciprocity_error(),
            error_estimate: self.error_estimate,
            evaluations: self.evaluations,
            each_direction: self.each_direction,
            nonzeros: self.nonzeros(),
            clamped_negative: self.clamped,
            closure: Closure::default(),
            seconds,
        }
    }
}
