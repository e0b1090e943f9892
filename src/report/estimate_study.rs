//! `study estimates`' report: one row per scene, tolerance and way of integrating, and the
//! largest ratio per tolerance.

use super::table::{TableFormat, plain_table};
use crate::study::estimates::EstimateStudy;

/// `study estimates` as a table.
pub fn estimate_table(study: &EstimateStudy, format: TableFormat) -> String {
    let rows: Vec<Vec<String>> = study
        .rows
        .iter()
        .map(|r| {
            vec![
                r.scene.clone(),
                r.n.to_string(),
                format!("{:.0e}", r.tolerance),
                if r.each_direction { "each direction" } else { "once" }.into(),
                format!("{:.1e}", r.error_estimate),
                format!("{:.1e}", r.largest_error),
                format!("{:.2} at ({}, {})", r.error_ratio, r.worst_entry.0, r.worst_entry.1),
                if r.each_direction { format!("{:.2}", r.reciprocity_ratio) } else { "-".into() },
                r.negative.to_string(),
                format!("{:.2}", r.evaluations as f64 / 1e6),
                format!("{:.2}", r.seconds),
                if r.holds { "yes" } else { "NO" }.into(),
            ]
        })
        .collect();
    let header = [
        "scene",
        "n",
        "tolerance",
        "pairs",
        "estimate",
        "error",
        "error ratio at (i, j)",
        "reciprocity ratio",
        "negative",
        "M evaluations",
        "s",
        "holds",
    ];
    let title = format!(
        "View factors' estimates against a run at {:.0e} (ratios at most 1 keep the promise)",
        study.reference_tolerance
    );
    let mut s = plain_table(&title, &header, &rows, format);
    s += "\n";
    for (tolerance, ratio) in &study.worst_ratio {
        s += &format!("largest ratio at {tolerance:.0e}: {ratio:.2}\n");
    }
    s += &format!("{} of {} runs broke the promise\n", study.failed, study.rows.len());
    s
}
