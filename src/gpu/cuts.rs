//! What the host keeps of the device's clipping of the elements of faces seen in part
//! (shaders/clip.wgsl): its pipelines, and a tile's clipping in flight until it is collected
//! (`GpuAssembler::collect_cuts`).

use super::layout::Params;

/// The clipping kernels: `assemble_cuts` over every pair of the faces seen in part,
/// `prepare_deep_cuts` and `assemble_deep_cuts` over those a shadow cuts, which the first lists.
pub(super) struct CutPipelines {
    pub(super) cuts: wgpu::ComputePipeline,
    pub(super) prepare_deep: wgpu::ComputePipeline,
    pub(super) deep: wgpu::ComputePipeline,
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
