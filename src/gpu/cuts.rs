//! The device's clipping of the elements of faces seen in part (shaders/clip.wgsl), host side:
//! its passes, and once a tile is done, its tallies and the pairs it left to the host, which the
//! host clips and `assemble_pieces` writes.

use super::assembly::{GpuAssembler, InFlight, Uploaded};
use super::compute;
use super::layout::{self, Params};
use super::tile_plan::{Geometry, host_pieces, record_pairs};
use crate::error::Result;
use crate::visibility::PairStats;

/// The clipping kernels: `assemble_cuts` over every pair of the faces seen in part,
/// `prepare_deep_cuts` and `assemble_deep_cuts` over those a shadow cuts, which the first lists.
pub(super) struct CutPipelines {
    cuts: wgpu::ComputePipeline,
    prepare_deep: wgpu::ComputePipeline,
    deep: wgpu::ComputePipeline,
}

impl CutPipelines {
    /// The pipelines of the three entry points, in that order.
    pub(super) fn new(pipelines: Vec<wgpu::ComputePipeline>) -> Self {
        let [cuts, prepare_deep, deep]: [wgpu::ComputePipeline; 3] =
            pipelines.try_into().expect("three cut pipelines");
        Self { cuts, prepare_deep, deep }
    }
}

/// A tile's clipping pass in flight: its tallies and the pairs it leaves to the host are in
/// `near`; those pairs are written over the same views.
pub(super) struct CutsInFlight {
    pub(super) params: Params,
    pub(super) views: wgpu::Buffer,
    pub(super) near: wgpu::Buffer,
    /// Pairs left to the host that the near list holds.
    pub(super) overflow_capacity: u64,
    /// The tile's cut records, and how many.
    pub(super) records: Vec<u32>,
    pub(super) cut_records: u32,
    /// Bytes one binding may hold.
    pub(super) max_binding: u64,
}

impl GpuAssembler<'_> {
    /// The clipping passes: every pair of the faces seen in part, then, with the near list and
    /// a buffer for their dispatch arguments, the pairs a shadow cuts, which the first lists.
    pub(super) fn encode_cuts(
        &self,
        cuts: &CutPipelines,
        encoder: &mut wgpu::CommandEncoder,
        group: &wgpu::BindGroup,
        (x, y): (u32, u32),
        deferred: Option<(&wgpu::Buffer, &wgpu::Buffer)>,
    ) {
        let mut pass = encoder.begin_compute_pass(&Default::default());
        pass.set_pipeline(&cuts.cuts);
        pass.set_bind_group(0, group, &[]);
        pass.dispatch_workgroups(x, y, 1);
        drop(pass);
        let Some((near, args)) = deferred else { return };
        let mut pass = encoder.begin_compute_pass(&Default::default());
        pass.set_pipeline(&cuts.prepare_deep);
        pass.set_bind_group(0, group, &[]);
        pass.dispatch_workgroups(1, 1, 1);
        drop(pass);
        encoder.copy_buffer_to_buffer(near, layout::DEEP_DISPATCH_OFFSET, args, 0, 12);
        let mut pass = encoder.begin_compute_pass(&Default::default());
        pass.set_pipeline(&cuts.deep);
        pass.set_bind_group(0, group, &[]);
        pass.dispatch_workgroups_indirect(args, 0);
    }

    /// The clipping pass's tallies of a submitted tile, once it is done, and the pairs it left
    /// to the host clipped there and written by `assemble_pieces` (then copied out again for
    /// the host). Past the list's capacity every pair of the tile's faces seen in part is.
    pub(super) fn collect_cuts(
        &self,
        done: &InFlight,
        cuts: &CutsInFlight,
        (g, uploaded): (Geometry, &Uploaded),
    ) -> Result<PairStats> {
        let ctx = self.ctx;
        let started = std::time::Instant::now();
        let header =
            compute::read_u32s(ctx, &cuts.near, 0, layout::NEAR_HEADER_BYTES as usize / 4)?;
        self.timings.lock().expect("timings lock").device_wait_seconds +=
            started.elapsed().as_secs_f64();
        let [hidden, facing_away, full, partial, left] =
            std::array::from_fn(|k| header[layout::CUT_TALLY_INDEX + k] as u64);
        let mut stats = PairStats::default();
        let mut pairs = if left <= cuts.overflow_capacity {
            stats.hidden = hidden;
            stats.facing_away = facing_away;
            stats.full = full;
            stats.partial = partial;
            stats.total = hidden + facing_away + full + partial;
            let first = layout::NEAR_HEADER_BYTES + 8 * cuts.params.near_capacity as u64;
            let listed = compute::read_u32s(ctx, &cuts.near, first, 2 * left as usize)?;
            listed.chunks_exact(2).map(|p| (p[0], p[1])).collect()
        } else {
            record_pairs(&cuts.records[..4 * cuts.cut_records as usize], g.mesh, g.disc)
        };
        self.timings.lock().expect("timings lock").pairs_clipped_on_device += stats.total;
        if pairs.is_empty() {
            return Ok(stats);
        }
        self.timings.lock().expect("timings lock").pairs_clipped_on_host += pairs.len() as u64;
        // In parts whose pieces fit a binding: a part that turns out larger is halved.
        let mut parts = Vec::new();
        parts.push(0..pairs.len());
        while let Some(part) = parts.pop() {
            let started = std::time::Instant::now();
            let (lists, part_stats) = host_pieces(done.rows.start, &mut pairs[part.clone()], g);
            self.timings.lock().expect("timings lock").planning_seconds +=
                started.elapsed().as_secs_f64();
            let (records, count, piece_offset, vertices) = lists.finish();
            let bytes = (4 * records.len()).max(vertices.len() * self.precision.bytes());
            if bytes as u64 > cuts.max_binding && part.len() > 1 {
                let middle = part.start + part.len() / 2;
                parts.extend([part.start..middle, middle..part.end]);
                continue;
            }
            stats += part_stats;
            compute::checked(ctx, "GPU assembly of the pairs left to the host", || {
                let (x, y, stride) = compute::grid(ctx, count as u64);
                let params = Params {
                    exception_count: count,
                    piece_offset,
                    stride,
                    near_capacity: 0,
                    cut_records: 0,
                    ..cuts.params
                };
                let params = compute::uniform(ctx, bytemuck::bytes_of(&params));
                let exceptions = compute::storage(ctx, bytemuck::cast_slice(&records));
                let vertices =
                    compute::storage(ctx, &layout::real_bytes(&vertices, self.precision));
                let near = compute::storage(ctx, &[0u8; layout::NEAR_HEADER_BYTES as usize + 8]);
                let (elements, tables) = (&uploaded.elements, &uploaded.tables);
                let buffers = [
                    &params,
                    &cuts.views,
                    elements,
                    tables,
                    &exceptions,
                    &vertices,
                    &done.out,
                    &near,
                ];
                let group = compute::bind_group(ctx, &self.layout, &buffers);
                let mut encoder = ctx.device.create_command_encoder(&Default::default());
                self.encode_pieces(&mut encoder, &group, (x, y));
                ctx.queue.submit([encoder.finish()]);
            })?;
        }
        if let Some(staging) = &done.staging {
            let mut encoder = ctx.device.create_command_encoder(&Default::default());
            encoder.copy_buffer_to_buffer(&done.out, 0, staging, 0, done.size.max(16));
            ctx.queue.submit([encoder.finish()]);
        }
        Ok(stats)
    }
}
