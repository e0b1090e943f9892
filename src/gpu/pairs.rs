//! Listed (node, element) pairs on the GPU: the compressed operator's exact blocks and the rows
//! and columns its cross approximations sample (src/operator), evaluated in batches by the
//! `assemble_pairs` kernel. Unlike the row tiles of [`super::assembly`], nothing here is n × n:
//! a batch holds exactly the pairs asked for, each with its own view of the element's face. The
//! elements of faces seen in part are clipped on the device where the kernels are f64
//! ([`super::pair_cuts`]).

use std::sync::Mutex;
use std::time::Instant;

use rayon::prelude::*;

use super::assembly::{GpuAssembler, TileLimits, Uploaded};
use super::compute;
use super::layout::{self, Params, VIEW_STRIDE};
use super::passes::dispatch;
use super::resident::DeviceTraffic;
use super::tables::RuleCounts;
use crate::assembly::{
    AssemblyOptions, CpuPairs, CutEvaluation, PairEvaluation, PairIntegrator, PairTask,
};
use crate::discretization::Discretization;
use crate::error::{Error, Result};
use crate::scene::Scene;
use crate::visibility::Visibility;

/// Piece count of a record that stands for the whole element (`WHOLE_ELEMENT` in the shader).
const WHOLE_ELEMENT: u32 = u32::MAX;

/// Each batch's buffers stay below this many bytes (and below the device's binding limit).
const BATCH_BYTES: u64 = 64 << 20;

/// The device's copy of a discretization, ready to evaluate listed pairs.
pub struct PairEvaluator<'a> {
    pub(super) assembler: &'a GpuAssembler<'a>,
    pub(super) scene: &'a Scene,
    pub(super) disc: &'a Discretization,
    /// Thin elements ([`crate::discretization::Placed::thin`]): their closed forms cancel, so their pairs are
    /// recomputed on the CPU, as the dense GPU path does.
    pub(super) thin: Vec<bool>,
    integrator: PairIntegrator,
    pub(super) unit: f64,
    pub(super) elements: wgpu::Buffer,
    pub(super) tables: wgpu::Buffer,
    pub(super) counts: RuleCounts,
    /// Bytes one batch's buffer may hold.
    pub(super) budget: u64,
    /// Bounds below the device's on the clipping of listed cuts (src/gpu/pair_cuts.rs).
    pub(super) limits: TileLimits,
    /// What crossed: the elements once, then each batch's records up and values down.
    traffic: Mutex<DeviceTraffic>,
    /// The batches' buffers, kept from one batch to the next.
    buffers: Mutex<BatchBuffers>,
}

/// A batch's device buffers, made when first needed and again only when a batch outgrows them:
/// a new set for every batch (four buffers of up to 64 MB each, thousands of batches on a large
/// operator) spent the GPU build's time in allocation rather than in the kernels.
#[derive(Default)]
struct BatchBuffers {
    views: Option<wgpu::Buffer>,
    records: Option<wgpu::Buffer>,
    vertices: Option<wgpu::Buffer>,
    output: Option<(wgpu::Buffer, wgpu::Buffer)>,
}

/// `slot`'s buffer if it holds `size` bytes, else a new one from `make` of at least that size
/// (the next power of two, so that growing batches do not make a buffer each).
fn fitted<T>(
    slot: &mut Option<T>,
    size: u64,
    capacity: impl Fn(&T) -> u64,
    make: impl FnOnce(u64) -> T,
) -> &T {
    let size = size.max(16);
    if slot.as_ref().is_none_or(|b| capacity(b) < size) {
        *slot = Some(make(size.next_power_of_two()));
    }
    slot.as_ref().expect("made above")
}

impl<'a> PairEvaluator<'a> {
    /// Uploads the elements of `disc` for `assembler`'s kernels.
    pub fn new(
        assembler: &'a GpuAssembler<'a>,
        scene: &'a Scene,
        disc: &'a Discretization,
        options: &AssemblyOptions,
    ) -> Result<Self> {
        if disc.method.nodes_per_element() != assembler.method.nodes_per_element() {
            return Err(Error::Gpu(format!(
                "kernels compiled for the {} method cannot evaluate the {} method",
                assembler.method.name(),
                disc.method.name()
            )));
        }
        let Uploaded { unit, elements, tables, counts, .. } =
            assembler.upload(scene, disc, options, &[])?;
        let limits = TileLimits::default();
        let budget = assembler.ctx.max_binding().min(BATCH_BYTES);
        let thin =
            (0..disc.element_count()).map(|j| options.far_field && disc.placed(j).thin).collect();
        let uploaded = elements.size() + tables.size();
        let traffic = DeviceTraffic { bytes_uploaded: uploaded, ..Default::default() };
        Ok(Self {
            assembler,
            scene,
            disc,
            thin,
            integrator: PairIntegrator::new(disc.method, options),
            unit,
            elements,
            tables,
            counts,
            budget,
            limits,
            traffic: Mutex::new(traffic),
            buffers: Mutex::new(BatchBuffers::default()),
        })
    }

    /// Within `limits` below the device's (the clipping kernel's stack, the pairs it may leave
    /// to the host, a binding's bytes): for tests of the fallbacks.
    pub fn limited(mut self, limits: TileLimits) -> Self {
        self.budget = self.budget.min(limits.binding_bytes);
        self.limits = limits;
        self
    }

    /// What has crossed so far, and how many batches were submitted.
    pub fn traffic(&self) -> DeviceTraffic {
        *self.traffic.lock().unwrap_or_else(|e| e.into_inner())
    }

    /// `bytes` up, `read_back` bytes down and `waited` seconds in one more submission.
    pub(super) fn count_submission(&self, bytes: u64, read_back: u64, waited: f64) {
        let mut t = self.traffic.lock().unwrap_or_else(|e| e.into_inner());
        t.bytes_uploaded += bytes;
        t.bytes_read_back += read_back;
        t.gpu_submissions += 1;
        t.device_wait_seconds += waited;
    }

    /// Pairs of faces seen in part clipped on the device, and left to the host.
    pub(super) fn count_clipping(&self, on_device: u64, on_host: u64) {
        let mut t = self.traffic.lock().unwrap_or_else(|e| e.into_inner());
        t.pairs_clipped_on_device += on_device;
        t.pairs_clipped_on_host += on_host;
    }

    /// Node `node` in the frame of face `face`, as `assemble_pairs` reads its view.
    pub(super) fn view_of(&self, node: usize, face: usize) -> [f64; VIEW_STRIDE] {
        let node = &self.disc.node(node);
        let frame = &self.scene.faces[face].frame;
        let (p, n) = (frame.to_local(node.position) * self.unit, frame.dir_to_local(node.normal));
        [p.x, p.y, p.z, n.x, n.y, n.z, node.rho / std::f64::consts::PI, 0.0]
    }

    /// One batch: views, records and pieces up, `assemble_pairs`, values back.
    fn batch(&self, tasks: &[PairTask], out: &mut [[f64; 3]]) -> Result<()> {
        let (disc, unit) = (self.disc, self.unit);
        // One array per task, so that the collect is indexed: each thread writes its part of
        // the vector in place (a flat map's collect gathers lists and copies them on one thread).
        let views: Vec<[f64; VIEW_STRIDE]> =
            tasks.par_iter().map(|t| self.view_of(t.node, disc.face_of(t.element))).collect();
        let mut records = Vec::with_capacity(4 * tasks.len());
        let mut piece_records = Vec::new();
        let mut vertices = Vec::new();
        for (k, t) in tasks.iter().enumerate() {
            let (first, count) = match &t.visible {
                Visibility::Partial(pieces) => {
                    let first = (piece_records.len() / 2) as u32;
                    let c = disc.centroid_in_face(t.element);
                    for piece in pieces {
                        piece_records
                            .extend_from_slice(&[(vertices.len() / 2) as u32, piece.len() as u32]);
                        vertices.extend(piece.iter().flat_map(|&q| {
                            let q = (q - c) * unit;
                            [q.x, q.y]
                        }));
                    }
                    (first, pieces.len() as u32)
                }
                _ => (0, WHOLE_ELEMENT),
            };
            records.extend_from_slice(&[k as u32, t.element as u32, first, count]);
        }
        let piece_offset = records.len() as u32;
        records.extend(piece_records);

        let (ctx, p) = (self.assembler.ctx, self.assembler.precision);
        let per = disc.method.nodes_per_element();
        let mut buffers = self.buffers.lock().unwrap_or_else(|e| e.into_inner());
        let values = compute::checked(ctx, "GPU pair evaluation", || {
            let (x, y, stride) = compute::grid(ctx, tasks.len() as u64);
            let params = Params {
                rows: tasks.len() as u32,
                elements: disc.element_count() as u32,
                faces: self.scene.faces.len() as u32,
                dof: disc.dof() as u32,
                imt_count: self.counts.imt as u32,
                rule_offset: self.counts.rule_offset as u32,
                band_count: self.counts.bands as u32,
                exception_count: tasks.len() as u32,
                piece_offset,
                stride,
                near_capacity: 0,
                ..Default::default()
            };
            let params = compute::uniform(ctx, bytemuck::bytes_of(&params));
            let BatchBuffers { views: v, records: r, vertices: w, output: o } = &mut *buffers;
            let upload = |slot: &mut Option<wgpu::Buffer>, bytes: &[u8]| {
                let buffer = fitted(slot, bytes.len() as u64, wgpu::Buffer::size, |size| {
                    compute::input(ctx, size)
                });
                if !bytes.is_empty() {
                    ctx.queue.write_buffer(buffer, 0, bytes);
                }
                bytes.len() as u64
            };
            let up = [
                upload(v, &layout::reals_as_bytes(views.as_flattened(), p)),
                upload(r, bytemuck::cast_slice(&records)),
                upload(w, &layout::reals_as_bytes(&vertices, p)),
            ];
            let (views, records, vertices) = (
                v.as_ref().expect("uploaded"),
                r.as_ref().expect("uploaded"),
                w.as_ref().expect("uploaded"),
            );
            // Bound by the layout, unused by this kernel.
            let near = compute::storage(ctx, &[0u8; layout::NEAR_HEADER_BYTES as usize + 8]);
            let size = (tasks.len() * per * p.bytes()) as u64;
            let (output, staging) =
                fitted(o, size, |(out, _)| out.size(), |size| compute::output(ctx, size));
            let group = compute::bind_group(
                ctx,
                &self.assembler.layout,
                &[&params, views, &self.elements, &self.tables, records, vertices, output, &near],
            );
            let mut encoder = ctx.device.create_command_encoder(&Default::default());
            dispatch(&mut encoder, &self.assembler.pairs, &group, (x, y));
            encoder.copy_buffer_to_buffer(output, 0, staging, 0, size.max(16));
            ctx.queue.submit([encoder.finish()]);
            let started = Instant::now();
            let values = compute::read_back(ctx, staging, size, p);
            let waited = started.elapsed().as_secs_f64();
            self.count_submission(params.size() + up.iter().sum::<u64>(), size, waited);
            values
        })??;
        for (o, v) in out.iter_mut().zip(values.chunks_exact(per)) {
            o[..per].copy_from_slice(v);
        }
        Ok(())
    }
}

impl PairEvaluation for PairEvaluator<'_> {
    /// The f64 kernels clip the elements of faces seen in part (src/gpu/pair_cuts.rs); the f32
    /// kernels take the host's pieces.
    fn clipper(&self) -> Option<&dyn CutEvaluation> {
        self.assembler.cut_pipelines().is_some().then_some(self as &dyn CutEvaluation)
    }

    /// In batches that fit the device's bindings; thin elements' pairs on the CPU.
    fn evaluate(&self, tasks: &[PairTask]) -> Result<Vec<[f64; 3]>> {
        let mut out = vec![[0.0; 3]; tasks.len()];
        let bytes = self.assembler.precision.bytes() as u64;
        let mut start = 0;
        while start < tasks.len() {
            let (mut end, mut vertices, mut words) = (start, 0u64, 0u64);
            while end < tasks.len() {
                let (pieces, v) = match &tasks[end].visible {
                    Visibility::Partial(pieces) => {
                        (pieces.len() as u64, pieces.iter().map(|p| p.len() as u64).sum())
                    }
                    _ => (0, 0),
                };
                let views = (end - start + 1) as u64 * (VIEW_STRIDE as u64 * bytes);
                let over = views > self.budget
                    || (vertices + v) * 2 * bytes > self.budget
                    || (words + 4 + 2 * pieces) * 4 > self.budget;
                if over && end > start {
                    break;
                }
                (vertices, words, end) = (vertices + v, words + 4 + 2 * pieces, end + 1);
            }
            self.batch(&tasks[start..end], &mut out[start..end])?;
            start = end;
        }
        // Thin elements' closed forms cancel: their pairs are evaluated again on the CPU.
        let thin: Vec<usize> = (0..tasks.len()).filter(|&k| self.thin[tasks[k].element]).collect();
        if !thin.is_empty() {
            let again: Vec<PairTask> = thin.iter().map(|&k| tasks[k].clone()).collect();
            let values = CpuPairs::new(self.disc, &self.integrator).evaluate(&again)?;
            for (&k, v) in thin.iter().zip(values) {
                out[k] = v;
            }
        }
        Ok(out)
    }
}
