//! K kept in device memory after its assembly, and its products there: only vectors cross
//! between host and device (x up, K x down), not the n × n matrix.

use std::sync::Mutex;
use std::time::Instant;

use serde::Serialize;

use super::GpuContext;
use super::assembly::{DeviceTiles, GpuAssembler};
use super::compute;
use super::shaders::{self, Precision};
use super::storage::StorageError;
use crate::assembly::{AssemblyOptions, Problem, ThinColumns};
use crate::error::{Error, Result};
use crate::progress::Progress;
use crate::visibility::PairStats;

/// What crossed between host and device, and how often the host submitted work.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct DeviceTraffic {
    /// Bytes written to the device (the scene's elements and tables, each tile's plan, the
    /// vectors of the products).
    pub bytes_uploaded: u64,
    /// Bytes read back (the products).
    pub bytes_read_back: u64,
    /// Command submissions (one per assembled tile, per batch of pairs, per product).
    pub gpu_submissions: u64,
    /// Host time spent waiting for the device: the device was busy at least that long.
    pub device_wait_seconds: f64,
    /// Pairs of faces seen in part that the device clipped (listed pairs of a compressed
    /// operator's exact blocks).
    pub pairs_clipped_on_device: u64,
    /// Those left to the host: past the clipping kernel's limits, or thin elements.
    pub pairs_clipped_on_host: u64,
}

impl std::ops::Add for DeviceTraffic {
    type Output = Self;

    fn add(self, other: Self) -> Self {
        Self {
            bytes_uploaded: self.bytes_uploaded + other.bytes_uploaded,
            bytes_read_back: self.bytes_read_back + other.bytes_read_back,
            gpu_submissions: self.gpu_submissions + other.gpu_submissions,
            device_wait_seconds: self.device_wait_seconds + other.device_wait_seconds,
            pairs_clipped_on_device: self.pairs_clipped_on_device + other.pairs_clipped_on_device,
            pairs_clipped_on_host: self.pairs_clipped_on_host + other.pairs_clipped_on_host,
        }
    }
}

/// One product's trip to the device and back, in one submission: `x` written to `x_buffer`,
/// `encode` records the kernels that write the product to `y_buffer`, whose first `x.len()`
/// reals come back through `staging`; the bytes, the submission and the wait are counted in
/// `traffic`.
pub(super) fn round_trip(
    ctx: &GpuContext,
    what: &str,
    (x_buffer, y_buffer, staging): (&wgpu::Buffer, &wgpu::Buffer, &wgpu::Buffer),
    x: &[f64],
    traffic: &Mutex<DeviceTraffic>,
    encode: impl FnOnce(&mut wgpu::CommandEncoder),
) -> Result<Vec<f64>> {
    let bytes = 8 * x.len() as u64;
    compute::checked(ctx, what, || {
        ctx.queue.write_buffer(x_buffer, 0, bytemuck::cast_slice(x));
        let mut encoder = ctx.device.create_command_encoder(&Default::default());
        encode(&mut encoder);
        encoder.copy_buffer_to_buffer(y_buffer, 0, staging, 0, bytes.max(16));
        ctx.queue.submit([encoder.finish()]);
    })?;
    let started = Instant::now();
    compute::wait(ctx, staging, bytes)?;
    let waited = started.elapsed().as_secs_f64();
    let mut y = vec![0.0; x.len()];
    compute::copy_mapped(staging, bytes, Precision::F64, &mut y)?;
    let mut t = traffic.lock().unwrap_or_else(|e| e.into_inner());
    t.bytes_uploaded += bytes;
    t.bytes_read_back += bytes;
    t.gpu_submissions += 1;
    t.device_wait_seconds += waited;
    Ok(y)
}

/// The buffers of products with `m` vectors at once.
struct Vectors {
    m: usize,
    x: wgpu::Buffer,
    y: wgpu::Buffer,
    staging: wgpu::Buffer,
    /// Per tile, its bind group (and its parameters' buffer, kept alive).
    groups: Vec<(wgpu::BindGroup, wgpu::Buffer)>,
}

/// K on the device (dense, row tiles as assembled), with the columns of the thin elements,
/// which the kernels cannot evaluate, kept on the host.
pub struct DeviceOperator {
    ctx: &'static GpuContext,
    dof: usize,
    tiles: DeviceTiles,
    layout: wgpu::BindGroupLayout,
    pipeline: wgpu::ComputePipeline,
    /// Columns of thin elements: zero in the vectors sent to the device, applied on the host.
    thin: Option<ThinColumns>,
    vectors: Mutex<Option<Vectors>>,
    traffic: Mutex<DeviceTraffic>,
    /// Pair classes of the assembly.
    pub stats: PairStats,
    /// The precision K is stored in, and what that did to it.
    pub storage: StorageError,
}

impl std::fmt::Debug for DeviceOperator {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "DeviceOperator {{ dof: {}, tiles: {} }}", self.dof, self.tiles.len())
    }
}

impl DeviceOperator {
    /// Assembles K for `problem` by `assembler` into device memory, its entries stored in
    /// `storage` (f64 kernels only: the products are summed in f64; f32 storage halves the
    /// memory and the products' reads, and its error is measured).
    pub fn assemble(
        assembler: &GpuAssembler<'static>,
        problem: &Problem,
        options: &AssemblyOptions,
        storage: Precision,
        progress: &dyn Progress,
    ) -> Result<Self> {
        let ctx = assembler.context();
        if assembler.precision() != Precision::F64 {
            return Err(Error::Gpu("the device-resident operator is built in f64".into()));
        }
        let source = shaders::matvec(storage);
        let (layout, mut pipelines) = compute::pipeline(ctx, &source, &["matvec"], 4, &[0], &[3])?;
        let pipeline = pipelines.pop().expect("one pipeline");
        progress.start("assembly", problem.disc.dof());
        let (tiles, stats, storage) =
            assembler.assemble_on_device(problem, options, storage, progress)?;
        progress.finish();
        let traffic = assembler.last_timings().traffic();
        Ok(Self {
            ctx,
            dof: problem.disc.dof(),
            tiles,
            layout,
            pipeline,
            thin: ThinColumns::new(problem, options),
            vectors: Mutex::new(None),
            traffic: Mutex::new(traffic),
            stats,
            storage,
        })
    }

    /// Number of unknowns.
    pub fn dof(&self) -> usize {
        self.dof
    }

    /// Bytes of K in device memory.
    pub fn device_bytes(&self) -> u64 {
        self.tiles.iter().map(|(_, b)| b.size()).sum()
    }

    /// What has crossed so far.
    pub fn traffic(&self) -> DeviceTraffic {
        *self.traffic.lock().unwrap_or_else(|e| e.into_inner())
    }

    /// `K x` for every `x` in `xs`, in one submission: the vectors go up, the products come
    /// down (2 × 8 × dof bytes per vector).
    pub fn apply_many(&self, xs: &[&[f64]]) -> Result<Vec<Vec<f64>>> {
        let (m, dof) = (xs.len(), self.dof);
        if m == 0 || dof == 0 {
            return Ok(vec![vec![0.0; dof]; m]);
        }
        let mut flat = Vec::with_capacity(m * dof);
        for x in xs {
            flat.extend_from_slice(x);
        }
        if let Some(thin) = &self.thin {
            // Their true columns are applied on the host below.
            for v in 0..m {
                thin.columns.iter().for_each(|&c| flat[v * dof + c] = 0.0);
            }
        }
        let mut held = self.vectors.lock().unwrap_or_else(|e| e.into_inner());
        if held.as_ref().is_none_or(|v| v.m != m) {
            *held = Some(self.vectors_for(m)?);
        }
        let v = held.as_ref().expect("vectors for m");
        let (buffers, what) = ((&v.x, &v.y, &v.staging), "the product on the device");
        let y = round_trip(self.ctx, what, buffers, &flat, &self.traffic, |encoder| {
            let mut pass = encoder.begin_compute_pass(&Default::default());
            pass.set_pipeline(&self.pipeline);
            for ((rows, _), (group, _)) in self.tiles.iter().zip(&v.groups) {
                pass.set_bind_group(0, group, &[]);
                pass.dispatch_workgroups(rows.len() as u32, 1, 1);
            }
        })?;
        let mut out: Vec<Vec<f64>> = y.chunks_exact(dof).map(<[f64]>::to_vec).collect();
        if let Some(thin) = &self.thin {
            for (x, y) in xs.iter().zip(&mut out) {
                thin.apply_add(x, y);
            }
        }
        Ok(out)
    }

    /// Buffers and bind groups for products of `m` vectors.
    fn vectors_for(&self, m: usize) -> Result<Vectors> {
        let ctx = self.ctx;
        let bytes = (8 * m * self.dof) as u64;
        compute::checked(ctx, "the vectors of the product on the device", || {
            let x = compute::input(ctx, bytes);
            let (y, staging) = compute::output(ctx, bytes);
            let groups = self
                .tiles
                .iter()
                .map(|(rows, matrix)| {
                    let params: [u32; 4] =
                        [rows.len() as u32, self.dof as u32, rows.start as u32, m as u32];
                    let params = compute::uniform(ctx, bytemuck::cast_slice(&params));
                    let group = compute::bind_group(ctx, &self.layout, &[&params, matrix, &x, &y]);
                    (group, params)
                })
                .collect();
            Vectors { m, x, y, staging, groups }
        })
    }
}
