//! The accuracy settings of a view factor computation ([`ViewFactorOptions`]) and the limit on
//! splitting an outer patch ([`MAX_SPLITS`]): what a caller chooses, apart from the scene.

use crate::error::{Error, Result};

/// Accuracy settings.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ViewFactorOptions {
    /// Absolute tolerance on each F_ij: the sum of its patches' error estimates (default 1e-10);
    /// on each touching triangle, also the tanh-sinh rule's on the mean of its integrand.
    pub tolerance: f64,
    /// Finest tanh-sinh level: step 2^-max_level (default 3).
    pub max_level: u32,
    /// Most times a touching part is split into four when the levels disagree (default 0).
    pub max_depth: u32,
    /// Integrate F_ij and F_ji each, so that reciprocity checks the accuracy (twice the work);
    /// otherwise each pair once, over the element of smaller area (default).
    pub each_direction: bool,
}

impl Default for ViewFactorOptions {
    fn default() -> Self {
        Self { tolerance: 1e-10, max_level: 3, max_depth: 0, each_direction: false }
    }
}

impl ViewFactorOptions {
    /// Refuses a tolerance that is not positive and a split depth beyond 6.
    pub fn validate(&self) -> Result<()> {
        if !(self.tolerance.is_finite() && self.tolerance > 0.0) {
            return Err(Error::InvalidParameter {
                name: "tolerance",
                value: self.tolerance.to_string(),
                reason: "must be positive".into(),
            });
        }
        if self.max_depth > 6 {
            return Err(Error::InvalidParameter {
                name: "max-depth",
                value: self.max_depth.to_string(),
                reason: "at most 6 (4^6 parts of an element)".into(),
            });
        }
        Ok(())
    }
}

/// Most rounds of splitting an outer patch: deeper, it is settled with its estimate (which
/// the reported `error_estimate` then shows).
pub const MAX_SPLITS: u32 = 6;
