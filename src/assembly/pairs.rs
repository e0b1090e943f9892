//! Values of listed (node, element) pairs, whatever computes them: the compressed operator asks
//! for its entries through [`PairEvaluation`] and does not know whether the CPU or a GPU answers.

use std::f64::consts::PI;

use rayon::prelude::*;

use super::integrator::PairIntegrator;
use crate::discretization::Discretization;
use crate::error::Result;
use crate::visibility::Visibility;

/// One (node, element) pair to evaluate.
#[derive(Clone, Debug, PartialEq)]
pub struct PairTask {
    /// Index of the collocation node.
    pub node: usize,
    /// Index of the element.
    pub element: usize,
    /// What the node sees of the element; a skipped pair is not listed.
    pub visible: Visibility,
}

/// Evaluates batches of pairs: entries of K, rho/π included.
pub trait PairEvaluation {
    /// The values of every task (rho/π included; the first `nodes_per_element` used, the rest
    /// zero). Large batches are split as the engine needs.
    fn evaluate(&self, tasks: &[PairTask]) -> Result<Vec<[f64; 3]>>;
}

/// [`PairEvaluation`] on the CPU's threads, by the dense path's kernels.
pub struct CpuPairs<'a> {
    disc: &'a Discretization,
    integrator: &'a PairIntegrator,
}

impl<'a> CpuPairs<'a> {
    /// Evaluates the pairs of `disc` with `integrator`.
    pub fn new(disc: &'a Discretization, integrator: &'a PairIntegrator) -> Self {
        Self { disc, integrator }
    }
}

impl PairEvaluation for CpuPairs<'_> {
    fn evaluate(&self, tasks: &[PairTask]) -> Result<Vec<[f64; 3]>> {
        Ok(tasks
            .par_iter()
            .map(|t| {
                let node = &self.disc.nodes[t.node];
                let values = self.integrator.integrate(
                    &self.disc.elements[t.element],
                    self.disc.basis(t.element),
                    node.position,
                    node.normal,
                    &t.visible,
                );
                values.map(|v| v * node.rho / PI)
            })
            .collect())
    }
}
