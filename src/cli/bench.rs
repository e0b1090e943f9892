//! `radiosity bench`: the same matrix on each backend, timed and compared.

use radiosity::error::{Error, Result};
use radiosity::operator::OperatorChoice;
use radiosity::pipeline::{self, Backend, BackendName};
use radiosity::report;

use super::args::BenchArgs;
use super::ranks::is_root;

pub(crate) fn run_bench(args: &BenchArgs) -> Result<()> {
    let mut options = args.geometry.options()?;
    args.operator.fill(&mut options);
    let mut config = args.geometry.scene.config_of(&options)?;
    config.progress = radiosity::progress::ProgressSink::default();
    let backends = match &args.backends {
        Some(named) => {
            let mut backends: Vec<Backend> = Vec::new();
            for &b in named {
                let b = Backend::named(b, args.precision);
                if backends.iter().any(|x| x.name() == b.name()) {
                    return Err(Error::InvalidParameter {
                        name: "backends",
                        value: b.name().into(),
                        reason: "each backend may be named once".into(),
                    });
                }
                backends.push(b);
            }
            backends
        }
        // Under mpirun the ranks build on their CPUs.
        None if config.ranks.is_some() => vec![Backend::Cpu],
        None => {
            let mut notes = Vec::new();
            let backends = pipeline::cpu_and_found_gpus(&[args.precision], &mut notes);
            notes.iter().for_each(|note| eprintln!("note: {note}"));
            backends
        }
    };
    let built = pipeline::build(&config)?;
    // Under auto only a CPU-only bench of a large system switches to the compressed operator;
    // asked for, it is built on each named backend and benched against the dense CPU assembly.
    let gpu_named = backends.iter().any(|b| *b != Backend::Cpu);
    let compressed_bench = match config.operator {
        OperatorChoice::Compressed => true,
        OperatorChoice::Auto => {
            !gpu_named
                && pipeline::operator_kind(&config, &built)? == pipeline::OperatorKind::Compressed
        }
        OperatorChoice::Dense => false,
    };
    if compressed_bench {
        return compressed(&config, &built, &backends, args);
    }
    if config.ranks.is_some() {
        return Err(Error::InvalidParameter {
            name: "operator",
            value: OperatorChoice::Dense.name().into(),
            reason: "under mpirun, bench times the compressed operator on the CPU: give \
                     --operator compressed --backends cpu"
                .into(),
        });
    }
    let r = radiosity::bench::run(&config, &built, &backends, args.repeats)?;
    if let Some(target) = &args.json {
        return report::write_json(&r, target);
    }
    println!(
        "{} ({} mesh, {} method): n = {}, dof = {}, {} pairs ({} evaluated)",
        r.scene, r.mesh, r.method, r.n, r.dof, r.pairs, r.pairs_evaluated
    );
    for (name, t) in [(BackendName::Cpu, &r.cpu), (BackendName::Gpu, &r.gpu)] {
        if let Some(t) = t {
            println!(
                "{name} ({}): setup {:.3} s, {:.3e} pairs/s (preparation {:.3} s, best of {})",
                t.precision, t.setup_seconds, t.pairs_per_second, t.preparation_seconds, r.repeats
            );
            if let Some(b) = &t.breakdown {
                println!(
                    "    {} tiles: host planning {:.3} s, waiting for the device {:.3} s, read-back {:.3} s \
                     ({:.2} GB/s)",
                    b.tiles,
                    b.planning_seconds,
                    b.device_wait_seconds,
                    b.readback_seconds,
                    b.read_back_gb_per_second
                );
                println!(
                    "    pairs of faces seen in part clipped on the device {}, on the host {}",
                    b.pairs_clipped_on_device, b.pairs_clipped_on_host
                );
            }
        }
    }
    if let Some(d) = &r.device {
        println!("device: {d}");
    }
    if let (Some(s), Some(a), Some(rel), Some(norm)) =
        (r.speedup, r.max_abs_diff, r.max_rel_diff, r.max_row_norm_rel_diff)
    {
        println!(
            "speedup (cpu time / gpu time): {s:.2}; max |difference| {a:.2e}, relative to the \
             row's largest entry {rel:.2e}, to the row's 1-norm {norm:.2e}"
        );
    }
    if let Some(share) = r.host_share {
        println!("host share (the GPU path's host planning / the CPU's setup): {share:.2}");
    }
    Ok(())
}

/// `bench` of the compressed operator against the dense CPU assembly.
fn compressed(
    config: &radiosity::pipeline::RunConfig,
    built: &pipeline::Problem,
    backends: &[Backend],
    args: &BenchArgs,
) -> Result<()> {
    if config.ranks.is_some() && backends.iter().any(|&b| b != Backend::Cpu) {
        return Err(Error::InvalidParameter {
            name: "backends",
            value: BackendName::Gpu.name().into(),
            reason: "under mpirun, bench builds on the CPU: give --backends cpu".into(),
        });
    }
    let r = radiosity::bench::run_compressed(config, built, backends, args.repeats)?;
    // Every rank took part; rank 0 prints.
    if !is_root() {
        return Ok(());
    }
    if let Some(target) = &args.json {
        return report::write_json(&r, target);
    }
    println!("{} ({} method): n = {}, dof = {}", r.scene, r.method, r.n, r.dof);
    println!(
        "compressed on the {} (tolerance {:.0e}): setup {:.3} s (best of {}), {:.1} MB, {} exact \
         and {} low-rank blocks (rank <= {})",
        r.backend,
        r.compression_tolerance,
        r.setup_seconds,
        r.repeats,
        r.operator_bytes as f64 / 1e6,
        r.blocks.near_blocks,
        r.blocks.far_blocks,
        r.blocks.max_rank
    );
    match (r.dense_setup_seconds, r.speedup, r.max_product_rel_diff) {
        (Some(d), Some(s), Some(diff)) => println!(
            "dense: setup {d:.3} s; speedup (dense / compressed) {s:.2}; products differ by \
             {diff:.2e} (relative)"
        ),
        _ => {
            println!("dense: not assembled above {} unknowns", radiosity::bench::DENSE_BENCH_LIMIT)
        }
    }
    if let Some(g) = &r.gpu {
        println!(
            "compressed on the gpu ({}, {}): setup {:.3} s in {} submissions ({:.3} s waiting \
             for the device); speedup (cpu / gpu) {:.2}; products differ from the cpu's by \
             {:.2e} (relative)",
            g.device.as_deref().unwrap_or("?"),
            g.precision,
            g.setup_seconds,
            g.gpu_submissions,
            g.device_wait_seconds,
            g.speedup,
            g.max_product_rel_diff
        );
        println!(
            "    exact blocks' pairs of faces seen in part clipped on the device {}, on the host \
             {}; pair classes {} the cpu's",
            g.pairs_clipped_on_device,
            g.pairs_clipped_on_host,
            if g.same_pair_classes { "equal to" } else { "differ from" }
        );
    }
    Ok(())
}
