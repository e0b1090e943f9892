//! The compressed operator's blocks in device memory and their product there
//! (`shaders/blocks.wgsl`): exact blocks (dense or sparse rows) and low-rank factors, uploaded
//! once; per product x goes up and K x comes down.

use std::sync::Mutex;

use super::GpuContext;
use super::compute;
use super::resident::{DeviceTraffic, round_trip};
use super::shaders;
use crate::error::{Error, Result};

/// The packed blocks as the kernels read them (the compressed operator's packed form, whose
/// layout `src/operator/packed.rs` describes).
#[derive(Clone, Copy, Debug)]
pub struct BlockArrays<'a> {
    /// Number of blocks.
    pub blocks: usize,
    /// Number of low-rank blocks.
    pub low_rank: usize,
    /// Values of every block.
    pub values: &'a [f64],
    /// Descriptors and index data.
    pub indices: &'a [u32],
    /// Where the low-rank blocks' numbers start in `indices`.
    pub low_rank_at: usize,
    /// Where the rows' contribution ranges start in `indices`.
    pub row_starts_at: usize,
    /// Where the contributions start in `indices`.
    pub contributions_at: usize,
    /// f64 values of scratch one product needs.
    pub scratch: usize,
}

/// What stays on the device between products.
struct Buffers {
    x: wgpu::Buffer,
    y: wgpu::Buffer,
    staging: wgpu::Buffer,
    group: wgpu::BindGroup,
    /// The blocks, the scratch and the parameters, kept alive for the bind group.
    _kept: Vec<wgpu::Buffer>,
}

/// The compressed operator on the device.
pub struct DeviceBlocks {
    ctx: &'static GpuContext,
    dof: usize,
    per: usize,
    node_order: Vec<usize>,
    element_order: Vec<usize>,
    pipelines: [wgpu::ComputePipeline; 3],
    buffers: Buffers,
    grid: ((u32, u32), (u32, u32), (u32, u32)),
    bytes: u64,
    traffic: Mutex<DeviceTraffic>,
}

impl std::fmt::Debug for DeviceBlocks {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "DeviceBlocks {{ dof: {}, bytes: {} }}", self.dof, self.bytes)
    }
}

impl DeviceBlocks {
    /// Uploads `arrays` (for `dof` unknowns, `per` basis functions per element, rows and
    /// columns in `node_order` and `element_order`); refused where the device lacks f64 or a
    /// buffer would pass its binding limit.
    pub fn upload(
        ctx: &'static GpuContext,
        dof: usize,
        (per, node_order, element_order): (usize, &[usize], &[usize]),
        arrays: BlockArrays,
    ) -> Result<Self> {
        if !ctx.adapter.f64 {
            return Err(Error::Gpu(format!("adapter '{}' has no SHADER_F64", ctx.adapter.name)));
        }
        let limits = &ctx.limits;
        let max_binding = limits.max_storage_buffer_binding_size.min(limits.max_buffer_size);
        let values_bytes = 8 * arrays.values.len() as u64;
        let index_bytes = 4 * arrays.indices.len() as u64;
        let scratch_bytes = 8 * arrays.scratch as u64;
        for (what, bytes) in
            [("values", values_bytes), ("indices", index_bytes), ("scratch", scratch_bytes)]
        {
            if bytes > max_binding {
                return Err(Error::Gpu(format!(
                    "the compressed operator's {what} take {bytes} bytes, over the device's \
                     binding limit of {max_binding}"
                )));
            }
        }
        let (layout, pipelines) = compute::pipeline(
            ctx,
            &shaders::blocks(),
            &["low_rank_t", "block_rows", "row_sums"],
            6,
            &[0],
            &[4, 5],
        )?;
        let pipelines: [wgpu::ComputePipeline; 3] = pipelines.try_into().expect("three pipelines");
        let max_x = limits.max_compute_workgroups_per_dimension.max(1);
        let groups = |n: usize| -> (u32, u32) {
            let n = n.max(1) as u64;
            ((n.min(max_x as u64)) as u32, n.div_ceil(max_x as u64) as u32)
        };
        let grid = (
            groups(arrays.low_rank),
            groups(arrays.blocks),
            groups(dof.div_ceil(super::layout::WORKGROUP as usize)),
        );
        let params: [u32; 8] = [
            arrays.blocks as u32,
            arrays.low_rank as u32,
            dof as u32,
            max_x,
            arrays.low_rank_at as u32,
            arrays.row_starts_at as u32,
            arrays.contributions_at as u32,
            0,
        ];
        let buffers = compute::checked(ctx, "uploading the compressed operator", || {
            let params = compute::uniform(ctx, bytemuck::cast_slice(&params));
            let values = compute::storage(ctx, bytemuck::cast_slice(arrays.values));
            let indices = compute::storage(ctx, bytemuck::cast_slice(arrays.indices));
            let x = ctx.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("x"),
                size: (8 * dof as u64).max(16),
                usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            });
            let scratch = compute::writable(ctx, scratch_bytes);
            let (y, staging) = compute::output(ctx, 8 * dof as u64);
            let group =
                compute::bind_group(ctx, &layout, &[&params, &values, &indices, &x, &scratch, &y]);
            Buffers { x, y, staging, group, _kept: vec![params, values, indices, scratch] }
        })?;
        let bytes = values_bytes + index_bytes;
        let traffic = DeviceTraffic { bytes_uploaded: bytes, ..Default::default() };
        Ok(Self {
            ctx,
            dof,
            per,
            node_order: node_order.to_vec(),
            element_order: element_order.to_vec(),
            pipelines,
            buffers,
            grid,
            bytes,
            traffic: Mutex::new(traffic),
        })
    }

    /// Number of unknowns.
    pub fn dof(&self) -> usize {
        self.dof
    }

    /// Bytes of the blocks on the device.
    pub fn device_bytes(&self) -> u64 {
        self.bytes
    }

    /// What has crossed so far.
    pub fn traffic(&self) -> DeviceTraffic {
        *self.traffic.lock().unwrap_or_else(|e| e.into_inner())
    }

    /// `K x` for every `x` in `xs`, one submission each.
    pub fn apply_many(&self, xs: &[&[f64]]) -> Result<Vec<Vec<f64>>> {
        xs.iter().map(|x| self.apply(x)).collect()
    }

    /// `K x`: x in the blocks' column order goes up, the product in their row order comes
    /// down.
    fn apply(&self, x: &[f64]) -> Result<Vec<f64>> {
        let (ctx, dof, per) = (self.ctx, self.dof, self.per);
        let mut xp = vec![0.0; dof];
        for (k, &e) in self.element_order.iter().enumerate() {
            xp[k * per..(k + 1) * per].copy_from_slice(&x[e * per..(e + 1) * per]);
        }
        let b = &self.buffers;
        let buffers = (&b.x, &b.y, &b.staging);
        let what = "the compressed product on the device";
        let yp = round_trip(ctx, what, buffers, &xp, &self.traffic, |encoder| {
            let (low_rank, blocks, rows) = self.grid;
            for (pipeline, (gx, gy)) in self.pipelines.iter().zip([low_rank, blocks, rows]) {
                let mut pass = encoder.begin_compute_pass(&Default::default());
                pass.set_pipeline(pipeline);
                pass.set_bind_group(0, &b.group, &[]);
                pass.dispatch_workgroups(gx, gy, 1);
            }
        })?;
        let mut y = vec![0.0; dof];
        for (k, &i) in self.node_order.iter().enumerate() {
            y[i] = yp[k];
        }
        Ok(y)
    }
}
