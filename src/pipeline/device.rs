//! Operators kept in the GPU's memory: the dense K assembled there, and the compressed
//! operator's blocks uploaded for GMRES's products.

use std::time::Instant;

use super::{Assembler, Backend, BuiltOperator, Problem, RunConfig};
use crate::error::{Error, Result};
use crate::gpu::{self, DeviceBlocks, DeviceOperator};
use crate::operator::CompressedOperator;

/// K assembled on the GPU by `assembler` (prepared in `preparation_seconds`) and left in its
/// memory.
pub(super) fn assemble_on_device(
    config: &RunConfig,
    problem: &Problem,
    assembler: &Assembler,
    preparation_seconds: f64,
) -> Result<BuiltOperator> {
    let Assembler::Gpu(gpu) = assembler else {
        unreachable!("a GPU backend gives the GPU's assembler")
    };
    let started = Instant::now();
    let (options, progress) = (&config.assembly, &*config.progress);
    let op = Box::new(DeviceOperator::assemble(gpu, problem, options, config.storage, progress)?);
    let setup_seconds = problem.plan_seconds + started.elapsed().as_secs_f64();
    Ok(BuiltOperator::Device { op, device: assembler.device(), setup_seconds, preparation_seconds })
}

/// The compressed operator's blocks uploaded to the GPU for GMRES's products, where the run is
/// on the GPU in f64 in one process; `None`, with a note saying why, where they cannot go there.
pub(super) fn blocks_on_device(
    config: &RunConfig,
    op: &CompressedOperator,
) -> Option<Box<DeviceBlocks>> {
    if config.backend != Backend::Gpu(gpu::Precision::F64) || config.ranks.is_some() {
        return None;
    }
    let uploaded = compressed_on_device(op, None).map_err(|e| e.to_string());
    match uploaded {
        Ok(blocks) => Some(Box::new(blocks)),
        Err(why) => {
            config.progress.note(&format!(
                "the compressed operator stays on the host ({why}); its products run there"
            ));
            None
        }
    }
}

/// The blocks of `op` uploaded to the GPU (f64) for its products there, in as many parts as
/// the device's largest binding asks for, or parts of at most `max_binding` bytes where given
/// (tests split small operators so).
pub fn compressed_on_device(
    op: &CompressedOperator,
    max_binding: Option<u64>,
) -> Result<DeviceBlocks> {
    let ctx = gpu::context_for(gpu::Precision::F64)?;
    let max_binding = max_binding.unwrap_or_else(|| ctx.max_binding());
    let parts = op.packed_parts(max_binding).ok_or_else(|| {
        Error::Gpu(format!(
            "the compressed operator is distributed, a block passes the binding limit of \
             {max_binding} bytes, or an offset passes u32"
        ))
    })?;
    let arrays: Vec<gpu::BlockArrays> = parts
        .iter()
        .map(|p| gpu::BlockArrays {
            blocks: p.blocks,
            low_rank: p.low_rank,
            values: &p.values,
            indices: &p.indices,
            low_rank_at: p.low_rank_at,
            row_starts_at: p.row_starts_at,
            contributions_at: p.contributions_at,
            scratch: p.scratch,
        })
        .collect();
    let orders = (op.per_element(), op.node_order(), op.element_order());
    DeviceBlocks::upload(ctx, op.dof(), orders, &arrays)
}
