//! The paper's tables and figures, reproduced, and the error-against-time studies: each row is one
//! [`crate::pipeline::run`], with the paper's printed value beside ours where it has one.

mod analysis;
pub mod cities;
pub mod compression;
pub mod estimates;
mod specs;
pub mod stability;

pub use analysis::{fit_rate, pareto_front};
pub use specs::{Kind, Placement, Series, StudySpec, study_ids};

use std::collections::HashMap;

use serde::Serialize;

use crate::assembly::Quadrature;
use crate::error::{Error, Result};
use crate::pipeline::{self, Backend, RunConfig, RunLabel};
use crate::progress::ProgressSink;
use crate::quadrature::ImtRule;

/// Options shared by all studies.
#[derive(Clone, Debug)]
pub struct StudyOptions {
    /// Largest n to run (default: the study's).
    pub max_n: Option<usize>,
    /// Where the series run: `None` the CPU, plus the GPU series where an adapter is found
    /// ([`Backend::found`]); the CPU only; or on the GPU everything that can run
    /// there (GPU series keep their precision), a missing adapter being an error.
    pub backend: Option<Backend>,
    /// Where progress goes (which run starts, assembly and emission stages).
    pub progress: ProgressSink,
}

/// One row of a study.
#[derive(Clone, Debug, Serialize)]
pub struct StudyRow {
    /// The series' label.
    pub series: String,
    /// What was run: scene, mesh, method, quadrature, backend, precision, n and dof.
    #[serde(flatten)]
    pub label: RunLabel,
    /// Max error at the nodes E_n.
    pub error: f64,
    /// E_{n/4} / E_n.
    pub ratio: Option<f64>,
    /// Matrix setup time (planning and assembly).
    pub setup_seconds: f64,
    /// Emissivity time.
    pub emission_seconds: f64,
    /// Linear solve time.
    pub solve_seconds: f64,
    /// The paper's E_n, where printed.
    pub paper_error: Option<f64>,
    /// The paper's ratio (from its printed E_n).
    pub paper_ratio: Option<f64>,
    /// `(E_n - paper E_n) / paper E_n`.
    pub relative_to_paper: Option<f64>,
    /// The paper's setup time, where printed.
    pub paper_setup_seconds: Option<f64>,
    /// `max |u_n - u_n(exact, cpu)| / max |u_n(exact, cpu)|` at the nodes (timing studies).
    pub integration_error: Option<f64>,
    /// Max error of u_n over sample points of all of S.
    pub surface_error: Option<f64>,
    /// Max error of the iterated solution E + K u_n over the same points.
    pub iterated_error: Option<f64>,
    /// On the Pareto front of (setup time, error) among the rows of its method (error-vs-time).
    pub pareto: Option<bool>,
}

/// Per series: the fitted rates, or why it did not run.
#[derive(Clone, Debug, Serialize)]
pub struct SeriesSummary {
    /// The series' label.
    pub series: String,
    /// p in E_n = O(h^p), least squares over the rows (h ~ n^(-1/2)).
    pub rate: Option<f64>,
    /// p from the last two rows alone, `log2(E_{n/4} / E_n)` (the paper quotes final ratios).
    pub last_rate: Option<f64>,
    /// The same for the error over all of S.
    pub surface_rate: Option<f64>,
    /// The same for the iterated solution over all of S.
    pub iterated_rate: Option<f64>,
    /// Why the series did not run.
    pub skipped: Option<String>,
}

/// A finished study.
#[derive(Clone, Debug, Serialize)]
pub struct StudyResult {
    /// Study id, e.g. `table-3.1`.
    pub study: String,
    /// Title.
    pub title: String,
    /// Rows, series by series.
    pub rows: Vec<StudyRow>,
    /// Fitted rates and skipped series.
    pub series: Vec<SeriesSummary>,
    /// Remarks.
    pub notes: Vec<String>,
    /// Plots written.
    pub figures: Vec<String>,
}

/// Where `series` runs when `asked` ([`StudyOptions::backend`]), or why it does not.
fn backend_for(series: &Series, asked: Option<Backend>) -> std::result::Result<Backend, String> {
    match (series.placement, asked) {
        (Placement::Selected, Some(Backend::Gpu(p))) if series.quadrature == Quadrature::Exact => {
            Ok(Backend::Gpu(p))
        }
        (Placement::Selected | Placement::Cpu, _) => Ok(Backend::Cpu),
        (Placement::Gpu(_), Some(Backend::Cpu)) => Err("left out: the CPU was asked for".into()),
        (Placement::Gpu(p), Some(Backend::Gpu(_))) => Ok(Backend::Gpu(p)),
        (Placement::Gpu(p), None) => Backend::Gpu(p).found().map_err(|e| format!("left out: {e}")),
    }
}

/// Runs the study `id`.
pub fn run_study(id: &str, options: &StudyOptions) -> Result<StudyResult> {
    let spec = StudySpec::find(id).ok_or_else(|| Error::UnknownName {
        kind: "study",
        name: id.into(),
        expected: study_ids().join(", "),
    })?;
    let mut reference = References::new();
    let mut rows = Vec::new();
    let mut summaries = Vec::new();
    for series in &spec.series {
        let label = series.label();
        match backend_for(series, options.backend) {
            Ok(backend) => {
                let first = rows.len();
                let run = SeriesRun { spec: &spec, series, backend, options };
                run.rows(&mut reference, &mut rows)?;
                summaries.push(summary(label, &rows[first..]));
            }
            Err(why) => summaries.push(SeriesSummary {
                series: label,
                rate: None,
                last_rate: None,
                surface_rate: None,
                iterated_rate: None,
                skipped: Some(why),
            }),
        }
    }
    if spec.kind == (Kind::Timing { plot: true }) {
        mark_pareto_fronts(&mut rows);
    }
    Ok(StudyResult {
        study: spec.id.into(),
        title: spec.title.into(),
        rows,
        series: summaries,
        notes: spec.notes.iter().map(|s| s.to_string()).collect(),
        figures: Vec::new(),
    })
}

/// Exact CPU solutions at the nodes by (method, n), the reference of the integration errors.
type References = HashMap<(&'static str, usize), Vec<f64>>;

/// One series of a study on its backend.
struct SeriesRun<'a> {
    spec: &'a StudySpec,
    series: &'a Series,
    backend: Backend,
    options: &'a StudyOptions,
}

impl SeriesRun<'_> {
    /// Runs the series at refine 0, 1, ... while n stays within the study's largest n, and
    /// appends its rows to `rows`. In a timing study, the exact CPU runs with the paper's IMT
    /// rule become the references of the others' integration errors.
    fn rows(&self, reference: &mut References, rows: &mut Vec<StudyRow>) -> Result<()> {
        let (spec, series) = (self.spec, self.series);
        let max_n = self.options.max_n.unwrap_or(spec.default_max_n);
        let timing = matches!(spec.kind, Kind::Timing { .. });
        let label = series.label();
        let mut previous: Option<(f64, Option<f64>)> = None;
        for refine in 0.. {
            let config = series_config(spec, series, refine, self.backend, &self.options.progress);
            let problem = pipeline::build(&config)?;
            if problem.mesh.len() > max_n {
                break;
            }
            self.options.progress.note(&format!(
                "{}: {label}: n = {}",
                spec.id,
                problem.mesh.len()
            ));
            let report = pipeline::run_problem(&config, problem)?.report;
            let error = report.error.expect("a true solution is set");
            let paper_error = lookup(series.paper, report.label.n);
            let paper_ratio = match (previous, paper_error) {
                (Some((_, Some(p))), Some(q)) => Some(p / q),
                _ => None,
            };
            let key = (report.label.method, report.label.n);
            let integration_error = if !timing {
                None
            } else if series.quadrature == Quadrature::Exact
                && self.backend == Backend::Cpu
                && series.imt_nodes == ImtRule::PAPER_NODES
            {
                reference.insert(key, report.u.clone());
                None
            } else {
                reference.get(&key).map(|exact| relative_difference(&report.u, exact))
            };
            rows.push(StudyRow {
                series: label.clone(),
                label: report.label.clone(),
                error,
                ratio: previous.map(|(e, _)| e / error),
                setup_seconds: report.setup_seconds,
                emission_seconds: report.emission_seconds,
                solve_seconds: report.solve_seconds,
                paper_error,
                paper_ratio,
                relative_to_paper: paper_error.map(|p| (error - p) / p),
                paper_setup_seconds: lookup(series.paper_seconds, report.label.n),
                integration_error,
                surface_error: report.over_surface.map(|s| s.interpolant),
                iterated_error: report.over_surface.map(|s| s.iterated),
                pareto: None,
            });
            previous = Some((error, paper_error));
        }
        Ok(())
    }
}

/// The run of `series` at `refine` on `backend`.
fn series_config(
    spec: &StudySpec,
    series: &Series,
    refine: u32,
    backend: Backend,
    progress: &ProgressSink,
) -> RunConfig {
    let mut config = RunConfig::paper(series.scene, refine);
    config.mesh = series.mesh;
    config.method = series.method;
    config.solution = Some(series.solution);
    config.assembly.quadrature = series.quadrature;
    config.assembly.imt_nodes = series.imt_nodes;
    config.backend = backend;
    config.progress = progress.clone();
    // Timings of small runs are noisy: the timing studies take the best of three.
    config.setup_repeats = if matches!(spec.kind, Kind::Timing { .. }) { 3 } else { 1 };
    config.surface_lattice = spec.surface_lattice;
    config
}

/// A series' fitted rates from its rows.
fn summary(label: String, done: &[StudyRow]) -> SeriesSummary {
    let rate_of = |f: &dyn Fn(&StudyRow) -> Option<f64>| {
        let points: Option<Vec<(usize, f64)>> =
            done.iter().map(|r| f(r).map(|e| (r.label.n, e))).collect();
        points.and_then(|p| fit_rate(&p))
    };
    SeriesSummary {
        series: label,
        rate: rate_of(&|r| Some(r.error)),
        last_rate: done.last().and_then(|r| r.ratio).map(f64::log2),
        surface_rate: rate_of(&|r| r.surface_error),
        iterated_rate: rate_of(&|r| r.iterated_error),
        skipped: None,
    }
}

/// Marks the rows on the Pareto front of error against setup time, per method.
fn mark_pareto_fronts(rows: &mut [StudyRow]) {
    for method in ["centroid", "linear"] {
        let points: Vec<(f64, f64)> = rows
            .iter()
            .filter(|r| r.label.method == method)
            .map(|r| (r.setup_seconds, r.error))
            .collect();
        let front = pareto_front(&points);
        for (row, on_front) in rows.iter_mut().filter(|r| r.label.method == method).zip(front) {
            row.pareto = Some(on_front);
        }
    }
}

fn lookup(table: &[(usize, f64)], n: usize) -> Option<f64> {
    table.iter().find(|(m, _)| *m == n).map(|(_, v)| *v)
}

/// `max |a - b| / max |b|`.
fn relative_difference(a: &[f64], b: &[f64]) -> f64 {
    let scale = b.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    a.iter().zip(b).fold(0.0f64, |m, (x, y)| m.max((x - y).abs())) / scale
}
