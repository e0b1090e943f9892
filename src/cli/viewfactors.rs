//! `radiosity viewfactors`: element view factors, reciprocity and closure.

use radiosity::error::{Error, Result};
use radiosity::mesh::Mesh;
use radiosity::pipeline::{self, Problem};
use radiosity::report;
use radiosity::scene::Scene;
use radiosity::viewfactors::{
    ClosureOptions, MAX_SPLITS, ViewFactorOptions, ViewFactorSummary, ViewFactors, view_factors,
};

use super::args::ViewFactorArgs;

/// The smallest tolerance f64 arithmetic can meet on an entry F_ij (about 64 ulp of 1).
const ROUNDING_FLOOR: f64 = 1e-14;

pub(crate) fn run_viewfactors(args: &ViewFactorArgs) -> Result<()> {
    let options = ViewFactorOptions {
        tolerance: args.tolerance,
        max_depth: args.max_depth,
        each_direction: args.each_direction,
        ..Default::default()
    };
    options.validate()?;
    let closure = ClosureOptions { condition: args.condition, drop_below: args.drop_below };
    closure.validate()?;
    if args.tolerance < ROUNDING_FLOOR {
        // Rounding in the closed forms and the sums of a pair's cells alone is about this: the
        // adaptive rule would split every cell to the limit and still miss it.
        eprintln!(
            "warning: --tolerance {:.1e} is below what f64 arithmetic delivers for a view factor \
             (about {ROUNDING_FLOOR:.0e}): every cell will be split to the limit ({MAX_SPLITS} \
             rounds), which takes long, and the estimates will still exceed it",
            args.tolerance
        );
    }
    let config = args.scene.config()?;
    let problem = pipeline::build(&config)?;
    let Problem { scene, mesh, planner, .. } = &problem;
    super::output::print_notes(scene);
    let started = std::time::Instant::now();
    let progress = super::progress::on_stderr();
    progress.start("viewfactors", mesh.len());
    let mut f = view_factors(scene, mesh, planner, &options, &*progress)?;
    progress.finish();
    let closure = f.close(&closure)?;
    let mut summary =
        f.summary(&scene.name, problem.plan_seconds + started.elapsed().as_secs_f64());
    summary.closure = closure;
    if summary.error_estimate > args.tolerance {
        // Cells deeper than the split limit are settled with the error they have.
        eprintln!(
            "warning: the largest estimated error of an entry, {:.1e}, exceeds --tolerance {:.1e}: \
             outer patches reached the split limit ({MAX_SPLITS} rounds) before their \
             estimates met it",
            summary.error_estimate, args.tolerance
        );
    }
    let sky = f.sky_view_factors();
    if let Some(path) = &args.output {
        write_matrix(path, &f, &sky, &scene.name)?;
    }
    if let Some(path) = &args.sky_view_factors {
        write_sky_view_factors(path, &sky, &f.areas, mesh, scene)?;
    }
    if let Some(target) = &args.json {
        return report::write_json(&summary, target);
    }
    print_summary(&summary, &f, scene, mesh);
    Ok(())
}

/// F as a NumPy file (`.npy`) or as CSV (`.csv`), one row per element, or only its non-zero
/// entries: SciPy's sparse CSR (`.npz`, `scipy.sparse.load_npz`, with the `sky` view factors
/// beside it) or Matrix Market (`.mtx`).
fn write_matrix(path: &str, f: &ViewFactors, sky: &[f64], surface: &str) -> Result<()> {
    let sparse = report::CsrRows::of_view_factors(f);
    if path.ends_with(".npz") {
        report::write_npz(path, sparse, &[("sky_view_factors", sky)])?;
    } else if path.ends_with(".mtx") {
        report::write_mtx(path, sparse, &format!("view factors F_ij of {surface}, row i"))?;
    } else if path.ends_with(".npy") {
        report::write_npy(path, f.len(), &f.to_dense())?;
    } else if path.ends_with(".csv") {
        let text: String = f
            .to_dense()
            .chunks(f.len())
            .map(|row| row.iter().map(|v| format!("{v:e}")).collect::<Vec<_>>().join(",") + "\n")
            .collect();
        std::fs::write(path, text)?;
    } else {
        return Err(Error::InvalidParameter {
            name: "output",
            value: path.to_string(),
            reason: "expected a .npy, .csv, .npz (sparse CSR) or .mtx (Matrix Market) file".into(),
        });
    }
    Ok(())
}

/// Each element's sky view factor as CSV (element, face, area, sky_view_factor) or NumPy.
fn write_sky_view_factors(
    path: &str,
    sky: &[f64],
    areas: &[f64],
    mesh: &Mesh,
    scene: &Scene,
) -> Result<()> {
    if path.ends_with(".npy") {
        return report::write_npy_vector(path, sky);
    }
    if !path.ends_with(".csv") {
        return Err(Error::InvalidParameter {
            name: "sky-view-factors",
            value: path.to_string(),
            reason: "expected a .csv or .npy file".into(),
        });
    }
    let mut text = String::from("element,face,area,sky_view_factor\n");
    for (i, e) in mesh.elements().iter().enumerate() {
        let face = &scene.faces[e.face].name;
        text.push_str(&format!("{i},{face},{:e},{:e}\n", areas[i], sky[i]));
    }
    std::fs::write(path, text)?;
    Ok(())
}

/// The summary as text, and the face-to-face view factors of scenes of at most 12 faces.
fn print_summary(summary: &ViewFactorSummary, f: &ViewFactors, scene: &Scene, mesh: &Mesh) {
    println!("{}: n = {} elements, {:.2} s", summary.surface, summary.n, summary.seconds);
    println!("row sums of F: min {:.15}, max {:.15}", summary.row_sum_min, summary.row_sum_max);
    if summary.each_direction {
        println!(
            "reciprocity: max |A_i F_ij - A_j F_ji| / max A_i F_ij = {:.2e}; quadrature error estimate {:.2e}",
            summary.reciprocity_error, summary.error_estimate
        );
    } else {
        println!(
            "quadrature error estimate {:.2e}; reciprocity by construction (each pair integrated \
             once, over the smaller element; --each-direction integrates both to check it)",
            summary.error_estimate
        );
    }
    println!(
        "sky view factors (1 - row sum): min {:.15}, max {:.15}",
        summary.sky_view_factor_min, summary.sky_view_factor_max
    );
    if let Some(c) = &summary.closure.conditioning {
        println!(
            "conditioned: reciprocity exact, {} rows scaled to 1; largest change of an entry \
             {:.2e} (estimate {:.2e})",
            c.rows_scaled, c.largest_change, summary.error_estimate
        );
    }
    if let Some(d) = &summary.closure.dropped {
        println!(
            "dropped {} entries below {:e} (both directions); largest row sum dropped {:.2e}, \
             counted as sky",
            d.entries, d.below, d.largest_row_sum
        );
    }
    if scene.faces.len() <= 12 {
        println!("face-to-face view factors (row: from):");
        for (a, row) in f.by_face(mesh).iter().enumerate() {
            let cells: Vec<String> = row.iter().map(|v| format!("{v:.10}")).collect();
            println!("  {:>12} {}", scene.faces[a].name, cells.join(" "));
        }
    }
}
