//! The memory estimate of a compressed operator's build ([`MemoryEstimate`]) from a sample of
//! its pairs, each followed down the block plan to the block that holds it.

use rayon::prelude::*;

use super::blocks::{
    self, BlockPlan, FacePairs, Located, PLAN_FAR_BYTES, PLAN_NEAR_BYTES, ShadowedPart,
};
use super::cluster::{self, ClusterTree};
use super::compressed::Block;
use super::entries::{Entries, PLACED_BYTES};
use super::estimate::MemoryEstimate;
use super::options::CompressionOptions;
use super::shadowed;
use super::stats::order_bytes;
use super::stored::{self, Precision};
use crate::visibility::{FaceSight, RecentHiders, Views, Visibility};

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
pub(super) fn build_list_bytes(plan: &BlockPlan) -> u64 {
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

/// Vectors of n values that the solve holds on a rank, with `threads` of its own: its rows of
/// GMRES's vectors, two per thread for the products, and over several ranks the whole `x` of
/// a product and what is gathered to make it.
fn solver_vectors(ranks: u64, threads: u64) -> u64 {
    let gathered = if ranks > 1 { 2 } else { 0 };
    GMRES_VECTORS.div_ceil(ranks.max(1)) + 2 * threads + gathered
}

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

impl Entries<'_> {
    /// How node i sees element j, by the row walk of the dense path's pair plan.
    fn pair_sight(&self, i: usize, j: usize, hiders: &mut RecentHiders) -> Sight {
        let node = &self.disc.node(i);
        let mut sight = Sight::Hidden;
        let faces = [(self.disc.face_of(j), std::iter::once(()))];
        self.planner.walk_row(&node.viewer(), faces, Views::Fresh(hiders), |_, _, seen| {
            sight = match seen {
                FaceSight::Hidden(_) => Sight::Hidden,
                FaceSight::Whole => Sight::Whole,
                FaceSight::Part(mut part) => match part.element(&self.disc.in_face(j)) {
                    Visibility::Skip(_) => Sight::Hidden,
                    Visibility::Full => Sight::Whole,
                    Visibility::Partial(_) => Sight::Part,
                },
            };
        });
        sight
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
pub(super) fn estimate_memory(
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
        solver: 8 * dof as u64 * solver_vectors(ranks as u64, threads),
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
    // far block's reach its break-even rank before it is refused), and its elements placed.
    let crossing = kinds
        .iter()
        .map(|(&(t, s), &continued)| {
            let (m, c) = entries.block_size(t, s);
            let rank = match ranks_found.get(&(t, s)) {
                Some(Some(k)) => *k as f64,
                Some(None) => entries.useful_rank(t, s).unwrap_or(0) as f64,
                None => imputed(continued, shape(t, s)),
            };
            let placed = (c / entries.per) as f64 * PLACED_BYTES as f64;
            CROSSING_BYTES as f64 * rank * (m + c) as f64 + placed
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
        crossing: (in_flight * crossing) as u64,
        error: (scale * (count * variance).sqrt()).round() as u64,
        samples: samples.len(),
        ..estimate
    }
}
