//! Reports: plain-text tables for people, JSON for programs.

use std::io::Write;
use std::path::Path;

use serde::Serialize;

use crate::error::Result;
use crate::study::StudyResult;

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

fn opt(v: Option<f64>, digits: usize) -> String {
    v.map(|x| format!("{x:.digits$}")).unwrap_or_else(|| "-".into())
}

fn sci(v: f64) -> String {
    if v != 0.0 && (v.abs() < 1e-2 || v.abs() >= 1e3) {
        format!("{v:.3e}")
    } else {
        format!("{v:.4}")
    }
}

/// A study as a text table: our E_n and ratio beside the paper's, and the times.
pub fn study_table(study: &StudyResult) -> String {
    let mut s = format!("{}\n\n", study.title);
    s += &format!(
        "{:<11} {:<13} {:>6} {:>6} {:>11} {:>6} {:>11} {:>6} {:>8} {:>9} {:>9} {:>8}\n",
        "surface",
        "mesh",
        "n",
        "dof",
        "E_n",
        "ratio",
        "paper E_n",
        "ratio",
        "vs paper",
        "setup s",
        "E s",
        "solve s"
    );
    for r in &study.rows {
        s += &format!(
            "{:<11} {:<13} {:>6} {:>6} {:>11} {:>6} {:>11} {:>6} {:>8} {:>9.3} {:>9.3} {:>8.3}\n",
            r.surface,
            r.mesh,
            r.n,
            r.dof,
            sci(r.error),
            opt(r.ratio, 2),
            r.paper_error.map(sci).unwrap_or_else(|| "-".into()),
            opt(r.paper_ratio, 2),
            r.relative_to_paper
                .map(|d| format!("{:+.2}%", 100.0 * d))
                .unwrap_or_else(|| "-".into()),
            r.setup_seconds,
            r.emission_seconds,
            r.solve_seconds,
        );
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
