//! A rank's share of the compressed operator's blocks in a distributed run
//! ([`crate::distributed`]): every rank holds the whole block plan and takes the blocks dealt to
//! it in two steps. The shadowed blocks go first, dealt by their estimated cost, and are built;
//! their stored bytes, which follow their partly visible pairs and which no estimate made before
//! sees, are then gathered, and the other blocks are dealt in rounds, the bytes gathered again
//! after each, so that the ranks' bytes come out about equal.

use super::blocks::{BlockPlan, NearBlock, ShadowedBlock};
use super::cluster::ClusterTree;

/// Cross-approximation steps assumed per low-rank block when estimating its cost (each step
/// evaluates one row and one column of the block).
const ESTIMATED_STEPS: usize = 12;

/// Blocks that are built together: the exact blocks of one node cluster (they share the nodes'
/// views of the faces), one low-rank block, or one shadowed block with its sub-blocks.
pub(super) struct Unit {
    /// Estimated entry evaluations, and entries stored (a low-rank block stores about as many
    /// as its cross approximation evaluates).
    cost: usize,
    near: Vec<NearBlock>,
    far: Option<(usize, usize)>,
    shadowed: Option<ShadowedBlock>,
}

/// What a unit's blocks are estimated to cost: a cluster pair's (rows, columns) and the cost of
/// a low-rank block of that size.
struct Costs<'a> {
    nodes: &'a ClusterTree,
    elements: &'a ClusterTree,
    per: usize,
}

impl Costs<'_> {
    fn size_of(&self, t: usize, s: usize) -> (usize, usize) {
        (self.nodes.clusters[t].len(), self.elements.clusters[s].len() * self.per)
    }

    /// An exact block evaluates and stores each entry.
    fn exact(&self, t: usize, s: usize) -> usize {
        let (m, c) = self.size_of(t, s);
        m * c
    }

    /// A low-rank block evaluates about `ESTIMATED_STEPS` rows and columns, never more than
    /// the whole block.
    fn low_rank(&self, t: usize, s: usize) -> usize {
        let (m, c) = self.size_of(t, s);
        (ESTIMATED_STEPS * (m + c)).min(m * c)
    }
}

/// The shadowed blocks of `plan` as units: each one's factors cost as a far block's, its leaves
/// as exact blocks.
fn shadowed_units(plan: &BlockPlan, costs: &Costs) -> Vec<Unit> {
    let units = plan.shadowed.iter().map(|b| Unit {
        cost: costs.low_rank(b.t, b.s)
            + b.leaves.iter().map(|&(t, s)| costs.exact(t, s)).sum::<usize>(),
        near: Vec::new(),
        far: None,
        shadowed: Some(b.clone()),
    });
    by_cost(units.collect())
}

/// The near blocks of `plan` as units, one per node cluster, and its far blocks, one each.
fn plain_units(plan: &BlockPlan, costs: &Costs) -> Vec<Unit> {
    let mut near = plan.near.clone();
    near.sort_unstable();
    let near = near.chunk_by(|a, b| a.t == b.t).map(|group| Unit {
        cost: group.iter().map(|b| costs.exact(b.t, b.s)).sum(),
        near: group.to_vec(),
        far: None,
        shadowed: None,
    });
    let far = plan.far.iter().map(|&(t, s)| Unit {
        cost: costs.low_rank(t, s),
        near: Vec::new(),
        far: Some((t, s)),
        shadowed: None,
    });
    by_cost(near.chain(far).collect())
}

/// `units` in the same order on every rank: by cost, largest first, then by the blocks
/// themselves.
fn by_cost(mut units: Vec<Unit>) -> Vec<Unit> {
    units.sort_unstable_by(|a, b| {
        let at = |u: &Unit| u.shadowed.as_ref().map(|b| (b.t, b.s));
        b.cost
            .cmp(&a.cost)
            .then_with(|| a.near.cmp(&b.near))
            .then_with(|| a.far.cmp(&b.far))
            .then_with(|| at(a).cmp(&at(b)))
    });
    units
}

/// The blocks of `units` dealt to `rank` by `dealt_to` (a unit's position to its rank).
fn taken(
    units: Vec<Unit>,
    rank: usize,
    mut dealt_to: impl FnMut(usize, &Unit) -> usize,
) -> BlockPlan {
    let mut mine = BlockPlan::default();
    for (position, unit) in units.into_iter().enumerate() {
        if dealt_to(position, &unit) == rank {
            mine.near.extend(unit.near);
            mine.far.extend(unit.far);
            mine.shadowed.extend(unit.shadowed);
        }
    }
    mine
}

/// The shadowed blocks of `plan` that rank `rank` of `size` builds first. They are dealt by
/// estimated cost in turns that go back and forth (0, 1, .., N-1, N-1, .., 0, ...), so that
/// every rank gets its like share of the large and the small ones.
pub(super) fn shadowed_share(
    plan: &BlockPlan,
    nodes: &ClusterTree,
    elements: &ClusterTree,
    per: usize,
    (rank, size): (usize, usize),
) -> BlockPlan {
    let units = shadowed_units(plan, &Costs { nodes, elements, per });
    taken(units, rank, |position, _| {
        let (turn, seat) = (position / size, position % size);
        if turn % 2 == 0 { seat } else { size - 1 - seat }
    })
}

/// Rounds in which the near and far blocks are dealt after the shadowed ones, and the share of
/// their estimated cost each round leaves to the rounds after it.
const ROUNDS: usize = 4;
const LEFT_AFTER_A_ROUND: f64 = 0.25;

/// The near and far blocks of `plan` in the rounds they are dealt in: largest first, each round
/// a quarter of the estimated cost of the one before, so that the last rounds' small blocks
/// even out what the estimate got wrong in the earlier ones.
pub(super) fn rest_rounds(
    plan: &BlockPlan,
    nodes: &ClusterTree,
    elements: &ClusterTree,
    per: usize,
) -> Vec<Vec<Unit>> {
    let units = plain_units(plan, &Costs { nodes, elements, per });
    let total: usize = units.iter().map(|u| u.cost).sum();
    let mut rounds: Vec<Vec<Unit>> = (0..ROUNDS).map(|_| Vec::new()).collect();
    let (mut round, mut dealt) = (0, 0);
    for unit in units {
        let left = total as f64 * LEFT_AFTER_A_ROUND.powi(round as i32 + 1);
        if round + 1 < ROUNDS && (total - dealt) as f64 <= left {
            round += 1;
        }
        dealt += unit.cost;
        rounds[round].push(unit);
    }
    rounds
}

/// The blocks of one round of [`rest_rounds`] that rank `rank` builds, where `held[r]` is what
/// rank r holds already, in bytes. Units are dealt largest first, each to the rank that holds
/// least so far (the lowest such rank), a unit counting as its estimated cost times
/// `entry_bytes`: so the ranks' bytes come out about equal whatever the blocks built before
/// turned out to hold.
pub(super) fn dealt(units: Vec<Unit>, held: &[u64], entry_bytes: u64, rank: usize) -> BlockPlan {
    let mut load = held.to_vec();
    taken(units, rank, |_, unit| {
        let least = (0..load.len()).min_by_key(|&r| (load[r], r)).expect("at least one rank");
        load[least] += unit.cost as u64 * entry_bytes;
        least
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::operator::blocks::Empty;
    use crate::operator::cluster::Item;
    use glam::DVec3;

    /// Every block goes to exactly one rank; the shadowed blocks are dealt by cost, and the rest
    /// even out the ranks' bytes, whatever the shadowed blocks turned out to hold.
    #[test]
    fn shares_cover_the_plan_once_and_balance_the_bytes() {
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
        let shadowed = pairs(&inner[1..3], 1).into_iter();
        let shadowed = shadowed
            .map(|(t, s)| ShadowedBlock {
                t,
                s,
                seen: vec![(t, s)],
                leaves: vec![(leaves[0], leaves[1])],
            })
            .collect();
        let empty = Empty { blocks: 5, pairs: 40 };
        let plan = BlockPlan { near, far, shadowed, empty };
        let cost = |p: &BlockPlan| -> u64 {
            let near: usize =
                p.near.iter().map(|b| tree.clusters[b.t].len() * tree.clusters[b.s].len()).sum();
            let far: usize = p
                .far
                .iter()
                .map(|&(t, s)| {
                    let (m, c) = (tree.clusters[t].len(), tree.clusters[s].len());
                    (ESTIMATED_STEPS * (m + c)).min(m * c)
                })
                .sum();
            (near + far) as u64
        };
        let whole: u64 = cost(&plan);
        for size in [1, 2, 3] {
            // What the ranks' shadowed blocks held: nothing, or a tenth of the rest's bytes at
            // rank 0 (which is then dealt that much less).
            for first in [0, whole] {
                let held: Vec<u64> = (0..size).map(|r| if r == 0 { first } else { 0 }).collect();
                let mut rounds: Vec<_> =
                    (0..size).map(|_| rest_rounds(&plan, &tree, &tree, 1).into_iter()).collect();
                let mut shares: Vec<(BlockPlan, BlockPlan)> = (0..size)
                    .map(|r| {
                        (shadowed_share(&plan, &tree, &tree, 1, (r, size)), BlockPlan::default())
                    })
                    .collect();
                shares[0].1.empty = plan.empty;
                // Each round dealt on every rank from the same bytes held, as the build
                // gathers them; here a unit holds what its cost says, 10 bytes an entry.
                let mut now = held.clone();
                for _ in 0..ROUNDS {
                    let mine: Vec<BlockPlan> = (rounds.iter_mut().enumerate())
                        .map(|(r, rounds)| {
                            let round = rounds.next().expect("ROUNDS rounds");
                            let costs: Vec<usize> = round.iter().map(|u| u.cost).collect();
                            assert!(costs.windows(2).all(|w| w[0] >= w[1]), "largest first");
                            dealt(round, &now, 10, r)
                        })
                        .collect();
                    for (r, m) in mine.into_iter().enumerate() {
                        now[r] += 10 * cost(&m);
                        shares[r].1.near.extend(m.near);
                        shares[r].1.far.extend(m.far);
                        shares[r].1.shadowed.extend(m.shadowed);
                    }
                }
                let all = |f: &dyn Fn(&BlockPlan) -> Vec<String>| {
                    let mut v: Vec<String> =
                        shares.iter().flat_map(|(a, b)| [f(a), f(b)].concat()).collect();
                    v.sort_unstable();
                    v
                };
                let list = |f: &dyn Fn(&BlockPlan) -> Vec<String>| {
                    let mut v = f(&plan);
                    v.sort_unstable();
                    v
                };
                let near = |p: &BlockPlan| p.near.iter().map(|b| format!("{b:?}")).collect();
                let far = |p: &BlockPlan| p.far.iter().map(|b| format!("{b:?}")).collect();
                let shadowed =
                    |p: &BlockPlan| p.shadowed.iter().map(|b| format!("{b:?}")).collect();
                assert_eq!(all(&near), list(&near), "{size} ranks");
                assert_eq!(all(&far), list(&far), "{size} ranks");
                assert_eq!(all(&shadowed), list(&shadowed), "{size} ranks");
                assert!(shares.iter().all(|(a, _)| a.near.is_empty() && a.far.is_empty()));
                assert!(shares.iter().all(|(_, b)| b.shadowed.is_empty()));
                assert_eq!(
                    shares.iter().map(|(a, b)| a.empty.blocks + b.empty.blocks).sum::<usize>(),
                    5
                );
                assert_eq!(shares.iter().map(|(_, b)| b.empty.pairs).sum::<u64>(), 40);
                // Each rank's bytes: what it held plus its units' at 10 bytes an entry.
                let bytes: Vec<u64> =
                    shares.iter().zip(&held).map(|((_, b), h)| h + 10 * cost(b)).collect();
                let (lo, hi) = (bytes.iter().min().unwrap(), bytes.iter().max().unwrap());
                assert!(*hi as f64 <= 1.1 * *lo as f64, "{size} ranks: bytes {bytes:?}");
            }
        }
    }
}
