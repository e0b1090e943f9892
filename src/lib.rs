//! Collocation assembler and solver for the occluded radiosity equation on polyhedral surfaces.
#![warn(missing_docs)]

pub mod assembly;
pub mod bench;
pub mod discretization;
pub mod error;
pub mod geometry;
pub mod gpu;
pub mod kernels;
pub mod mesh;
pub mod operator;
pub mod pipeline;
pub mod problems;
pub mod progress;
pub mod quadrature;
pub mod report;
pub mod scene;
pub mod solution;
pub mod solve;
pub mod stability;
pub mod study;
pub mod surface_error;
pub mod viewfactors;
pub mod visibility;

pub use error::{Error, Result};
