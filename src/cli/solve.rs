//! `radiosity solve`: one run, its outputs (VTU, CSV, PNG) and its summary.

use radiosity::error::Result;
use radiosity::pipeline::{self, RunReport};
use radiosity::report;

use super::args::{OutputArgs, SolveArgs, parse_point, parse_size};
use super::ranks::is_root;

pub(crate) fn write_outputs(
    run: &pipeline::Run,
    out: &OutputArgs,
    picture: (glam::DVec3, report::Tone),
) -> Result<()> {
    let field = run.field();
    if let Some(path) = &out.vtu {
        report::write_vtu(&field, std::path::Path::new(path))?;
    }
    if let Some(path) = &out.csv {
        report::write_node_csv(&field, std::path::Path::new(path))?;
    }
    if let Some(path) = &out.png {
        let size = parse_size("png-size", &out.png_size)?;
        let mut camera = report::Camera::default_view(&field, picture.0);
        // The user gives points in their coordinates; the scene is drawn in its local frame.
        let origin = run.scene.origin;
        if let Some(t) = &out.target {
            camera.target = parse_point("target", t)? - origin;
        }
        if let Some(e) = &out.eye {
            camera.eye = parse_point("eye", e)? - origin;
        }
        let r = &run.report;
        let title = format!("{}: u, {} method, n = {}", r.label.surface, r.label.method, r.label.n);
        report::render_png(
            &field,
            &camera,
            size,
            (&title, "u"),
            picture.1,
            std::path::Path::new(path),
        )?;
    }
    Ok(())
}

pub(crate) fn print_run(r: &RunReport) {
    let alpha = r.label.alpha.map(|a| format!(", alpha = {a}")).unwrap_or_default();
    println!(
        "{} ({} mesh, {} method{alpha}): n = {}, dof = {}",
        r.label.surface, r.label.mesh, r.label.method, r.label.n, r.label.dof
    );
    if let Some(device) = &r.device {
        println!(
            "assembled on {device} in {} (kernels compiled in {:.3} s, not in the setup time)",
            r.label.precision, r.preparation_seconds
        );
    }
    if let Some(e) = r.error {
        println!("max error at the nodes E_n = {e:.6e}");
    }
    if let Some(s) = &r.over_surface {
        println!(
            "max error over S ({} points): u_n {:.6e}, iterated solution E + K u_n {:.6e}",
            s.points, s.interpolant, s.iterated
        );
    }
    let of = match (r.bands.is_empty(), r.cases.is_empty()) {
        (false, _) => " (mean of the bands)",
        (_, false) => " (mean of the cases)",
        _ => "",
    };
    println!(
        "solution at the nodes{of}: min {:.6}, mean {:.6}, max {:.6}",
        r.solution_range[0], r.solution_range[1], r.solution_range[2]
    );
    for b in &r.bands {
        let [lo, mean, hi] = b.solution_range;
        println!(
            "band {}: min {lo:.6}, mean {mean:.6}, max {hi:.6}; solve {:.3} s ({}, {} iterations, \
             relative residual {:.1e})",
            b.band, b.solve_seconds, b.solver, b.iterations, b.residual
        );
    }
    for c in &r.cases {
        let [lo, mean, hi] = c.solution_range;
        println!(
            "case {}: min {lo:.6}, mean {mean:.6}, max {hi:.6} ({}, {} iterations, relative \
             residual {:.1e})",
            c.case, c.solver, c.iterations, c.residual
        );
    }
    let mut iterations = match r.condition_estimate {
        Some(k) => format!(", condition ~{k:.1e}, {} refinement steps", r.refinement_steps),
        None => format!(", {} iterations", r.iterations),
    };
    if r.rows_eliminated > 0 {
        iterations += &format!(
            ", {} unknowns known as u = E (rho = 0 or nothing in view)",
            r.rows_eliminated
        );
    }
    println!(
        "setup {:.3} s, emissivity {:.3} s, solve {:.3} s ({}{iterations}, relative residual {:.1e})",
        r.setup_seconds, r.emission_seconds, r.solve_seconds, r.solver, r.residual
    );
    if let Some(t) = &r.transfers {
        print_transfers(t);
    }
    let p = &r.pairs;
    println!(
        "pairs: {} total, {} skipped, {} full, {} partial",
        p.total,
        p.skipped(),
        p.full,
        p.partial
    );
}

/// Where K assembled on the GPU was kept, what crossed, and what its storage did to it.
fn print_transfers(t: &pipeline::DeviceTransfers) {
    let kept = match t.operator_location {
        "device" => "kept in the GPU's memory",
        _ => "read back to the host",
    };
    let mb = |bytes: u64| bytes as f64 / 1e6;
    println!(
        "operator {kept}: {:.2} MB uploaded, {:.2} MB read back, {} submissions; the device \
         idle at most {:.0} % of setup and solve",
        mb(t.bytes_uploaded),
        mb(t.bytes_read_back),
        t.gpu_submissions,
        100.0 * t.device_idle_fraction
    );
    if let Some(s) = t.storage.filter(|s| s.storage == radiosity::gpu::Precision::F32) {
        let bound = match s.solution_bound {
            Some(b) => format!("u within {b:.1e} (relative) of u with K stored in f64"),
            None => "no bound on u (||K|| >= 1)".into(),
        };
        println!(
            "stored in f32: ||K - fl(K)|| / ||K|| = {:.1e} (max norm, measured); {bound}",
            s.matrix
        );
    }
}

/// Solves, writes the outputs asked for, and prints the summary (or JSON).
pub(crate) fn run(args: &SolveArgs) -> Result<()> {
    let config = args.config()?;
    // Checked before the solve, which may take long.
    let picture = (args.colour.up(&config.scene)?, args.colour.tone);
    let run = pipeline::run_keeping_mesh(&config)?;
    // Every rank of a distributed run holds the solution; rank 0 writes and prints it.
    if !is_root() {
        return Ok(());
    }
    write_outputs(&run, &args.outputs, picture)?;
    let r = &run.report;
    for note in &r.notes {
        eprintln!("note: {note}");
    }
    for w in &r.warnings {
        eprintln!("warning: {w}");
    }
    match &args.json {
        Some(target) => report::write_json(&r, target),
        None => {
            print_run(r);
            Ok(())
        }
    }
}
