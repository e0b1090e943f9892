//! `radiosity inspect`: row sums of K/rho and pair classes.

use serde::Serialize;

use radiosity::error::{Error, Result};
use radiosity::pipeline::{self, Problem};
use radiosity::report;

use super::args::SolveArgs;

/// What `inspect` prints.
#[derive(Serialize)]
pub(crate) struct Inspection {
    surface: String,
    mesh: &'static str,
    method: &'static str,
    alpha: Option<f64>,
    backend: &'static str,
    n: usize,
    dof: usize,
    row_sum_min: f64,
    row_sum_max: f64,
    pairs_total: u64,
    pairs_skipped: u64,
    pairs_full: u64,
    pairs_partial: u64,
    pairs_same_plane: u64,
    pairs_facing_away: u64,
    pairs_hidden: u64,
    occluders_possible: bool,
    setup_seconds: f64,
    operator: &'static str,
    compression_tolerance: Option<f64>,
    operator_bytes: u64,
    memory_estimate_bytes: Option<u64>,
    #[serde(flatten)]
    blocks: Option<radiosity::operator::OperatorStats>,
    peak_rss_bytes: Option<u64>,
    #[serde(flatten, skip_serializing_if = "Option::is_none")]
    distributed: Option<radiosity::distributed::DistributedReport>,
}

pub(crate) fn inspect(args: &SolveArgs) -> Result<()> {
    let o = &args.outputs;
    if o.vtu.is_some() || o.csv.is_some() || o.png.is_some() {
        return Err(Error::InvalidParameter {
            name: "vtu/csv/png",
            value: "given".into(),
            reason: "inspect solves nothing; the outputs belong to solve".into(),
        });
    }
    if !args.colour.channels()?.is_empty() {
        return Err(Error::InvalidParameter {
            name: "bands",
            value: args.colour.bands.clone(),
            reason: "inspect solves nothing; the colour bands belong to solve".into(),
        });
    }
    for (given, flag) in
        [(&args.emission_file, "emission-file"), (&args.operator_file, "operator-file")]
    {
        if let Some(value) = given {
            return Err(Error::InvalidParameter {
                name: flag,
                value: value.clone(),
                reason: format!(
                    "inspect builds its operator and solves nothing; --{flag} belongs to solve"
                ),
            });
        }
    }
    let config = args.config()?;
    let problem = pipeline::build(&config)?;
    let Problem { scene, mesh, disc, planner, .. } = &problem;
    super::output::print_notes(scene);
    // The operator `solve` would use, decided and built where `solve` builds it.
    let built = pipeline::build_operator(&config, &problem)?;
    let row_sums = built.apply(&vec![1.0; disc.dof()])?;
    let summary = built.summary(&config);
    let distributed = built.distributed_report();
    // Every rank of a distributed run holds the row sums; rank 0 prints them.
    if !super::ranks::is_root() {
        return Ok(());
    }
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for (node, sum) in disc.nodes().zip(&row_sums) {
        if node.rho > 0.0 {
            let s = sum / node.rho;
            lo = lo.min(s);
            hi = hi.max(s);
        }
    }
    let out = Inspection {
        surface: scene.name.clone(),
        mesh: config.mesh.name(),
        method: config.method.name(),
        alpha: config.method.alpha(),
        backend: config.backend.name(),
        n: mesh.len(),
        dof: disc.dof(),
        row_sum_min: lo,
        row_sum_max: hi,
        pairs_total: summary.pairs.total,
        pairs_skipped: summary.pairs.skipped(),
        pairs_full: summary.pairs.full,
        pairs_partial: summary.pairs.partial,
        pairs_same_plane: summary.pairs.same_plane,
        pairs_facing_away: summary.pairs.facing_away,
        pairs_hidden: summary.pairs.hidden,
        occluders_possible: planner.has_occlusion(),
        setup_seconds: summary.setup_seconds,
        operator: summary.operator,
        compression_tolerance: summary.compression_tolerance,
        operator_bytes: summary.operator_bytes,
        memory_estimate_bytes: summary.memory_estimate_bytes,
        blocks: summary.blocks,
        peak_rss_bytes: pipeline::peak_rss_bytes(),
        distributed,
    };
    match &args.json {
        Some(target) => report::write_json(&out, target),
        None => {
            print_inspection(&out, config.compression.tolerance);
            Ok(())
        }
    }
}

/// The inspection as text.
fn print_inspection(out: &Inspection, tolerance: f64) {
    println!(
        "{} ({} mesh, {} method): n = {}, dof = {}",
        out.surface, out.mesh, out.method, out.n, out.dof
    );
    println!("row sums of K/rho: min {:.15}, max {:.15}", out.row_sum_min, out.row_sum_max);
    println!(
        "pairs: {} total, {} skipped ({} same plane, {} facing away, {} hidden), {} full, {} partial",
        out.pairs_total,
        out.pairs_skipped,
        out.pairs_same_plane,
        out.pairs_facing_away,
        out.pairs_hidden,
        out.pairs_full,
        out.pairs_partial
    );
    if let Some(b) = &out.blocks {
        println!(
            "compressed operator (tolerance {:.0e}, values in {}): {:.1} MB ({:.1} MB of low-rank \
             factors); {} exact blocks ({} entries), {} low-rank blocks (standing for {} entries, \
             rank <= {}), {} empty blocks, {} admissible blocks kept exact{}; the exact blocks' \
             row walks viewed {:.0} faces per node ({:.1} of them finding nothing seen)",
            tolerance,
            radiosity::operator::precision_for(tolerance).name(),
            out.operator_bytes as f64 / 1e6,
            b.low_rank_bytes as f64 / 1e6,
            b.near_blocks,
            b.near_entries,
            b.far_blocks,
            b.far_entries,
            b.max_rank,
            b.empty_blocks,
            b.incompressible_blocks,
            match b.shadowed_blocks {
                0 => String::new(),
                k => format!(", {k} shadowed blocks"),
            },
            b.faces_viewed as f64 / out.dof.max(1) as f64,
            b.faces_viewed_unseen as f64 / out.dof.max(1) as f64
        );
    }
    println!("setup {:.3} s on the {}", out.setup_seconds, out.backend);
}
