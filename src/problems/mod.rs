//! Test problems of the paper (sec. 3.2): true solutions u on the 4-piece and 5-piece surfaces,
//! and the emissivity `E = u - (rho/π) ∫ u G V dS` at the collocation nodes (or any points of S)
//! that makes u the solution; and emission cases given by the user, many right-hand sides for one
//! operator.

mod cases;
mod emission;
mod solutions;

pub use cases::EmissionCases;
pub use emission::{Emission, EmissionOptions, emission_at};
pub use solutions::{FaceFunction, SolutionName, TrueSolution};
