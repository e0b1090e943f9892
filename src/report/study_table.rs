//! A study of the paper's tables as text: our errors and rates beside the paper's, and times.

use crate::study::{StudyResult, StudyRow};

use super::table::TableFormat;

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
