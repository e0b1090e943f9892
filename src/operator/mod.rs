//! The compressed collocation operator for large n (ARCHITECTURE.md): K applied to vectors
//! without the dense n × n matrix, in about n log n memory and time.
//!
//! Rows (collocation nodes) and columns (elements, with their basis functions) are ordered by
//! cluster trees ([`cluster`]); the block tree pairs node clusters with element clusters
//! ([`blocks`]). Each block is one of:
//!
//! - *nothing*: every element lies in a plane with, or behind the tangent plane of, every node
//!   of the block, or the other way round, so G = 0 there;
//! - *smooth and admissible*: every element is in front of every node's plane and faces it, no
//!   occluder reaches into the shaft between the two boxes (so V = 1), and the clusters are far
//!   apart for their size; the kernel is analytic there and the block is stored as a low-rank
//!   product built by adaptive cross approximation ([`aca`]) from true collocation entries;
//! - a leaf that is neither: every entry computed exactly by the pair plan and kernels of the
//!   dense path, partly visible elements included (paper sec. 2.7), and stored as it is.
//!
//! So the only error added to the dense path is the tolerance of the low-rank blocks, which the
//! user sets, and which tests measure against the dense matrix.

pub mod aca;
mod batched;
mod blocks;
mod build;
mod built;
pub mod cluster;
mod compressed;
mod entries;
mod estimate;
mod guard;
mod options;
pub mod packed;
mod sampling;
mod saved;
mod shadowed;
mod share;
mod sight;
mod stats;
mod stored;

pub use compressed::{CompressedOperator, RankShare};
pub use estimate::MemoryEstimate;
pub use options::{
    AUTO_COMPRESSED_ABOVE, CULLING_FROM_FACES, CULLING_UP_TO_DOF, CompressionOptions,
    DEFAULT_TOLERANCE, FaceCulling, MIN_ELEMENTS_PER_FACE, OperatorChoice, ProblemShape,
    SHADOWED_FROM_ELEMENTS_PER_FACE, ShadowedBlocks,
};
pub use saved::{BinaryReader, BinaryWriter};
pub use stats::OperatorStats;
pub use stored::{F32_FROM_TOLERANCE, Precision, precision_for};

#[cfg(test)]
mod plan_tests;
#[cfg(test)]
mod tests;
