//! What the build of a compressed operator gathers: the blocks built and the pairs met, grouped
//! by node cluster, and the blocks kept in the end.

use super::compressed::{Block, block_stats};
use super::stats::OperatorStats;
use super::stored::BlockData;
use crate::visibility::PairStats;

/// The blocks `(t, s, ..)` of `blocks` grouped by node cluster (runs of one `t`, in order).
pub(super) fn by_node_cluster<T: Copy + Ord>(
    blocks: &[(usize, usize, T)],
) -> Vec<Vec<(usize, usize, T)>> {
    let mut sorted = blocks.to_vec();
    sorted.sort_unstable();
    sorted.chunk_by(|a, b| a.0 == b.0).map(<[_]>::to_vec).collect()
}

/// The blocks built and what was met building them: the classes of the pairs evaluated
/// exactly and the admissible blocks found incompressible. Exact blocks that held nothing are
/// among the blocks until [`kept_blocks`] counts and drops them.
#[derive(Default)]
pub(super) struct Built {
    pub(super) blocks: Vec<Block>,
    pub(super) pairs: PairStats,
    pub(super) incompressible: u64,
}

impl Built {
    /// Adds a block, with the pair classes its exact entries met and whether it was admissible
    /// but found incompressible.
    pub(super) fn push(&mut self, block: Block, pairs: PairStats, incompressible: bool) {
        self.add(pairs, incompressible);
        self.blocks.push(block);
    }

    pub(super) fn add(&mut self, pairs: PairStats, incompressible: bool) {
        self.pairs += pairs;
        self.incompressible += u64::from(incompressible);
    }

    /// What both met; only `self` holds blocks (the parts of a build write theirs into their
    /// slots of one list and tally the rest).
    pub(super) fn merged(mut self, other: Built) -> Self {
        debug_assert!(other.blocks.is_empty());
        self.pairs += other.pairs;
        self.incompressible += other.incompressible;
        self
    }

    /// Two builds in one: `other`'s blocks after `self`'s, and what both met.
    pub(super) fn joined(mut self, mut other: Built) -> Self {
        self.blocks.append(&mut other.blocks);
        self.merged(other)
    }
}

/// The blocks built that hold something, in one list, with their statistics and the pair
/// classes met (`empty`: the blocks the plan left out).
pub(super) fn kept_blocks(
    built: Built,
    empty: usize,
    per: usize,
) -> (Vec<Block>, OperatorStats, PairStats) {
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
