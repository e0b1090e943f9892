//! How the collocation integrals are evaluated: the exact method (sec. 4.1) or one of the paper's
//! graded quadrature methods (sec. 4.2), and their parameters.

use serde::Serialize;

use crate::error::{Error, Result};
use crate::kernels::graded::{self, GradedRule};
use crate::quadrature::ImtRule;

crate::vocabulary::named_options! {
    /// The rules for the collocation integrals by name; [`Quadrature`] carries their levels.
    #[derive(Clone, Copy, Debug, PartialEq, Eq)]
    pub enum QuadratureRule as "quadrature" {
        /// Closed forms, and for the linear method one IMT quadrature per edge (sec. 4.1)
        Exact = "exact",
        /// The paper's graded 7-point rule (sec. 4.2)
        SevenPoint = "seven-point",
        /// The paper's graded collapsed Gauss rule (sec. 4.2)
        Gauss = "gauss",
    }
}

/// The method for the collocation integrals (paper sec. 4.2).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
#[serde(tag = "quadrature", rename_all = "kebab-case")]
pub enum Quadrature {
    /// Closed forms, and for the linear method one IMT quadrature per edge (sec. 4.1).
    Exact,
    /// Composite Stroud T2:5-1 over 4^L subtriangles, L <= `max_level` ([`graded`]).
    SevenPoint {
        /// MaxLev.
        max_level: u32,
        /// The level is MaxLev while the node is within `near_ratio` element diameters.
        near_ratio: f64,
    },
    /// Collapsed Gauss–Legendre with 2^(`ibase` + L) points per dimension, L <= `max_level`.
    Gauss {
        /// IBase.
        ibase: u32,
        /// MaxLev.
        max_level: u32,
        /// The level is MaxLev while the node is within `near_ratio` element diameters.
        near_ratio: f64,
    },
}

/// Largest number of points per element of a graded rule (keeps a mistyped level from running for
/// hours).
const MAX_POINTS: usize = 1 << 16;

impl Quadrature {
    /// The paper's 7-point method for Table 4.1 (MaxLev 3) with our default grading.
    pub const PAPER_SEVEN_POINT: Self =
        Self::SevenPoint { max_level: 3, near_ratio: graded::DEFAULT_NEAR };

    /// The paper's Gauss method with (IBase, MaxLev) and our default grading.
    pub fn paper_gauss(ibase: u32, max_level: u32) -> Self {
        Self::Gauss { ibase, max_level, near_ratio: graded::DEFAULT_NEAR }
    }

    /// The rule `rule` at these levels (used by the graded rules only), validated.
    pub fn named(
        rule: QuadratureRule,
        ibase: u32,
        max_level: u32,
        near_ratio: f64,
    ) -> Result<Self> {
        let q = match rule {
            QuadratureRule::Exact => Self::Exact,
            QuadratureRule::SevenPoint => Self::SevenPoint { max_level, near_ratio },
            QuadratureRule::Gauss => Self::Gauss { ibase, max_level, near_ratio },
        };
        q.validate()?;
        Ok(q)
    }

    /// The rule's name.
    pub fn rule(&self) -> QuadratureRule {
        match self {
            Self::Exact => QuadratureRule::Exact,
            Self::SevenPoint { .. } => QuadratureRule::SevenPoint,
            Self::Gauss { .. } => QuadratureRule::Gauss,
        }
    }

    /// `exact`, `seven-point` or `gauss`.
    pub fn name(&self) -> &'static str {
        self.rule().name()
    }

    /// A short label with the parameters, e.g. `gauss(1,4)`.
    pub fn label(&self) -> String {
        match *self {
            Self::Exact => self.name().into(),
            Self::SevenPoint { max_level, near_ratio } if near_ratio == graded::DEFAULT_NEAR => {
                format!("seven-point({max_level})")
            }
            Self::SevenPoint { max_level, near_ratio } => {
                format!("seven-point({max_level}; near {near_ratio})")
            }
            Self::Gauss { ibase, max_level, near_ratio } if near_ratio == graded::DEFAULT_NEAR => {
                format!("gauss({ibase},{max_level})")
            }
            Self::Gauss { ibase, max_level, near_ratio } => {
                format!("gauss({ibase},{max_level}; near {near_ratio})")
            }
        }
    }

    /// Checks the parameters.
    pub fn validate(&self) -> Result<()> {
        let (near_ratio, points) = match *self {
            Self::Exact => return Ok(()),
            Self::SevenPoint { max_level, near_ratio } => {
                (near_ratio, 7usize.saturating_mul(4usize.saturating_pow(max_level)))
            }
            Self::Gauss { ibase, max_level, near_ratio } => {
                (near_ratio, 4usize.saturating_pow(ibase.saturating_add(max_level)))
            }
        };
        if !(near_ratio.is_finite() && near_ratio > 0.0) {
            return Err(Error::InvalidParameter {
                name: "near-ratio",
                value: near_ratio.to_string(),
                reason: "must be finite and positive".into(),
            });
        }
        if points > MAX_POINTS {
            return Err(Error::InvalidParameter {
                name: "max-level",
                value: self.label(),
                reason: format!(
                    "the finest rule would have {points} points per element; at most {MAX_POINTS}"
                ),
            });
        }
        Ok(())
    }

    /// The graded rule of the numerical methods; `None` for the exact method.
    pub fn graded_rule(&self) -> Option<GradedRule> {
        match *self {
            Self::Exact => None,
            Self::SevenPoint { max_level, near_ratio } => {
                Some(GradedRule::seven_point(max_level, near_ratio))
            }
            Self::Gauss { ibase, max_level, near_ratio } => {
                Some(GradedRule::gauss(ibase, max_level, near_ratio))
            }
        }
    }
}

/// How the collocation integrals are evaluated.
#[derive(Clone, Debug, PartialEq)]
pub struct AssemblyOptions {
    /// Exact method or a graded quadrature method.
    pub quadrature: Quadrature,
    /// Subintervals of the IMT rule for the one non-elementary moment (paper: 128); exact method.
    pub imt_nodes: usize,
    /// Use the far-field rule ([`crate::kernels::far_field::FarFieldRule::standard`]) for elements
    /// (and visible pieces) far from the node in the linear method, and its subdivided form for
    /// thin elements in both methods. Off: the paper's closed forms for every pair. Exact method
    /// only.
    pub far_field: bool,
    /// Evaluate the centroid method's closed form for fully visible elements several at a time
    /// in vector registers ([`crate::kernels::lanes`]); off: one at a time, the scalar reference
    /// (the two agree to a few ulps).
    pub lanes: bool,
}

impl Default for AssemblyOptions {
    /// The exact method with 128 IMT nodes, the far-field rule for the linear method, and the
    /// vectorised closed forms.
    fn default() -> Self {
        Self {
            quadrature: Quadrature::Exact,
            imt_nodes: ImtRule::PAPER_NODES,
            far_field: true,
            lanes: true,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parameters_are_checked() {
        assert!(Quadrature::PAPER_SEVEN_POINT.validate().is_ok());
        assert!(Quadrature::paper_gauss(1, 5).validate().is_ok());
        assert!(Quadrature::paper_gauss(4, 5).validate().is_err());
        assert!(Quadrature::SevenPoint { max_level: 9, near_ratio: 1.0 }.validate().is_err());
        let bad = Quadrature::Gauss { ibase: 1, max_level: 3, near_ratio: f64::NAN };
        assert!(bad.validate().unwrap_err().to_string().contains("near-ratio"));
    }

    #[test]
    fn labels_name_the_parameters() {
        assert_eq!(Quadrature::paper_gauss(1, 4).label(), "gauss(1,4)");
        assert_eq!(Quadrature::PAPER_SEVEN_POINT.label(), "seven-point(3)");
        let wide = Quadrature::SevenPoint { max_level: 3, near_ratio: 2.0 };
        assert_eq!(wide.label(), "seven-point(3; near 2)");
    }
}
