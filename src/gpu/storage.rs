//! K stored on the device in f32 (`--storage f32`): each tile, assembled in f64, is narrowed on
//! the device (`shaders/narrow.wgsl`), and the rounding it adds is measured there, row by row,
//! so that the report can say how far the stored matrix is from the computed one and what that
//! may do to the solution.

use std::ops::Range;

use serde::Serialize;

use super::GpuContext;
use super::compute;
use super::shaders::{self, Precision};
use crate::error::Result;

/// What storing K in `storage` precision did to it, measured on every entry.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct StorageError {
    /// Precision of the stored entries (`storage` in reports).
    pub storage: Precision,
    /// `||K - fl(K)||_inf / ||K||_inf` (`storage_error`): the largest row sum of the roundings
    /// over the largest row sum of |K|; 0 in f64.
    #[serde(rename = "storage_error")]
    pub matrix: f64,
    /// A bound on `||u - u_stored||_inf / ||u_stored||_inf` (`storage_solution_bound`):
    /// `u - u_stored = -(I - K)^-1 (fl(K) - K) u_stored` and `||(I - K)^-1||_inf <= 1 / (1 -
    /// ||K||_inf)`, so `||fl(K) - K||_inf / (1 - ||K||_inf)`; `None` where `||K||_inf >= 1`.
    #[serde(rename = "storage_solution_bound")]
    pub solution_bound: Option<f64>,
}

impl StorageError {
    /// Exact storage (f64).
    pub fn none() -> Self {
        Self { storage: Precision::F64, matrix: 0.0, solution_bound: Some(0.0) }
    }

    /// From each row's (sum of |K_ij| as computed in f64, sum of its roundings to f32).
    fn from_row_norms(norms: &[f64]) -> Self {
        let (mut k, mut d) = (0.0f64, 0.0f64);
        for row in norms.chunks_exact(2) {
            k = k.max(row[0]);
            d = d.max(row[1]);
        }
        let matrix = if k > 0.0 { d / k } else { 0.0 };
        let solution_bound = (k < 1.0).then(|| d / (1.0 - k));
        Self { storage: Precision::F32, matrix, solution_bound }
    }
}

/// The narrowing of f64 tiles of a `dof` × `dof` matrix into f32 ones, and the rows' norms,
/// which stay on the device until [`Narrowing::error`] reads them.
pub(super) struct Narrowing {
    dof: usize,
    layout: wgpu::BindGroupLayout,
    pipeline: wgpu::ComputePipeline,
    norms: wgpu::Buffer,
    staging: wgpu::Buffer,
}

impl Narrowing {
    pub(super) fn new(ctx: &GpuContext, dof: usize) -> Result<Self> {
        let (layout, mut pipelines) =
            compute::pipeline(ctx, &shaders::narrow(), &["narrow_rows"], 4, &[0], &[2, 3])?;
        let pipeline = pipelines.pop().expect("one pipeline");
        let (norms, staging) =
            compute::checked(ctx, "the storage's norms", || compute::output(ctx, 16 * dof as u64))?;
        Ok(Self { dof, layout, pipeline, norms, staging })
    }

    /// Records in `encoder` the narrowing of the tile `rows` held in `wide` (f64), and returns
    /// its f32 buffer with the buffers the pass needs alive until it has run.
    pub(super) fn encode(
        &self,
        ctx: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        rows: Range<usize>,
        wide: &wgpu::Buffer,
    ) -> (wgpu::Buffer, wgpu::Buffer) {
        let narrow = compute::writable(ctx, (4 * rows.len() * self.dof) as u64);
        let params: [u32; 4] = [rows.len() as u32, self.dof as u32, rows.start as u32, 0];
        let params = compute::uniform(ctx, bytemuck::cast_slice(&params));
        let group = compute::bind_group(ctx, &self.layout, &[&params, wide, &narrow, &self.norms]);
        let mut pass = encoder.begin_compute_pass(&Default::default());
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(0, &group, &[]);
        pass.dispatch_workgroups(rows.len() as u32, 1, 1);
        drop(pass);
        (narrow, params)
    }

    /// The error of the storage, from the rows' norms (16 dof bytes read back), once every
    /// tile has been narrowed.
    pub(super) fn error(&self, ctx: &GpuContext) -> Result<(StorageError, u64)> {
        let bytes = 16 * self.dof as u64;
        compute::checked(ctx, "reading the storage's norms", || {
            let mut encoder = ctx.device.create_command_encoder(&Default::default());
            encoder.copy_buffer_to_buffer(&self.norms, 0, &self.staging, 0, bytes.max(16));
            ctx.queue.submit([encoder.finish()]);
        })?;
        let norms = compute::read_back(ctx, &self.staging, bytes, Precision::F64)?;
        Ok((StorageError::from_row_norms(&norms), bytes))
    }
}
