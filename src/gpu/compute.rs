//! Small helpers over wgpu: pipelines from WGSL, buffers, dispatch grids and read-back.

use rayon::prelude::*;
use wgpu::util::DeviceExt;

use super::GpuContext;
use super::context::PipelineKey;
use super::layout::{NEAR_HEADER_BYTES, WORKGROUP};
use super::shaders::Precision;
use crate::error::{Error, Result};

/// Compute pipelines for `entries` in `source`, with an explicit layout of buffers: `uniforms` lists
/// the uniform bindings, `writable` the read-write storage bindings, the rest are read-only
/// storage. Compiled once per device: a second call with the same arguments returns the same
/// pipelines (wgpu's handles are shared, not copied).
pub fn pipeline(
    ctx: &GpuContext,
    source: &str,
    entries: &[&str],
    bindings: u32,
    uniforms: &[u32],
    writable: &[u32],
) -> Result<(wgpu::BindGroupLayout, Vec<wgpu::ComputePipeline>)> {
    let key: PipelineKey = (
        source.to_string(),
        entries.iter().map(|e| e.to_string()).collect(),
        bindings,
        uniforms.to_vec(),
        writable.to_vec(),
    );
    // Held while compiling: two threads asking for the same kernels compile them once.
    let mut compiled = ctx.compiled.lock().expect("pipeline cache lock");
    if let Some(found) = compiled.get(&key) {
        return Ok(found.clone());
    }
    let made = compile(ctx, source, entries, bindings, uniforms, writable)?;
    compiled.insert(key, made.clone());
    Ok(made)
}

/// [`pipeline`]'s compilation.
fn compile(
    ctx: &GpuContext,
    source: &str,
    entries: &[&str],
    bindings: u32,
    uniforms: &[u32],
    writable: &[u32],
) -> Result<(wgpu::BindGroupLayout, Vec<wgpu::ComputePipeline>)> {
    let layout_entries: Vec<wgpu::BindGroupLayoutEntry> = (0..bindings)
        .map(|b| wgpu::BindGroupLayoutEntry {
            binding: b,
            visibility: wgpu::ShaderStages::COMPUTE,
            ty: wgpu::BindingType::Buffer {
                ty: if uniforms.contains(&b) {
                    wgpu::BufferBindingType::Uniform
                } else {
                    wgpu::BufferBindingType::Storage { read_only: !writable.contains(&b) }
                },
                has_dynamic_offset: false,
                min_binding_size: None,
            },
            count: None,
        })
        .collect();
    let scope = ctx.device.push_error_scope(wgpu::ErrorFilter::Validation);
    let module = ctx.device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some("radiosity"),
        source: wgpu::ShaderSource::Wgsl(source.into()),
    });
    let bind_layout = ctx.device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: None,
        entries: &layout_entries,
    });
    let pipeline_layout = ctx.device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
        label: None,
        bind_group_layouts: &[Some(&bind_layout)],
        immediate_size: 0,
    });
    let pipelines = entries
        .iter()
        .map(|entry| {
            ctx.device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                label: Some(entry),
                layout: Some(&pipeline_layout),
                module: &module,
                entry_point: Some(entry),
                compilation_options: Default::default(),
                cache: None,
            })
        })
        .collect();
    if let Some(e) = pollster::block_on(scope.pop()) {
        return Err(Error::Gpu(format!("shader or pipeline creation failed: {e}")));
    }
    Ok((bind_layout, pipelines))
}

/// Runs `work` (buffer creation, binding, submission) inside error scopes, so that a validation
/// or out-of-memory error comes back as [`Error::Gpu`] naming `what`, instead of reaching wgpu's
/// default handler, which panics.
pub fn checked<T>(ctx: &GpuContext, what: &str, work: impl FnOnce() -> T) -> Result<T> {
    let out_of_memory = ctx.device.push_error_scope(wgpu::ErrorFilter::OutOfMemory);
    let validation = ctx.device.push_error_scope(wgpu::ErrorFilter::Validation);
    let value = work();
    let errors = [pollster::block_on(validation.pop()), pollster::block_on(out_of_memory.pop())];
    match errors.into_iter().flatten().next() {
        Some(e) => Err(Error::Gpu(format!("{what} failed on the device: {e}"))),
        None => Ok(value),
    }
}

/// A read-only storage buffer holding `bytes` (at least 16 bytes, as empty bindings are invalid).
pub fn storage(ctx: &GpuContext, bytes: &[u8]) -> wgpu::Buffer {
    let padded;
    let contents = if bytes.len() < 16 {
        padded = [bytes, &[0u8; 16][..16 - bytes.len()]].concat();
        &padded[..]
    } else {
        bytes
    };
    ctx.device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: None,
        contents,
        usage: wgpu::BufferUsages::STORAGE,
    })
}

/// A uniform buffer.
pub fn uniform(ctx: &GpuContext, bytes: &[u8]) -> wgpu::Buffer {
    ctx.device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: None,
        contents: bytes,
        usage: wgpu::BufferUsages::UNIFORM,
    })
}

/// A writable storage buffer of `size` bytes that can be copied out.
pub fn writable(ctx: &GpuContext, size: u64) -> wgpu::Buffer {
    ctx.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("out"),
        size: size.max(16),
        usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
        mapped_at_creation: false,
    })
}

/// A read-only storage buffer of `size` bytes (at least 16) that the host writes to later.
pub fn input(ctx: &GpuContext, size: u64) -> wgpu::Buffer {
    ctx.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("in"),
        size: size.max(16),
        usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    })
}

/// A writable storage buffer of `size` bytes that can be copied out, and its staging twin.
pub fn output(ctx: &GpuContext, size: u64) -> (wgpu::Buffer, wgpu::Buffer) {
    let size = size.max(16);
    let out = writable(ctx, size);
    let staging = ctx.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("staging"),
        size,
        usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    (out, staging)
}

/// A bind group of whole buffers in binding order.
pub fn bind_group(
    ctx: &GpuContext,
    layout: &wgpu::BindGroupLayout,
    buffers: &[&wgpu::Buffer],
) -> wgpu::BindGroup {
    let entries: Vec<wgpu::BindGroupEntry> = buffers
        .iter()
        .enumerate()
        .map(|(k, b)| wgpu::BindGroupEntry { binding: k as u32, resource: b.as_entire_binding() })
        .collect();
    ctx.device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: None,
        layout,
        entries: &entries,
    })
}

/// Workgroup grid `(x, y)` covering `invocations`, and the invocations per grid row.
pub fn grid(ctx: &GpuContext, invocations: u64) -> (u32, u32, u32) {
    let groups = invocations.div_ceil(WORKGROUP as u64).max(1);
    let max_x = ctx.limits.max_compute_workgroups_per_dimension.max(1) as u64;
    let x = groups.min(max_x);
    let y = groups.div_ceil(x);
    (x as u32, y as u32, (x * WORKGROUP as u64) as u32)
}

/// Maps a staging buffer for reading and waits for the device to finish the work before it.
pub fn wait(ctx: &GpuContext, staging: &wgpu::Buffer, size: u64) -> Result<()> {
    let slice = staging.slice(..size.max(16));
    let (tx, rx) = std::sync::mpsc::channel();
    slice.map_async(wgpu::MapMode::Read, move |r| {
        let _ = tx.send(r);
    });
    ctx.device
        .poll(wgpu::PollType::wait_indefinitely())
        .map_err(|e| Error::Gpu(format!("waiting for the device failed: {e}")))?;
    rx.recv()
        .map_err(|_| Error::Gpu("mapping callback never ran".into()))?
        .map_err(|e| Error::Gpu(format!("mapping the output failed: {e}")))?;
    Ok(())
}

/// Reals per part of a parallel copy out of a staging buffer.
const COPY_CHUNK: usize = 1 << 16;

/// Converts the reals of a staging buffer mapped by [`wait`] into `out` and unmaps it.
pub fn copy_mapped(
    staging: &wgpu::Buffer,
    size: u64,
    precision: Precision,
    out: &mut [f64],
) -> Result<()> {
    with_mapped(staging, size, |bytes| {
        // On all cores: copying out of mapped memory is bound by bandwidth, and on one thread it
        // would take most of a GPU assembly's time on a real card (docs/gpu.md).
        match precision {
            Precision::F64 => {
                let values: &[f64] = bytemuck::cast_slice(bytes);
                out.par_chunks_mut(COPY_CHUNK)
                    .zip(values.par_chunks(COPY_CHUNK))
                    .for_each(|(o, v)| o.copy_from_slice(v));
            }
            Precision::F32 => {
                let values: &[f32] = bytemuck::cast_slice(bytes);
                out.par_chunks_mut(COPY_CHUNK)
                    .zip(values.par_chunks(COPY_CHUNK))
                    .for_each(|(o, v)| o.iter_mut().zip(v).for_each(|(o, v)| *o = f64::from(*v)));
            }
        }
    })
}

/// `read(bytes)` of the first `size` bytes of a staging buffer mapped by [`wait`], which is
/// unmapped after.
fn with_mapped<T>(staging: &wgpu::Buffer, size: u64, read: impl FnOnce(&[u8]) -> T) -> Result<T> {
    let value = {
        let view = staging
            .slice(..size.max(16))
            .get_mapped_range()
            .map_err(|e| Error::Gpu(format!("mapped range: {e}")))?;
        read(&view[..size as usize])
    };
    staging.unmap();
    Ok(value)
}

/// A near list (shaders/collocation.wgsl, `NearList`) holding `pairs` pairs after its header
/// and then `deferred` single indices, and the buffer its indirect dispatch arguments are
/// copied into (a buffer bound read-write cannot also drive the dispatch that binds it).
pub fn near_list(ctx: &GpuContext, pairs: u64, deferred: u64) -> (wgpu::Buffer, wgpu::Buffer) {
    let list = ctx.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("near"),
        size: NEAR_HEADER_BYTES + 8 * pairs.max(1) + 4 * deferred.next_multiple_of(2),
        usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
        mapped_at_creation: false,
    });
    let args = ctx.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("near dispatch"),
        size: 16,
        usage: wgpu::BufferUsages::INDIRECT | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    (list, args)
}

/// Waits for the device and returns the reals of a staging buffer.
pub fn read_back(
    ctx: &GpuContext,
    staging: &wgpu::Buffer,
    size: u64,
    precision: Precision,
) -> Result<Vec<f64>> {
    wait(ctx, staging, size)?;
    let mut out = vec![0.0; size as usize / precision.bytes()];
    copy_mapped(staging, size, precision, &mut out)?;
    Ok(out)
}

/// `count` u32 of `buffer` from byte `offset`, once the work before is done (a copy, submitted
/// and waited for).
pub fn read_u32s(
    ctx: &GpuContext,
    buffer: &wgpu::Buffer,
    offset: u64,
    count: usize,
) -> Result<Vec<u32>> {
    if count == 0 {
        return Ok(Vec::new());
    }
    let size = 4 * count as u64;
    let staging = ctx.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("staging"),
        size: size.max(16),
        usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    let mut encoder = ctx.device.create_command_encoder(&Default::default());
    encoder.copy_buffer_to_buffer(buffer, offset, &staging, 0, size);
    ctx.queue.submit([encoder.finish()]);
    wait(ctx, &staging, size)?;
    with_mapped(&staging, size, bytemuck::pod_collect_to_vec::<u8, u32>)
}
