//! `study compression`'s report: its table and its plot.

use crate::error::Result;

use super::plot;
use super::table::{TableFormat, plain_table};

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
