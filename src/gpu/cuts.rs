//! What the host keeps of the device's clipping of the elements of faces seen in part
//! (shaders/clip.wgsl): its pipelines, and a tile's clipping in flight until it is collected
//! (`GpuAssembler::collect_cuts`).

use super::layout::{self, Params};
use crate::visibility::PairStats;

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
    /// The tile's cut records (without the last, which holds the pass's pair count).
    pub(super) records: Vec<u32>,
    /// Bytes one binding may hold.
    pub(super) max_binding: u64,
}

/// The pairs a clipping pass classified, by class, and how many it left to the host, from the
/// near list's header (u32 words).
pub(super) fn tallies(header: &[u32]) -> (PairStats, u64) {
    let [hidden, facing_away, full, partial, left] =
        std::array::from_fn(|k| u64::from(header[layout::CUT_TALLY_INDEX + k]));
    let total = hidden + facing_away + full + partial;
    let stats = PairStats { hidden, facing_away, full, partial, total, ..Default::default() };
    (stats, left)
}
