//! What the pairs of one computation share ([`Context`]): the scene, its mesh and discretization,
//! the pair planner, the inner integrator and the options. Its methods live with what they do:
//! `pair.rs` (one pair's F_ij), `cells.rs`, `touching.rs`, `part.rs`, `integrand.rs`,
//! `sight.rs` and `row.rs`.

use super::options::ViewFactorOptions;
use crate::assembly::PairIntegrator;
use crate::discretization::Discretization;
use crate::mesh::Mesh;
use crate::scene::Scene;
use crate::visibility::PairPlanner;

/// What the pairs of one computation share.
pub(super) struct Context<'a> {
    pub(super) scene: &'a Scene,
    pub(super) mesh: &'a Mesh,
    pub(super) disc: &'a Discretization,
    pub(super) planner: &'a PairPlanner,
    pub(super) integrator: &'a PairIntegrator,
    pub(super) options: &'a ViewFactorOptions,
}
