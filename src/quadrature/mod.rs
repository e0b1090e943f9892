//! One-dimensional quadrature rules: Gauss–Legendre, the IMT rule of the paper (sec. 4.1), and
//! adaptive Gauss–Kronrod integration (for the reference integrals, iterated over triangles).

mod adaptive;
mod gauss_legendre;
mod imt;

pub use adaptive::{Tolerance, integrate_adaptive, integrate_triangle};
pub use gauss_legendre::GaussLegendre;
pub use imt::ImtRule;
