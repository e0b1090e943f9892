//! The paper's tables, reproduced: each row is one [`crate::pipeline::run`], with the paper's
//! printed value beside ours.

mod tables;

pub use tables::{StudySpec, TableColumn, study_ids};

use serde::Serialize;

use crate::error::{Error, Result};
use crate::pipeline::{self, RunConfig};

/// Options shared by all studies.
#[derive(Clone, Debug)]
pub struct StudyOptions {
    /// Largest n to run (default: the paper's largest for the study).
    pub max_n: Option<usize>,
    /// Where the matrices are assembled.
    pub backend: crate::pipeline::Backend,
    /// Show progress on stderr.
    pub progress: bool,
}

/// One row of a study.
#[derive(Clone, Debug, Serialize)]
pub struct StudyRow {
    /// Scene name (`four-piece`, `five-piece`).
    pub surface: String,
    /// `uniform` or `discontinuity`.
    pub mesh: &'static str,
    /// `centroid` or `linear`.
    pub method: &'static str,
    /// α of the linear method.
    pub alpha: Option<f64>,
    /// How the collocation integrals were evaluated.
    pub quadrature: &'static str,
    /// `cpu` or `gpu`.
    pub backend: &'static str,
    /// Elements.
    pub n: usize,
    /// Unknowns.
    pub dof: usize,
    /// Max error at the nodes E_n.
    pub error: f64,
    /// E_{n/4} / E_n.
    pub ratio: Option<f64>,
    /// Matrix setup time.
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
}

/// A finished study.
#[derive(Clone, Debug, Serialize)]
pub struct StudyResult {
    /// Study id, e.g. `table-3.1`.
    pub study: String,
    /// Title.
    pub title: String,
    /// Rows, column by column of the paper's table.
    pub rows: Vec<StudyRow>,
}

/// Runs the study `id`.
pub fn run_study(id: &str, options: &StudyOptions) -> Result<StudyResult> {
    let spec = StudySpec::find(id).ok_or_else(|| Error::UnknownName {
        kind: "study",
        name: id.into(),
        expected: study_ids().join(", "),
    })?;
    let max_n = options.max_n.unwrap_or_else(|| spec.largest_n());
    let mut rows = Vec::new();
    for column in &spec.columns {
        let mut previous: Option<(f64, Option<f64>)> = None;
        for refine in 0.. {
            let mut config = RunConfig::paper(column.scene, refine);
            config.mesh = column.mesh;
            config.method = spec.method;
            config.solution = Some(spec.solution);
            config.progress = options.progress;
            config.backend = options.backend;
            let (_, mesh, _) = pipeline::build(&config)?;
            if mesh.len() > max_n {
                break;
            }
            if options.progress {
                eprintln!(
                    "{}: {} {} n = {}",
                    spec.id,
                    column.scene,
                    column.mesh.name(),
                    mesh.len()
                );
            }
            let report = pipeline::run(&config)?;
            let error = report.error.expect("a true solution is set");
            let paper_error = column.paper.iter().find(|(n, _)| *n == report.n).map(|(_, e)| *e);
            let ratio = previous.map(|(e, _)| e / error);
            let paper_ratio = match (previous, paper_error) {
                (Some((_, Some(p))), Some(q)) => Some(p / q),
                _ => None,
            };
            rows.push(StudyRow {
                surface: report.surface,
                mesh: report.mesh,
                method: report.method,
                alpha: report.alpha,
                quadrature: report.quadrature,
                backend: report.backend,
                n: report.n,
                dof: report.dof,
                error,
                ratio,
                setup_seconds: report.setup_seconds,
                emission_seconds: report.emission_seconds,
                solve_seconds: report.solve_seconds,
                paper_error,
                paper_ratio,
                relative_to_paper: paper_error.map(|p| (error - p) / p),
            });
            previous = Some((error, paper_error));
        }
    }
    Ok(StudyResult { study: spec.id.into(), title: spec.title.into(), rows })
}
