//! Which operator is stored, how it is compressed, and the memory the run may hold:
//! `OperatorArgs`.

use clap::Args;
use radiosity::operator::{OperatorChoice, ShadowedBlocks};
use radiosity::pipeline::RunOptions;

use super::named::named;

/// Which operator to store, and how to compress it.
#[derive(Args)]
pub(crate) struct OperatorArgs {
    /// Operator (auto: compressed above 12 000 unknowns)
    #[arg(
        long,
        value_parser = named::<OperatorChoice>(),
        default_value_t = RunOptions::default().operator
    )]
    pub(crate) operator: OperatorChoice,
    /// Relative error of each low-rank block of the compressed operator, in (0, 1): its cross
    /// approximation's, and half as much again from its recompression
    #[arg(long, value_name = "T", default_value_t = RunOptions::default().compression_tolerance)]
    pub(crate) compression_tolerance: f64,
    /// Compress the blocks that occluders or tangent planes cut once, without occlusion, and
    /// keep only their partly visible pairs exact: less memory and setup where faces hold many
    /// elements [default: where they hold at least 512 on average]
    #[arg(long, conflicts_with = "no_shadowed_blocks")]
    pub(crate) shadowed_blocks: bool,
    /// Never make shadowed blocks: split the blocks that occluders or tangent planes cut down
    /// to exact leaves and low-rank blocks
    #[arg(long)]
    pub(crate) no_shadowed_blocks: bool,
    /// Most memory the run may hold resident (bytes, or with K, M, G or T: powers of 1024); a
    /// matrix that would pass it is refused before it is built, a compressed operator before
    /// its build where the estimate of its peak (from a sample of its blocks) cannot fit, or
    /// else where its build reaches it [default: 80 % of the available memory for each large
    /// structure]
    #[arg(long, value_name = "BYTES", value_parser = radiosity::assembly::parse_size)]
    pub(crate) memory_limit: Option<u64>,
}

impl OperatorArgs {
    /// The operator's options, into `options`.
    pub(crate) fn fill(&self, options: &mut RunOptions) {
        options.operator = self.operator;
        options.compression_tolerance = self.compression_tolerance;
        options.shadowed_blocks = match (self.shadowed_blocks, self.no_shadowed_blocks) {
            (true, _) => ShadowedBlocks::On,
            (_, true) => ShadowedBlocks::Off,
            _ => ShadowedBlocks::Auto,
        };
        options.memory_limit = self.memory_limit;
    }
}
