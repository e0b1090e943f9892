//! The elements of faces seen in part by listed nodes, clipped and integrated on the device:
//! the clipping kernel of the row tiles (shaders/clip.wgsl) in its listed-pairs mode. The
//! compressed operator's exact blocks hand over each (node, face) they see in part once, with
//! the box tree over the block's elements of the face ([`FaceCut`]), instead of each element's
//! visible pieces, so the host's work grows with the faces seen in part, not their elements.
//!
//! A batch's buffers: a view per cut (the node in the face's frame, as `assemble_pairs` reads
//! it); per cut a record (first pair, its view, where its elements are listed, where the face's
//! view is), a last record with the batch's pair count, then the elements; the box trees and
//! the faces' views. Pairs the kernel cannot hold, and those of thin elements (whose closed
//! forms cancel and which the CPU evaluates), are left to the caller.

use std::collections::HashMap;
use std::time::Instant;

use super::compute;
use super::cuts::tallies as tallies_of;
use super::layout::{self, Params, VIEW_STRIDE};
use super::pairs::PairEvaluator;
use super::tile_plan::push_cut_view;
use crate::assembly::{CutEvaluation, CutValues, FaceCut};
use crate::error::Result;
use crate::visibility::{ElementBoxes, FaceView, PairStats};

/// An element the kernel leaves to the host (`LEFT_TO_HOST` in shaders/clip.wgsl).
const LEFT_TO_HOST: u32 = u32::MAX;

/// Reals of a box tree node (`BOX_NODE_STRIDE` in shaders/clip.wgsl).
const BOX_NODE_REALS: usize = 7;

/// Reals of a face's view as the clipping kernel reads it ([`push_cut_view`]).
fn view_reals(view: &FaceView) -> usize {
    match view {
        FaceView::Visible { shadows, .. } => {
            6 + shadows.iter().map(|s| 5 + 2 * s.len()).sum::<usize>()
        }
        FaceView::Skip(_) => 0,
    }
}

/// A batch of cuts as the kernel reads them.
struct CutBatch {
    views: Vec<f64>,
    records: Vec<u32>,
    vertices: Vec<f64>,
    /// Pairs in the batch.
    pairs: u64,
    /// The batch's pairs left to the host from the start (thin elements): (cut, position).
    thin: Vec<(usize, usize)>,
}

impl PairEvaluator<'_> {
    /// The kernel's input for `cuts`.
    fn cut_batch(&self, cuts: &[FaceCut]) -> CutBatch {
        let (disc, unit) = (self.disc, self.unit);
        let mut views = Vec::with_capacity(cuts.len() * VIEW_STRIDE);
        let pairs: usize = cuts.iter().map(|c| c.elements.len()).sum();
        let lists_start = 4 * (cuts.len() + 1);
        let mut records = Vec::with_capacity(lists_start + pairs);
        let mut lists = Vec::with_capacity(pairs);
        let mut vertices = Vec::new();
        let mut trees: HashMap<*const ElementBoxes, u32> = HashMap::new();
        let mut thin = Vec::new();
        let mut first = 0u32;
        for (c, cut) in cuts.iter().enumerate() {
            let face = disc.face_of(cut.elements[0]);
            views.extend(self.view_of(cut.node, face));
            let tree = *trees
                .entry(std::ptr::from_ref(cut.tree))
                .or_insert_with(|| layout::pack_box_trees([cut.tree], unit, &mut vertices)[0]);
            let view_at = vertices.len() as u32;
            push_cut_view(cut.view, unit, tree, &mut vertices);
            records.extend_from_slice(&[
                first,
                c as u32,
                (lists_start + lists.len()) as u32,
                view_at,
            ]);
            for (position, &j) in cut.elements.iter().enumerate() {
                if self.thin[j] {
                    thin.push((c, position));
                    lists.push(LEFT_TO_HOST);
                } else {
                    lists.push(j as u32);
                }
            }
            first += cut.elements.len() as u32;
        }
        records.extend_from_slice(&[first, 0, 0, 0]);
        records.extend(lists);
        CutBatch { views, records, vertices, pairs: pairs as u64, thin }
    }

    /// What one cut adds to a batch's buffers, in bytes: views, records, vertices, output.
    fn cut_bytes(&self, cut: &FaceCut) -> [u64; 4] {
        let bytes = self.assembler.precision.bytes() as u64;
        let pairs = cut.elements.len() as u64;
        let tree = BOX_NODE_REALS * cut.tree.nodes().count();
        [
            VIEW_STRIDE as u64 * bytes,
            4 * (4 + pairs),
            (view_reals(cut.view) + tree) as u64 * bytes,
            pairs * self.disc.method.nodes_per_element() as u64 * bytes,
        ]
    }

    /// The cuts `cuts` in one submission: their values to `out` (the cut's values from
    /// `first_value`), their classes and the pairs left to the caller (cut indices from
    /// `first_cut`) added to `out`.
    fn clip_batch(
        &self,
        cuts: &[FaceCut],
        first_cut: usize,
        first_value: usize,
        out: &mut CutValues,
    ) -> Result<()> {
        let batch = self.cut_batch(cuts);
        let (ctx, p) = (self.assembler.ctx, self.assembler.precision);
        let pipelines = self.assembler.cut_pipelines().expect("a clipper has the cut pipelines");
        let per = self.disc.method.nodes_per_element();
        let pairs = batch.pairs;
        let budget = self.budget;
        let header = layout::NEAR_HEADER_BYTES;
        // Pairs left to the host listed as the tile's are (past the list, the host takes all).
        let overflow_capacity =
            pairs.min(budget.saturating_sub(header) / 8).min(self.limits.near_pairs).min(1 << 20);
        let grid_limit =
            ctx.limits.max_compute_workgroups_per_dimension as u64 * layout::WORKGROUP as u64;
        let room = budget.saturating_sub(header) / 4;
        let deep_capacity = pairs.min(room.saturating_sub(2 * overflow_capacity)).min(grid_limit);
        let (values, tallies, listed) =
            compute::checked(ctx, "GPU clipping of listed pairs", || {
                let (x, y, stride) = compute::grid(ctx, pairs);
                let params = Params {
                    rows: cuts.len() as u32,
                    elements: self.disc.element_count() as u32,
                    faces: self.scene.faces.len() as u32,
                    dof: self.disc.dof() as u32,
                    imt_count: self.counts.imt as u32,
                    rule_offset: self.counts.rule_offset as u32,
                    band_count: self.counts.bands as u32,
                    stride,
                    cut_records: cuts.len() as u32,
                    piece_limit: self.limits.pieces_on_device.min(layout::MAX_PIECES),
                    overflow_capacity: overflow_capacity as u32,
                    deep_capacity: deep_capacity as u32,
                    pair_cuts: 1,
                    ..Default::default()
                };
                let params = compute::uniform(ctx, bytemuck::bytes_of(&params));
                let views = compute::storage(ctx, &layout::real_bytes(&batch.views, p));
                let records = compute::storage(ctx, bytemuck::cast_slice(&batch.records));
                let vertices = compute::storage(ctx, &layout::real_bytes(&batch.vertices, p));
                let (near, near_args) = compute::near_list(ctx, overflow_capacity, deep_capacity);
                let size = pairs * (per * p.bytes()) as u64;
                let (output, staging) = compute::output(ctx, size);
                let group = compute::bind_group(
                    ctx,
                    &self.assembler.layout,
                    &[
                        &params,
                        &views,
                        &self.elements,
                        &self.tables,
                        &records,
                        &vertices,
                        &output,
                        &near,
                    ],
                );
                let mut encoder = ctx.device.create_command_encoder(&Default::default());
                let deferred = (deep_capacity > 0).then_some((&near, &near_args));
                self.assembler.encode_cuts(pipelines, &mut encoder, &group, (x, y), deferred);
                encoder.copy_buffer_to_buffer(&output, 0, &staging, 0, size.max(16));
                ctx.queue.submit([encoder.finish()]);
                let started = Instant::now();
                let values = compute::read_back(ctx, &staging, size, p)?;
                let tallies = compute::read_u32s(ctx, &near, 0, header as usize / 4)?;
                let left = u64::from(tallies[layout::CUT_TALLY_INDEX + 4]);
                let listed = if left <= overflow_capacity {
                    compute::read_u32s(ctx, &near, header, 2 * left as usize)?
                } else {
                    Vec::new()
                };
                let uploaded =
                    [&params, &views, &records, &vertices].iter().map(|b| b.size()).sum::<u64>();
                self.count_submission(uploaded, size, started.elapsed().as_secs_f64());
                Ok::<_, crate::error::Error>((values, tallies, listed))
            })??;
        for (o, v) in out.values[first_value..].iter_mut().zip(values.chunks_exact(per)) {
            o[..per].copy_from_slice(v);
        }
        let (stats, left) = tallies_of(&tallies);
        let left_before = out.left.len();
        if left <= overflow_capacity {
            out.stats += stats;
            // A listed pair's index in the batch, to its cut and position.
            let firsts: Vec<u32> =
                batch.records[..4 * cuts.len()].iter().step_by(4).copied().collect();
            out.left.extend(listed.chunks_exact(2).map(|pair| {
                let c = firsts.partition_point(|&f| f <= pair[0]) - 1;
                (first_cut + c, (pair[0] - firsts[c]) as usize)
            }));
            out.left.extend(batch.thin.iter().map(|&(c, position)| (first_cut + c, position)));
        } else {
            // More were left than the list holds: the host clips every pair of the batch.
            for (c, cut) in cuts.iter().enumerate() {
                out.left.extend((0..cut.elements.len()).map(|position| (first_cut + c, position)));
            }
        }
        let on_host = (out.left.len() - left_before) as u64;
        self.count_clipping(pairs - on_host, on_host);
        Ok(())
    }
}

impl CutEvaluation for PairEvaluator<'_> {
    /// In batches whose buffers fit the device's bindings.
    fn evaluate_cuts(&self, cuts: &[FaceCut]) -> Result<CutValues> {
        let pairs = cuts.iter().map(|c| c.elements.len()).sum();
        let mut out = CutValues {
            values: vec![[0.0; 3]; pairs],
            stats: PairStats::default(),
            left: Vec::new(),
        };
        let (mut start, mut first_value) = (0, 0);
        while start < cuts.len() {
            // As many cuts as keep every buffer within a binding (one at least); a tree shared
            // by several cuts is counted for each.
            let (mut end, mut used) = (start, [16u64; 4]);
            while end < cuts.len() {
                let more = self.cut_bytes(&cuts[end]);
                let next: [u64; 4] = std::array::from_fn(|k| used[k] + more[k]);
                if end > start && next.iter().any(|&b| b > self.budget) {
                    break;
                }
                (used, end) = (next, end + 1);
            }
            self.clip_batch(&cuts[start..end], start, first_value, &mut out)?;
            first_value += cuts[start..end].iter().map(|c| c.elements.len()).sum::<usize>();
            start = end;
        }
        Ok(out)
    }
}
