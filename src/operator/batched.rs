//! The operator's blocks from batched pair evaluations ([`PairEvaluation`]: the GPU's pair
//! kernel, or the CPU's threads). Every cross approximation advances in lockstep ([`Aca`] as a state
//! machine): the rows and columns they all ask for next are listed and evaluated in one batch,
//! so a block of rank k costs about 2k rounds for all blocks together, not 2k trips to the device
//! per block. The exact blocks are planned on the host by the dense path's pair plan (in
//! parallel) and evaluated in batches: partly visible pairs with their exact visible pieces, or,
//! where the engine clips ([`crate::assembly::CutEvaluation`]), each face seen in part handed
//! over once per node with its view.
//! The pair lists hold what is evaluated and nothing else: no n × n work anywhere.

use std::ops::Range;

use rayon::prelude::*;

use super::aca::{Aca, Request};
use super::blocks::{BlockPlan, FacePairs};
use super::built::{Built, by_node_cluster};
use super::compressed::Block;
use super::entries::{BlockFace, Entries, NodeViews, PartSeen};
use super::guard::MemoryGuard;
use super::shadowed;
use super::stored::BlockData;
use crate::assembly::{CutEvaluation, CutValues, FaceCut, PairEvaluation, PairTask};
use crate::error::Result;
use crate::progress::Progress;
use crate::visibility::{PairStats, Visibility};

/// Pairs listed per round on the host (tasks and their values): bounds the memory of a round;
/// the engine sizes its own batches.
const PAIRS_PER_ROUND: usize = 1 << 21;

/// A far block under construction.
struct Crossing {
    t: usize,
    s: usize,
    aca: Aca,
}

/// Where a task's values go in the sampled row or column: `len` of them, from value `from` of
/// the task, to position `at`.
struct Slot {
    at: usize,
    from: usize,
    len: usize,
}

/// The blocks of `plan` (near ones exact, far ones compressed to `tolerance` or exact when their
/// rank would not pay), with the pair classes met and the blocks found incompressible.
pub(super) fn build_blocks(
    entries: &Entries,
    plan: &BlockPlan,
    faces: &FacePairs,
    tolerance: f64,
    device: &dyn PairEvaluation,
    guard: &MemoryGuard,
    progress: &dyn Progress,
) -> Result<Built> {
    let mut exact: Vec<(usize, usize, bool)> =
        plan.near.iter().map(|b| (b.t, b.s, false)).collect();
    let mut crossings = Vec::new();
    for &(t, s) in &plan.far {
        match entries.useful_rank(t, s) {
            Some(max_rank) => {
                let (m, c) = entries.block_size(t, s);
                crossings.push(Crossing { t, s, aca: Aca::new(m, c, tolerance, max_rank) });
            }
            None => exact.push((t, s, true)),
        }
    }
    // Shadowed blocks walk their leaves' pairs and compress as the CPU's build does: their
    // entries are mostly partly visible pairs, which the host integrates anyway. They come
    // first, as on the CPU, where their compression's scratch adds least to the peak; their
    // slots go last in the list.
    let mut slots: Vec<Block> =
        (0..shadowed::sub_blocks(&plan.shadowed)).map(|_| Block::nothing()).collect();
    let met =
        shadowed::build(entries, &plan.shadowed, faces, tolerance, guard, progress, &mut slots);
    let mut built =
        cross_approximate(entries, faces, crossings, &mut exact, device, guard, progress)?;
    exact_blocks(entries, exact, device, guard, progress, &mut built)?;
    built = built.merged(met);
    built.blocks.extend(slots);
    guard.check(0)?;
    Ok(built)
}

/// The low-rank blocks of `crossings`, advanced in lockstep; a block whose rank would not pay is
/// added to `exact` (incompressible).
fn cross_approximate(
    entries: &Entries,
    faces: &FacePairs,
    mut crossings: Vec<Crossing>,
    exact: &mut Vec<(usize, usize, bool)>,
    device: &dyn PairEvaluation,
    guard: &MemoryGuard,
    progress: &dyn Progress,
) -> Result<Built> {
    let mut built = Built::default();
    while !crossings.is_empty() {
        let sizes: Vec<usize> = crossings.iter().map(|x| request_len(entries, x)).collect();
        for range in rounds(&sizes) {
            advance(entries, faces, device, &mut crossings[range])?;
        }
        // Finishing a block transposes its factors: on all cores, as a large operator has
        // hundreds of thousands of them.
        let (running, finished): (Vec<Crossing>, Vec<Crossing>) =
            crossings.into_par_iter().partition(|x| x.aca.request().is_some());
        let finished: Vec<(usize, usize, Option<_>)> =
            finished.into_par_iter().map(|x| (x.t, x.s, x.aca.finish())).collect();
        for (t, s, lr) in finished {
            match lr {
                Some(lr) => {
                    let block = entries.block(t, s, BlockData::low_rank(lr, entries.precision));
                    guard.add(block.bytes());
                    built.push(block, PairStats::default(), false);
                    progress.advance(1);
                }
                None => exact.push((t, s, true)),
            }
        }
        crossings = running;
        guard.check(0)?;
    }
    Ok(built)
}

/// The `exact` blocks (with whether each is incompressible) into `built`, their pairs planned
/// on the host by the row walk and evaluated by `device` in rounds. Where `device` clips the
/// elements of faces seen in part itself, the host hands it each such face's view once per node
/// instead of each element's visible pieces.
fn exact_blocks(
    entries: &Entries,
    mut exact: Vec<(usize, usize, bool)>,
    device: &dyn PairEvaluation,
    guard: &MemoryGuard,
    progress: &dyn Progress,
    built: &mut Built,
) -> Result<()> {
    // By node cluster, so that each node's views of the faces are found once per round.
    exact.sort_unstable();
    let sizes: Vec<usize> = exact
        .iter()
        .map(|&(t, s, _)| {
            let (m, c) = entries.block_size(t, s);
            m * c / entries.per
        })
        .collect();
    let clipper = device.clipper();
    let clips = clipper.is_some();
    for range in rounds(&sizes) {
        let blocks = &exact[range];
        let mut planned: Vec<PlannedBlock> = by_node_cluster(blocks)
            .into_par_iter()
            .flat_map_iter(|group| {
                let mut views = entries.node_views();
                group
                    .into_iter()
                    .map(|(t, s, _)| PlannedBlock::new(entries, t, s, &mut views, clips))
                    .collect::<Vec<_>>()
            })
            .collect();
        let task_offsets = offsets(planned.iter().map(|p| p.tasks.len()));
        let tasks: Vec<PairTask> = planned.iter_mut().flat_map(|p| p.tasks.drain(..)).collect();
        let values = device.evaluate(&tasks)?;
        drop(tasks);
        let (cut_values, cut_offsets) = match clipper {
            Some(clipper) => {
                let (values, stats) = clipped_parts(entries, clipper, device, &planned)?;
                built.add(stats, false);
                let lengths = planned.iter().map(PlannedBlock::part_pairs);
                (values, offsets(lengths))
            }
            None => (Vec::new(), vec![0; planned.len()]),
        };
        let per = entries.per;
        let done: Vec<_> = blocks
            .par_iter()
            .zip(planned.par_iter())
            .zip(task_offsets.par_iter().zip(&cut_offsets))
            .map(|((&(t, s, incompressible), plan), (&offset, &cut_offset))| {
                let (m, c) = entries.block_size(t, s);
                let mut data = vec![0.0; m * c];
                for (&a, v) in plan.at.iter().zip(&values[offset..]) {
                    data[a..a + per].copy_from_slice(&v[..per]);
                }
                let mut cut_values = cut_values[cut_offset..].iter();
                for part in &plan.parts {
                    let face = &plan.faces[part.face];
                    for (&k, v) in face.columns.iter().zip(cut_values.by_ref()) {
                        let a = part.row * c + k * per;
                        data[a..a + per].copy_from_slice(&v[..per]);
                    }
                }
                let mut block = entries.block(t, s, BlockData::exact(data));
                block.compact(entries.precision);
                (block, plan.stats, incompressible)
            })
            .collect();
        progress.advance(done.len());
        guard.add(done.iter().map(|d| d.0.bytes()).sum());
        done.into_iter()
            .for_each(|(block, stats, incompressible)| built.push(block, stats, incompressible));
        guard.check(0)?;
    }
    Ok(())
}

/// One exact block's plan: the pairs the host lists and where their values go, the classes it
/// met, and, where the engine clips, the block's faces and those of them its nodes see in part.
struct PlannedBlock {
    tasks: Vec<PairTask>,
    at: Vec<usize>,
    stats: PairStats,
    faces: Vec<BlockFace>,
    parts: Vec<PartSeen>,
}

impl PlannedBlock {
    fn new(entries: &Entries, t: usize, s: usize, views: &mut NodeViews, clips: bool) -> Self {
        let width = entries.block_size(t, s).1;
        let mut faces = entries.block_faces(s);
        let (mut tasks, mut at, mut parts) = (Vec::new(), Vec::new(), Vec::new());
        let list = |r: usize, k: usize, i: usize, j: usize, visible| {
            tasks.push(PairTask { node: i, element: j, visible });
            at.push(r * width + k * entries.per);
        };
        let stats = entries.walk_block(t, &faces, views, list, clips.then_some(&mut parts));
        if !clips {
            faces.clear();
        }
        Self { tasks, at, stats, faces, parts }
    }

    /// Pairs of the faces its nodes see in part, listed for the engine.
    fn part_pairs(&self) -> usize {
        self.parts.iter().map(|p| self.faces[p.face].elements.len()).sum()
    }
}

/// The values of the pairs of the faces seen in part in `planned`, block after block, part
/// after part, clipped by `clipper`, with their classes; the pairs it leaves are clipped here
/// as the row walk does and evaluated by `device`.
fn clipped_parts(
    entries: &Entries,
    clipper: &dyn CutEvaluation,
    device: &dyn PairEvaluation,
    planned: &[PlannedBlock],
) -> Result<(Vec<[f64; 3]>, PairStats)> {
    let cuts: Vec<FaceCut> = planned
        .iter()
        .flat_map(|b| {
            b.parts.iter().map(|p| {
                let f = &b.faces[p.face];
                FaceCut { node: p.node, view: &p.view, tree: &f.tree, elements: &f.elements }
            })
        })
        .collect();
    let CutValues { mut values, mut stats, left } = clipper.evaluate_cuts(&cuts)?;
    let starts = offsets(cuts.iter().map(|c| c.elements.len()));
    let (mut tasks, mut slots) = (Vec::new(), Vec::new());
    for (c, position) in left {
        let cut = &cuts[c];
        let visible = entries.planner.visible(cut.view, cut.tree.polygon(position));
        stats.record(&visible, 1);
        values[starts[c] + position] = [0.0; 3];
        if !matches!(visible, Visibility::Skip(_)) {
            tasks.push(PairTask { node: cut.node, element: cut.elements[position], visible });
            slots.push(starts[c] + position);
        }
    }
    for (slot, v) in slots.into_iter().zip(device.evaluate(&tasks)?) {
        values[slot] = v;
    }
    Ok((values, stats))
}

/// One step of every crossing in `crossings`: their requested rows and columns evaluated in one
/// batch and supplied.
fn advance(
    entries: &Entries,
    faces: &FacePairs,
    device: &dyn PairEvaluation,
    crossings: &mut [Crossing],
) -> Result<()> {
    let mut samples: Vec<(Vec<PairTask>, Vec<Slot>)> =
        crossings.par_iter().map(|x| sample(entries, faces, x)).collect();
    let offsets = offsets(samples.iter().map(|s| s.0.len()));
    let tasks: Vec<PairTask> = samples.iter_mut().flat_map(|s| s.0.drain(..)).collect();
    let values = device.evaluate(&tasks)?;
    crossings.par_iter_mut().zip(samples.par_iter()).zip(offsets.par_iter()).for_each(
        |((x, (_, slots)), &offset)| {
            let mut sampled = vec![0.0; request_len(entries, x)];
            for (slot, v) in slots.iter().zip(&values[offset..]) {
                sampled[slot.at..slot.at + slot.len]
                    .copy_from_slice(&v[slot.from..slot.from + slot.len]);
            }
            x.aca.supply(sampled);
        },
    );
    Ok(())
}

/// The pairs of the row or column `x` asks for that are not zero (in a smooth block every pair
/// is wholly visible or gives nothing), and where their values go.
fn sample(entries: &Entries, faces: &FacePairs, x: &Crossing) -> (Vec<PairTask>, Vec<Slot>) {
    let (tc, sc) = (&entries.nodes.clusters[x.t], &entries.elements.clusters[x.s]);
    let node_ids = &entries.nodes.order[tc.start..tc.end];
    let element_ids = &entries.elements.order[sc.start..sc.end];
    let per = entries.per;
    let (mut tasks, mut slots) = (Vec::new(), Vec::new());
    let mut list = |i: usize, j: usize, slot: Slot| {
        if entries.smooth_sees(i, j, faces) {
            tasks.push(PairTask { node: i, element: j, visible: Visibility::Full });
            slots.push(slot);
        }
    };
    match x.aca.request().expect("only running crossings are sampled") {
        Request::Row(r) => {
            for (k, &j) in element_ids.iter().enumerate() {
                list(node_ids[r], j, Slot { at: k * per, from: 0, len: per });
            }
        }
        Request::Column(q) => {
            let (j, basis) = (element_ids[q / per], q % per);
            for (r, &i) in node_ids.iter().enumerate() {
                list(i, j, Slot { at: r, from: basis, len: 1 });
            }
        }
    }
    (tasks, slots)
}

/// Values in the row or column `x` asks for next.
fn request_len(entries: &Entries, x: &Crossing) -> usize {
    let (m, c) = entries.block_size(x.t, x.s);
    match x.aca.request() {
        Some(Request::Row(_)) => c,
        Some(Request::Column(_)) => m,
        None => 0,
    }
}

/// Bytes the host holds for one round of exact blocks, at most (a block larger than a round
/// alone is not bounded by it): per pair, its task twice (listed per block, then gathered), the
/// position of its entry, its values read back and the block's entries before they are
/// compacted; partly visible pairs' pieces are not counted.
pub(super) const ROUND_BYTES: u64 = (PAIRS_PER_ROUND
    * (2 * std::mem::size_of::<PairTask>()
        + std::mem::size_of::<usize>()
        + std::mem::size_of::<[f64; 3]>()
        + 3 * std::mem::size_of::<f64>())) as u64;

/// Consecutive ranges of items whose sizes add up to at most [`PAIRS_PER_ROUND`] (one item
/// alone may exceed it).
fn rounds(sizes: &[usize]) -> Vec<Range<usize>> {
    let mut ranges = Vec::new();
    let (mut start, mut total) = (0, 0);
    for (k, &size) in sizes.iter().enumerate() {
        if total + size > PAIRS_PER_ROUND && k > start {
            ranges.push(start..k);
            (start, total) = (k, 0);
        }
        total += size;
    }
    if start < sizes.len() {
        ranges.push(start..sizes.len());
    }
    ranges
}

/// Where each of a sequence of lists starts in their concatenation.
fn offsets(lengths: impl Iterator<Item = usize>) -> Vec<usize> {
    lengths
        .scan(0, |next, len| {
            let at = *next;
            *next += len;
            Some(at)
        })
        .collect()
}
