//! Reports: plain-text tables for people, JSON for programs, plots and NumPy files.

pub mod plot;

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

/// A column of the study table: header, and the cell of a row (`None`: empty).
type Column = (&'static str, fn(&StudyRow) -> Option<String>);

const COLUMNS: [Column; 14] = [
    ("n", |r| Some(r.n.to_string())),
    ("dof", |r| Some(r.dof.to_string())),
    ("E_n", |r| Some(sci(r.error))),
    ("ratio", |r| r.ratio.map(|x| format!("{x:.2}"))),
    ("paper E_n", |r| r.paper_error.map(sci)),
    ("ratio", |r| r.paper_ratio.map(|x| format!("{x:.2}"))),
    ("vs paper", |r| r.relative_to_paper.map(|d| format!("{:+.2}%", 100.0 * d))),
    ("u_n over S", |r| r.surface_error.map(sci)),
    ("iterated", |r| r.iterated_error.map(sci)),
    ("int. err", |r| r.integration_error.map(|e| format!("{e:.1e}"))),
    ("setup s", |r| Some(format!("{:.3}", r.setup_seconds))),
    ("paper s", |r| r.paper_setup_seconds.map(|t| format!("{t}"))),
    ("E s", |r| Some(format!("{:.3}", r.emission_seconds))),
    ("solve s", |r| Some(format!("{:.3}", r.solve_seconds))),
];

/// A study as text: per series our E_n and ratio beside the paper's, and the times; then the
/// fitted rates, skipped series, notes and plots.
pub fn study_table(study: &StudyResult) -> String {
    let columns: Vec<&Column> =
        COLUMNS.iter().filter(|(_, cell)| study.rows.iter().any(|r| cell(r).is_some())).collect();
    let mut header = String::new();
    for (name, _) in &columns {
        header += &format!("{name:>11}");
    }
    let mut s = format!("{}\n", study.title);
    for summary in &study.series {
        s += &format!("\n{}", summary.series);
        if let Some(why) = &summary.skipped {
            s += &format!(": {why}\n");
            continue;
        }
        let rates: Vec<String> = [
            ("nodes", summary.rate),
            ("u_n over S", summary.surface_rate),
            ("iterated", summary.iterated_rate),
        ]
        .iter()
        .filter_map(|(what, rate)| rate.map(|p| format!("{what} O(h^{p:.2})")))
        .collect();
        if !rates.is_empty() {
            s += &format!("  (fitted: {})", rates.join(", "));
        }
        s += &format!("\n{header}\n");
        for r in study.rows.iter().filter(|r| r.series == summary.series) {
            for (_, cell) in &columns {
                let text = cell(r).unwrap_or_else(|| "-".into());
                s += &format!("{text:>11}");
            }
            if r.pareto == Some(true) {
                s += "  Pareto";
            }
            s += "\n";
        }
    }
    for note in &study.notes {
        s += &format!("\nNote: {note}\n");
    }
    for path in &study.figures {
        s += &format!("wrote {path}\n");
    }
    s
}

/// Writes K as a NumPy .npy file (float64, C order, dof × dof).
pub fn write_npy(path: &str, matrix: &crate::assembly::CollocationMatrix) -> Result<()> {
    use npyz::WriterBuilder;
    let file = std::io::BufWriter::new(std::fs::File::create(path)?);
    let n = matrix.dof() as u64;
    let mut writer =
        npyz::WriteOptions::<f64>::new().default_dtype().shape(&[n, n]).writer(file).begin_nd()?;
    writer.extend(matrix.as_slice().iter().copied())?;
    writer.finish()?;
    Ok(())
}
