//! Reports: plain-text tables for people, JSON for programs, plots and NumPy files.

mod nodes_csv;
pub mod plot;
mod render;
mod sparse;
mod study_figures;
mod vtk;

pub use nodes_csv::write_node_csv;
pub use render::{Camera, DEFAULT_VIEW, Tone, render_png};
pub use sparse::{CsrRows, write_mtx, write_npz};
pub use study_figures::write_study_figures;
pub use vtk::write_vtu;

use std::io::Write;
use std::path::Path;

use serde::Serialize;

use crate::error::Result;
use crate::study::{StudyResult, StudyRow};

/// Writes `value` as pretty JSON to `target` (`-` for standard output).
pub fn write_json<T: Serialize>(value: &T, target: &str) -> Result<()> {
    let text =
        serde_json::to_string_pretty(value).map_err(|e| std::io::Error::other(e.to_string()))?;
    if target == "-" {
        let mut out = std::io::stdout().lock();
        writeln!(out, "{text}")?;
    } else {
        std::fs::write(Path::new(target), text + "\n")?;
    }
    Ok(())
}

fn sci(v: f64) -> String {
    if v != 0.0 && (v.abs() < 1e-2 || v.abs() >= 1e3) {
        format!("{v:.3e}")
    } else {
        format!("{v:.4}")
    }
}

/// Seconds to three significant digits.
fn seconds(t: f64) -> String {
    if t < 0.01 { format!("{t:.2e}") } else { format!("{t:.3}") }
}

/// A column of the study table: header, and the cell of a row (`None`: empty).
type Column = (&'static str, fn(&StudyRow) -> Option<String>);

const COLUMNS: [Column; 14] = [
    ("n", |r| Some(r.label.n.to_string())),
    ("dof", |r| Some(r.label.dof.to_string())),
    ("E_n", |r| Some(sci(r.error))),
    ("ratio", |r| r.ratio.map(|x| format!("{x:.2}"))),
    ("paper E_n", |r| r.paper_error.map(sci)),
    ("ratio", |r| r.paper_ratio.map(|x| format!("{x:.2}"))),
    ("vs paper", |r| r.relative_to_paper.map(|d| format!("{:+.2}%", 100.0 * d))),
    ("u_n over S", |r| r.surface_error.map(sci)),
    ("iterated", |r| r.iterated_error.map(sci)),
    ("int. err", |r| r.integration_error.map(|e| format!("{e:.1e}"))),
    ("setup s", |r| Some(seconds(r.setup_seconds))),
    ("paper s", |r| r.paper_setup_seconds.map(|t| format!("{t}"))),
    ("E s", |r| Some(seconds(r.emission_seconds))),
    ("solve s", |r| Some(seconds(r.solve_seconds))),
];

/// How a study is printed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TableFormat {
    /// Aligned columns for a terminal.
    Text,
    /// GitHub-flavoured Markdown tables.
    Markdown,
}

/// A study as a table per series: our E_n and ratio beside the paper's, errors over S or of the
/// integration where measured, and the times; with the fitted rates, skipped series, notes and
/// plots.
pub fn study_table(study: &StudyResult, format: TableFormat) -> String {
    let columns: Vec<&Column> =
        COLUMNS.iter().filter(|(_, cell)| study.rows.iter().any(|r| cell(r).is_some())).collect();
    let markdown = format == TableFormat::Markdown;
    let line = |cells: Vec<String>| {
        if markdown {
            format!("| {} |\n", cells.join(" | "))
        } else {
            cells.iter().map(|c| format!("{c:>11}")).collect::<String>() + "\n"
        }
    };
    let header = line(columns.iter().map(|(name, _)| name.to_string()).collect())
        + &if markdown {
            line(columns.iter().map(|_| "---:".into()).collect())
        } else {
            String::new()
        };
    let mut s =
        if markdown { format!("**{}**\n", study.title) } else { format!("{}\n", study.title) };
    for summary in &study.series {
        s += &if markdown {
            format!("\n*{}*", summary.series)
        } else {
            format!("\n{}", summary.series)
        };
        if let Some(why) = &summary.skipped {
            s += &format!(": {why}\n");
            continue;
        }
        let rates: Vec<String> = [
            ("nodes", summary.rate),
            ("last two n", summary.last_rate),
            ("u_n over S", summary.surface_rate),
            ("iterated", summary.iterated_rate),
        ]
        .iter()
        .filter_map(|(what, rate)| rate.map(|p| format!("{what} O(h^{p:.2})")))
        .collect();
        if !rates.is_empty() {
            s += &format!("  (fitted: {})", rates.join(", "));
        }
        s += if markdown { "\n\n" } else { "\n" };
        s += &header;
        for r in study.rows.iter().filter(|r| r.series == summary.series) {
            let mut cells: Vec<String> =
                columns.iter().map(|(_, cell)| cell(r).unwrap_or_else(|| "-".into())).collect();
            if r.pareto == Some(true) {
                if let Some(first) = cells.first_mut() {
                    *first = format!("{first}*");
                }
            }
            s += &line(cells);
        }
    }
    if study.rows.iter().any(|r| r.pareto == Some(true)) {
        s += "\n* on the Pareto front of its method (no row of the method is both faster and more accurate)\n";
    }
    for note in &study.notes {
        s += &format!("\nNote: {note}\n");
    }
    for path in &study.figures {
        s += &format!("\nwrote {path}\n");
    }
    s
}

/// A plain table: a left-aligned first column (names) and right-aligned others.
fn plain_table(title: &str, header: &[&str], rows: &[Vec<String>], format: TableFormat) -> String {
    let mut s = String::new();
    match format {
        TableFormat::Markdown => {
            s += &format!("**{title}**\n\n| {} |\n", header.join(" | "));
            let align: Vec<&str> =
                (0..header.len()).map(|k| if k == 0 { "---" } else { "---:" }).collect();
            s += &format!("| {} |\n", align.join(" | "));
            for r in rows {
                s += &format!("| {} |\n", r.join(" | "));
            }
        }
        TableFormat::Text => {
            let width = |k: usize| {
                rows.iter()
                    .map(|r| r[k].chars().count())
                    .chain([header[k].len()])
                    .max()
                    .unwrap_or(0)
            };
            let widths: Vec<usize> = (0..header.len()).map(width).collect();
            let line = |cells: Vec<&str>| {
                let mut l = String::new();
                for (k, c) in cells.iter().enumerate() {
                    let pad = widths[k] - c.chars().count();
                    if k == 0 {
                        l += &format!("{c}{}", " ".repeat(pad));
                    } else {
                        l += &format!("  {}{c}", " ".repeat(pad));
                    }
                }
                l + "\n"
            };
            s += &format!("{title}\n\n");
            s += &line(header.to_vec());
            for r in rows {
                s += &line(r.iter().map(String::as_str).collect());
            }
        }
    }
    s
}

/// `study compression` as a table: one row per run, then the fitted growth exponents.
pub fn compression_table(
    study: &crate::study::compression::CompressionStudy,
    format: TableFormat,
) -> String {
    let opt = |v: Option<f64>| v.map_or("-".to_string(), |x| format!("{x:.1e}"));
    let rows: Vec<Vec<String>> = study
        .rows
        .iter()
        .map(|r| {
            vec![
                r.method.to_string(),
                r.n.to_string(),
                r.dof.to_string(),
                r.operator.to_string(),
                opt(r.compression_tolerance),
                r.error.map_or("-".into(), |e| format!("{e:.6e}")),
                opt(r.difference_from_dense),
                format!("{:.2}", r.setup_seconds),
                format!("{:.2}", r.solve_seconds),
                format!("{:.1}", r.operator_bytes as f64 / 1e6),
                r.max_rank.map_or("-".into(), |k| k.to_string()),
            ]
        })
        .collect();
    let header = [
        "method",
        "n",
        "dof",
        "operator",
        "tolerance",
        "E_n",
        "vs dense",
        "setup s",
        "solve s",
        "operator MB",
        "max rank",
    ];
    let shadowed = if study.shadowed_blocks { ", shadowed blocks" } else { "" };
    let title = format!("Compressed operator, {}{shadowed}", study.scene);
    let mut s = plain_table(&title, &header, &rows, format);
    let fits: Vec<Vec<String>> = study
        .fits
        .iter()
        .map(|f| {
            vec![
                f.method.to_string(),
                opt(f.compression_tolerance),
                format!("{} .. {}", f.n_range[0], f.n_range[1]),
                format!("{:.2}", f.time_exponent),
                format!("{:.2}", f.memory_exponent),
            ]
        })
        .collect();
    s += "\n";
    s += &plain_table(
        "Growth in n (least squares on log-log; tolerance '-' is dense)",
        &["method", "tolerance", "n", "time exponent", "memory exponent"],
        &fits,
        format,
    );
    for note in &study.left_out {
        s += &format!("\nleft out: {note}\n");
    }
    for path in &study.figures {
        s += &format!("\nwrote {path}\n");
    }
    s
}

/// `study compression`'s plot, one line per method and tolerance (and dense), written to `dir`
/// as PNG and SVG: E_n against setup + solve time where every run knows E_n (the paper's
/// surfaces), else setup + solve time against n.
pub fn write_compression_figure(
    study: &crate::study::compression::CompressionStudy,
    dir: &std::path::Path,
) -> Result<Vec<String>> {
    let errors = study.rows.iter().all(|r| r.error.is_some());
    let point = |r: &crate::study::compression::CompressionRow| {
        let seconds = r.setup_seconds + r.solve_seconds;
        match r.error {
            Some(e) if errors => (seconds, e),
            _ => (r.n as f64, seconds),
        }
    };
    let mut lines: Vec<plot::Line> = Vec::new();
    for fit_key in study.rows.iter().map(|r| (r.method, r.compression_tolerance)) {
        if lines.iter().any(|l| l.label == line_label(fit_key)) {
            continue;
        }
        let points = study
            .rows
            .iter()
            .filter(|r| (r.method, r.compression_tolerance) == fit_key)
            .map(point)
            .collect();
        let color = lines.len();
        lines.push(plot::Line {
            label: line_label(fit_key),
            points,
            color,
            dashed: fit_key.1.is_none(),
        });
    }
    let figure = plot::Figure {
        panels: vec![plot::Panel {
            caption: if errors {
                format!("{}: E_n against run time", study.scene)
            } else {
                format!("{}: run time against n", study.scene)
            },
            x_label: if errors { "setup + solve (s)" } else { "n" }.into(),
            y_label: if errors { "E_n" } else { "setup + solve (s)" }.into(),
            lines,
            front: Vec::new(),
        }],
        columns: 1,
    };
    let paths = plot::write_figure(&figure, &dir.join("compression"))?;
    Ok(paths.iter().map(|p| p.display().to_string()).collect())
}

fn line_label((method, tolerance): (&str, Option<f64>)) -> String {
    match tolerance {
        Some(t) => format!("{method}, compressed {t:.0e}"),
        None => format!("{method}, dense"),
    }
}

/// `study stability` as a table: one row per case, method and backend.
pub fn stability_table(
    result: &crate::study::stability::StabilityResult,
    format: TableFormat,
) -> String {
    let rows: Vec<Vec<String>> = result
        .rows
        .iter()
        .map(|r| {
            vec![
                r.case.clone(),
                r.method.into(),
                format!("{}-{}", r.backend, r.precision),
                format!("{:.6e}", r.reference),
                format!("{:.1e}", r.relative_error),
                r.closed_forms_error.map_or("-".into(), |e| format!("{e:.1e}")),
                format!("{:.0e}", r.bound),
                if r.passed { "ok".into() } else { "FAILED".into() },
            ]
        })
        .collect();
    let header =
        ["case", "method", "backend", "reference", "rel. error", "closed forms", "bound", ""];
    let mut s = plain_table(
        "Stability of the collocation integrals at extreme geometry",
        &header,
        &rows,
        format,
    );
    s += &format!("\n{} of {} rows within their bounds\n", rows.len() - result.failed, rows.len());
    for note in &result.notes {
        s += &format!("\nNote: {note}\n");
    }
    s
}

/// `study stiff` as a table: one row per scene and rho.
pub fn stiff_table(result: &crate::study::stability::StiffResult, format: TableFormat) -> String {
    let opt = |v: Option<f64>| v.map_or("-".to_string(), |x| format!("{x:.1e}"));
    let rows: Vec<Vec<String>> = result
        .rows
        .iter()
        .map(|r| {
            vec![
                r.case.clone(),
                r.method.into(),
                format!("{}", r.rho),
                r.dof.to_string(),
                opt(r.condition_estimate),
                opt(r.error_lu),
                opt(r.error_refined),
                r.refinement_steps.map_or("-".into(), |k| k.to_string()),
                opt(r.bound),
                opt(r.error_gmres),
                opt(r.gmres_vs_lu),
                r.gmres_iterations.map_or("-".into(), |k| k.to_string()),
                r.status.clone(),
            ]
        })
        .collect();
    let header = [
        "case",
        "method",
        "rho",
        "dof",
        "condition",
        "LU error",
        "refined",
        "steps",
        "bound",
        "GMRES error",
        "vs LU",
        "its",
        "status",
    ];
    let mut s =
        plain_table("Stiff systems: rho -> 1 in open and closed boxes", &header, &rows, format);
    for note in &result.notes {
        s += &format!("\nNote: {note}\n");
    }
    s
}

/// Writes K as a NumPy .npy file (float64, C order, dof × dof).
pub fn write_npy(path: &str, n: usize, values: &[f64]) -> Result<()> {
    use npyz::WriterBuilder;
    let file = std::io::BufWriter::new(std::fs::File::create(path)?);
    let n = n as u64;
    let mut writer =
        npyz::WriteOptions::<f64>::new().default_dtype().shape(&[n, n]).writer(file).begin_nd()?;
    writer.extend(values.iter().copied())?;
    writer.finish()?;
    Ok(())
}
