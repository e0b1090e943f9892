//! Device acquisition: picks an adapter (a real GPU first, then a software one such as Mesa's
//! lavapipe), checks f64 support, and builds the device and queue once.

use crate::error::{Error, Result};

/// How to choose the adapter.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct AdapterRequest {
    /// Use only adapters whose name contains this text (case-insensitive); the environment variable
    /// `RADIOSITY_GPU_ADAPTER` sets it when this is `None`.
    pub name: Option<String>,
    /// Require `SHADER_F64` (the double-precision kernels).
    pub require_f64: bool,
}

/// What was chosen.
#[derive(Clone, Debug, PartialEq, Eq, serde::Serialize)]
pub struct AdapterSummary {
    /// Adapter name, e.g. "llvmpipe (LLVM 15.0.6, 256 bits)".
    pub name: String,
    /// Backend, e.g. "Vulkan".
    pub backend: String,
    /// Device type, e.g. "Cpu" or "DiscreteGpu".
    pub device_type: String,
    /// Whether the device has `SHADER_F64`.
    pub f64: bool,
    /// Driver and its version, as the adapter reports them (e.g. "llvmpipe, Mesa 22.3.6").
    pub driver: String,
}

/// A device and queue with the facts the work functions need.
pub struct GpuContext {
    /// The device.
    pub device: wgpu::Device,
    /// Its queue.
    pub queue: wgpu::Queue,
    /// The adapter.
    pub adapter: AdapterSummary,
    /// The device's limits.
    pub limits: wgpu::Limits,
    /// The pipelines compiled on this device, by what they were compiled from
    /// ([`super::compute::pipeline`]): an assembler made again for the same kernels (every
    /// `Assembler::new` of a study's cases, every GPU test) reuses them instead of compiling
    /// the kernels again, which takes tens of seconds under lavapipe.
    pub(super) compiled: std::sync::Mutex<CompiledPipelines>,
}

/// What a call of [`super::compute::pipeline`] compiles from: the source, its entry points and the buffers'
/// layout (bindings, uniform ones, writable ones).
pub(super) type PipelineKey = (String, Vec<String>, u32, Vec<u32>, Vec<u32>);

/// Pipelines compiled on a device, by what they were compiled from.
pub(super) type CompiledPipelines =
    std::collections::HashMap<PipelineKey, (wgpu::BindGroupLayout, Vec<wgpu::ComputePipeline>)>;

/// Text of the error when no adapter exists, with how to get one.
pub const INSTALL_HINT: &str = "install Mesa's lavapipe (Debian/Ubuntu: `apt-get install -y mesa-vulkan-drivers libvulkan1`) \
     or a GPU driver with Vulkan; tests skip the GPU only when RADIOSITY_GPU=skip is set";

fn rank(info: &wgpu::AdapterInfo) -> u32 {
    let kind = match info.device_type {
        wgpu::DeviceType::DiscreteGpu => 0,
        wgpu::DeviceType::IntegratedGpu => 1,
        wgpu::DeviceType::VirtualGpu => 2,
        wgpu::DeviceType::Cpu => 3,
        wgpu::DeviceType::Other => 4,
    };
    let backend = if info.backend == wgpu::Backend::Vulkan { 0 } else { 1 };
    kind * 2 + backend
}

impl GpuContext {
    /// The largest buffer one binding may hold: what any kernel's buffer must stay within.
    pub fn max_binding(&self) -> u64 {
        self.limits.max_storage_buffer_binding_size.min(self.limits.max_buffer_size)
    }

    /// Picks an adapter and creates the device; fails with [`Error::Gpu`] when none fits.
    pub fn new(request: &AdapterRequest) -> Result<Self> {
        pollster::block_on(Self::new_async(request))
    }

    async fn new_async(request: &AdapterRequest) -> Result<Self> {
        let instance = wgpu::Instance::new(wgpu::InstanceDescriptor::new_without_display_handle());
        let name = request
            .name
            .clone()
            .or_else(|| std::env::var("RADIOSITY_GPU_ADAPTER").ok())
            .map(|n| n.to_lowercase());
        let mut adapters = instance.enumerate_adapters(wgpu::Backends::all()).await;
        if adapters.is_empty() {
            return Err(Error::Gpu(format!("no GPU adapter found; {INSTALL_HINT}")));
        }
        let all: Vec<String> = adapters
            .iter()
            .map(|a| format!("{} ({:?})", a.get_info().name, a.get_info().backend))
            .collect();
        adapters.retain(|a| {
            let info = a.get_info();
            let named = name.as_ref().is_none_or(|n| info.name.to_lowercase().contains(n));
            let f64_ok = !request.require_f64 || a.features().contains(wgpu::Features::SHADER_F64);
            named && f64_ok
        });
        adapters.sort_by_key(|a| rank(&a.get_info()));
        let Some(adapter) = adapters.into_iter().next() else {
            return Err(Error::Gpu(format!(
                "no adapter fits (name filter {:?}, f64 required: {}); adapters found: {}",
                name,
                request.require_f64,
                all.join(", ")
            )));
        };
        let info = adapter.get_info();
        let has_f64 = adapter.features().contains(wgpu::Features::SHADER_F64);
        let limits = adapter.limits();
        let required_features =
            if has_f64 { wgpu::Features::SHADER_F64 } else { wgpu::Features::empty() };
        let (device, queue) = adapter
            .request_device(&wgpu::DeviceDescriptor {
                label: Some("radiosity"),
                required_features,
                required_limits: limits.clone(),
                experimental_features: wgpu::ExperimentalFeatures::default(),
                memory_hints: wgpu::MemoryHints::Performance,
                trace: wgpu::Trace::Off,
            })
            .await
            .map_err(|e| Error::Gpu(format!("could not open a device on '{}': {e}", info.name)))?;
        Ok(Self {
            device,
            queue,
            adapter: AdapterSummary {
                name: info.name.clone(),
                backend: format!("{:?}", info.backend),
                device_type: format!("{:?}", info.device_type),
                f64: has_f64,
                driver: format!("{}, {}", info.driver, info.driver_info),
            },
            limits,
            compiled: Default::default(),
        })
    }
}
