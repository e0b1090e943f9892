//! Collocation assembler and solver for the occluded radiosity equation on polyhedral surfaces.
//!
//! The modules are listed in the order data flows through them, lowest layer first; a module
//! uses only those above it in this list (ARCHITECTURE.md; `tests/module_graph.rs` checks it).
#![warn(missing_docs)]

// Foundations: errors, progress, plane geometry and quadrature rules.
pub mod error;
pub mod geometry;
pub mod progress;
pub mod quadrature;

// The scene and the collocation integrals' closed forms.
pub mod kernels;
pub mod scene;

// The pair plan: what each point sees of each face, exactly.
pub mod visibility;

// The mesh and the collocation scheme on it.
pub mod discretization;
pub mod mesh;

// The collocation matrix, and what evaluates its entries.
pub mod assembly;

// Engines and products built on assembly: the GPU, the compressed operator, true solutions
// and their emission, view factors.
pub mod gpu;
pub mod operator;
pub mod problems;
pub mod viewfactors;

// Solving, and what is measured of a solution.
pub mod solution;
pub mod solve;
pub mod surface_error;

// Runs over several processes (MPI), and one run from a configuration, end to end.
pub mod distributed;
pub mod pipeline;

// Whole-run benchmarks and the paper's studies.
pub mod bench;
pub mod study;

// Tables, JSON, plots and files of the results.
pub mod report;

pub use error::{Error, Result};
