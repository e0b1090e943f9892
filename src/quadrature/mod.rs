//! Quadrature rules: Gauss–Legendre, the IMT rule of the paper (sec. 4.1), adaptive Gauss–Kronrod
//! integration (for the reference integrals, iterated over triangles), and fixed rules on the unit
//! triangle (sec. 4: Stroud's 7-point rule, composites, collapsed Gauss).

mod adaptive;
mod gauss_legendre;
mod imt;
mod tanh_sinh;
mod triangle;

pub use adaptive::{Tolerance, integrate_adaptive, integrate_triangle};
pub use gauss_legendre::GaussLegendre;
pub use imt::{IMT_LANES, ImtRule};
pub(crate) use tanh_sinh::TanhSinh;
pub use triangle::{LANES as RULE_LANES, PointLanes, TriangleRule};
