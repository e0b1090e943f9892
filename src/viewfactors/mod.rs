//! Element-to-element view factors `F_ij = (1/A_i) ∫_{T_i} (1/π) ∫_{T_j, visible from P} G dA_Q dA_P`.
//!
//! The inner integral is the exact point-to-element integral of the collocation matrix (closed
//! forms over the exactly visible pieces, [`crate::assembly::PairIntegrator`]). The outer one is
//! chosen per pair, as View3D chooses its method by separation, but kept exact:
//!
//! - visibility first, per pair of faces and then of elements: no occluder between the faces, or
//!   none in the shaft of the two elements ([`PairPlanner::shaft_occluders`]), and the whole
//!   element is seen from every point, with no per-point visibility work; one occluder across the
//!   whole shaft, and F_ij = 0;
//! - otherwise T_i is cut along the planes where the visible part of T_j changes shape (each
//!   occluder's plane, and the vertex–edge event planes between T_j and the occluders and between
//!   occluders, the EV and VE events of `mesh/shadow_lines.rs`, each only across the pieces
//!   that its segment of T_i reaches), and where it crosses T_j's plane, so that the integrand
//!   is smooth on every piece. An event at an edge that two
//!   occluders share, seen on its plane from the same side of both (inside a solid's shadow),
//!   changes nothing and is not cut along, nor one at a vertex all of whose edges are such.
//!   Where a corner of T_j lies on T_i (a contact along part of an edge, a point contact), or
//!   an edge of T_j crosses an edge of T_i that lies in T_j's plane (where that contact ends),
//!   T_i is also cut across there, so that the contact's ends are corners of pieces;
//! - each piece keeps only the pair's occluders in its own shaft to T_j
//!   ([`PairPlanner::polygon_shaft`]), less those that a convex solid among them hides from the
//!   whole piece (a city's buildings behind a nearer one): none, and it sees T_j whole; one
//!   across that shaft, and it sees nothing; otherwise each point's view is shadowed by those
//!   alone ([`PairPlanner::part_view_among`], no search);
//! - each piece is covered by quadrilaterals and triangles (`patch.rs`), integrated by Gauss
//!   rules (tensor through the bilinear map, collapsed on a triangle) of an order fitted to
//!   their separation from T_j and from the poles of the shadow corners the piece has (the
//!   Bernstein-ellipse bound), and again with one order more, whose difference is the error
//!   estimate; the nested tensor tanh-sinh rule takes the triangles that touch T_j (d log d
//!   behaviour beside a common edge) or a point where an occluder's edge meets T_i (where the
//!   shadow's limit depends on the direction), collapsed at the corner nearest either, with
//!   Bailey's estimate from its last three levels (`kept_error`); where T_j reaches behind
//!   T_i's plane, or the views from nine probe points differ in shape, the triangle's four
//!   quarters are integrated too, their sum kept and its difference from the whole's counted
//!   in the estimate (the levels of one rule can agree while missing the integral). The pair
//!   is globally adaptive: the patch with the largest estimate is split in four until the
//!   estimates together are within `--tolerance` on F_ij. The estimates also find what the a
//!   priori order does not see: the curved events of three mutually skew edges, which are not
//!   cut along.
//!
//! Each pair is integrated once, over the element of smaller area: F_ji = A_i F_ij / A_j then
//! has the error of F_ij times A_i / A_j <= 1 (as View3D computes A_i F_ij once per pair). With
//! [`ViewFactorOptions::each_direction`] both are integrated, and reciprocity measures the
//! accuracy (1e-12 on the paper's surfaces, 1e-9 on the occluded box). Pairs that touch or
//! nearly touch are integrated both ways whatever the option, and reconciled: a gap beyond
//! F_ij's estimate is integrated again at tighter tolerances, or counted in the estimate
//! (`reconcile.rs`), so that no kind of contact needs a rule of its own for the estimate to
//! hold.
//!
//! For open scenes, `closure.rs` gives each element's sky view factor (1 - Σ_j F_ij), conditions
//! the matrix for models that need closure (reciprocity exact, no row above 1, no entry moved
//! beyond the run's estimate) and drops pairs below a threshold.
//!
//! The files: [`view_factors`] (`compute.rs`) drives the rows, checking close pairs by
//! `reconcile.rs`; `options.rs`, `matrix.rs`, `summary.rs`, `closure.rs` and `check.rs` hold
//! what a caller sets and gets. One pair's integral is
//! `Context::pair` (`pair.rs`), on the `Context` the pairs share (`context.rs`) and what its
//! row keeps (`row.rs`): T_i cut along `events.rs`'s planes, each piece a `Part` (`part.rs`;
//! its poles from `poles.rs`, an opening from `opening.rs`) covered by patches (`patch.rs`)
//! whose cells (`cells.rs`) take the rules of `outer_rules.rs`, touching triangles
//! (`touching.rs`) the tanh-sinh rule of `outer.rs`; the integrand at each point is
//! `integrand.rs`'s, seen as `sight.rs` says.
//!
//! [`PairPlanner::shaft_occluders`]: crate::visibility::PairPlanner::shaft_occluders
//! [`PairPlanner::polygon_shaft`]: crate::visibility::PairPlanner::polygon_shaft
//! [`PairPlanner::part_view_among`]: crate::visibility::PairPlanner::part_view_among

mod cells;
mod check;
mod closure;
mod compute;
mod context;
mod events;
mod integrand;
mod matrix;
mod opening;
mod options;
mod outer;
mod outer_rules;
mod pair;
mod part;
mod patch;
mod poles;
mod reconcile;
mod row;
mod sight;
mod summary;
mod touching;

pub use check::EstimateCheck;
pub use closure::{Closure, ClosureOptions, Conditioning, Dropped};
pub use compute::view_factors;
pub use matrix::ViewFactors;
pub use options::{MAX_SPLITS, ViewFactorOptions};
pub use summary::ViewFactorSummary;

#[cfg(test)]
mod tests;
