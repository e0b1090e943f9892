//! Assembly of the collocation matrix on the GPU, in row tiles.
//!
//! Per tile the host computes ([`super::tile_plan`]), for every (node, face), whether the node
//! sees the face and the node's coordinates in the face's frame, and for a face seen in part
//! (clipped or shadowed) its view: the first pass evaluates every element of every face the node
//! sees whole, the clipping pass (f64) clips each element of a face seen in part on the device and
//! integrates its pieces. A pair the clipping kernel cannot hold is left to the host, which clips
//! it and has `assemble_pieces` write it (counted in [`GpuTimings`]). The f32 kernels take the
//! host's pieces of every element not fully visible instead. Tiles are sized so no binding exceeds
//! the device's limits, and the next tile is planned while the device works on the current one.

use std::collections::VecDeque;
use std::ops::Range;

use super::GpuContext;
use super::compute;
use super::cuts::{CutPipelines, CutsInFlight, tallies};
use super::layout::{self, Params, VIEW_STRIDE};
use super::passes::{Listed, dispatch, encode_listed};
use super::shaders::{self, Precision};
use super::storage::{Narrowing, StorageError};
use super::tables::{RuleCounts, far_field_rule, tables};
use super::tile_plan::{Clipping, Geometry, TilePlan, host_pieces, plan_tile, record_pairs};
use crate::assembly::{Assembly, AssemblyOptions, CollocationMatrix, Problem, face_boxes};
use crate::discretization::{Discretization, Method};
use crate::error::{Error, Result};
use crate::mesh::Mesh;
use crate::progress::Progress;
use crate::scene::Scene;
use crate::visibility::{ElementBoxes, PairStats};

/// Upper bounds on the work of one tile, below what the device allows (for tests and tuning).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct TileLimits {
    /// Rows per tile.
    pub rows: usize,
    /// Pairs the near list may hold; pairs beyond it are evaluated in the first pass. As many
    /// of those the clipping kernel leaves to the host may be listed; past that, the host clips
    /// every pair of the tile's faces seen in part.
    pub near_pairs: u64,
    /// Bytes one storage binding may hold (the device's `max_storage_buffer_binding_size` when
    /// smaller): lets tests drive the tiling of a small scene as a device would a large one.
    pub binding_bytes: u64,
    /// Pieces the clipping kernel holds at once (at most [`layout::MAX_PIECES`]); a pair that
    /// needs more is clipped on the host. Fewer drive that fallback in tests.
    pub pieces_on_device: u32,
}

impl Default for TileLimits {
    /// No bounds beyond the device's.
    fn default() -> Self {
        Self {
            rows: usize::MAX,
            near_pairs: u64::MAX,
            binding_bytes: u64::MAX,
            pieces_on_device: layout::MAX_PIECES,
        }
    }
}

/// Where the time of the last GPU assembly went (wall clock).
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct GpuTimings {
    /// Host: pair plan of the tiles (visibility, exception lists).
    pub planning_seconds: f64,
    /// Waiting for the device to finish a tile (kernels, and the copy to the staging buffer).
    pub device_wait_seconds: f64,
    /// Copying results out of mapped staging buffers into the matrix.
    pub readback_seconds: f64,
    /// Tiles.
    pub tiles: usize,
    /// Bytes written to the device: the elements, the rule tables, and each tile's plan.
    pub bytes_uploaded: u64,
    /// Bytes of the matrix read back (none when it stays on the device).
    pub bytes_read_back: u64,
    /// Those bytes over the time of copying them out of the mapped staging buffers.
    pub read_back_gb_per_second: f64,
    /// Pairs of faces seen in part that the device clipped.
    pub pairs_clipped_on_device: u64,
    /// Pairs of faces seen in part clipped on the host: where the kernels are f32, or where a
    /// pair outgrew the clipping kernel's limits.
    pub pairs_clipped_on_host: u64,
}

impl GpuTimings {
    /// What crossed between host and device in the assembly: one submission per tile.
    pub fn traffic(&self) -> super::DeviceTraffic {
        super::DeviceTraffic {
            bytes_uploaded: self.bytes_uploaded,
            bytes_read_back: self.bytes_read_back,
            gpu_submissions: self.tiles as u64,
            device_wait_seconds: self.device_wait_seconds,
            pairs_clipped_on_device: self.pairs_clipped_on_device,
            pairs_clipped_on_host: self.pairs_clipped_on_host,
        }
    }
}

/// Compiled pipelines for one precision and collocation method.
pub struct GpuAssembler<'a> {
    pub(super) ctx: &'a GpuContext,
    pub(super) precision: Precision,
    pub(super) method: Method,
    pub(super) layout: wgpu::BindGroupLayout,
    full: wgpu::ComputePipeline,
    prepare_near: wgpu::ComputePipeline,
    near: wgpu::ComputePipeline,
    pieces: wgpu::ComputePipeline,
    /// `assemble_pairs`: listed pairs (src/gpu/pairs.rs).
    pub(super) pairs: wgpu::ComputePipeline,
    /// The elements of faces seen in part, clipped on the device (f64 only).
    cuts: Option<CutPipelines>,
    pub(super) timings: std::sync::Mutex<GpuTimings>,
}

/// What [`GpuAssembler::upload`] puts on the device.
pub(super) struct Uploaded {
    /// Scene lengths times `unit` are what the device sees.
    pub(super) unit: f64,
    /// The packed elements ([`layout::pack_elements`]).
    pub(super) elements: wgpu::Buffer,
    /// The IMT and far-field tables.
    pub(super) tables: wgpu::Buffer,
    /// Where the tables' parts start.
    pub(super) counts: RuleCounts,
    /// Where each face's element box tree starts in `elements` (none uploaded: empty).
    pub(super) tree_offsets: Vec<u32>,
}

pub(super) struct InFlight {
    pub(super) rows: Range<usize>,
    /// The tile's entries on the device.
    pub(super) out: wgpu::Buffer,
    /// Their copy for the host; none when the tile stays on the device.
    pub(super) staging: Option<wgpu::Buffer>,
    pub(super) size: u64,
    /// What the host needs to finish the clipping pass; none without one.
    cuts: Option<CutsInFlight>,
}

/// Tiles submitted and not yet collected, at most: while the host copies the oldest out of its
/// staging buffer, the device computes the next ones and the host plans the one after.
const TILES_IN_FLIGHT: usize = 3;

/// Whether a submitted tile is copied out for the host or kept on the device.
#[derive(Clone, Copy)]
enum Keep {
    Host,
    Device,
}

/// Tiles of K kept on the device: rows, and their entries row-major.
pub type DeviceTiles = Vec<(Range<usize>, wgpu::Buffer)>;

/// Where an assembly's tiles go: into the host's matrix, or kept on the device (as computed,
/// or narrowed to f32).
enum Destination<'m> {
    Host(&'m mut CollocationMatrix),
    Device(&'m mut DeviceTiles, Option<&'m Narrowing>),
}

impl<'a> GpuAssembler<'a> {
    /// Compiles the kernels for `method`; f64 needs an adapter with `SHADER_F64`.
    pub fn new(ctx: &'a GpuContext, precision: Precision, method: Method) -> Result<Self> {
        if precision == Precision::F64 && !ctx.adapter.f64 {
            return Err(Error::Gpu(format!(
                "adapter '{}' has no SHADER_F64; use single precision, or {}",
                ctx.adapter.name,
                super::INSTALL_HINT
            )));
        }
        let source = shaders::collocation(
            precision,
            method.nodes_per_element() as u32,
            far_field_rule(precision, method, true).is_some(),
        );
        let mut entries = vec![
            "assemble_full",
            "prepare_near",
            "assemble_near",
            "assemble_pieces",
            "assemble_pairs",
        ];
        if precision == Precision::F64 {
            entries.extend(["assemble_cuts", "prepare_deep_cuts", "assemble_deep_cuts"]);
        }
        let (layout, mut pipelines) =
            compute::pipeline(ctx, &source, &entries, 8, &[0, 3], &[6, 7])?;
        let cuts = (precision == Precision::F64).then(|| CutPipelines::new(pipelines.split_off(5)));
        let [full, prepare_near, near, pieces, pairs]: [wgpu::ComputePipeline; 5] =
            pipelines.try_into().expect("five pipelines");
        Ok(Self {
            cuts,
            ctx,
            precision,
            method,
            layout,
            full,
            prepare_near,
            near,
            pieces,
            pairs,
            timings: Default::default(),
        })
    }

    /// Precision of the kernels.
    pub fn precision(&self) -> Precision {
        self.precision
    }

    /// The device the kernels run on.
    pub fn context(&self) -> &'a GpuContext {
        self.ctx
    }

    /// The clipping kernels (f64 only).
    pub(super) fn cut_pipelines(&self) -> Option<&CutPipelines> {
        self.cuts.as_ref()
    }

    /// Where the time of the last [`Self::assemble`] went.
    pub fn last_timings(&self) -> GpuTimings {
        *self.timings.lock().expect("timings lock")
    }

    /// The elements of `disc` and the rule tables on the device, lengths in units of the
    /// scene's size (a power of two, exact), so that no square or fourth power of a length
    /// under- or overflows, in f32 least of all.
    /// With `trees`, the faces' element box trees follow the elements, for the clipping kernel.
    pub(super) fn upload(
        &self,
        scene: &Scene,
        disc: &Discretization,
        options: &AssemblyOptions,
        trees: &[ElementBoxes],
    ) -> Result<Uploaded> {
        let (ctx, p) = (self.ctx, self.precision);
        let largest_face = scene.faces.iter().map(|f| f.size()).fold(0.0, f64::max);
        let unit = crate::geometry::power_of_two_unit(largest_face);
        let mut packed = layout::pack_elements(disc, unit);
        let tree_offsets = layout::pack_box_trees(trees, unit, &mut packed);
        let elements = compute::storage(ctx, &layout::real_bytes(&packed, p));
        let (table_values, counts) = tables(options, self.method, p)?;
        let tables = compute::uniform(ctx, &layout::real_bytes(&table_values, p));
        Ok(Uploaded { unit, elements, tables, counts, tree_offsets })
    }

    /// Assembles K like [`crate::assembly::assemble`]. `progress` advances by the rows finished.
    pub fn assemble(
        &self,
        problem: &Problem,
        options: &AssemblyOptions,
        progress: &dyn Progress,
    ) -> Result<Assembly> {
        self.assemble_with_limits(problem, options, TileLimits::default(), progress)
    }

    /// [`Self::assemble`] within `limits` (the device's limits may make tiles smaller still).
    pub fn assemble_with_limits(
        &self,
        problem: &Problem,
        options: &AssemblyOptions,
        limits: TileLimits,
        progress: &dyn Progress,
    ) -> Result<Assembly> {
        let mut matrix = CollocationMatrix::zeros(problem.disc.dof())?;
        let destination = Destination::Host(&mut matrix);
        let stats = self.assemble_tiles(problem, options, limits, destination, progress)?;
        Ok(Assembly { matrix, stats })
    }

    /// K assembled into device memory and left there, tile by tile of rows (each tile's
    /// entries row-major in `storage`: the kernels' precision, or f32 narrowed on the device
    /// from f64 kernels), with the pair classes and what the storage did to K; nothing is read
    /// back but the rows' norms of a narrowed K. The thin elements' columns are as the kernels
    /// give them (see [`crate::assembly::recompute_thin_columns`]).
    pub fn assemble_on_device(
        &self,
        problem: &Problem,
        options: &AssemblyOptions,
        storage: Precision,
        progress: &dyn Progress,
    ) -> Result<(DeviceTiles, PairStats, StorageError)> {
        let narrowing = match (self.precision, storage) {
            (Precision::F64, Precision::F32) => Some(Narrowing::new(self.ctx, problem.disc.dof())?),
            (p, s) if p == s => None,
            _ => {
                return Err(Error::Gpu(format!(
                    "K computed in {} cannot be stored in {}",
                    self.precision.name(),
                    storage.name()
                )));
            }
        };
        let mut tiles = Vec::new();
        let destination = Destination::Device(&mut tiles, narrowing.as_ref());
        let limits = TileLimits::default();
        let stats = self.assemble_tiles(problem, options, limits, destination, progress)?;
        let error = match &narrowing {
            Some(n) => {
                let (error, bytes) = n.error(self.ctx)?;
                self.timings.lock().expect("timings lock").bytes_read_back += bytes;
                error
            }
            None => StorageError::none(),
        };
        Ok((tiles, stats, error))
    }

    /// Plans, submits and collects the tiles of K into `destination`.
    fn assemble_tiles(
        &self,
        problem: &Problem,
        options: &AssemblyOptions,
        limits: TileLimits,
        mut destination: Destination,
        progress: &dyn Progress,
    ) -> Result<PairStats> {
        let Problem { scene, mesh, disc, planner, .. } = problem;
        if disc.method.nodes_per_element() != self.method.nodes_per_element() {
            return Err(Error::Gpu(format!(
                "kernels compiled for the {} method cannot assemble the {} method",
                self.method.name(),
                disc.method.name()
            )));
        }
        let ctx = self.ctx;
        let dof = disc.dof();
        let p = self.precision;
        let boxes = face_boxes(mesh, disc);
        let trees = if self.cuts.is_some() { &boxes[..] } else { &[] };
        let uploaded = self.upload(scene, disc, options, trees)?;
        let max_binding = ctx.max_binding().min(limits.binding_bytes);
        // Per row of a tile: its output and its views of every face (a scene of 10 000 faces has
        // 5 MB of views per row in f64, more than its output row).
        let row_bytes = (dof * p.bytes()) as u64;
        let view_bytes = (mesh.face_count() * VIEW_STRIDE * p.bytes()) as u64;
        // Every per-row buffer and the host's staging copy stay below 64 MiB per tile, and the
        // rows of a tile fit in one dimension of the dispatch grid.
        let rows_per_tile = ((max_binding.min(64 << 20) / row_bytes.max(view_bytes).max(1))
            as usize)
            .min(ctx.limits.max_compute_workgroups_per_dimension as usize)
            .min(limits.rows)
            .clamp(1, dof.max(1));
        let tiles: Vec<Range<usize>> =
            (0..dof).step_by(rows_per_tile).map(|s| s..(s + rows_per_tile).min(dof)).collect();

        let mut stats = PairStats::default();
        *self.timings.lock().expect("timings lock") = GpuTimings {
            bytes_uploaded: uploaded.elements.size() + uploaded.tables.size(),
            ..Default::default()
        };
        let unit = uploaded.unit;
        let trees = &uploaded.tree_offsets;
        let geometry = Geometry { scene, mesh, disc, boxes: &boxes, planner, unit, trees };
        let clipping = if self.cuts.is_some() { Clipping::Device } else { Clipping::Host };
        let timed_plan = |t: &Range<usize>| {
            let started = std::time::Instant::now();
            let plan = plan_tile(t.clone(), geometry, clipping);
            let mut timings = self.timings.lock().expect("timings lock");
            timings.planning_seconds += started.elapsed().as_secs_f64();
            plan
        };
        // The visible pieces of a tile are known only once it is planned: a tile whose pieces or
        // exception records outgrow a binding is split in two and planned again.
        let mut queue: std::collections::VecDeque<Range<usize>> = tiles.into();
        let mut plan_next = || {
            while let Some(t) = queue.pop_front() {
                let plan = timed_plan(&t);
                if t.len() == 1 || plan.fits(max_binding, p) {
                    return Some(plan);
                }
                let middle = t.start + t.len() / 2;
                queue.push_front(middle..t.end);
                queue.push_front(t.start..middle);
            }
            None
        };
        let keep = match &destination {
            Destination::Host(_) => Keep::Host,
            Destination::Device(..) => Keep::Device,
        };
        let device_limits = (max_binding, limits.near_pairs, limits.pieces_on_device);
        let mut in_flight: VecDeque<InFlight> = VecDeque::with_capacity(TILES_IN_FLIGHT);
        let mut next_plan = plan_next();
        while let Some(plan) = next_plan.take() {
            self.timings.lock().expect("timings lock").tiles += 1;
            stats += plan.stats;
            self.timings.lock().expect("timings lock").pairs_clipped_on_host +=
                plan.clipped_on_host;
            let submitted = self.submit(plan, disc, mesh, &uploaded, device_limits, keep)?;
            in_flight.push_back(submitted);
            if in_flight.len() == TILES_IN_FLIGHT {
                let done = in_flight.pop_front().expect("a tile in flight");
                stats += self.finish(done, &mut destination, (geometry, &uploaded), progress)?;
            }
            // Plan the next tile while the device works on those in flight.
            next_plan = plan_next();
        }
        while let Some(done) = in_flight.pop_front() {
            stats += self.finish(done, &mut destination, (geometry, &uploaded), progress)?;
        }
        let mut t = self.timings.lock().expect("timings lock");
        if t.readback_seconds > 0.0 {
            t.read_back_gb_per_second = t.bytes_read_back as f64 / t.readback_seconds / 1e9;
        }
        drop(t);
        if let Destination::Device(..) = destination {
            let started = std::time::Instant::now();
            ctx.device
                .poll(wgpu::PollType::wait_indefinitely())
                .map_err(|e| Error::Gpu(format!("waiting for the device failed: {e}")))?;
            self.timings.lock().expect("timings lock").device_wait_seconds +=
                started.elapsed().as_secs_f64();
        }
        Ok(stats)
    }

    /// Sends the tile `plan` to the device over the `uploaded` elements and tables.
    fn submit(
        &self,
        plan: TilePlan,
        disc: &Discretization,
        mesh: &Mesh,
        uploaded: &Uploaded,
        (max_binding, max_near_pairs, piece_limit): (u64, u64, u32),
        keep: Keep,
    ) -> Result<InFlight> {
        let Uploaded { elements, tables, counts, .. } = uploaded;
        let ctx = self.ctx;
        let p = self.precision;
        let dof = disc.dof();
        let rows = plan.rows.len();
        let view_bytes = layout::real_bytes(&plan.views, p);
        let vertex_bytes = layout::real_bytes(&plan.vertices, p);
        let exception_bytes: &[u8] = bytemuck::cast_slice(&plan.exceptions);
        for (what, len) in [
            ("views", view_bytes.len()),
            ("visible pieces", vertex_bytes.len()),
            ("exceptions", exception_bytes.len()),
        ] {
            if len as u64 > max_binding {
                return Err(Error::Gpu(format!(
                    "{what} of one tile take {len} bytes, over the device's binding limit of {max_binding}"
                )));
            }
        }
        // Buffers, bindings and the submission inside error scopes: a device limit met here is
        // an error of this run, not a panic in wgpu's default handler.
        let submitted = compute::checked(ctx, "GPU assembly", || {
            let (exc_x, exc_y, stride) = compute::grid(ctx, plan.exception_count as u64);
            let pairs = (rows * disc.element_count()) as u64;
            let near_capacity = self.near_capacity(pairs, max_binding, max_near_pairs);
            // The pairs the clipping kernel leaves to the host are listed after the near pairs,
            // as many as the binding holds (past that, the host clips all the tile's).
            let overflow_capacity = plan
                .cut_pairs
                .min(max_binding.saturating_sub(layout::NEAR_HEADER_BYTES) / 8 - near_capacity)
                .min(max_near_pairs)
                .min(1 << 20);
            // The pairs a shadow cuts, listed for a pass of their own, as many as the binding and
            // one dispatch hold (past that, the first pass clips them in place).
            let grid_limit =
                ctx.limits.max_compute_workgroups_per_dimension as u64 * layout::WORKGROUP as u64;
            let room = max_binding.saturating_sub(layout::NEAR_HEADER_BYTES) / 4;
            let deep_capacity =
                plan.cut_pairs.min(room - 2 * (near_capacity + overflow_capacity)).min(grid_limit);
            let (cut_x, cut_y, cut_stride) = compute::grid(ctx, plan.cut_pairs);
            let params = Params {
                rows: rows as u32,
                elements: disc.element_count() as u32,
                faces: mesh.face_count() as u32,
                dof: dof as u32,
                imt_count: counts.imt as u32,
                rule_offset: counts.rule_offset as u32,
                band_count: counts.bands as u32,
                exception_count: plan.exception_count,
                piece_offset: plan.piece_offset,
                stride: if plan.cut_records > 0 { cut_stride } else { stride },
                near_capacity: near_capacity as u32,
                cut_records: plan.cut_records,
                piece_limit: piece_limit.min(layout::MAX_PIECES),
                overflow_capacity: overflow_capacity as u32,
                deep_capacity: deep_capacity as u32,
                ..Default::default()
            };
            let params_buffer = compute::uniform(ctx, bytemuck::bytes_of(&params));
            let (near, near_args) =
                compute::near_list(ctx, near_capacity + overflow_capacity, deep_capacity);
            self.timings.lock().expect("timings lock").bytes_uploaded += (view_bytes.len()
                + vertex_bytes.len()
                + exception_bytes.len()
                + std::mem::size_of::<Params>())
                as u64;
            let views = compute::storage(ctx, &view_bytes);
            let exceptions = compute::storage(ctx, exception_bytes);
            let vertices = compute::storage(ctx, &vertex_bytes);
            let size = (rows * dof * p.bytes()) as u64;
            let (out, staging) = match keep {
                Keep::Device => (compute::writable(ctx, size), None),
                Keep::Host => {
                    let (out, staging) = compute::output(ctx, size);
                    (out, Some(staging))
                }
            };
            let group = compute::bind_group(
                ctx,
                &self.layout,
                &[&params_buffer, &views, elements, tables, &exceptions, &vertices, &out, &near],
            );
            let mut encoder = ctx.device.create_command_encoder(&Default::default());
            let groups_x = (disc.element_count() as u32).div_ceil(layout::WORKGROUP);
            let deferred = (near_capacity > 0).then_some((&near, &near_args));
            self.encode_passes(&mut encoder, &group, (groups_x, rows as u32), deferred);
            // Second passes, ordered after the first, which leaves them the faces seen in part.
            if plan.exception_count > 0 {
                self.encode_pieces(&mut encoder, &group, (exc_x, exc_y));
            }
            if let (Some(cuts), true) = (&self.cuts, plan.cut_records > 0) {
                let deferred = (deep_capacity > 0).then_some((&near, &near_args));
                self.encode_cuts(cuts, &mut encoder, &group, (cut_x, cut_y), deferred);
            }
            if let Some(staging) = &staging {
                encoder.copy_buffer_to_buffer(&out, 0, staging, 0, size.max(16));
            }
            ctx.queue.submit([encoder.finish()]);
            let cuts = (plan.cut_records > 0).then_some((params, views, near, overflow_capacity));
            Ok::<_, Error>((out, staging, size, cuts))
        })??;
        let (out, staging, size, cuts) = submitted;
        // The cut records are kept for the rare tile whose pairs left to the host outnumber
        // the list: the host then clips every pair they hold.
        let cuts = cuts.map(|(params, views, near, overflow_capacity)| {
            let mut records = plan.exceptions;
            records.truncate(4 * plan.cut_records as usize);
            CutsInFlight { params, views, near, overflow_capacity, records, max_binding }
        });
        Ok(InFlight { rows: plan.rows, out, staging, size, cuts })
    }

    /// Pairs the near list of a tile of `pairs` holds: every pair of the tile (linear method),
    /// up to what one indirect dispatch and one binding allow; pairs beyond it are evaluated in
    /// the first pass. None for the centroid method.
    fn near_capacity(&self, pairs: u64, max_binding: u64, max_near_pairs: u64) -> u64 {
        if self.method.nodes_per_element() != 3 {
            return 0;
        }
        let limits = &self.ctx.limits;
        let grid_limit =
            limits.max_compute_workgroups_per_dimension as u64 * layout::WORKGROUP as u64;
        let binding_limit = max_binding.saturating_sub(layout::NEAR_HEADER_BYTES) / 8;
        pairs.min(grid_limit).min(binding_limit).min(max_near_pairs)
    }

    /// The first pass over a tile's grid of (element groups, rows), then, with the near list
    /// and its dispatch arguments, the pairs it deferred with every lane busy.
    fn encode_passes(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        group: &wgpu::BindGroup,
        (groups_x, rows): (u32, u32),
        deferred: Option<(&wgpu::Buffer, &wgpu::Buffer)>,
    ) {
        let listed = deferred.map(|(near, args)| Listed {
            prepare: &self.prepare_near,
            pass: &self.near,
            arguments_at: layout::NEAR_DISPATCH_OFFSET,
            near,
            args,
        });
        encode_listed(encoder, group, &self.full, (groups_x, rows), listed);
    }

    /// The clipping passes: every pair of the faces seen in part, then, with the near list and
    /// a buffer for their dispatch arguments, the pairs a shadow cuts, which the first lists.
    pub(super) fn encode_cuts(
        &self,
        cuts: &CutPipelines,
        encoder: &mut wgpu::CommandEncoder,
        group: &wgpu::BindGroup,
        grid: (u32, u32),
        deferred: Option<(&wgpu::Buffer, &wgpu::Buffer)>,
    ) {
        let listed = deferred.map(|(near, args)| Listed {
            prepare: &cuts.prepare_deep,
            pass: &cuts.deep,
            arguments_at: layout::DEEP_DISPATCH_OFFSET,
            near,
            args,
        });
        encode_listed(encoder, group, &cuts.cuts, grid, listed);
    }

    /// The clipping pass's tallies of a submitted tile, once it is done, and the pairs it left
    /// to the host clipped there and written by `assemble_pieces` (then copied out again for
    /// the host). Past the list's capacity every pair of the tile's faces seen in part is.
    fn collect_cuts(
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
        let (tallied, left) = tallies(&header);
        let mut stats = PairStats::default();
        let mut pairs = if left <= cuts.overflow_capacity {
            stats = tallied;
            let first = layout::NEAR_HEADER_BYTES + 8 * cuts.params.near_capacity as u64;
            let listed = compute::read_u32s(ctx, &cuts.near, first, 2 * left as usize)?;
            listed.chunks_exact(2).map(|p| (p[0], p[1])).collect()
        } else {
            record_pairs(&cuts.records, g.mesh, g.disc)
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

    /// `assemble_pieces` over the exceptions bound in `group`.
    pub(super) fn encode_pieces(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        group: &wgpu::BindGroup,
        grid: (u32, u32),
    ) {
        dispatch(encoder, &self.pieces, group, grid);
    }

    /// Collects a submitted tile: copied into the host's matrix, or its buffer kept (narrowed
    /// first where asked); returns the pairs classified on the device.
    fn finish(
        &self,
        mut done: InFlight,
        destination: &mut Destination,
        geometry: (Geometry, &Uploaded),
        progress: &dyn Progress,
    ) -> Result<PairStats> {
        let stats = match done.cuts.take() {
            Some(cuts) => self.collect_cuts(&done, &cuts, geometry)?,
            None => PairStats::default(),
        };
        let (matrix, staging) = match (destination, &done.staging) {
            (Destination::Device(tiles, narrowing), _) => {
                progress.advance(done.rows.len());
                let out = match narrowing {
                    Some(narrowing) => compute::checked(self.ctx, "narrowing K to f32", || {
                        let mut encoder =
                            self.ctx.device.create_command_encoder(&Default::default());
                        let (narrow, _params) =
                            narrowing.encode(self.ctx, &mut encoder, done.rows.clone(), &done.out);
                        self.ctx.queue.submit([encoder.finish()]);
                        narrow
                    })?,
                    None => done.out,
                };
                tiles.push((done.rows, out));
                return Ok(stats);
            }
            (Destination::Host(matrix), Some(staging)) => (matrix, staging),
            (Destination::Host(_), None) => unreachable!("host tiles are staged"),
        };
        let started = std::time::Instant::now();
        compute::wait(self.ctx, staging, done.size)?;
        let waited = started.elapsed().as_secs_f64();
        let started = std::time::Instant::now();
        let dof = matrix.dof();
        compute::copy_mapped(
            staging,
            done.size,
            self.precision,
            matrix.rows_slice_mut(done.rows.clone()),
        )?;
        let mut t = self.timings.lock().expect("timings lock");
        t.device_wait_seconds += waited;
        t.readback_seconds += started.elapsed().as_secs_f64();
        t.bytes_read_back += done.size;
        drop(t);
        debug_assert_eq!(done.size as usize, done.rows.len() * dof * self.precision.bytes());
        progress.advance(done.rows.len());
        Ok(stats)
    }
}
