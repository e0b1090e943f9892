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

/// One part's blocks on the device, with its bind group and grid.
struct Part {
    group: wgpu::BindGroup,
    /// Workgroups of the three passes: low-rank blocks, blocks, rows.
    grid: [(u32, u32); 3],
    /// The blocks, the scratch and the parameters, kept alive for the bind group.
    _kept: [wgpu::Buffer; 4],
}

/// The compressed operator on the device.
pub struct DeviceBlocks {
    ctx: &'static GpuContext,
    dof: usize,
    per: usize,
    node_order: Vec<usize>,
    element_order: Vec<usize>,
    pipelines: [wgpu::ComputePipeline; 3],
    x: wgpu::Buffer,
    y: wgpu::Buffer,
    staging: wgpu::Buffer,
    parts: Vec<Part>,
    bytes: u64,
    traffic: Mutex<DeviceTraffic>,
}

impl std::fmt::Debug for DeviceBlocks {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let (dof, parts, bytes) = (self.dof, self.parts.len(), self.bytes);
        write!(f, "DeviceBlocks {{ dof: {dof}, parts: {parts}, bytes: {bytes} }}")
    }
}

impl DeviceBlocks {
    /// Uploads `parts` (for `dof` unknowns, `per` basis functions per element, rows and
    /// columns in `node_order` and `element_order`; the product is the sum of the parts'
    /// products); refused where the device lacks f64 or a buffer would pass its binding limit.
    pub fn upload(
        ctx: &'static GpuContext,
        dof: usize,
        (per, node_order, element_order): (usize, &[usize], &[usize]),
        parts: &[BlockArrays],
    ) -> Result<Self> {
        if !ctx.adapter.f64 {
            return Err(Error::Gpu(format!("adapter '{}' has no SHADER_F64", ctx.adapter.name)));
        }
        let max_binding = ctx.max_binding();
        for arrays in parts {
            let values_bytes = 8 * arrays.values.len() as u64;
            let index_bytes = 4 * arrays.indices.len() as u64;
            let scratch_bytes = 8 * arrays.scratch as u64;
            for (what, bytes) in
                [("values", values_bytes), ("indices", index_bytes), ("scratch", scratch_bytes)]
            {
                if bytes > max_binding {
                    return Err(Error::Gpu(format!(
                        "a part of the compressed operator's {what} takes {bytes} bytes, over \
                         the device's binding limit of {max_binding}"
                    )));
                }
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
        let max_x = ctx.limits.max_compute_workgroups_per_dimension.max(1);
        let groups = |n: usize| -> (u32, u32) {
            let n = n.max(1) as u64;
            ((n.min(max_x as u64)) as u32, n.div_ceil(max_x as u64) as u32)
        };
        let bytes = parts.iter().map(|a| 8 * a.values.len() as u64 + 4 * a.indices.len() as u64);
        let bytes = bytes.sum();
        let rows_grid = groups(dof.div_ceil(super::layout::WORKGROUP as usize));
        let (x, y, staging, parts) =
            compute::checked(ctx, "uploading the compressed operator", || {
                let x = compute::input(ctx, 8 * dof as u64);
                let (y, staging) = compute::output(ctx, 8 * dof as u64);
                let parts = parts
                    .iter()
                    .enumerate()
                    .map(|(n, arrays)| {
                        let params: [u32; 8] = [
                            arrays.blocks as u32,
                            arrays.low_rank as u32,
                            dof as u32,
                            max_x,
                            arrays.low_rank_at as u32,
                            arrays.row_starts_at as u32,
                            arrays.contributions_at as u32,
                            u32::from(n > 0),
                        ];
                        let params = compute::uniform(ctx, bytemuck::cast_slice(&params));
                        let values = compute::storage(ctx, bytemuck::cast_slice(arrays.values));
                        let indices = compute::storage(ctx, bytemuck::cast_slice(arrays.indices));
                        let scratch = compute::writable(ctx, 8 * arrays.scratch as u64);
                        let group = compute::bind_group(
                            ctx,
                            &layout,
                            &[&params, &values, &indices, &x, &scratch, &y],
                        );
                        let grid = [groups(arrays.low_rank), groups(arrays.blocks), rows_grid];
                        Part { group, grid, _kept: [params, values, indices, scratch] }
                    })
                    .collect();
                (x, y, staging, parts)
            })?;
        let traffic = DeviceTraffic { bytes_uploaded: bytes, ..Default::default() };
        Ok(Self {
            ctx,
            dof,
            per,
            node_order: node_order.to_vec(),
            element_order: element_order.to_vec(),
            pipelines,
            x,
            y,
            staging,
            parts,
            bytes,
            traffic: Mutex::new(traffic),
        })
    }

    /// Number of parts the blocks were uploaded in (one binding each).
    pub fn parts(&self) -> usize {
        self.parts.len()
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
        let buffers = (&self.x, &self.y, &self.staging);
        let what = "the compressed product on the device";
        let yp = round_trip(ctx, what, buffers, &xp, &self.traffic, |encoder| {
            // Part after part: each pass of a part sees the last part's writes to y.
            for part in &self.parts {
                for (pipeline, &(gx, gy)) in self.pipelines.iter().zip(&part.grid) {
                    let mut pass = encoder.begin_compute_pass(&Default::default());
                    pass.set_pipeline(pipeline);
                    pass.set_bind_group(0, &part.group, &[]);
                    pass.dispatch_workgroups(gx, gy, 1);
                }
            }
        })?;
        let mut y = vec![0.0; dof];
        for (k, &i) in self.node_order.iter().enumerate() {
            y[i] = yp[k];
        }
        Ok(y)
    }
}
