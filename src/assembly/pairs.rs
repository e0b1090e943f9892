//! Values of listed (node, element) pairs, whatever computes them: the compressed operator asks
//! for its entries through [`PairEvaluation`] and does not know whether the CPU or a GPU answers.

use std::f64::consts::PI;

use rayon::prelude::*;

use super::integrator::PairIntegrator;
use crate::discretization::Discretization;
use crate::error::Result;
use crate::visibility::{ElementBoxes, FaceView, PairStats, Visibility};

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

    /// The engine's clipping of the elements of faces seen in part, where it has one: the
    /// caller then hands it each face's view instead of each element's visible pieces.
    fn clipper(&self) -> Option<&dyn CutEvaluation> {
        None
    }
}

/// The listed elements of one face that a node sees in part, for an engine that clips them
/// itself: they are classified and clipped as [`crate::visibility::PartSight::elements`] does
/// with `tree`.
pub struct FaceCut<'a> {
    /// Index of the collocation node.
    pub node: usize,
    /// The node's view of the face: the tangent plane's clip and the shadows.
    pub view: &'a FaceView,
    /// The box tree over the listed elements (face coordinates, in their order).
    pub tree: &'a ElementBoxes,
    /// The listed elements, by index.
    pub elements: &'a [usize],
}

/// What an engine made of a list of [`FaceCut`]s.
pub struct CutValues {
    /// The values of every listed element of every cut, in order (as
    /// [`PairEvaluation::evaluate`] gives them; zero for a pair seen not at all or left).
    pub values: Vec<[f64; 3]>,
    /// The classes of the pairs the engine classified.
    pub stats: PairStats,
    /// The pairs (cut, position in its list) the engine left to the caller, neither
    /// classified nor evaluated: the caller clips them on the host.
    pub left: Vec<(usize, usize)>,
}

/// Clips the elements of faces seen in part and integrates their pieces (the GPU's clipping
/// kernel, shaders/clip.wgsl).
pub trait CutEvaluation {
    /// The values of the listed elements of every cut. Large lists are split as the engine
    /// needs.
    fn evaluate_cuts(&self, cuts: &[FaceCut]) -> Result<CutValues>;
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
                let node = &self.disc.node(t.node);
                let values = self.integrator.integrate(
                    &self.disc.placed(t.element),
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
