//! Compute passes as the GPU's assembly records them: one over a grid of workgroups, and one
//! over the pairs an earlier pass listed (an indirect dispatch whose size the device wrote).

/// A pass over the pairs an earlier pass listed: `prepare` (one invocation) writes its dispatch
/// arguments into the list `near` at `arguments_at`, whence they are copied to `args`, which
/// drives `pass` (a buffer bound read-write cannot also drive the dispatch that binds it).
pub(super) struct Listed<'p> {
    pub(super) prepare: &'p wgpu::ComputePipeline,
    pub(super) pass: &'p wgpu::ComputePipeline,
    pub(super) arguments_at: u64,
    pub(super) near: &'p wgpu::Buffer,
    pub(super) args: &'p wgpu::Buffer,
}

/// `first` over a grid of workgroups, then, where given, the pass over the pairs it listed.
pub(super) fn encode_listed(
    encoder: &mut wgpu::CommandEncoder,
    group: &wgpu::BindGroup,
    first: &wgpu::ComputePipeline,
    grid: (u32, u32),
    listed: Option<Listed>,
) {
    dispatch(encoder, first, group, grid);
    let Some(Listed { prepare, pass, arguments_at, near, args }) = listed else { return };
    dispatch(encoder, prepare, group, (1, 1));
    encoder.copy_buffer_to_buffer(near, arguments_at, args, 0, 12);
    let mut compute = encoder.begin_compute_pass(&Default::default());
    compute.set_pipeline(pass);
    compute.set_bind_group(0, group, &[]);
    compute.dispatch_workgroups_indirect(args, 0);
}

/// One compute pass of `pipeline` over a grid of (x, y) workgroups.
pub(super) fn dispatch(
    encoder: &mut wgpu::CommandEncoder,
    pipeline: &wgpu::ComputePipeline,
    group: &wgpu::BindGroup,
    (x, y): (u32, u32),
) {
    let mut pass = encoder.begin_compute_pass(&Default::default());
    pass.set_pipeline(pipeline);
    pass.set_bind_group(0, group, &[]);
    pass.dispatch_workgroups(x, y, 1);
}
