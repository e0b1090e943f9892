//! Collocation assembler and solver for the occluded radiosity equation on polyhedral surfaces.
//!
//! The modules are listed by layer, lowest first, as ARCHITECTURE.md's table has them: a module
//! uses only modules of lower layers, listed above it (`tests/suite/module_graph/` checks both).
//! Each layer is a group of its own, since rustfmt sorts the modules within a group.
#![warn(missing_docs)]

// Foundations: errors, progress, the collectives of a run over several processes (MPI),
// plane geometry and quadrature rules.
pub mod distributed;
pub mod error;
pub mod geometry;
pub mod progress;
pub mod quadrature;

// The names users give the options' values.
pub mod vocabulary;

// The collocation integrals' closed forms, and the scene.
pub mod kernels;
pub mod scene;

// The pair plan: what each point sees of each face, exactly.
pub mod visibility;

// The mesh.
pub mod mesh;

// The collocation scheme on the mesh.
pub mod discretization;

// The collocation matrix, and what evaluates its entries.
pub mod assembly;

// Engines and products built on assembly: the GPU, the compressed operator, true solutions
// and their emission, view factors, direct sunlight.
pub mod gpu;
pub mod operator;
pub mod problems;
pub mod sun;
pub mod viewfactors;

// Solving, and what is measured of a solution.
pub mod solution;
pub mod solve;
pub mod surface_error;

// One run from a configuration, end to end; shortwave light under the sun and the sky.
pub mod pipeline;
pub mod shortwave;

// Whole-run benchmarks and the paper's studies.
pub mod bench;
pub mod study;

// Tables, JSON, plots and files of the results.
pub mod report;

pub use error::{Error, Result};
