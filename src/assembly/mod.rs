//! Assembly of the collocation matrix K of (2.43): `K[i][c] = rho_i/π ∫_{Δ_j} V G φ_c dS` for node i
//! and basis function c of element j, over the pair plan of [`crate::visibility`].
//!
//! Rows are independent and assembled in parallel; for each (node, face) the face view is computed
//! once, and elements of unobstructed faces skip all visibility work.

mod integrator;
mod matrix;
mod memory;
mod options;
mod pairs;
mod problem;
mod rows;
mod thin;

pub use integrator::PairIntegrator;
pub(crate) use integrator::{FullPair, LaneObserver, push_fan};
pub use matrix::CollocationMatrix;
pub use memory::{
    MEMORY_SHARE, allowance_source, available_memory, check_fits, gib, memory_allowance,
    memory_limit, parse_size, peak_rss_bytes, resident_bytes, set_memory_limit, size_text,
};
pub use options::{AssemblyOptions, Quadrature, QuadratureRule};
pub use pairs::{CpuPairs, CutEvaluation, CutValues, FaceCut, PairEvaluation, PairTask};
pub use problem::Problem;
pub(crate) use rows::face_boxes;
pub use rows::{Assembly, apply_at, assemble};
pub use thin::{ThinColumns, recompute_thin_columns};

#[cfg(test)]
mod tests;
