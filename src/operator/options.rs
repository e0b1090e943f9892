//! The choices a run makes about its operator: dense or compressed, the compression's
//! tolerance and clusters, and whether shadowed blocks are made.

use serde::Serialize;

use crate::assembly::{Problem, gib, memory_allowance};
use crate::error::{Error, Result};

crate::vocabulary::named_options! {
    /// Which operator a run stores; `auto` is dense up to [`AUTO_COMPRESSED_ABOVE`] unknowns
    /// and beyond compressed unless the faces are too small for its blocks
    /// ([`OperatorChoice::decide`]).
    #[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
    #[serde(rename_all = "lowercase")]
    pub enum OperatorChoice as "operator" {
        /// Compressed for large problems whose faces hold enough elements, else dense
        Auto = "auto" default,
        /// Every entry stored (the reference)
        Dense = "dense",
        /// Exact blocks near, low-rank blocks far
        Compressed = "compressed",
    }
}

/// What the automatic choice of operator looks at.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ProblemShape {
    /// Unknowns.
    pub dof: usize,
    /// Elements of the mesh.
    pub elements: usize,
    /// Faces of the scene.
    pub faces: usize,
}

impl ProblemShape {
    /// The shape of `problem`.
    pub fn of(problem: &Problem) -> Self {
        Self {
            dof: problem.disc.dof(),
            elements: problem.mesh.len(),
            faces: problem.scene.faces.len(),
        }
    }

    /// Mean elements per face, what both automatic choices look at.
    pub fn elements_per_face(&self) -> f64 {
        self.elements as f64 / self.faces.max(1) as f64
    }
}

impl OperatorChoice {
    /// Whether a problem of this shape is compressed, and for [`OperatorChoice::Auto`] above
    /// [`AUTO_COMPRESSED_ABOVE`] unknowns, what decided it. A cluster of the compressed
    /// operator lies on one face, so faces of few elements (a city's walls at refine 0) make
    /// its blocks single pairs, each classified by a shaft test: slower than the dense row
    /// walk. Such a problem stays dense while its matrix fits in memory.
    pub fn decide(self, shape: ProblemShape) -> (bool, Option<String>) {
        match self {
            Self::Dense => (false, None),
            Self::Compressed => (true, None),
            Self::Auto if shape.dof <= AUTO_COMPRESSED_ABOVE => (false, None),
            Self::Auto => {
                let per_face = shape.elements_per_face();
                let dense_bytes = 8.0 * (shape.dof as f64).powi(2);
                let fits = memory_allowance().is_none_or(|a| dense_bytes <= a);
                let dense_gib = gib(dense_bytes);
                let (compressed, why) = if !fits {
                    (true, format!("the dense matrix would need {dense_gib:.1} GiB"))
                } else if per_face < MIN_ELEMENTS_PER_FACE {
                    let why = format!(
                        "{per_face:.1} elements per face, fewer than {MIN_ELEMENTS_PER_FACE}: \
                         the compressed operator's blocks would be a few pairs each; the dense \
                         matrix needs {dense_gib:.1} GiB"
                    );
                    (false, why)
                } else {
                    (true, format!("{} unknowns, {per_face:.0} elements per face", shape.dof))
                };
                let name = if compressed { Self::Compressed.name() } else { Self::Dense.name() };
                (compressed, Some(format!("operator auto: {name} ({why})")))
            }
        }
    }
}

/// Above this many unknowns [`OperatorChoice::Auto`] compresses (docs/performance.md: the
/// compressed setup is faster than the dense one from about here on), where faces hold at
/// least [`MIN_ELEMENTS_PER_FACE`] elements on average.
pub const AUTO_COMPRESSED_ABOVE: usize = 12_000;

/// Mean elements per face below which [`OperatorChoice::Auto`] keeps the dense matrix while it
/// fits (docs/performance.md: the generated cities).
pub const MIN_ELEMENTS_PER_FACE: f64 = 16.0;

/// Default relative tolerance of the low-rank blocks.
pub const DEFAULT_TOLERANCE: f64 = 1e-6;

/// How the operator is compressed.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct CompressionOptions {
    /// Relative Frobenius-norm error of each low-rank block.
    pub tolerance: f64,
    /// Admissibility: a block is far when `min(diam) <= eta * distance`.
    pub eta: f64,
    /// Near blocks of clusters this small are stored exactly rather than split further.
    pub leaf_size: usize,
    /// Blocks where visibility varies (occluders in the shaft, elements straddling a tangent
    /// plane) are split down to clusters this small: their partly visible pairs lie near a
    /// surface in pair space, so smaller leaves store fewer entries around them.
    pub mixed_leaf_size: usize,
    /// Whether admissible blocks that occluders or tangent planes cut become shadowed blocks
    /// (`operator/shadowed.rs`): compressed once without occlusion, exact only on their partly
    /// visible pairs.
    pub shadowed_blocks: ShadowedBlocks,
    /// Whether the faces each node cluster may see are found first (`operator/sight.rs`), so
    /// that the plan and the row walks skip the others without a test.
    pub face_culling: FaceCulling,
    /// The mesh's refinement level, where known: a build refused for memory names the coarser
    /// levels that would fit.
    #[serde(skip)]
    pub refine: Option<u32>,
}

crate::vocabulary::named_options! {
    /// Whether the compressed operator has shadowed blocks
    /// ([`CompressionOptions::shadowed_blocks`]).
    #[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
    #[serde(rename_all = "lowercase")]
    pub enum ShadowedBlocks as "shadowed-blocks" {
        /// Where faces hold many elements on average
        Auto = "auto" default,
        /// Always
        On = "on",
        /// Never: such blocks are split down to exact leaves and low-rank blocks
        Off = "off",
    }
}

impl ShadowedBlocks {
    /// Whether a problem of this shape has shadowed blocks, and for [`ShadowedBlocks::Auto`]
    /// what decided it. A shadowed block's one factorisation stands for the many small blocks
    /// its shadows would split it into, and its leaves are four mixed leaves wide: on large
    /// faces that saves setup and memory, on faces of a few leaves it is one more cross
    /// approximation, at a tighter tolerance, over blocks that end mostly exact.
    pub fn decide(self, shape: ProblemShape) -> (bool, Option<String>) {
        match self {
            Self::On => (true, None),
            Self::Off => (false, None),
            Self::Auto => {
                let per_face = shape.elements_per_face();
                let on = per_face >= SHADOWED_FROM_ELEMENTS_PER_FACE;
                let (name, than) = if on { ("on", "at least") } else { ("off", "fewer than") };
                let why = format!(
                    "shadowed blocks {name} ({per_face:.0} elements per face, {than} \
                     {SHADOWED_FROM_ELEMENTS_PER_FACE})"
                );
                (on, Some(why))
            }
        }
    }
}

impl From<bool> for ShadowedBlocks {
    /// [`ShadowedBlocks::On`] or [`ShadowedBlocks::Off`].
    fn from(on: bool) -> Self {
        if on { Self::On } else { Self::Off }
    }
}

/// Whether the compressed operator's build first finds the faces each node cluster may see
/// ([`CompressionOptions::face_culling`]). The operator is the same either way; only the time
/// differs.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum FaceCulling {
    /// On scenes of at least [`CULLING_FROM_FACES`] faces and at most [`CULLING_UP_TO_DOF`]
    /// unknowns.
    #[default]
    Auto,
    /// Always.
    On,
    /// Never: every face of a block is viewed, and blocks are proved empty one by one.
    Off,
}

impl FaceCulling {
    /// Whether a problem of this shape is culled.
    pub fn decide(self, shape: ProblemShape) -> bool {
        match self {
            Self::On => true,
            Self::Off => false,
            Self::Auto => shape.faces >= CULLING_FROM_FACES && shape.dof <= CULLING_UP_TO_DOF,
        }
    }
}

impl From<bool> for FaceCulling {
    /// [`FaceCulling::On`] or [`FaceCulling::Off`].
    fn from(on: bool) -> Self {
        if on { Self::On } else { Self::Off }
    }
}

/// Faces from which [`FaceCulling::Auto`] culls. Each node's walk costs about as much on a
/// city of 842 faces (a tessellated 12 x 12 city: setup 1.18 times as long with it) as on one
/// of 3 406 (24 x 24: 0.87 times as long), where the plan's blocks hidden by many houses
/// together, which the walks prune, grow like n²; the two break even between them.
pub const CULLING_FROM_FACES: usize = 2048;

/// Unknowns up to which [`FaceCulling::Auto`] culls. The nodes' walks come before the memory
/// estimate (which counts the blocks they settle), at 0.3–0.6 ms a node on one core: beyond
/// this a run that cannot fit (`city:200x200`, 641 602 unknowns) would take minutes to be
/// refused instead of seconds.
pub const CULLING_UP_TO_DOF: usize = 1 << 18;

/// Mean elements per face from which [`ShadowedBlocks::Auto`] makes shadowed blocks. On large
/// faces a shadowed block's one factorisation stands for the many small blocks its shadows
/// would split it into, and saves time and memory; on faces of a few leaves it is one more
/// cross approximation, at a tighter tolerance, over blocks that end mostly exact, and costs
/// time. The two break even at about this size (docs/performance.md, "The compressed
/// operator", measured per scene with them and without).
pub const SHADOWED_FROM_ELEMENTS_PER_FACE: f64 = 512.0;

impl Default for CompressionOptions {
    fn default() -> Self {
        // eta 2: more blocks are admissible than with eta 1, which saves setup time and memory,
        // while eta 3 gains nothing more and raises the ranks. Mixed leaves of 32: exact blocks
        // store only what is seen, so larger leaves cost little memory and save the
        // classification of many small blocks (faster than 16 on the paper's surface, the rooms
        // and the cities; 64 was faster on the cities but stored more on the rooms). Measured
        // in docs/performance.md, "The compressed operator".
        Self {
            tolerance: DEFAULT_TOLERANCE,
            eta: 2.0,
            leaf_size: 32,
            mixed_leaf_size: 32,
            shadowed_blocks: ShadowedBlocks::Auto,
            face_culling: FaceCulling::Auto,
            refine: None,
        }
    }
}

impl CompressionOptions {
    /// Refuses a tolerance outside (0, 1), a non-positive eta or an empty leaf.
    pub fn validate(&self) -> Result<()> {
        if !(self.tolerance > 0.0 && self.tolerance < 1.0) {
            return Err(Error::InvalidParameter {
                name: "compression tolerance",
                value: self.tolerance.to_string(),
                reason: "the relative error of the low-rank blocks must lie in (0, 1)".into(),
            });
        }
        if !(self.eta > 0.0 && self.eta.is_finite()) {
            return Err(Error::InvalidParameter {
                name: "eta",
                value: self.eta.to_string(),
                reason: "the admissibility parameter must be positive and finite".into(),
            });
        }
        if self.leaf_size == 0 || self.mixed_leaf_size == 0 {
            return Err(Error::InvalidParameter {
                name: "leaf size",
                value: format!("{} / {}", self.leaf_size, self.mixed_leaf_size),
                reason: "a leaf cluster holds at least one item".into(),
            });
        }
        Ok(())
    }
}
