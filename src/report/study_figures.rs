//! The plots of a study: convergence (error against n, with fitted rates) and error against setup
//! time (with the Pareto front).

use std::path::Path;

use super::plot::{Figure, Line, Panel, write_figure};
use crate::error::Result;
use crate::study::{Kind, SeriesSummary, StudyResult, StudyRow, StudySpec};

/// Writes the plots of `result` into `dir` as `<id>.png` and `<id>.svg`, for the studies that
/// draw them; returns their paths.
pub fn write_study_figures(result: &StudyResult, dir: &Path) -> Result<Vec<String>> {
    let Some(spec) = StudySpec::find(&result.study) else { return Ok(Vec::new()) };
    let figure = match spec.kind {
        Kind::Table | Kind::Timing { plot: false } => return Ok(Vec::new()),
        Kind::Convergence => convergence(result),
        Kind::Timing { plot: true } => error_vs_time(result),
    };
    let paths = write_figure(&figure, &dir.join(spec.id))?;
    Ok(paths.iter().map(|p| p.display().to_string()).collect())
}

fn rows_of<'a>(result: &'a StudyResult, series: &str) -> Vec<&'a StudyRow> {
    result.rows.iter().filter(|r| r.series == series).collect()
}

/// An error measure to plot: its name, fitted rate, value per row, and whether dashed.
type ErrorKind = (&'static str, Option<f64>, fn(&StudyRow) -> Option<f64>, bool);

fn rate_text(rate: Option<f64>) -> String {
    rate.map(|p| format!("O(h^{p:.2})")).unwrap_or_default()
}

/// One panel per surface; per series the nodal error (solid) and, where measured, the errors of
/// u_n and of the iterated solution over all of S (dashed).
fn convergence(result: &StudyResult) -> Figure {
    let mut surfaces: Vec<&str> = Vec::new();
    for r in &result.rows {
        if !surfaces.contains(&r.label.surface.as_str()) {
            surfaces.push(&r.label.surface);
        }
    }
    let panels = surfaces
        .iter()
        .map(|&surface| {
            let mut lines = Vec::new();
            let summaries: Vec<&SeriesSummary> = result
                .series
                .iter()
                .filter(|s| {
                    rows_of(result, &s.series).first().is_some_and(|r| r.label.surface == surface)
                })
                .collect();
            for (k, summary) in summaries.iter().enumerate() {
                let rows = rows_of(result, &summary.series);
                let mesh = rows[0].label.mesh;
                let kinds: [ErrorKind; 3] = [
                    ("nodes", summary.rate, |r| Some(r.error), false),
                    ("u_n over S", summary.surface_rate, |r| r.surface_error, true),
                    ("E + K u_n over S", summary.iterated_rate, |r| r.iterated_error, true),
                ];
                for (j, (what, rate, value, dashed)) in kinds.into_iter().enumerate() {
                    let points: Vec<(f64, f64)> = rows
                        .iter()
                        .filter_map(|r| value(r).map(|e| (r.label.n as f64, e)))
                        .collect();
                    if points.is_empty() {
                        continue;
                    }
                    let last = if j == 0 {
                        summary.last_rate.map(|p| format!(", last {p:.2}")).unwrap_or_default()
                    } else {
                        String::new()
                    };
                    lines.push(Line {
                        label: format!("{mesh}, {what}: {}{last}", rate_text(rate)),
                        points,
                        color: 3 * k + j,
                        dashed,
                    });
                }
            }
            Panel {
                caption: format!("{} surface, {} method", surface, result.rows[0].label.method),
                x_label: "n (triangles)".into(),
                y_label: "maximum error".into(),
                lines,
                front: Vec::new(),
            }
        })
        .collect::<Vec<_>>();
    Figure { columns: panels.len(), panels }
}

/// Per method, the error at the nodes against setup time for every series, with the Pareto front,
/// and beside it the integration error against setup time.
fn error_vs_time(result: &StudyResult) -> Figure {
    let mut panels = Vec::new();
    for method in ["centroid", "linear"] {
        let ran: Vec<&SeriesSummary> = result
            .series
            .iter()
            .filter(|s| {
                rows_of(result, &s.series).first().is_some_and(|r| r.label.method == method)
            })
            .collect();
        if ran.is_empty() {
            continue;
        }
        let line = |k: usize, summary: &SeriesSummary, value: fn(&StudyRow) -> Option<f64>| {
            let points: Vec<(f64, f64)> = rows_of(result, &summary.series)
                .iter()
                .filter_map(|r| value(r).map(|e| (r.setup_seconds, e)))
                .collect();
            let label = summary
                .series
                .replace("five-piece uniform ", "")
                .replace(&format!("{method} "), "");
            (!points.is_empty()).then_some(Line { label, points, color: k, dashed: k >= 10 })
        };
        let front = result
            .rows
            .iter()
            .filter(|r| r.label.method == method && r.pareto == Some(true))
            .map(|r| (r.setup_seconds, r.error))
            .collect();
        panels.push(Panel {
            caption: format!("{method} method: max error at the nodes vs setup time"),
            x_label: "setup seconds (one point per n)".into(),
            y_label: "E_n".into(),
            lines: ran
                .iter()
                .enumerate()
                .filter_map(|(k, s)| line(k, s, |r| Some(r.error)))
                .collect(),
            front,
        });
        panels.push(Panel {
            caption: format!("{method} method: integration error vs setup time"),
            x_label: "setup seconds (one point per n)".into(),
            y_label: "max |u_n - u_n(exact, cpu)| / max |u_n(exact, cpu)|".into(),
            lines: ran
                .iter()
                .enumerate()
                .filter_map(|(k, s)| line(k, s, |r| r.integration_error))
                .collect(),
            front: Vec::new(),
        });
    }
    Figure { panels, columns: 2 }
}
