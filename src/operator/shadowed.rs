//! Admissible blocks that occluders cut (a room seen through slats, walls across a street), or
//! whose elements cross the nodes' tangent planes (a tilted slat's plane through a wall).
//! Without occlusion, and continued across the tangent planes, their kernel is smooth, so the
//! whole block's kernel is compressed once, by cross approximation as a far block is, and its
//! sub-blocks share those factors: a sub-block its nodes see whole is their product, and a leaf
//! that a shadow boundary or a tangent plane crosses keeps one bit for each element a node sees
//! whole (the product's entry) and the exact integral of each element it sees in part.
//! Exactness of partly visible elements is kept; what the factors stand for are fully visible
//! pairs, to the compression tolerance, so memory and time follow the partly visible pairs
//! instead of the leaves around them.

use std::sync::Arc;

use rayon::prelude::*;

use super::blocks::{FacePairs, ShadowedBlock};
use super::built::{Built, by_node_cluster};
use super::compressed::Block;
use super::entries::Entries;
use super::guard::MemoryGuard;
use super::stored::{BlockData, FactorSlice, Factors, ShadowedLeaf, SparseRows, mask_words};
use crate::progress::Progress;
use crate::visibility::PairStats;

/// What a leaf's pairs gave before the factors exist: the mask of the elements seen whole and
/// the exact entries of those seen in part.
struct LeafParts {
    whole: Box<[u64]>,
    partial: SparseRows,
    stats: PairStats,
}

/// Bytes a leaf's parts take in the build's lists besides their values (the list of parts and
/// the list they are found in).
pub(super) const LEAF_PARTS_BYTES: u64 =
    (std::mem::size_of::<Option<LeafParts>>() + std::mem::size_of::<(usize, LeafParts)>()) as u64;

/// Sub-blocks of the plan's shadowed blocks, as many as slots [`build`] fills.
pub(super) fn sub_blocks(blocks: &[ShadowedBlock]) -> usize {
    blocks.iter().map(|b| b.seen.len() + b.leaves.len()).sum()
}

/// Builds the shadowed blocks into `slots` ([`sub_blocks`] of them: each block's sub-blocks
/// seen whole, then its leaves). The leaves' pairs come first, by node cluster as the exact
/// blocks' do; then each block's unoccluded kernel is compressed, to the tolerance times the
/// square root of the share of its entries that are seen (the error of the factors spreads
/// over the whole block, and only the seen part of it is kept). A block whose rank would not
/// pay is built as the plain plan would have it: leaves exact, sub-blocks seen whole
/// compressed on their own.
pub(super) fn build(
    entries: &Entries,
    blocks: &[ShadowedBlock],
    faces: &FacePairs,
    tolerance: f64,
    guard: &MemoryGuard,
    progress: &dyn Progress,
    slots: &mut [Block],
) -> Built {
    let per = entries.per;
    let leaves: Vec<(usize, usize, usize)> =
        blocks.iter().flat_map(|b| &b.leaves).enumerate().map(|(at, &(t, s))| (t, s, at)).collect();
    let mut parts: Vec<Option<LeafParts>> = (0..leaves.len()).map(|_| None).collect();
    let found: Vec<Vec<(usize, LeafParts)>> = by_node_cluster(&leaves)
        .into_par_iter()
        .map(|group| {
            let mut views = entries.node_views();
            let mut out = Vec::with_capacity(group.len());
            for (t, s, at) in group {
                if guard.is_over() {
                    break;
                }
                let (m, width) = entries.block_size(t, s);
                let mut whole = vec![0u64; m * mask_words(width)];
                let (values, stats) =
                    entries.exact_entries(t, s, &mut views, Some(whole.as_mut_slice()));
                let partial = SparseRows::from_dense(&values, width, entries.precision);
                let leaf = LeafParts { whole: whole.into_boxed_slice(), partial, stats };
                guard.add(8 * leaf.whole.len() as u64 + leaf.partial.bytes());
                out.push((at, leaf));
            }
            out
        })
        .collect();
    found.into_iter().flatten().for_each(|(at, leaf)| parts[at] = Some(leaf));

    // Each block with its slots and its leaves' parts.
    let mut work = Vec::with_capacity(blocks.len());
    let (mut slots, mut parts) = (slots, parts.as_mut_slice());
    for block in blocks {
        let (mine, rest) =
            std::mem::take(&mut slots).split_at_mut(block.seen.len() + block.leaves.len());
        let (leaf_parts, after) = std::mem::take(&mut parts).split_at_mut(block.leaves.len());
        work.push((block, mine, leaf_parts));
        (slots, parts) = (rest, after);
    }
    work.into_par_iter()
        .map(|(block, slots, leaf_parts)| {
            let mut met = Built::default();
            if guard.is_over() {
                return met;
            }
            let (seen_slots, leaf_slots) = slots.split_at_mut(block.seen.len());
            let area = |t: usize, s: usize| {
                let (m, c) = entries.block_size(t, s);
                (m * c) as f64
            };
            let seen = block.seen.iter().map(|&(t, s)| area(t, s)).sum::<f64>()
                + leaf_parts
                    .iter()
                    .flatten()
                    .map(|p| {
                        let whole: u32 = p.whole.iter().map(|w| w.count_ones()).sum();
                        f64::from(whole) + p.partial.values.len() as f64
                    })
                    .sum::<f64>();
            let share = seen / area(block.t, block.s);
            let factors = (share > 0.0)
                .then(|| entries.low_rank(block.t, block.s, faces, tolerance * share.sqrt(), true))
                .flatten();
            // Where sub-block (t, s) starts in the factors' rows and columns.
            let (rows, columns) = (&entries.nodes.clusters, &entries.elements.clusters);
            let slice = |factors: &Arc<Factors>, t: usize, s: usize| FactorSlice {
                factors: factors.clone(),
                row0: (rows[t].start - rows[block.t].start) as u32,
                col0: ((columns[s].start - columns[block.s].start) * per) as u32,
            };
            match factors {
                Some(lr) => {
                    let factors = Arc::new(Factors::from_low_rank(lr, entries.precision));
                    guard.add(factors.u.bytes() + factors.v.bytes());
                    for (slot, &(t, s)) in seen_slots.iter_mut().zip(&block.seen) {
                        *slot = entries.block(t, s, BlockData::Seen(slice(&factors, t, s)));
                    }
                    for ((slot, &(t, s)), part) in
                        leaf_slots.iter_mut().zip(&block.leaves).zip(leaf_parts.iter_mut())
                    {
                        let Some(LeafParts { whole, partial, stats }) = part.take() else {
                            continue;
                        };
                        met.add(stats, false);
                        let leaf = ShadowedLeaf { slice: slice(&factors, t, s), whole, partial };
                        *slot = if leaf.whole_entries() == 0 && leaf.partial.values.is_empty() {
                            Block::nothing()
                        } else {
                            entries.block(t, s, BlockData::Leaf(Box::new(leaf)))
                        };
                    }
                }
                None => {
                    // As the plain plan: the seen sub-blocks compressed on their own (exact
                    // where that does not pay), the leaves exact.
                    for (slot, &(t, s)) in seen_slots.iter_mut().zip(&block.seen) {
                        *slot = entries.compressed_or_exact(t, s, faces, tolerance, &mut met);
                        guard.add(slot.bytes());
                    }
                    let mut views = entries.node_views();
                    for ((slot, &(t, s)), part) in
                        leaf_slots.iter_mut().zip(&block.leaves).zip(leaf_parts.iter_mut())
                    {
                        let Some(part) = part.take() else { continue };
                        if part.whole.iter().all(|&w| w == 0) && part.partial.values.is_empty() {
                            met.add(part.stats, false);
                            continue;
                        }
                        let (b, stats) = entries.exact_block(t, s, &mut views);
                        met.add(stats, false);
                        guard.add(b.bytes());
                        *slot = b;
                    }
                }
            }
            progress.advance(block.seen.len() + block.leaves.len());
            met
        })
        .reduce(Built::default, Built::merged)
}
