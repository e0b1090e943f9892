//! A rank's share of the compressed operator's blocks in a distributed run
//! ([`crate::distributed`]): every rank holds the whole block plan and takes the blocks dealt to
//! it, so that the ranks' estimated costs come out about equal.

use super::blocks::{BlockPlan, Empty, NearBlock, ShadowedBlock};
use super::cluster::ClusterTree;

/// Cross-approximation steps assumed per low-rank block when estimating its cost (each step
/// evaluates one row and one column of the block).
const ESTIMATED_STEPS: usize = 12;

/// Blocks that are built together: the exact blocks of one node cluster (they share the nodes'
/// views of the faces), one low-rank block, or one shadowed block with its sub-blocks.
struct Unit {
    /// Estimated entry evaluations.
    cost: usize,
    near: Vec<NearBlock>,
    far: Option<(usize, usize)>,
    shadowed: Option<ShadowedBlock>,
}

/// The blocks of `plan` that rank `rank` of `size` builds. Units are sorted by estimated cost
/// and dealt out in turns that go back and forth (0, 1, .., N-1, N-1, .., 0, ...), so that every
/// rank gets its like share of the large and the small ones, whatever the estimate's error is
/// for a kind of block. The empty blocks are counted at rank 0.
pub(super) fn share_of(
    plan: &BlockPlan,
    nodes: &ClusterTree,
    elements: &ClusterTree,
    per: usize,
    (rank, size): (usize, usize),
) -> BlockPlan {
    let size_of = |t: usize, s: usize| (nodes.clusters[t].len(), elements.clusters[s].len() * per);
    let mut near = plan.near.clone();
    near.sort_unstable();
    let mut units: Vec<Unit> = near
        .chunk_by(|a, b| a.t == b.t)
        .map(|group| Unit {
            cost: group.iter().map(|b| size_of(b.t, b.s)).map(|(m, c)| m * c).sum(),
            near: group.to_vec(),
            far: None,
            shadowed: None,
        })
        .collect();
    let far_cost = |(m, c): (usize, usize)| (ESTIMATED_STEPS * (m + c)).min(m * c);
    units.extend(plan.far.iter().map(|&(t, s)| Unit {
        cost: far_cost(size_of(t, s)),
        near: Vec::new(),
        far: Some((t, s)),
        shadowed: None,
    }));
    // A shadowed block: its factors as a far block's, its leaves as exact blocks.
    units.extend(plan.shadowed.iter().map(|b| {
        let leaves: usize = b.leaves.iter().map(|&(t, s)| size_of(t, s)).map(|(m, c)| m * c).sum();
        Unit {
            cost: far_cost(size_of(b.t, b.s)) + leaves,
            near: Vec::new(),
            far: None,
            shadowed: Some(b.clone()),
        }
    }));
    // The same order on every rank: by cost, then by the blocks themselves.
    units.sort_unstable_by(|a, b| {
        let at = |u: &Unit| u.shadowed.as_ref().map(|b| (b.t, b.s));
        b.cost
            .cmp(&a.cost)
            .then_with(|| a.near.cmp(&b.near))
            .then_with(|| a.far.cmp(&b.far))
            .then_with(|| at(a).cmp(&at(b)))
    });
    let mut mine = BlockPlan {
        empty: if rank == 0 { plan.empty } else { Empty::default() },
        ..Default::default()
    };
    for (position, unit) in units.into_iter().enumerate() {
        let (turn, seat) = (position / size, position % size);
        let dealt_to = if turn % 2 == 0 { seat } else { size - 1 - seat };
        if dealt_to == rank {
            mine.near.extend(unit.near);
            mine.far.extend(unit.far);
            mine.shadowed.extend(unit.shadowed);
        }
    }
    mine
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::operator::cluster::Item;
    use glam::DVec3;

    /// Every block goes to exactly one rank, and the ranks' estimated costs are close.
    #[test]
    fn shares_cover_the_plan_once_and_balance() {
        let items: Vec<Item> = (0..256)
            .map(|i| {
                let p = DVec3::new((i % 16) as f64, (i / 16) as f64, 0.0);
                Item { point: p, lo: p, hi: p, face: 0 }
            })
            .collect();
        let tree = ClusterTree::new(&items, 4);
        // Near blocks between leaves, far ones between larger clusters, as a plan has them.
        let (leaves, inner): (Vec<usize>, Vec<usize>) =
            (0..tree.clusters.len()).partition(|&t| tree.clusters[t].children.is_none());
        let pairs = |list: &[usize], stride: usize| -> Vec<(usize, usize)> {
            let all = list.iter().flat_map(|&t| list.iter().map(move |&s| (t, s)));
            all.step_by(stride).collect()
        };
        let near = pairs(&leaves, 3).into_iter();
        let near = near.map(|(t, s)| NearBlock { t, s, seen_whole: (t + s) % 2 == 0 }).collect();
        let far = pairs(&inner[1..], 5);
        let empty = Empty { blocks: 5, pairs: 40 };
        let plan = BlockPlan { near, far, shadowed: Vec::new(), empty };
        for size in [1, 2, 3] {
            let shares: Vec<BlockPlan> =
                (0..size).map(|r| share_of(&plan, &tree, &tree, 1, (r, size))).collect();
            let mut near: Vec<_> = shares.iter().flat_map(|p| p.near.clone()).collect();
            let mut far: Vec<_> = shares.iter().flat_map(|p| p.far.clone()).collect();
            let (mut want_near, mut want_far) = (plan.near.clone(), plan.far.clone());
            near.sort_unstable();
            want_near.sort_unstable();
            far.sort_unstable();
            want_far.sort_unstable();
            assert_eq!((near, far), (want_near, want_far), "{size} ranks");
            assert_eq!(shares.iter().map(|p| p.empty.blocks).sum::<usize>(), 5);
            assert_eq!(shares.iter().map(|p| p.empty.pairs).sum::<u64>(), 40);
            let cost = |p: &BlockPlan| -> usize {
                let near: usize = p
                    .near
                    .iter()
                    .map(|b| tree.clusters[b.t].len() * tree.clusters[b.s].len())
                    .sum();
                let far: usize = p
                    .far
                    .iter()
                    .map(|&(t, s)| {
                        let (m, c) = (tree.clusters[t].len(), tree.clusters[s].len());
                        (ESTIMATED_STEPS * (m + c)).min(m * c)
                    })
                    .sum();
                near + far
            };
            let costs: Vec<usize> = shares.iter().map(cost).collect();
            let (lo, hi) = (costs.iter().min().unwrap(), costs.iter().max().unwrap());
            assert!(*hi as f64 <= 1.1 * *lo as f64, "{size} ranks: costs {costs:?}");
        }
    }
}
