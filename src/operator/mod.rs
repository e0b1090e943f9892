//! The compressed collocation operator for large n (ARCHITECTURE.md): K applied to vectors
//! without the dense n × n matrix, in about n log n memory and time.
//!
//! Rows (collocation nodes) and columns (elements, with their basis functions) are ordered by
//! cluster trees ([`cluster`]); the block tree pairs node clusters with element clusters
//! ([`blocks`]). Each block is one of:
//!
//! - *nothing*: every element lies in a plane with, or behind the tangent plane of, every node
//!   of the block, or the other way round, so G = 0 there;
//! - *smooth and admissible*: every element is in front of every node's plane and faces it, no
//!   occluder reaches into the shaft between the two boxes (so V = 1), and the clusters are far
//!   apart for their size; the kernel is analytic there and the block is stored as a low-rank
//!   product built by adaptive cross approximation ([`aca`]) from true collocation entries;
//! - a leaf that is neither: every entry computed exactly by the pair plan and kernels of the
//!   dense path, partly visible elements included (paper sec. 2.7), and stored as it is.
//!
//! So the only error added to the dense path is the tolerance of the low-rank blocks, which the
//! user sets, and which tests measure against the dense matrix.

pub mod aca;
mod batched;
mod blocks;
pub mod cluster;
mod estimate;
pub mod packed;
mod saved;
mod shadowed;
mod share;
mod stored;

pub use estimate::MemoryEstimate;
pub use saved::{BinaryReader, BinaryWriter};
pub use stored::{F32_FROM_TOLERANCE, Precision};

use std::f64::consts::PI;
use std::ops::Range;
use std::sync::atomic::{AtomicU64, Ordering};

use rayon::prelude::*;
use serde::Serialize;

use crate::assembly::{
    AssemblyOptions, PairEvaluation, PairIntegrator, Problem, allowance_source, memory_allowance,
    resident_bytes,
};
use crate::discretization::Discretization;
use crate::distributed::{Collective, Ranks};
use crate::error::{Error, Result};
use crate::kernels::lanes;
use crate::mesh::Mesh;
use crate::progress::{Progress, in_stage};
use crate::visibility::{
    ElementBoxes, FaceSight, KeptViews, PairPlanner, PairStats, RecentHiders, Views, Visibility,
    by_face,
};

use blocks::{
    BlockPlan, FacePairs, Located, PLAN_FAR_BYTES, PLAN_NEAR_BYTES, PlanBudget, ShadowedPart,
};
use cluster::{ClusterTree, Item};
use stored::BlockData;

/// Which operator a run stores.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum OperatorChoice {
    /// Dense up to [`AUTO_COMPRESSED_ABOVE`] unknowns; beyond, compressed unless the faces are
    /// too small for its blocks ([`OperatorChoice::decide`]).
    #[default]
    Auto,
    /// The dense matrix: every entry stored (the reference).
    Dense,
    /// Low-rank blocks far away, exact blocks near.
    Compressed,
}

/// What the automatic choice of operator looks at.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ProblemShape {
    /// Unknowns.
    pub dof: usize,
    /// Elements of the mesh.
    pub elements: usize,
    /// Faces of the scene.
    pub faces: usize,
}

impl ProblemShape {
    /// The shape of `problem`.
    pub fn of(problem: &Problem) -> Self {
        Self {
            dof: problem.disc.dof(),
            elements: problem.mesh.len(),
            faces: problem.scene.faces.len(),
        }
    }

    /// Mean elements per face, what both automatic choices look at.
    pub fn elements_per_face(&self) -> f64 {
        self.elements as f64 / self.faces.max(1) as f64
    }
}

impl OperatorChoice {
    /// Whether a problem of this shape is compressed, and for [`OperatorChoice::Auto`] above
    /// [`AUTO_COMPRESSED_ABOVE`] unknowns, what decided it. A cluster of the compressed
    /// operator lies on one face, so faces of few elements (a city's walls at refine 0) make
    /// its blocks single pairs, each classified by a shaft test: slower than the dense row
    /// walk. Such a problem stays dense while its matrix fits in memory.
    pub fn decide(self, shape: ProblemShape) -> (bool, Option<String>) {
        match self {
            Self::Dense => (false, None),
            Self::Compressed => (true, None),
            Self::Auto if shape.dof <= AUTO_COMPRESSED_ABOVE => (false, None),
            Self::Auto => {
                let per_face = shape.elements_per_face();
                let dense_bytes = 8.0 * (shape.dof as f64).powi(2);
                let fits = memory_allowance().is_none_or(|a| dense_bytes <= a);
                let gib = dense_bytes / (1u64 << 30) as f64;
                let (compressed, why) = if !fits {
                    (true, format!("the dense matrix would need {gib:.1} GiB"))
                } else if per_face < MIN_ELEMENTS_PER_FACE {
                    let why = format!(
                        "{per_face:.1} elements per face, fewer than {MIN_ELEMENTS_PER_FACE}: \
                         the compressed operator's blocks would be a few pairs each; the dense \
                         matrix needs {gib:.1} GiB"
                    );
                    (false, why)
                } else {
                    (true, format!("{} unknowns, {per_face:.0} elements per face", shape.dof))
                };
                let name = if compressed { "compressed" } else { "dense" };
                (compressed, Some(format!("operator auto: {name} ({why})")))
            }
        }
    }
}

/// Above this many unknowns [`OperatorChoice::Auto`] compresses (docs/performance.md: the
/// compressed setup is faster than the dense one from about here on), where faces hold at
/// least [`MIN_ELEMENTS_PER_FACE`] elements on average.
pub const AUTO_COMPRESSED_ABOVE: usize = 12_000;

/// Mean elements per face below which [`OperatorChoice::Auto`] keeps the dense matrix while it
/// fits (docs/performance.md: the generated cities).
pub const MIN_ELEMENTS_PER_FACE: f64 = 16.0;

/// Default relative tolerance of the low-rank blocks.
pub const DEFAULT_TOLERANCE: f64 = 1e-6;

/// How the operator is compressed.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct CompressionOptions {
    /// Relative Frobenius-norm error of each low-rank block.
    pub tolerance: f64,
    /// Admissibility: a block is far when `min(diam) <= eta * distance`.
    pub eta: f64,
    /// Near blocks of clusters this small are stored exactly rather than split further.
    pub leaf_size: usize,
    /// Blocks where visibility varies (occluders in the shaft, elements straddling a tangent
    /// plane) are split down to clusters this small: their partly visible pairs lie near a
    /// surface in pair space, so smaller leaves store fewer entries around them.
    pub mixed_leaf_size: usize,
    /// Whether admissible blocks that occluders or tangent planes cut become shadowed blocks
    /// (`operator/shadowed.rs`): compressed once without occlusion, exact only on their partly
    /// visible pairs.
    pub shadowed_blocks: ShadowedBlocks,
    /// The mesh's refinement level, where known: a build refused for memory names the coarser
    /// levels that would fit.
    #[serde(skip)]
    pub refine: Option<u32>,
}

/// Whether the compressed operator has shadowed blocks ([`CompressionOptions::shadowed_blocks`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum ShadowedBlocks {
    /// Where faces hold at least [`SHADOWED_FROM_ELEMENTS_PER_FACE`] elements on average
    /// ([`ShadowedBlocks::decide`]).
    #[default]
    Auto,
    /// Always.
    On,
    /// Never: such blocks are split down to exact leaves and low-rank blocks.
    Off,
}

impl ShadowedBlocks {
    /// Whether a problem of this shape has shadowed blocks, and for [`ShadowedBlocks::Auto`]
    /// what decided it. A shadowed block's one factorisation stands for the many small blocks
    /// its shadows would split it into, and its leaves are four mixed leaves wide: on large
    /// faces that saves setup and memory, on faces of a few leaves it is one more cross
    /// approximation, at a tighter tolerance, over blocks that end mostly exact.
    pub fn decide(self, shape: ProblemShape) -> (bool, Option<String>) {
        match self {
            Self::On => (true, None),
            Self::Off => (false, None),
            Self::Auto => {
                let per_face = shape.elements_per_face();
                let on = per_face >= SHADOWED_FROM_ELEMENTS_PER_FACE;
                let (name, than) = if on { ("on", "at least") } else { ("off", "fewer than") };
                let why = format!(
                    "shadowed blocks {name} ({per_face:.0} elements per face, {than} \
                     {SHADOWED_FROM_ELEMENTS_PER_FACE})"
                );
                (on, Some(why))
            }
        }
    }
}

impl From<bool> for ShadowedBlocks {
    /// [`ShadowedBlocks::On`] or [`ShadowedBlocks::Off`].
    fn from(on: bool) -> Self {
        if on { Self::On } else { Self::Off }
    }
}

/// Mean elements per face from which [`ShadowedBlocks::Auto`] makes shadowed blocks. On large
/// faces a shadowed block's one factorisation stands for the many small blocks its shadows
/// would split it into, and saves time and memory; on faces of a few leaves it is one more
/// cross approximation, at a tighter tolerance, over blocks that end mostly exact, and costs
/// time. The two break even at about this size (docs/performance.md, "The compressed
/// operator", measured per scene with them and without).
pub const SHADOWED_FROM_ELEMENTS_PER_FACE: f64 = 512.0;

impl Default for CompressionOptions {
    fn default() -> Self {
        // eta 2: more blocks are admissible than with eta 1, which saves setup time and memory,
        // while eta 3 gains nothing more and raises the ranks. Mixed leaves of 32: exact blocks
        // store only what is seen, so larger leaves cost little memory and save the
        // classification of many small blocks (faster than 16 on the paper's surface, the rooms
        // and the cities; 64 was faster on the cities but stored more on the rooms). Measured
        // in docs/performance.md, "The compressed operator".
        Self {
            tolerance: DEFAULT_TOLERANCE,
            eta: 2.0,
            leaf_size: 32,
            mixed_leaf_size: 32,
            shadowed_blocks: ShadowedBlocks::Auto,
            refine: None,
        }
    }
}

impl CompressionOptions {
    /// Refuses a tolerance outside (0, 1), a non-positive eta or an empty leaf.
    pub fn validate(&self) -> Result<()> {
        if !(self.tolerance > 0.0 && self.tolerance < 1.0) {
            return Err(Error::InvalidParameter {
                name: "compression tolerance",
                value: self.tolerance.to_string(),
                reason: "the relative error of the low-rank blocks must lie in (0, 1)".into(),
            });
        }
        if !(self.eta > 0.0 && self.eta.is_finite()) {
            return Err(Error::InvalidParameter {
                name: "eta",
                value: self.eta.to_string(),
                reason: "the admissibility parameter must be positive and finite".into(),
            });
        }
        if self.leaf_size == 0 || self.mixed_leaf_size == 0 {
            return Err(Error::InvalidParameter {
                name: "leaf size",
                value: format!("{} / {}", self.leaf_size, self.mixed_leaf_size),
                reason: "a leaf cluster holds at least one item".into(),
            });
        }
        Ok(())
    }
}

/// Block statistics of a compressed operator.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct OperatorStats {
    /// Bytes of the stored blocks (values and their index data); reports carry it beside the
    /// dense operator's as `operator_bytes`.
    #[serde(skip)]
    pub operator_bytes: u64,
    /// Entries stored as they are (exact near blocks).
    pub near_entries: u64,
    /// Blocks stored exactly.
    pub near_blocks: u64,
    /// Low-rank blocks.
    pub far_blocks: u64,
    /// Entries the low-rank blocks stand for.
    pub far_entries: u64,
    /// Largest rank of a low-rank block.
    pub max_rank: usize,
    /// Blocks found to hold nothing (G = 0 throughout) and not stored.
    pub empty_blocks: u64,
    /// Admissible blocks kept exact because their rank would not have saved memory.
    pub incompressible_blocks: u64,
    /// Of `operator_bytes`, the low-rank blocks' factors (a shadowed block's once, however
    /// many of its parts read them); the rest is the exact entries and the blocks' index. Not
    /// among [`OperatorStats::counts`]: a saved operator's bytes are counted anew from the
    /// blocks read (a shadowed block's parts are written as blocks of their own).
    pub low_rank_bytes: u64,
    /// Shadowed blocks (`--shadowed-blocks`), each one factorisation that its parts read: seen
    /// whole among `far_blocks`, leaves among `near_blocks`. None in a loaded operator, whose
    /// file holds the parts as blocks of their own.
    pub shadowed_blocks: u64,
}

impl OperatorStats {
    /// Length of [`OperatorStats::counts`].
    pub const COUNTS: usize = 8;

    /// The statistics in a fixed order (bytes, near entries, near blocks, far blocks, far
    /// entries, largest rank, empty blocks, incompressible blocks), as saved operators and
    /// messages between processes carry them.
    pub fn counts(&self) -> [u64; Self::COUNTS] {
        [
            self.operator_bytes,
            self.near_entries,
            self.near_blocks,
            self.far_blocks,
            self.far_entries,
            self.max_rank as u64,
            self.empty_blocks,
            self.incompressible_blocks,
        ]
    }

    /// The statistics of [`OperatorStats::counts`].
    pub fn from_counts(
        [
            operator_bytes,
            near_entries,
            near_blocks,
            far_blocks,
            far_entries,
            max_rank,
            empty_blocks,
            incompressible_blocks,
        ]: [u64; Self::COUNTS],
    ) -> Self {
        Self {
            operator_bytes,
            near_entries,
            near_blocks,
            far_blocks,
            far_entries,
            max_rank: max_rank as usize,
            empty_blocks,
            incompressible_blocks,
            low_rank_bytes: 0,
            shadowed_blocks: 0,
        }
    }
}

/// The statistics of two parts of one operator together: counts add, the largest rank is the
/// larger one.
impl std::ops::AddAssign for OperatorStats {
    fn add_assign(&mut self, o: Self) {
        self.operator_bytes += o.operator_bytes;
        self.near_entries += o.near_entries;
        self.near_blocks += o.near_blocks;
        self.far_blocks += o.far_blocks;
        self.far_entries += o.far_entries;
        self.max_rank = self.max_rank.max(o.max_rank);
        self.empty_blocks += o.empty_blocks;
        self.incompressible_blocks += o.incompressible_blocks;
        self.low_rank_bytes += o.low_rank_bytes;
        self.shadowed_blocks += o.shadowed_blocks;
    }
}

/// A block of K: rows `rows` of the node order, columns of the elements `cols` of the element
/// order (each with its basis functions).
#[derive(Clone, Debug)]
struct Block {
    /// Rows and element columns as u32 (four bytes less each than usize: an operator keeps a
    /// million blocks and more).
    rows: Range<u32>,
    cols: Range<u32>,
    data: BlockData,
}

/// K as exact near blocks and low-rank far blocks.
#[derive(Clone, Debug)]
pub struct CompressedOperator {
    dof: usize,
    per: usize,
    /// `node_order[k]`: the node at row k of the blocks (the node cluster tree's order).
    node_order: Vec<usize>,
    /// `element_order[k]`: the element at column group k (the element cluster tree's order).
    element_order: Vec<usize>,
    blocks: Vec<Block>,
    /// Statistics of the blocks.
    pub stats: OperatorStats,
    /// Pair classes of the exact blocks.
    pub pairs: PairStats,
    /// Rows of nodes that reflect nothing (rho = 0): zero, u = E there.
    pub zero_rows: usize,
    /// The GPU that evaluated the entries (name and backend), if one did.
    pub device: Option<String>,
    /// In a distributed run, this rank's part: it holds only its blocks, and the products sum
    /// every rank's. `stats` and `pairs` are then the whole operator's.
    pub share: Option<RankShare>,
    /// What its build was estimated to hold at its peak before it began (none for an operator
    /// read from a file).
    pub memory_estimate: Option<Box<MemoryEstimate>>,
}

/// A rank's part of a distributed compressed operator.
#[derive(Clone, Debug)]
pub struct RankShare {
    /// The ranks the operator is spread over.
    pub ranks: Ranks,
    /// Bytes of this rank's blocks.
    pub operator_bytes: u64,
    /// Time of the build this rank spent waiting for the others in collectives.
    pub waited_seconds: f64,
}

/// Admissible blocks whose break-even rank is below this are stored exactly.
const MIN_USEFUL_RANK: usize = 4;

impl CompressedOperator {
    /// Builds K for `problem`; `progress` counts the blocks (stage
    /// `compression`). With `batches` (the GPU's pair kernel), the entries are evaluated by it in
    /// batches (the exact blocks' pairs planned on the host, the cross approximations in
    /// lockstep), else on the CPU block by block.
    pub fn build(
        problem: &Problem,
        assembly: &AssemblyOptions,
        options: &CompressionOptions,
        batches: Option<&dyn PairEvaluation>,
        progress: &dyn Progress,
    ) -> Result<Self> {
        Self::build_with(problem, assembly, options, batches, progress, None)
    }

    /// As [`CompressedOperator::build`], this rank's part of the operator spread over `ranks`
    /// ([`crate::distributed`]): every rank calls it with the same problem. The block plan is
    /// walked in parts and gathered, each rank builds its share of the blocks, and the
    /// products sum the ranks' parts, so that every rank gets the whole `K x`.
    pub fn build_shared(
        problem: &Problem,
        assembly: &AssemblyOptions,
        options: &CompressionOptions,
        batches: Option<&dyn PairEvaluation>,
        progress: &dyn Progress,
        ranks: &Ranks,
    ) -> Result<Self> {
        Self::build_with(problem, assembly, options, batches, progress, Some(ranks))
    }

    fn build_with(
        problem: &Problem,
        assembly: &AssemblyOptions,
        options: &CompressionOptions,
        batches: Option<&dyn PairEvaluation>,
        progress: &dyn Progress,
        ranks: Option<&Ranks>,
    ) -> Result<Self> {
        let Problem { scene, mesh, disc, planner, .. } = problem;
        let waited_before = ranks.map(|r| r.traffic().seconds);
        options.validate()?;
        assembly.quadrature.validate()?;
        let (shadowed, why) = options.shadowed_blocks.decide(ProblemShape::of(problem));
        if let Some(why) = why {
            progress.note(&why);
        }
        let options = &CompressionOptions { shadowed_blocks: shadowed.into(), ..*options };
        let per = disc.method.nodes_per_element();
        // Everything the build holds counts from here on (the guard's look at the resident
        // memory): the cluster trees, the plan, the lists, the blocks.
        let mut guard = MemoryGuard::new(disc.dof());
        let precision = Precision::for_tolerance(options.tolerance);
        let integrator = match precision {
            Precision::F32 => PairIntegrator::for_single_precision(disc.method, assembly),
            Precision::F64 => PairIntegrator::new(disc.method, assembly),
        };
        let faces = FacePairs::new(scene, planner, options);
        let (nodes, elements) = in_stage(progress, "blocks", || cluster_trees(mesh, disc, options));
        let entries = Entries {
            mesh,
            disc,
            planner,
            integrator: &integrator,
            nodes: &nodes,
            elements: &elements,
            per,
            precision,
        };
        // Before the plan is walked and its blocks built, what they will hold is estimated from
        // a sample of it, and a run that cannot fit is refused now rather than after minutes.
        let size = ranks.map_or(1, |r| r.size());
        let estimate = in_stage(progress, "memory estimate", || {
            estimate_memory(&entries, &faces, options, scene.faces.len(), size)
        });
        progress.note(&estimate.note());
        guard.estimate = Some(estimate);
        let refusal = guard.refusal(&estimate, options.refine);
        let mine = u64::from(refusal.is_some());
        // Every rank refuses if one does (the others would wait for it in the collectives).
        if ranks.map_or(mine == 1, |r| r.gather(&[mine]).iter().any(|v| v[0] == 1)) {
            return Err(refusal.unwrap_or_else(|| guard.refused_elsewhere(&estimate)));
        }
        // The plan stops where its lists pass what the trees leave of the allowance.
        let budget = guard.plan_budget(estimate.trees);
        let plan = in_stage(progress, "blocks", || match ranks {
            Some(ranks) => {
                let whole = BlockPlan::new_shared(
                    &nodes,
                    &elements,
                    &faces,
                    options,
                    &**ranks,
                    budget.as_ref(),
                );
                let rank = (ranks.rank(), ranks.size());
                share::share_of(&whole, &nodes, &elements, per, rank)
            }
            None => BlockPlan::new(&nodes, &elements, &faces, options, budget.as_ref()),
        });
        if let Some(budget) = &budget {
            let over = budget.is_over();
            let over =
                ranks.map_or(over, |r| r.gather(&[u64::from(over)]).iter().any(|v| v[0] == 1));
            if over {
                return Err(guard.plan_too_large(budget, estimate.trees));
            }
        }
        // What the exact blocks store for certain, with the build's lists and the blocks'
        // slots, must fit before any is computed (counting every exact block in full would
        // refuse runs that fit: a partly visible block stores anything from none to all of its
        // entries, and on a city most store few); then every block built counts, and the build
        // stops where it would pass the allowance.
        let reflects = |i: usize| disc.nodes[i].rho != 0.0;
        let certain = plan.certain_near_entries(&nodes, &elements, per, reflects);
        guard.check(precision.bytes() * certain + build_list_bytes(&plan))?;

        let sub_blocks = shadowed::sub_blocks(&plan.shadowed);
        progress.start("compression", plan.near.len() + plan.far.len() + sub_blocks);
        let tolerance = options.tolerance;
        let built = match batches {
            Some(evaluator) => batched::build_blocks(
                &entries, &plan, &faces, tolerance, evaluator, &guard, progress,
            )?,
            None => build_block_by_block(&entries, &plan, &faces, tolerance, &guard, progress)?,
        };
        progress.finish();

        let (blocks, mut stats, mut pairs) = kept_blocks(built, plan.empty, per);
        stats.operator_bytes += order_bytes(disc.dof(), per);
        let share = ranks.map(|ranks| {
            let operator_bytes = stats.operator_bytes;
            (stats, pairs) = summed_over(&**ranks, stats, pairs);
            let waited_seconds = ranks.traffic().seconds - waited_before.unwrap_or(0.0);
            RankShare { ranks: ranks.clone(), operator_bytes, waited_seconds }
        });
        let zero_rows = disc.nodes.iter().filter(|n| n.rho == 0.0).count();
        Ok(Self {
            dof: disc.dof(),
            per,
            node_order: nodes.order,
            element_order: elements.order,
            blocks,
            stats,
            pairs,
            zero_rows,
            device: None,
            share,
            memory_estimate: Some(Box::new(estimate)),
        })
    }

    /// Number of unknowns.
    pub fn dof(&self) -> usize {
        self.dof
    }

    /// `K x`: the blocks in parallel, each adding into its rows.
    pub fn apply(&self, x: &[f64]) -> Vec<f64> {
        let mut y = self.products(&[x], |data, x, y| data.apply_add(x, y));
        y.pop().expect("one product")
    }

    /// `K x` for every `x` in `xs` together: each block is read once for all of them (many
    /// right-hand sides cost the operator's memory traffic once per round, not once per
    /// vector). Each product equals [`CompressedOperator::apply`]'s up to the order of sums.
    pub fn apply_many(&self, xs: &[&[f64]]) -> Vec<Vec<f64>> {
        let m = xs.len();
        if m <= 1 {
            return xs.iter().map(|x| self.apply(x)).collect();
        }
        self.products(xs, |data, x, y| data.apply_add_many(x, y, m))
    }

    /// `K x` for every `x` in `xs`, the vectors interleaved in the blocks' orders (`x[k * m +
    /// v]`: vector v at column k, m vectors) and each block adding its part by `add(data, x, y)`
    /// into its rows, the blocks in parallel.
    fn products(
        &self,
        xs: &[&[f64]],
        add: impl Fn(&BlockData, &[f64], &mut [f64]) + Sync,
    ) -> Vec<Vec<f64>> {
        let (m, per, dof) = (xs.len(), self.per, self.dof);
        let mut xp = vec![0.0; dof * m];
        for (k, &e) in self.element_order.iter().enumerate() {
            for q in 0..per {
                let column = k * per + q;
                for (v, x) in xs.iter().enumerate() {
                    xp[column * m + v] = x[e * per + q];
                }
            }
        }
        let mut yp = self
            .blocks
            .par_iter()
            .with_min_len(16)
            .fold(
                || vec![0.0; dof * m],
                |mut y, b| {
                    let xs = &xp[b.col_range().start * per * m..b.col_range().end * per * m];
                    add(&b.data, xs, &mut y[b.row_range().start * m..b.row_range().end * m]);
                    y
                },
            )
            .reduce(
                || vec![0.0; dof * m],
                |mut a, b| {
                    a.iter_mut().zip(&b).for_each(|(a, b)| *a += b);
                    a
                },
            );
        if let Some(share) = &self.share {
            share.ranks.sum(&mut yp);
        }
        let mut ys = vec![vec![0.0; dof]; m];
        for (k, &i) in self.node_order.iter().enumerate() {
            for (v, y) in ys.iter_mut().enumerate() {
                y[i] = yp[k * m + v];
            }
        }
        ys
    }

    /// Largest `max_i |(K_c x - K x)_i| / max_i |(K x)_i|` against a reference product
    /// `x -> K x` (the dense matrix's, or another compressed operator's) over three vectors:
    /// ones (the row sums), one of one sign, one of both signs.
    pub fn max_product_difference(&self, reference: &dyn Fn(&[f64]) -> Vec<f64>) -> f64 {
        let n = self.dof;
        let vectors: [Vec<f64>; 3] = [
            vec![1.0; n],
            (0..n).map(|i| 1.0 + (i as f64 * 0.37).sin()).collect(),
            (0..n).map(|i| (i as f64 * 1.3).cos()).collect(),
        ];
        vectors
            .iter()
            .map(|x| {
                let (a, b) = (self.apply(x), reference(x));
                let diff = a.iter().zip(&b).fold(0.0f64, |m, (p, q)| m.max((p - q).abs()));
                diff / b.iter().fold(0.0f64, |m, v| m.max(v.abs())).max(f64::MIN_POSITIVE)
            })
            .fold(0.0, f64::max)
    }
}

impl Block {
    /// Block `rows` × `cols` holding `data`.
    fn new(rows: Range<usize>, cols: Range<usize>, data: BlockData) -> Self {
        // An operator of 2^32 unknowns would take far more memory than any machine has.
        let narrow = |r: Range<usize>| -> Range<u32> {
            let fit = |v: usize| u32::try_from(v).expect("fewer than 2^32 rows and columns");
            fit(r.start)..fit(r.end)
        };
        Block { rows: narrow(rows), cols: narrow(cols), data }
    }

    /// A block of no rows holding nothing (a slot before its block is built).
    fn nothing() -> Self {
        Block::new(0..0, 0..0, BlockData::exact(Vec::new()))
    }

    /// Its rows, in the node order.
    fn row_range(&self) -> Range<usize> {
        self.rows.start as usize..self.rows.end as usize
    }

    /// Its columns, in the element order (elements, each with its basis functions).
    fn col_range(&self) -> Range<usize> {
        self.cols.start as usize..self.cols.end as usize
    }

    /// Stores an exact block by what it holds, as soon as it is built, in `precision`:
    /// nothing where every pair is hidden (it is then counted empty and left out), its
    /// non-zero entries alone where that takes fewer bytes (hidden pairs in a block seen
    /// through slats or between buildings), so that memory follows the pairs that are seen.
    fn compact(&mut self, precision: Precision) {
        let data = std::mem::replace(&mut self.data, BlockData::exact(Vec::new()));
        self.data = data.compacted(self.row_range().len(), precision);
    }

    /// Bytes of its stored values (and of the column indices of a sparse block).
    fn bytes(&self) -> u64 {
        self.data.bytes()
    }
}

/// What the build of a compressed operator holds against what may be used
/// ([`memory_allowance`] when the build starts: what `--memory-limit` leaves above what the
/// process holds, or a share of the available memory): before the plan, the estimate of its
/// peak ([`MemoryGuard::refusal`]); while the plan is walked, its lists ([`PlanBudget`]); while
/// the blocks are built, the blocks stored and the growth of the process's resident memory, so
/// that the build's transient buffers count too. A build that outgrows it stops with
/// [`Error::OperatorTooLarge`] instead of ending in the out-of-memory killer.
struct MemoryGuard {
    dof: usize,
    allowance: Option<f64>,
    /// Where the allowance comes from, in words.
    source: String,
    /// What the process held when the build began.
    resident: u64,
    /// The estimate made before the plan.
    estimate: Option<MemoryEstimate>,
    stored: AtomicU64,
    /// Resident memory when the build started.
    resident_at_start: Option<u64>,
    /// The most the resident memory has grown above that, at the looks so far.
    grown: AtomicU64,
    /// Stored bytes at the last look.
    looked_at: AtomicU64,
}

/// The guard looks at the resident memory each time the stored blocks grow by this much.
const LOOK_EVERY: u64 = 16 << 20;

/// A size in words.
fn size(bytes: f64) -> String {
    crate::assembly::size_text(bytes)
}

impl MemoryGuard {
    fn new(dof: usize) -> Self {
        Self { source: allowance_source(), ..Self::with_allowance(dof, memory_allowance()) }
    }

    /// A guard of `allowance` bytes (tests give their own).
    fn with_allowance(dof: usize, allowance: Option<f64>) -> Self {
        let resident_at_start = resident_bytes();
        Self {
            dof,
            allowance,
            source: "the guard's allowance; see --memory-limit".into(),
            resident: resident_at_start.unwrap_or(0),
            estimate: None,
            stored: AtomicU64::new(0),
            resident_at_start,
            grown: AtomicU64::new(0),
            looked_at: AtomicU64::new(0),
        }
    }

    /// The error refusing the build before it begins, where even the low end of `estimate`
    /// (two standard errors below it) exceeds the allowance; `refine`, the mesh's level where
    /// known, for the advice.
    fn refusal(&self, estimate: &MemoryEstimate, refine: Option<u32>) -> Option<Error> {
        let available = self.allowance?;
        if estimate.low_bytes() as f64 <= available {
            return None;
        }
        let peak = estimate.peak_bytes() as f64;
        Some(Error::OperatorTooLarge {
            dof: self.dof,
            needed_gib: gib(peak),
            available_gib: gib(available),
            what: format!(
                "the compressed operator of {} unknowns would need about {} at the peak of its \
                 build (at least {}: the estimate less two standard errors; stored operator \
                 about {}{}), but {} may be used ({})",
                self.dof,
                size(peak),
                size(estimate.low_bytes() as f64),
                size(estimate.operator_bytes() as f64),
                estimate.mostly_blocks().map_or(String::new(), |why| format!("; {why}")),
                size(available),
                self.source
            ),
            advice: estimate.advice(available, self.resident, refine),
        })
    }

    /// The error of a rank whose estimate fits where another rank's does not.
    fn refused_elsewhere(&self, estimate: &MemoryEstimate) -> Error {
        let available = self.allowance.unwrap_or(0.0);
        let peak = estimate.peak_bytes() as f64;
        Error::OperatorTooLarge {
            dof: self.dof,
            needed_gib: gib(peak),
            available_gib: gib(available),
            what: format!(
                "the compressed operator of {} unknowns was refused: another rank may use less \
                 than its estimate of about {} at the peak (this one may use {})",
                self.dof,
                size(peak),
                size(available)
            ),
            advice: "give every rank the same --memory-limit, or use machines with more memory"
                .into(),
        }
    }

    /// The plan's budget: what the allowance leaves beside the cluster trees (`trees` bytes);
    /// `None` without an allowance.
    fn plan_budget(&self, trees: u64) -> Option<PlanBudget> {
        self.allowance.map(|a| PlanBudget::new((a - trees as f64).max(0.0) as u64))
    }

    /// The error of a plan whose walk passed `budget` (beside the trees' `trees` bytes).
    fn plan_too_large(&self, budget: &PlanBudget, trees: u64) -> Error {
        let available = self.allowance.unwrap_or(0.0);
        let taken = (budget.used() + trees) as f64;
        Error::OperatorTooLarge {
            dof: self.dof,
            needed_gib: gib(taken),
            available_gib: gib(available),
            what: format!(
                "the compressed operator of {} unknowns was stopped while its block plan was \
                 walked: the plan's lists (counted twice: they grow by doubling) and the cluster \
                 trees had reached {}, more than the {} that may be used ({}){}",
                self.dof,
                size(taken),
                size(available),
                self.source,
                self.estimate_was(taken)
            ),
            advice: format!(
                "{BUILD_ADVICE}; the plan grows with the square of the unknowns where faces hold \
                 few elements (a city at refine 0)"
            ),
        }
    }

    /// What the estimate made before said, for a build stopped at `taken` bytes.
    fn estimate_was(&self, taken: f64) -> String {
        match &self.estimate {
            Some(e) if (e.peak_bytes() as f64) < taken => {
                format!(
                    "; the estimate made before, about {}, was low",
                    size(e.peak_bytes() as f64)
                )
            }
            Some(e) => format!("; estimated before at about {}", size(e.peak_bytes() as f64)),
            None => String::new(),
        }
    }

    /// Counts `bytes` stored.
    fn add(&self, bytes: u64) {
        let stored = self.stored.fetch_add(bytes, Ordering::Relaxed) + bytes;
        let last = self.looked_at.load(Ordering::Relaxed);
        if stored >= last + LOOK_EVERY
            && self
                .looked_at
                .compare_exchange(last, stored, Ordering::Relaxed, Ordering::Relaxed)
                .is_ok()
        {
            self.look();
        }
    }

    /// Takes the growth of the resident memory since the build began into account.
    fn look(&self) {
        if let (Some(start), Some(now)) = (self.resident_at_start, resident_bytes()) {
            self.grown.fetch_max(now.saturating_sub(start), Ordering::Relaxed);
        }
    }

    /// Memory the build has taken: the blocks stored, or the growth of the resident memory
    /// where that was more.
    fn used(&self) -> u64 {
        self.stored.load(Ordering::Relaxed).max(self.grown.load(Ordering::Relaxed))
    }

    /// Bytes kept aside from the allowance for what the guard does not see at once: the growth
    /// between two of its looks at the memory, and the cross approximations in flight (as
    /// estimated).
    fn aside(&self) -> f64 {
        (LOOK_EVERY + self.estimate.map_or(0, |e| e.crossing)) as f64
    }

    /// Bytes the blocks and the build's buffers may take while the blocks are built: the
    /// allowance less what is kept aside.
    fn cap(&self) -> Option<f64> {
        self.allowance.map(|a| a - self.aside())
    }

    /// Whether what is used exceeds the cap.
    fn is_over(&self) -> bool {
        self.over_by(0)
    }

    /// Whether what is used, with `more`, exceeds the cap: the blocks other threads are
    /// building and the growth since the last look are not seen yet.
    fn over_by(&self, more: u64) -> bool {
        self.cap().is_some_and(|cap| (self.used() + more) as f64 > cap)
    }

    /// The error when what is used, with `more` bytes, exceeds the cap.
    fn check(&self, more: u64) -> Result<()> {
        self.look();
        if !self.over_by(more) {
            return Ok(());
        }
        let available = self.allowance.unwrap_or(0.0);
        let cap = self.cap().unwrap_or(0.0);
        let taken = (self.used() + more) as f64;
        let stopped = if cap > 0.0 {
            format!(
                "it had taken {} with what it was about to allocate, more than the {} it may \
                 take: the {} that may be used ({}) less {} kept aside for what the guard does \
                 not see at once (the growth between two of its looks at the memory, the cross \
                 approximations in flight)",
                size(taken),
                size(cap),
                size(available),
                self.source,
                size(self.aside())
            )
        } else {
            format!(
                "the {} that may be used ({}) leaves nothing once {} are kept aside for what the \
                 guard does not see at once",
                size(available),
                self.source,
                size(self.aside())
            )
        };
        Err(Error::OperatorTooLarge {
            dof: self.dof,
            needed_gib: gib(taken),
            available_gib: gib(available),
            what: format!(
                "the build of the compressed operator of {} unknowns was stopped: {stopped}{}",
                self.dof,
                self.estimate_was(taken)
            ),
            advice: BUILD_ADVICE.into(),
        })
    }
}

/// What a build stopped for memory may try.
const BUILD_ADVICE: &str = "raise --memory-limit or --compression-tolerance, use a coarser mesh \
     (each refinement level multiplies the memory by about 5) or a machine with more memory";

/// Bytes in GiB.
fn gib(bytes: f64) -> f64 {
    bytes / (1u64 << 30) as f64
}

/// Bytes of a block's entry in the build's lists of exact blocks: the list, its copy sorted by
/// node cluster, and the groups ([`build_block_by_block`]).
const LIST_NEAR_BYTES: u64 = 3 * std::mem::size_of::<(usize, usize, bool)>() as u64;
/// Bytes of a far block's entry in the build's lists.
const LIST_FAR_BYTES: u64 = std::mem::size_of::<&(usize, usize)>() as u64;
/// Bytes of a shadowed block's leaf in the build's lists ([`shadowed::build`]).
const LIST_LEAF_BYTES: u64 =
    3 * std::mem::size_of::<(usize, usize, usize)>() as u64 + shadowed::LEAF_PARTS_BYTES;
/// Bytes of a block's slot, which the operator keeps as its index.
const SLOT_BYTES: u64 = std::mem::size_of::<Block>() as u64;

/// Bytes of the build's working lists and of the blocks' slots for `plan`: what
/// [`build_block_by_block`] and [`shadowed::build`] allocate beside the blocks' values.
fn build_list_bytes(plan: &BlockPlan) -> u64 {
    let leaves: usize = plan.shadowed.iter().map(|b| b.leaves.len()).sum();
    let slots = plan.near.len() + plan.far.len() + shadowed::sub_blocks(&plan.shadowed);
    LIST_NEAR_BYTES * plan.near.len() as u64
        + LIST_FAR_BYTES * plan.far.len() as u64
        + LIST_LEAF_BYTES * leaves as u64
        + SLOT_BYTES * slots as u64
}

/// Pairs sampled for the memory estimate: a standard error of a few per cent where the stored
/// entries are a per cent of the pairs or more, in about a second on most scenes.
const ESTIMATE_SAMPLES: usize = 4096;

/// Further pairs whose sight is looked at in the exact block (or shadowed leaf) of each sampled
/// pair: how full the block is decides how it is stored (dense, sparse rows with their masks, or
/// dropped when nothing in it is seen).
const SIGHTS_PER_BLOCK: usize = 8;

/// Entry evaluations that the estimate's cross approximations of the sampled low-rank and
/// shadowed blocks may take together (a second or two of one core); the sampled blocks beyond
/// are given the mean rank of those of their kind nearest in shape.
const ESTIMATE_EVALUATIONS: usize = 1 << 23;

/// Rank assumed where no sampled block of a kind was cross-approximated, and when choosing
/// which ones to approximate within [`ESTIMATE_EVALUATIONS`].
const ASSUMED_RANK: usize = 16;

/// Bytes a cross approximation holds per cross and per row or column of its block while it
/// runs: the crosses, their copies as matrices, the QR factors and the recompressed factors, in
/// f64 (`aca::aca`).
const CROSSING_BYTES: u64 = 32;

/// Vectors of n values that GMRES keeps for one right-hand side: `solve::RESTART` + 2 (the
/// solver's layer is above the operator's, which cannot name it).
const GMRES_VECTORS: u64 = 32;

/// How a node sees an element.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Sight {
    /// Not at all (or its row is zero: rho = 0): no entry.
    Hidden,
    /// Whole.
    Whole,
    /// In part: an exact entry even in a shadowed block.
    Part,
}

/// The sights of the pairs looked at in one block: how many were seen at all, and in part.
#[derive(Clone, Copy, Debug, Default)]
struct Fill {
    looked: u32,
    seen: u32,
    part: u32,
}

impl Fill {
    fn add(&mut self, sight: Sight) {
        self.looked += 1;
        self.seen += u32::from(sight != Sight::Hidden);
        self.part += u32::from(sight == Sight::Part);
    }

    /// Share of the pairs seen, and seen in part.
    fn shares(&self) -> (f64, f64) {
        let n = f64::from(self.looked.max(1));
        (f64::from(self.seen) / n, f64::from(self.part) / n)
    }
}

/// The sampled parts of the memory, per pair (bytes, and blocks) or summed.
#[derive(Clone, Copy, Debug, Default)]
struct Sampled {
    plan: f64,
    lists: f64,
    index: f64,
    exact: f64,
    factors: f64,
    blocks: f64,
    /// Pairs in exact blocks or shadowed leaves (the row walks' views follow them).
    walked: f64,
}

impl Sampled {
    /// What the sampled parts add to the peak (the kept blocks' slots are among the lists').
    fn bytes(&self) -> f64 {
        self.plan + self.lists + self.exact + self.factors
    }

    fn add(&mut self, o: &Sampled) {
        self.plan += o.plan;
        self.lists += o.lists;
        self.index += o.index;
        self.exact += o.exact;
        self.factors += o.factors;
        self.blocks += o.blocks;
        self.walked += o.walked;
    }
}

/// Bytes of a cluster tree's clusters (its order counts with the operator's).
fn tree_bytes(tree: &ClusterTree) -> u64 {
    let faces: usize = tree.clusters.iter().map(|c| c.faces.capacity()).sum();
    (tree.clusters.capacity() * std::mem::size_of::<cluster::Cluster>()
        + faces * std::mem::size_of::<usize>()) as u64
}

/// What the build of the operator of `entries` will hold at its peak ([`MemoryEstimate`]), over
/// `ranks` processes: the cluster trees counted; the plan, the lists, the blocks' slots and
/// their values from [`ESTIMATE_SAMPLES`] pairs drawn uniformly (seeded: the same estimate on
/// every run and rank). Each pair is followed down the block tree by the plan's own decisions
/// to the block that holds it ([`BlockPlan::locate`]), and stands for its block's bytes over
/// the block's pairs: the plan's and the lists' entries and the slot of its block; for an exact
/// block or a shadowed leaf, its values as the build stores them, from the sights of the pair
/// and of [`SIGHTS_PER_BLOCK`] more in the block (dense, sparse rows with their masks, nothing
/// where none is seen); for a low-rank or shadowed block, its factors (cross-approximated for
/// the sampled blocks while [`ESTIMATE_EVALUATIONS`] last). The sums, times the pairs over the
/// samples, estimate the totals; the row walks' views, the cross approximations in flight and
/// the solver's vectors follow from them and from n.
fn estimate_memory(
    entries: &Entries,
    faces: &FacePairs,
    options: &CompressionOptions,
    scene_faces: usize,
    ranks: usize,
) -> MemoryEstimate {
    use rand::{Rng, SeedableRng};

    let (nodes, elements, per) = (entries.nodes, entries.elements, entries.per);
    let (n_nodes, n_elements) = (nodes.order.len(), elements.order.len());
    let dof = entries.disc.dof();
    let value = entries.precision.bytes() as f64;
    let threads = rayon::current_num_threads() as u64;
    let estimate = MemoryEstimate {
        dof,
        trees: tree_bytes(nodes) + tree_bytes(elements),
        orders: order_bytes(dof, per),
        solver: 8 * dof as u64 * (GMRES_VECTORS + 2 * threads),
        ranks,
        single: entries.precision == Precision::F32,
        ..Default::default()
    };
    if n_nodes == 0 || n_elements == 0 {
        return estimate;
    }
    let samples: Vec<(Located, Fill)> = (0..ESTIMATE_SAMPLES)
        .into_par_iter()
        .map_init(RecentHiders::default, |hiders, k| {
            let mut rng = rand::rngs::StdRng::seed_from_u64(0x5eed_0000 + k as u64);
            let at = (rng.random_range(0..n_nodes), rng.random_range(0..n_elements));
            let located = BlockPlan::locate(nodes, elements, faces, options, at);
            let walked = match located {
                Located::Near { t, s, .. } => Some((t, s)),
                Located::Far { t, s } => entries.useful_rank(t, s).is_none().then_some((t, s)),
                Located::Shadowed { part: ShadowedPart::Leaf(t, s), .. } => Some((t, s)),
                Located::Shadowed { .. } | Located::Empty => None,
            };
            let mut fill = Fill::default();
            if let Some((t, s)) = walked {
                let (tc, sc) = (&nodes.clusters[t], &elements.clusters[s]);
                let others = (0..SIGHTS_PER_BLOCK).map(|_| {
                    (rng.random_range(tc.start..tc.end), rng.random_range(sc.start..sc.end))
                });
                for (k, l) in std::iter::once(at).chain(others) {
                    fill.add(entries.pair_sight(nodes.order[k], elements.order[l], hiders));
                }
            }
            (located, fill)
        })
        .collect();

    // The ranks of the low-rank and shadowed blocks met, in the order met (at random), while
    // the evaluations last.
    let mut chosen = Vec::new();
    let mut left = ESTIMATE_EVALUATIONS;
    let mut widths = Vec::new();
    let mut kinds = std::collections::HashMap::new();
    for (located, _) in &samples {
        let (t, s, continued) = match *located {
            Located::Far { t, s } if entries.useful_rank(t, s).is_some() => (t, s, false),
            Located::Shadowed { t, s, .. } => (t, s, true),
            _ => continue,
        };
        if kinds.insert((t, s), continued).is_none() {
            let (m, c) = entries.block_size(t, s);
            widths.push(m + c);
            let cost = ASSUMED_RANK * (m + c);
            if cost <= left {
                left -= cost;
                chosen.push((t, s, continued));
            }
        }
    }
    let tolerance = options.tolerance;
    let ranks_found: std::collections::HashMap<(usize, usize), Option<usize>> = chosen
        .par_iter()
        .map(|&(t, s, continued)| {
            let rank = entries.low_rank(t, s, faces, tolerance, continued).map(|lr| lr.k);
            ((t, s), rank)
        })
        .collect();
    // A block not approximated is given the mean rank of those of its kind (far or shadowed)
    // nearest in shape (log2 of its rows and of its columns): the budget leaves out the largest
    // ones met late, and those met first are the ones of most pairs, of higher ranks than
    // narrower blocks of as many rows and columns (an incompressible far block counts as its
    // break-even rank; an incompressible shadowed block has no factors).
    let shape = |t: usize, s: usize| {
        let (m, c) = entries.block_size(t, s);
        let log = |v: usize| i64::from(usize::BITS - v.leading_zeros());
        (log(m), log(c))
    };
    let mut by_shape: std::collections::HashMap<(bool, (i64, i64)), (f64, f64)> =
        Default::default();
    for &(t, s, continued) in &chosen {
        let rank = match ranks_found[&(t, s)] {
            Some(k) => k as f64,
            None if continued => 0.0,
            None => entries.useful_rank(t, s).unwrap_or(0) as f64,
        };
        let (sum, count) = by_shape.entry((continued, shape(t, s))).or_default();
        *sum += rank;
        *count += 1.0;
    }
    let imputed = |continued: bool, at: (i64, i64)| {
        by_shape
            .iter()
            .filter(|((kind, _), _)| *kind == continued)
            .min_by_key(|((_, b), _)| ((b.0 - at.0).abs() + (b.1 - at.1).abs(), *b))
            .map_or(ASSUMED_RANK as f64, |(_, (sum, count))| sum / count)
    };
    // A block's factors, or its entries where its rank did not pay.
    let factor_bytes = |t: usize, s: usize, continued: bool| -> f64 {
        let (m, c) = entries.block_size(t, s);
        match ranks_found.get(&(t, s)) {
            Some(Some(k)) => (k * (m + c)) as f64 * value,
            Some(None) if continued => 0.0,
            Some(None) => (m * c) as f64 * value,
            None => {
                let most = entries.useful_rank(t, s).unwrap_or(0) as f64;
                imputed(continued, shape(t, s)).min(most) * (m + c) as f64 * value
            }
        }
    };
    // The largest cross approximation met: its crosses, as many as its rank (an incompressible
    // far block's reach its break-even rank before it is refused).
    let crossing = kinds
        .iter()
        .map(|(&(t, s), &continued)| {
            let (m, c) = entries.block_size(t, s);
            let rank = match ranks_found.get(&(t, s)) {
                Some(Some(k)) => *k as f64,
                Some(None) => entries.useful_rank(t, s).unwrap_or(0) as f64,
                None => imputed(continued, shape(t, s)),
            };
            rank * (m + c) as f64
        })
        .fold(0.0, f64::max);

    let pairs = |t: usize, s: usize| (nodes.clusters[t].len() * elements.clusters[s].len()) as f64;
    let masks = |t: usize, s: usize| {
        let (m, width) = entries.block_size(t, s);
        8.0 * (m * stored::mask_words(width)) as f64
    };
    // An exact block as `Block::compact` stores it: nothing where nothing is seen, else its
    // values dense or, where fewer bytes, its non-zero ones with the rows' masks.
    let exact_block = |x: &mut Sampled, t: usize, s: usize, fill: Fill, list: u64| {
        let p = pairs(t, s);
        let (seen, _) = fill.shares();
        let dense = p * per as f64 * value;
        x.plan += PLAN_NEAR_BYTES as f64 / p;
        x.lists += (list + SLOT_BYTES) as f64 / p;
        x.blocks += 1.0 / p;
        x.walked += 1.0;
        if fill.seen > 0 {
            x.index += SLOT_BYTES as f64 / p;
            x.exact += dense.min(masks(t, s) + seen * dense) / p;
        }
    };
    let (mut sum, mut sum_squares) = (Sampled::default(), 0.0);
    for &(located, fill) in &samples {
        let mut x = Sampled::default();
        match located {
            Located::Empty => {}
            Located::Near { t, s, .. } => exact_block(&mut x, t, s, fill, LIST_NEAR_BYTES),
            Located::Far { t, s } if entries.useful_rank(t, s).is_none() => {
                exact_block(&mut x, t, s, fill, LIST_NEAR_BYTES + LIST_FAR_BYTES);
            }
            Located::Far { t, s } => {
                let p = pairs(t, s);
                x.plan += PLAN_FAR_BYTES as f64 / p;
                x.lists += (LIST_FAR_BYTES + SLOT_BYTES) as f64 / p;
                x.index += SLOT_BYTES as f64 / p;
                x.factors += factor_bytes(t, s, false) / p;
                x.blocks += 1.0 / p;
            }
            Located::Shadowed { t, s, part } => {
                let p = pairs(t, s);
                x.plan += std::mem::size_of::<blocks::ShadowedBlock>() as f64 / p;
                x.factors += factor_bytes(t, s, true) / p;
                if let ShadowedPart::Seen(a, b) = part {
                    let p = pairs(a, b);
                    x.plan += PLAN_FAR_BYTES as f64 / p;
                    x.lists += SLOT_BYTES as f64 / p;
                    x.index += SLOT_BYTES as f64 / p;
                    x.blocks += 1.0 / p;
                }
                if let ShadowedPart::Leaf(a, b) = part {
                    // The mask of the elements seen whole and the partly seen ones' entries,
                    // with their own masks; dropped where nothing is seen.
                    let p = pairs(a, b);
                    x.plan += PLAN_FAR_BYTES as f64 / p;
                    x.lists += (LIST_LEAF_BYTES + SLOT_BYTES) as f64 / p;
                    x.blocks += 1.0 / p;
                    x.walked += 1.0;
                    if fill.seen > 0 {
                        let (_, part) = fill.shares();
                        x.index += SLOT_BYTES as f64 / p;
                        x.exact += (2.0 * masks(a, b) + part * p * per as f64 * value) / p;
                    }
                }
            }
        }
        sum_squares += x.bytes() * x.bytes();
        sum.add(&x);
    }
    let count = samples.len() as f64;
    let scale = n_nodes as f64 * n_elements as f64 / count;
    let variance = (sum_squares / count - (sum.bytes() / count).powi(2)).max(0.0);
    let total = |v: f64| (v * scale).round() as u64;
    // Each thread keeps the views of the faces its node cluster's exact blocks meet, for each
    // of the cluster's nodes: at most every face, at most as many as the elements walked per
    // node over the elements of a face (a face's elements share its view).
    let walked_per_node = sum.walked * scale / n_nodes as f64;
    let per_face = n_elements as f64 / scene_faces.max(1) as f64;
    let faces_met = (walked_per_node / per_face.max(1.0)).min(scene_faces as f64);
    let view_bytes = 2.0 * std::mem::size_of::<(usize, crate::visibility::FaceView)>() as f64;
    let cluster = options.leaf_size.max(options.mixed_leaf_size) as f64;
    // Each thread may be approximating one of the widest blocks at once (those at least half as
    // wide as the widest met).
    let widest = widths.iter().copied().max().unwrap_or(0);
    let wide = widths.iter().filter(|&&w| 2 * w >= widest).count() as u64;
    let in_flight = threads.min(wide).max(1) as f64;
    MemoryEstimate {
        plan: total(sum.plan),
        lists: total(sum.lists),
        index: total(sum.index),
        exact: total(sum.exact),
        factors: total(sum.factors),
        blocks: total(sum.blocks),
        views: (threads as f64 * cluster * faces_met * view_bytes) as u64,
        crossing: (in_flight * CROSSING_BYTES as f64 * crossing) as u64,
        error: (scale * (count * variance).sqrt()).round() as u64,
        samples: samples.len(),
        ..estimate
    }
}

/// The blocks `(t, s, ..)` of `blocks` grouped by node cluster (runs of one `t`, in order).
fn by_node_cluster<T: Copy + Ord>(blocks: &[(usize, usize, T)]) -> Vec<Vec<(usize, usize, T)>> {
    let mut sorted = blocks.to_vec();
    sorted.sort_unstable();
    sorted.chunk_by(|a, b| a.0 == b.0).map(<[_]>::to_vec).collect()
}

/// The cluster trees of the nodes (points) and of the elements (their bounding boxes).
fn cluster_trees(
    mesh: &Mesh,
    disc: &Discretization,
    options: &CompressionOptions,
) -> (ClusterTree, ClusterTree) {
    let node_items: Vec<Item> = disc
        .nodes
        .iter()
        .map(|n| Item { point: n.position, lo: n.position, hi: n.position, face: n.face })
        .collect();
    let element_items: Vec<Item> = mesh
        .elements()
        .iter()
        .map(|e| {
            let [a, b, c] = e.vertices;
            Item { point: e.centroid(), lo: a.min(b).min(c), hi: a.max(b).max(c), face: e.face }
        })
        .collect();
    let leaf = options.mixed_leaf_size.min(options.leaf_size);
    (ClusterTree::new(&node_items, leaf), ClusterTree::new(&element_items, leaf))
}

/// The blocks built and what was met building them: the classes of the pairs evaluated
/// exactly and the admissible blocks found incompressible. Exact blocks that held nothing are
/// among the blocks until [`kept_blocks`] counts and drops them.
#[derive(Default)]
struct Built {
    blocks: Vec<Block>,
    pairs: PairStats,
    incompressible: u64,
}

impl Built {
    /// Adds a block, with the pair classes its exact entries met and whether it was admissible
    /// but found incompressible.
    fn push(&mut self, block: Block, pairs: PairStats, incompressible: bool) {
        self.add(pairs, incompressible);
        self.blocks.push(block);
    }

    fn add(&mut self, pairs: PairStats, incompressible: bool) {
        self.pairs += pairs;
        self.incompressible += u64::from(incompressible);
    }

    /// What both met; only `self` holds blocks (the parts of a build write theirs into their
    /// slots of one list and tally the rest).
    fn merged(mut self, other: Built) -> Self {
        debug_assert!(other.blocks.is_empty());
        self.pairs += other.pairs;
        self.incompressible += other.incompressible;
        self
    }
}

/// The blocks of `plan` on the CPU, block by block: near ones exact, far ones compressed to
/// `tolerance` or exact when their rank would not pay.
fn build_block_by_block(
    entries: &Entries,
    plan: &BlockPlan,
    faces: &FacePairs,
    tolerance: f64,
    guard: &MemoryGuard,
    progress: &dyn Progress,
) -> Result<Built> {
    // Admissible blocks too small for a low rank to pay are exact from the start.
    let (small, far): (Vec<_>, Vec<_>) =
        plan.far.iter().partition(|&&(t, s)| entries.useful_rank(t, s).is_none());
    let exact: Vec<(usize, usize, bool)> = plan
        .near
        .iter()
        .map(|b| (b.t, b.s, false))
        .chain(small.into_iter().map(|(t, s)| (t, s, true)))
        .collect();
    let groups = by_node_cluster(&exact);
    // Each block is written into its own slot of the one list the operator keeps: a million
    // blocks gathered in parts and then joined were the peak of the furnished room's build.
    let shadowed_slots = shadowed::sub_blocks(&plan.shadowed);
    let mut blocks: Vec<Block> =
        (0..exact.len() + far.len() + shadowed_slots).map(|_| Block::nothing()).collect();
    let (near_slots, rest) = blocks.split_at_mut(exact.len());
    let (far_slots, shadowed_slots) = rest.split_at_mut(far.len());
    let mut slots_of_groups = Vec::with_capacity(groups.len());
    let mut near_rest = near_slots;
    for group in &groups {
        let (slots, after) = std::mem::take(&mut near_rest).split_at_mut(group.len());
        slots_of_groups.push((group, slots));
        near_rest = after;
    }
    // The exact blocks of one node cluster together: each node's views of the faces are found
    // once for all of them.
    let near = slots_of_groups.into_par_iter().map(|(group, slots)| {
        let mut views = NodeViews::default();
        let mut met = Built::default();
        for (&(t, s, incompressible), slot) in group.iter().zip(slots) {
            if guard.is_over() {
                break;
            }
            let (block, stats) = entries.exact_block(t, s, &mut views);
            guard.add(block.bytes());
            met.add(stats, incompressible);
            *slot = block;
        }
        progress.advance(group.len());
        met
    });
    let far = far_slots.par_iter_mut().zip(far).map(|(slot, (t, s))| {
        let mut met = Built::default();
        if !guard.is_over() {
            *slot = entries.compressed_or_exact(t, s, faces, tolerance, &mut met);
            guard.add(slot.bytes());
        }
        progress.advance(1);
        met
    });
    let mut met = near.chain(far).reduce(Built::default, Built::merged);
    let shadowed =
        shadowed::build(entries, &plan.shadowed, faces, tolerance, guard, progress, shadowed_slots);
    met = met.merged(shadowed);
    guard.check(0)?;
    Ok(Built { blocks, ..met })
}

/// The blocks built that hold something, in one list, with their statistics and the pair
/// classes met (`empty`: the blocks the plan left out).
fn kept_blocks(built: Built, empty: usize, per: usize) -> (Vec<Block>, OperatorStats, PairStats) {
    let Built { mut blocks, pairs, incompressible } = built;
    let before = blocks.len();
    // Every exact block was compacted when built: one of zeros holds nothing. Dropped in
    // place, in the list's own memory.
    blocks.retain(|b| !matches!(&b.data, BlockData::Dense(d) if d.is_empty()));
    blocks.shrink_to_fit();
    let stats = OperatorStats {
        empty_blocks: (empty + before - blocks.len()) as u64,
        incompressible_blocks: incompressible,
        ..block_stats(&blocks, per)
    };
    (blocks, stats, pairs)
}

/// What `blocks` themselves tell of an operator: blocks and entries by kind, the largest rank,
/// and the bytes they take with their index (a shadowed block's shared factors once).
fn block_stats(blocks: &[Block], per: usize) -> OperatorStats {
    let mut stats = OperatorStats::default();
    let index_bytes = std::mem::size_of::<Block>() as u64;
    let mut shared = std::collections::HashSet::new();
    let mut count_factors =
        |stats: &mut OperatorStats, factors: &std::sync::Arc<stored::Factors>| {
            if shared.insert(std::sync::Arc::as_ptr(factors)) {
                let bytes = factors.u.bytes() + factors.v.bytes();
                stats.operator_bytes += bytes;
                stats.low_rank_bytes += bytes;
                stats.max_rank = stats.max_rank.max(factors.rank());
            }
        };
    for block in blocks {
        match &block.data {
            BlockData::Dense(d) => {
                stats.near_blocks += 1;
                stats.near_entries += d.len() as u64;
            }
            BlockData::Sparse(rows) => {
                stats.near_blocks += 1;
                stats.near_entries += rows.values.len() as u64;
            }
            BlockData::LowRank(f) => {
                stats.far_blocks += 1;
                stats.far_entries += (block.row_range().len() * f.columns()) as u64;
                stats.max_rank = stats.max_rank.max(f.rank());
                stats.low_rank_bytes += block.bytes();
            }
            BlockData::Seen(slice) => {
                stats.far_blocks += 1;
                stats.far_entries +=
                    (block.row_range().len() * block.col_range().len() * per) as u64;
                count_factors(&mut stats, &slice.factors);
            }
            BlockData::Leaf(leaf) => {
                stats.near_blocks += 1;
                stats.near_entries += leaf.partial.values.len() as u64;
                stats.far_entries += leaf.whole_entries();
                count_factors(&mut stats, &leaf.slice.factors);
            }
        }
        stats.operator_bytes += block.bytes() + index_bytes;
    }
    stats.shadowed_blocks = shared.len() as u64;
    stats
}

/// Bytes of the node and element orders of an operator of `dof` unknowns, `per` to an element.
fn order_bytes(dof: usize, per: usize) -> u64 {
    8 * (dof + dof / per) as u64
}

/// The whole operator's statistics from every rank's (a collective: every rank calls it).
fn summed_over(
    ranks: &dyn Collective,
    stats: OperatorStats,
    pairs: PairStats,
) -> (OperatorStats, PairStats) {
    let more = [stats.low_rank_bytes, stats.shadowed_blocks];
    let mine: Vec<u64> = stats.counts().into_iter().chain(pairs.counts()).chain(more).collect();
    let (mut stats, mut pairs) = (OperatorStats::default(), PairStats::default());
    for counts in ranks.gather(&mine) {
        let (s, rest) = counts.split_at(OperatorStats::COUNTS);
        let (p, more) = rest.split_at(rest.len() - 2);
        stats += OperatorStats {
            low_rank_bytes: more[0],
            shadowed_blocks: more[1],
            ..OperatorStats::from_counts(s.try_into().expect("a rank's statistics"))
        };
        pairs += PairStats::from_counts(p.try_into().expect("a rank's pair classes"));
    }
    (stats, pairs)
}

/// The views of faces found so far from each node of one node cluster, kept while its blocks
/// are computed one after another.
#[derive(Default)]
struct NodeViews {
    cluster: Option<usize>,
    rows: Vec<KeptViews>,
}

impl NodeViews {
    /// Ready for node cluster `t` of `m` nodes (cleared when it is another cluster).
    fn prepare(&mut self, t: usize, m: usize) {
        if self.cluster != Some(t) {
            self.cluster = Some(t);
            self.rows.clear();
            self.rows.resize_with(m, KeptViews::default);
        }
    }
}

/// Computes entries of K for blocks.
struct Entries<'a> {
    mesh: &'a Mesh,
    disc: &'a Discretization,
    planner: &'a PairPlanner,
    integrator: &'a PairIntegrator,
    nodes: &'a ClusterTree,
    elements: &'a ClusterTree,
    per: usize,
    /// The precision the blocks store their values in (from the tolerance).
    precision: Precision,
}

impl Entries<'_> {
    /// Walks the pairs of block (t, s) by the dense path's pair plan (the row walk of
    /// [`PairPlanner::walk_row`]), calling `each(r, k, i, j, visibility)` for every pair that is
    /// not skipped: row r of the block (node i), element k of the block (element j). `views`
    /// keeps the nodes' views of faces between blocks of the same node cluster.
    fn visible_pairs(
        &self,
        t: usize,
        s: usize,
        views: &mut NodeViews,
        mut each: impl FnMut(usize, usize, usize, usize, Visibility),
    ) -> PairStats {
        let (tc, sc) = (&self.nodes.clusters[t], &self.elements.clusters[s]);
        let element_ids = &self.elements.order[sc.start..sc.end];
        // The block's elements face by face (positions k in the block), as the walk takes them.
        let by_face =
            by_face(element_ids.iter().enumerate().map(|(k, &j)| (self.disc.elements[j].face, k)));
        // Each face's elements in the block with the boxes of their halves, for the nodes
        // that see the face in part.
        let boxes: Vec<ElementBoxes> = by_face
            .iter()
            .map(|(_, list)| {
                let element = |&k: &usize| self.disc.elements[element_ids[k]].in_face();
                ElementBoxes::new(list.iter().map(element).collect())
            })
            .collect();
        let mut stats = PairStats::default();
        views.prepare(t, tc.len());
        for (r, &i) in self.nodes.order[tc.start..tc.end].iter().enumerate() {
            let viewer = self.disc.nodes[i].viewer();
            let faces = by_face.iter().map(|(face, list)| (*face, list.iter().copied()));
            let kept = Views::Kept(&mut views.rows[r]);
            stats += self.planner.walk_row(&viewer, faces, kept, |face, list, sight| match sight {
                FaceSight::Hidden(_) => {}
                FaceSight::Whole => {
                    list.for_each(|k| each(r, k, i, element_ids[k], Visibility::Full))
                }
                FaceSight::Part(mut part) => {
                    let g = by_face.iter().position(|(f, _)| *f == face).expect("a block's face");
                    part.elements(&boxes[g], |at, vis| {
                        if !matches!(vis, Visibility::Skip(_)) {
                            let k = by_face[g].1[at];
                            each(r, k, i, element_ids[k], vis)
                        }
                    });
                }
            });
        }
        stats
    }

    /// How node i sees element j, by the row walk of the dense path's pair plan.
    fn pair_sight(&self, i: usize, j: usize, hiders: &mut RecentHiders) -> Sight {
        let (node, el) = (&self.disc.nodes[i], &self.disc.elements[j]);
        let mut sight = Sight::Hidden;
        let faces = [(el.face, std::iter::once(()))];
        self.planner.walk_row(&node.viewer(), faces, Views::Fresh(hiders), |_, _, seen| {
            sight = match seen {
                FaceSight::Hidden(_) => Sight::Hidden,
                FaceSight::Whole => Sight::Whole,
                FaceSight::Part(mut part) => match part.element(&el.in_face()) {
                    Visibility::Skip(_) => Sight::Hidden,
                    Visibility::Full => Sight::Whole,
                    Visibility::Partial(_) => Sight::Part,
                },
            };
        });
        sight
    }

    /// Every entry of the block, by the dense path's pair plan and kernels, stored by what it
    /// holds ([`Block::compact`]).
    fn exact_block(&self, t: usize, s: usize, views: &mut NodeViews) -> (Block, PairStats) {
        let (data, stats) = self.exact_entries(t, s, views, None);
        let mut block = self.block(t, s, BlockData::exact(data));
        block.compact(self.precision);
        (block, stats)
    }

    /// The entries of block (t, s), row-major. With `whole` (mask words of the block's columns
    /// per row, as [`stored::SparseRows`] has them), an element the node sees whole is not
    /// integrated but marked there, in the rows of nodes that reflect (a shadowed block's
    /// factors give those entries).
    fn exact_entries(
        &self,
        t: usize,
        s: usize,
        views: &mut NodeViews,
        mut whole: Option<&mut [u64]>,
    ) -> (Vec<f64>, PairStats) {
        let per = self.per;
        let (m, width) = self.block_size(t, s);
        let words = stored::mask_words(width);
        // Zeros written, not mapped (`vec!` of zeros would leave a large block's pages to the
        // zero page, which the lanes' additions read before they write).
        let mut data = Vec::with_capacity(m * width);
        data.resize(m * width, 0.0);
        // The centroid method's closed forms wait in lanes, each with where its value goes and
        // the node's rho / pi; a partly visible element's pieces add into its entry.
        let mut batch = lanes::Batch::<(usize, f64)>::default();
        let stats = self.visible_pairs(t, s, views, |r, k, i, j, vis| {
            let node = &self.disc.nodes[i];
            if let Some(mask) = whole.as_deref_mut() {
                if matches!(vis, Visibility::Full) {
                    if node.rho != 0.0 {
                        for c in k * per..(k + 1) * per {
                            mask[r * words + c / 64] |= 1 << (c % 64);
                        }
                    }
                    return;
                }
            }
            let el = &self.disc.elements[j];
            let at = r * width + k * per;
            let scale = node.rho / PI;
            let sink = |(at, scale): (usize, f64), v: f64| data[at] += scale * v;
            let Some(values) = self.integrator.integrate_or_batch(
                el,
                &self.disc.bases[j],
                node.position,
                node.normal,
                &vis,
                ((at, scale), &mut batch),
                sink,
            ) else {
                return;
            };
            for (c, v) in values.iter().take(per).enumerate() {
                data[at + c] = scale * v;
            }
        });
        batch.flush(|(at, scale), v| data[at] += scale * v);
        (data, stats)
    }

    /// Rows and columns (elements × basis functions) of block (t, s).
    fn block_size(&self, t: usize, s: usize) -> (usize, usize) {
        (self.nodes.clusters[t].len(), self.elements.clusters[s].len() * self.per)
    }

    /// Block (t, s) holding `data`.
    fn block(&self, t: usize, s: usize, data: BlockData) -> Block {
        let (tc, sc) = (&self.nodes.clusters[t], &self.elements.clusters[s]);
        Block::new(tc.start..tc.end, sc.start..sc.end, data)
    }

    /// Whether node i (original index) gives element j anything, where the block's plan says
    /// the element is wholly visible from the node unless their faces give nothing.
    fn smooth_sees(&self, i: usize, j: usize, faces: &FacePairs) -> bool {
        let node = &self.disc.nodes[i];
        let el = &self.disc.elements[j];
        node.rho != 0.0
            && !faces.nothing_between(
                node.face,
                node.position,
                el,
                &self.mesh.elements()[j].vertices,
            )
    }

    /// The values of the pairs (node i, element j) of a smooth block, in order: all of each
    /// element's basis functions, or only `basis`. The centroid method's closed forms are
    /// evaluated in lanes. `continued`: the kernel over every element whole, without testing
    /// each pair for planes that make it give nothing ([`FacePairs::nothing_between`]).
    fn smooth_values(
        &self,
        pairs: impl Iterator<Item = (usize, usize)>,
        basis: Option<usize>,
        faces: &FacePairs,
        continued: bool,
    ) -> Vec<f64> {
        let take = if basis.is_some() { 1 } else { self.per };
        let mut out = Vec::new();
        let mut batch = lanes::Batch::<(usize, f64)>::default();
        for (i, j) in pairs {
            let at = out.len();
            out.resize(at + take, 0.0);
            let gives = if continued {
                self.disc.nodes[i].rho != 0.0
            } else {
                self.smooth_sees(i, j, faces)
            };
            if !gives {
                continue;
            }
            let node = &self.disc.nodes[i];
            let scale = node.rho / PI;
            let sink = |(at, scale): (usize, f64), v: f64| out[at] += scale * v;
            let Some(values) = self.integrator.integrate_or_batch(
                &self.disc.elements[j],
                &self.disc.bases[j],
                node.position,
                node.normal,
                &Visibility::Full,
                ((at, scale), &mut batch),
                sink,
            ) else {
                continue;
            };
            match basis {
                Some(b) => out[at] = scale * values[b],
                None => (0..take).for_each(|c| out[at + c] = scale * values[c]),
            }
        }
        batch.flush(|(at, scale), v| out[at] += scale * v);
        out
    }

    /// Rank beyond which block (t, s)'s factors take more memory than the block itself, or
    /// `None` when that is below [`MIN_USEFUL_RANK`] (computed exactly without trying).
    fn useful_rank(&self, t: usize, s: usize) -> Option<usize> {
        let (m, c) = self.block_size(t, s);
        let max_rank = (m * c) / (m + c);
        (max_rank >= MIN_USEFUL_RANK).then_some(max_rank)
    }

    /// The admissible block (t, s) as a low-rank product, or exact where its rank would not save
    /// memory (counted in `met` as incompressible).
    fn compressed_or_exact(
        &self,
        t: usize,
        s: usize,
        faces: &FacePairs,
        tolerance: f64,
        met: &mut Built,
    ) -> Block {
        match self.low_rank(t, s, faces, tolerance, false) {
            Some(lr) => self.block(t, s, BlockData::low_rank(lr, self.precision)),
            None => {
                let (block, stats) = self.exact_block(t, s, &mut NodeViews::default());
                met.add(stats, true);
                block
            }
        }
    }

    /// The factors of block (t, s) with every element seen whole (the kernel without
    /// occlusion), to `tolerance`, or `None` when their rank would not save memory.
    fn low_rank(
        &self,
        t: usize,
        s: usize,
        faces: &FacePairs,
        tolerance: f64,
        continued: bool,
    ) -> Option<aca::LowRank> {
        let (tc, sc) = (&self.nodes.clusters[t], &self.elements.clusters[s]);
        let per = self.per;
        let (m, c) = (tc.len(), sc.len() * per);
        let node_ids = &self.nodes.order[tc.start..tc.end];
        let element_ids = &self.elements.order[sc.start..sc.end];
        // Where no pair can give nothing, every entry is the kernel over the whole element, as
        // in a continued block.
        let continued = continued || faces.every_pair_gives(tc, sc);
        let row = |r: usize| {
            let i = node_ids[r];
            self.smooth_values(element_ids.iter().map(|&j| (i, j)), None, faces, continued)
        };
        let col = |q: usize| {
            let (j, basis) = (element_ids[q / per], q % per);
            self.smooth_values(node_ids.iter().map(|&i| (i, j)), Some(basis), faces, continued)
        };
        aca::aca(m, c, row, col, tolerance, self.useful_rank(t, s)?)
    }
}

#[cfg(test)]
mod tests;
