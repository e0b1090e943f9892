//! What a compressed operator tells of itself: its blocks and entries by kind, ranks and bytes,
//! on one rank or summed over all.

use serde::Serialize;

use crate::distributed::Collective;
use crate::visibility::PairStats;

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
    /// Views of faces that the exact blocks' row walks computed (a node views a face once for
    /// the blocks of one of its clusters, and not where the planes tell: faces in its plane or
    /// behind it): over the unknowns, the faces examined per node. Not among
    /// [`OperatorStats::counts`] (none in a loaded operator).
    pub faces_viewed: u64,
    /// Of `faces_viewed`, the views that found nothing of the face seen (hidden, or behind the
    /// node's tangent plane): faces examined in vain, which a tighter set of the faces in sight
    /// would not examine. Not among [`OperatorStats::counts`] (none in a loaded operator).
    pub faces_viewed_unseen: u64,
    /// Faces that the exact blocks' row walks took as hidden without a view, being outside
    /// what their node may see (`operator/sight.rs`; each time a block asked). Not among
    /// [`OperatorStats::counts`] (none in a loaded operator).
    pub faces_culled: u64,
    /// (Node, element) pairs in the blocks found to hold nothing: pairs the plan culled whole,
    /// without a test of their own. Not among [`OperatorStats::counts`] (none in a loaded
    /// operator).
    pub empty_block_pairs: u64,
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
            faces_viewed: 0,
            faces_viewed_unseen: 0,
            faces_culled: 0,
            empty_block_pairs: 0,
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
        self.faces_viewed += o.faces_viewed;
        self.faces_viewed_unseen += o.faces_viewed_unseen;
        self.faces_culled += o.faces_culled;
        self.empty_block_pairs += o.empty_block_pairs;
    }
}

/// Bytes of the node and element orders of an operator of `dof` unknowns, `per` to an element.
pub(super) fn order_bytes(dof: usize, per: usize) -> u64 {
    8 * (dof + dof / per) as u64
}

/// The whole operator's statistics from every rank's (a collective: every rank calls it).
pub(super) fn summed_over(
    ranks: &dyn Collective,
    stats: OperatorStats,
    pairs: PairStats,
) -> (OperatorStats, PairStats) {
    let more = [
        stats.low_rank_bytes,
        stats.shadowed_blocks,
        stats.faces_viewed,
        stats.empty_block_pairs,
        stats.faces_culled,
        stats.faces_viewed_unseen,
    ];
    let mine: Vec<u64> = stats.counts().into_iter().chain(pairs.counts()).chain(more).collect();
    let (mut stats, mut pairs) = (OperatorStats::default(), PairStats::default());
    for counts in ranks.gather(&mine) {
        let (s, rest) = counts.split_at(OperatorStats::COUNTS);
        let (p, more) = rest.split_at(rest.len() - more.len());
        stats += OperatorStats {
            low_rank_bytes: more[0],
            shadowed_blocks: more[1],
            faces_viewed: more[2],
            empty_block_pairs: more[3],
            faces_culled: more[4],
            faces_viewed_unseen: more[5],
            ..OperatorStats::from_counts(s.try_into().expect("a rank's statistics"))
        };
        pairs += PairStats::from_counts(p.try_into().expect("a rank's pair classes"));
    }
    (stats, pairs)
}
