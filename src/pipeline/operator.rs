//! Building the operator a run solves with, of the kind [`operator_kind`] decides: the dense
//! matrix timed over repeated assemblies, kept on the GPU, or compressed; or read from a file.

use std::time::Instant;

use super::choice::{OperatorKind, check_distributed, check_saved, operator_kind};
use super::device::{assemble_on_device, blocks_on_device};
use super::saved::load_operator;
use super::{Assembler, BuiltOperator, Problem, REPEAT_BELOW_SECONDS, RunConfig, TimedAssembly};
use crate::assembly::PairEvaluation;
use crate::error::{Error, Result};
use crate::gpu;
use crate::operator::{CompressedOperator, CompressionOptions};
use crate::solve;

/// Assembles K for `config` up to `config.setup_repeats` times (fewer once one assembly takes over
/// [`REPEAT_BELOW_SECONDS`]) with the backend `assembler`, prepared in `preparation_seconds`;
/// the setup time is the pair planner's plus the fastest assembly's.
fn assemble_timed(
    config: &RunConfig,
    problem: &Problem,
    assembler: &Assembler,
    preparation_seconds: f64,
) -> Result<TimedAssembly> {
    let progress = &*config.progress;
    let mut timed = None;
    let mut fastest = f64::INFINITY;
    for _ in 0..config.setup_repeats.max(1) {
        progress.start("assembly", problem.disc.dof());
        let started = Instant::now();
        let assembled = assembler.assemble(problem, &config.assembly, progress)?;
        let seconds = started.elapsed().as_secs_f64();
        fastest = fastest.min(seconds);
        timed = Some(assembled);
        progress.finish();
        if seconds > REPEAT_BELOW_SECONDS {
            break;
        }
    }
    let assembled = timed.expect("at least one assembly");
    let setup_seconds = problem.plan_seconds + fastest;
    let (device, gpu) = (assembler.device(), assembler.last_timings());
    Ok(TimedAssembly { assembled, device, gpu, setup_seconds, preparation_seconds })
}

/// The operator of the kind [`operator_kind`] decides for `config` and `problem` (its setup
/// time includes the pair planner's), or the one saved in `config.operator_file`.
pub fn build_operator(config: &RunConfig, problem: &Problem) -> Result<BuiltOperator> {
    if let Some(path) = &config.operator_file {
        check_saved(config)?;
        return load_operator(path, config, problem);
    }
    let kind = operator_kind(config, problem)?;
    // The run's backend, prepared once (on the GPU: its kernels compiled) for whichever build.
    let started = Instant::now();
    let assembler =
        Assembler::new(config.backend, problem.disc.method, config.assembly.quadrature)?;
    let preparation_seconds = started.elapsed().as_secs_f64();
    let dense = || assemble_timed(config, problem, &assembler, preparation_seconds);
    match kind {
        OperatorKind::DenseOnDevice => {
            match assemble_on_device(config, problem, &assembler, preparation_seconds) {
                Ok(built) => Ok(built),
                Err(e) => {
                    config.progress.note(&format!(
                        "the matrix is kept on the host in f64 ({e}); the products run there"
                    ));
                    Ok(BuiltOperator::Dense(dense()?))
                }
            }
        }
        OperatorKind::Dense => Ok(BuiltOperator::Dense(dense()?)),
        OperatorKind::Compressed => {
            let started = Instant::now();
            let (op, build_traffic) = build_compressed(config, &assembler, problem)?;
            let setup_seconds = problem.plan_seconds + started.elapsed().as_secs_f64();
            let on_device = blocks_on_device(config, &op);
            Ok(BuiltOperator::Compressed {
                op: Box::new(op),
                on_device,
                build_traffic,
                setup_seconds,
                preparation_seconds,
            })
        }
    }
}

/// The compressed operator of `config` for `problem`, its entries evaluated by `assembler` (the
/// CPU, or the GPU's pair kernel in batches, with what crossed to the GPU and back and how many
/// batches were submitted); refused where the configuration needs the dense matrix (LU).
pub fn build_compressed(
    config: &RunConfig,
    assembler: &Assembler,
    problem: &Problem,
) -> Result<(CompressedOperator, Option<gpu::DeviceTraffic>)> {
    if config.solver.choice == solve::SolverChoice::Lu {
        return Err(Error::InvalidParameter {
            name: "solver",
            value: solve::SolverChoice::Lu.name().into(),
            reason: "LU needs the dense matrix; the compressed operator is solved by GMRES \
                     (the iterative solver), or choose the dense operator"
                .into(),
        });
    }
    if let Some(ranks) = &config.ranks {
        check_distributed(config, ranks.size())?;
    }
    let Problem { scene, disc, .. } = problem;
    let device = match assembler {
        Assembler::Cpu => None,
        Assembler::Gpu(g) => Some(gpu::PairEvaluator::new(g, scene, disc, &config.assembly)?),
    };
    let batches = device.as_ref().map(|d| d as &dyn PairEvaluation);
    // The mesh's level, for the advice of a refusal for memory.
    let compression = &CompressionOptions { refine: Some(config.refine), ..config.compression };
    let (assembly, progress) = (&config.assembly, &*config.progress);
    let mut op = match &config.ranks {
        Some(ranks) => CompressedOperator::build_shared(
            problem,
            assembly,
            compression,
            batches,
            progress,
            ranks,
        )?,
        None => CompressedOperator::build(problem, assembly, compression, batches, progress)?,
    };
    op.device = assembler.device();
    Ok((op, device.map(|d| d.traffic())))
}
