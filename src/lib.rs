//! Collocation assembler and solver for the occluded radiosity equation on polyhedral surfaces.
#![warn(missing_docs)]

pub mod geometry;
pub mod kernels;
pub mod quadrature;
