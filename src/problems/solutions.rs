//! The true solutions (3.2), (3.3) and (3.4), face by face.

use std::fmt;
use std::sync::Arc;

use glam::DVec3;

use crate::error::{Error, Result};
use crate::scene::{Scene, SurfaceParameters};

crate::vocabulary::named_options! {
    /// The true solutions by name; [`TrueSolution`] carries their parameters.
    #[derive(Clone, Copy, Debug, PartialEq, Eq)]
    pub enum SolutionName as "solution" {
        /// No true solution: the faces' own emission
        None = "none",
        /// u = x^2 + y^2 (3.2)
        X2y2 = "x2y2",
        /// The shadow solution (3.3), with beta and gamma
        Shadow = "shadow",
        /// The edge solution (3.4), with beta
        Edge = "edge",
    }
}

/// A known solution u of the radiosity equation (paper sec. 3.2); rho = 1.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum TrueSolution {
    /// (3.2): u = x² + y².
    X2Y2,
    /// (3.3): on S1 `ψ_γ(x, y) [(2B - x)_+ (2B - y)_+]^β` with `ψ_γ = exp(-γ (2B - x)(2B - y))`;
    /// 1 on S2, S3, S4; 0 on S5.
    Shadow {
        /// Exponent β >= 0.
        beta: f64,
        /// Decay γ.
        gamma: f64,
    },
    /// (3.4): on S1 `(A - y)^β`; 1 on S2, S3, S4; 0 on S5.
    Edge {
        /// Exponent β > 0.
        beta: f64,
    },
}

/// u restricted to one face.
#[derive(Clone)]
pub enum FaceFunction {
    /// A quadratic in global coordinates: `x·A x + b·x + c` with A symmetric.
    Quadratic {
        /// Symmetric matrix, row-major.
        a: [[f64; 3]; 3],
        /// Linear part.
        b: DVec3,
        /// Constant.
        c: f64,
    },
    /// Any function; integrated adaptively, after cutting the face along `kinks` (planes
    /// `normal·x = offset` across which u or its derivatives jump).
    General {
        /// The function.
        f: Arc<dyn Fn(DVec3) -> f64 + Send + Sync>,
        /// Planes `(normal, offset)` of the lines where u is not smooth.
        kinks: Vec<(DVec3, f64)>,
        /// Size of u on the face, for absolute tolerances.
        magnitude: f64,
    },
}

impl fmt::Debug for FaceFunction {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Quadratic { a, b, c } => write!(f, "Quadratic {{ a: {a:?}, b: {b}, c: {c} }}"),
            Self::General { kinks, magnitude, .. } => {
                write!(f, "General {{ kinks: {kinks:?}, magnitude: {magnitude} }}")
            }
        }
    }
}

impl FaceFunction {
    /// The constant function.
    pub fn constant(c: f64) -> Self {
        Self::Quadratic { a: [[0.0; 3]; 3], b: DVec3::ZERO, c }
    }

    /// Value at a point of the face.
    pub fn eval(&self, x: DVec3) -> f64 {
        match self {
            Self::Quadratic { a, b, c } => {
                let ax = DVec3::new(
                    a[0][0] * x.x + a[0][1] * x.y + a[0][2] * x.z,
                    a[1][0] * x.x + a[1][1] * x.y + a[1][2] * x.z,
                    a[2][0] * x.x + a[2][1] * x.y + a[2][2] * x.z,
                );
                x.dot(ax) + b.dot(x) + c
            }
            Self::General { f, .. } => f(x),
        }
    }
}

impl TrueSolution {
    /// Command-line name: `x2y2`, `shadow`, `edge`.
    pub fn name(&self) -> &'static str {
        let name = match self {
            Self::X2Y2 => SolutionName::X2y2,
            Self::Shadow { .. } => SolutionName::Shadow,
            Self::Edge { .. } => SolutionName::Edge,
        };
        name.name()
    }

    /// The solution named `name` with the given parameters (β, γ as applicable); `none` is no
    /// solution. β and γ given to a solution without them are refused.
    pub fn named(
        name: SolutionName,
        beta: Option<f64>,
        gamma: Option<f64>,
    ) -> Result<Option<Self>> {
        let sol = match name {
            SolutionName::None | SolutionName::X2y2 if beta.is_some() || gamma.is_some() => {
                return Err(Error::InvalidParameter {
                    name: "beta/gamma",
                    value: "given".into(),
                    reason: "beta and gamma belong to the shadow or edge solution".into(),
                });
            }
            SolutionName::None => return Ok(None),
            SolutionName::X2y2 => Self::X2Y2,
            SolutionName::Shadow => {
                Self::Shadow { beta: beta.unwrap_or(1.0), gamma: gamma.unwrap_or(1.5) }
            }
            SolutionName::Edge => {
                if let Some(g) = gamma {
                    return Err(Error::InvalidParameter {
                        name: "gamma",
                        value: g.to_string(),
                        reason:
                            "the edge solution (3.4) has no gamma; it belongs to the shadow solution (3.3)"
                                .into(),
                    });
                }
                Self::Edge { beta: beta.unwrap_or(0.5) }
            }
        };
        sol.validate()?;
        Ok(Some(sol))
    }

    fn validate(&self) -> Result<()> {
        let bad = |name: &'static str, value: f64, reason: &str| {
            Err(Error::InvalidParameter { name, value: value.to_string(), reason: reason.into() })
        };
        match *self {
            Self::X2Y2 => Ok(()),
            Self::Shadow { beta, gamma } => {
                if !(beta.is_finite() && beta >= 0.0) {
                    return bad("beta", beta, "must be finite and >= 0");
                }
                if !gamma.is_finite() {
                    return bad("gamma", gamma, "must be finite");
                }
                Ok(())
            }
            Self::Edge { beta } => {
                if !(beta.is_finite() && beta > 0.0) {
                    return bad("beta", beta, "must be finite and > 0");
                }
                Ok(())
            }
        }
    }

    /// u on each face of `scene`, which must be one of the paper's surfaces for (3.3) and (3.4).
    pub fn on_faces(&self, scene: &Scene, p: &SurfaceParameters) -> Result<Vec<FaceFunction>> {
        if let Self::X2Y2 = self {
            // x² + y² in the user's coordinates, x = x' + o_x in the scene's local ones.
            let a = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 0.0]];
            let o = scene.origin;
            let (b, c) = (DVec3::new(2.0 * o.x, 2.0 * o.y, 0.0), o.x * o.x + o.y * o.y);
            return Ok(scene.faces.iter().map(|_| FaceFunction::Quadratic { a, b, c }).collect());
        }
        // (3.3) and (3.4) are written in the paper's coordinates, where its surfaces stay.
        let paper =
            scene.faces.iter().all(|f| matches!(f.name.as_str(), "S1" | "S2" | "S3" | "S4" | "S5"))
                && scene.face_index("S1").is_some()
                && scene.origin == DVec3::ZERO;
        if !paper {
            return Err(Error::SolutionNeedsPaperSurface {
                solution: self.name().into(),
                scene: scene.name.clone(),
            });
        }
        p.validate()?;
        let s1 = match *self {
            Self::Shadow { beta, gamma } => {
                let two_b = 2.0 * p.b;
                FaceFunction::General {
                    f: Arc::new(move |x: DVec3| {
                        let (dx, dy) = ((two_b - x.x).max(0.0), (two_b - x.y).max(0.0));
                        if dx == 0.0 || dy == 0.0 {
                            return 0.0;
                        }
                        (-gamma * dx * dy).exp() * (dx * dy).powf(beta)
                    }),
                    kinks: vec![(DVec3::X, two_b), (DVec3::Y, two_b)],
                    magnitude: 1.0f64.max((two_b * two_b).powf(beta)),
                }
            }
            Self::Edge { beta } => {
                let a = p.a;
                FaceFunction::General {
                    f: Arc::new(move |x: DVec3| (a - x.y).max(0.0).powf(beta)),
                    kinks: vec![],
                    magnitude: a.powf(beta),
                }
            }
            Self::X2Y2 => unreachable!("handled above"),
        };
        Ok(scene
            .faces
            .iter()
            .map(|f| match f.name.as_str() {
                "S1" => s1.clone(),
                "S5" => FaceFunction::constant(0.0),
                _ => FaceFunction::constant(1.0),
            })
            .collect())
    }
}

impl fmt::Display for TrueSolution {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::X2Y2 => f.write_str("u = x^2 + y^2 (3.2)"),
            Self::Shadow { beta, gamma } => {
                write!(f, "u of (3.3) with (beta, gamma) = ({beta}, {gamma})")
            }
            Self::Edge { beta } => write!(f, "u of (3.4) with beta = {beta}"),
        }
    }
}
