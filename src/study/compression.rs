//! `study compression`: the compressed operator ([`crate::operator`]) as n grows, at several
//! tolerances, against the dense operator where that fits: E_n (where the true solution is
//! known), the difference of the solutions, time, memory, and fitted growth exponents. On the
//! five-piece surface by default (centroid and linear), or on any scene (`--scene`: centroid,
//! its own emission, from the first refinement with [`SCENE_MIN_N`] elements).

use serde::Serialize;

use crate::discretization::Method;
use crate::distributed::Ranks;
use crate::error::{Error, Result};
use crate::mesh::{Mesh, MeshKind};
use crate::operator::{CompressionOptions, DEFAULT_TOLERANCE, OperatorChoice};
use crate::pipeline::{self, Backend, RunConfig, SceneSource};
use crate::progress::{ProgressSink, in_stage};
use crate::scene::BuiltinScene;
use crate::solve::{SolverChoice, SolverOptions};

/// Tolerances of the compressed runs.
pub const TOLERANCES: [f64; 3] = [1e-3, 1e-6, 1e-9];

/// Dense runs (the reference) up to this many unknowns: the matrix takes 8 dof² bytes.
pub const DENSE_LIMIT: usize = 12_288;

/// Largest n by default: the runs up to it take a few minutes on two cores.
pub const DEFAULT_MAX_N: usize = 40_960;

/// Smallest n of the study on the five-piece surface.
const FIRST_REFINE: u32 = 4;

/// On other scenes, the first refinement with at least this many elements: timings of smaller
/// ones say little about growth.
pub const SCENE_MIN_N: usize = 1_000;

/// One run.
#[derive(Clone, Debug, Serialize)]
pub struct CompressionRow {
    /// `centroid` or `linear`.
    pub method: &'static str,
    /// Elements.
    pub n: usize,
    /// Unknowns.
    pub dof: usize,
    /// `dense` or `compressed`.
    pub operator: &'static str,
    /// `cpu` or `gpu`: where the operator's entries were evaluated.
    pub backend: &'static str,
    /// Tolerance of the compressed operator.
    pub compression_tolerance: Option<f64>,
    /// E_n, the largest nodal error against u = x² + y² (none where no true solution is known:
    /// scenes other than the paper's surfaces).
    pub error: Option<f64>,
    /// `max |u - u_dense| / max |u_dense|`, where the dense run fits.
    pub difference_from_dense: Option<f64>,
    /// Building the operator.
    pub setup_seconds: f64,
    /// Solving.
    pub solve_seconds: f64,
    /// Memory of the stored operator.
    pub operator_bytes: u64,
    /// Peak resident memory of the process so far.
    pub peak_rss_bytes: Option<u64>,
    /// Largest rank of a low-rank block.
    pub max_rank: Option<usize>,
    /// GMRES iterations (0 for LU).
    pub iterations: usize,
    /// Ranks the operator was spread over (a distributed run's compressed rows).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub ranks: Option<usize>,
}

/// Growth of time and memory in n, fitted by least squares on log-log data.
#[derive(Clone, Debug, Serialize)]
pub struct GrowthFit {
    /// Method.
    pub method: &'static str,
    /// Tolerance (`None`: dense).
    pub compression_tolerance: Option<f64>,
    /// Exponent p of setup + solve time ~ n^p.
    pub time_exponent: f64,
    /// Exponent of the stored operator's memory.
    pub memory_exponent: f64,
    /// Smallest and largest n fitted.
    pub n_range: [usize; 2],
}

/// The study's result.
#[derive(Clone, Debug, Serialize)]
pub struct CompressionStudy {
    /// Study id.
    pub study: &'static str,
    /// The scene (`five-piece` unless another was asked for).
    pub scene: String,
    /// Whether the compressed runs used shadowed blocks.
    pub shadowed_blocks: bool,
    /// Every run.
    pub rows: Vec<CompressionRow>,
    /// Growth exponents per method and tolerance.
    pub fits: Vec<GrowthFit>,
    /// Runs left out because their operator would not fit in memory, with the reason.
    pub left_out: Vec<String>,
    /// Plots written.
    pub figures: Vec<String>,
}

/// What the study runs: on which scene, up to which n, at which tolerances.
#[derive(Clone, Debug)]
pub struct CompressionSeries {
    /// The scene; `None`: the five-piece surface, both methods, against u = x² + y².
    pub scene: Option<SceneSource>,
    /// Largest number of elements (default [`DEFAULT_MAX_N`]).
    pub max_n: Option<usize>,
    /// Tolerances of the compressed runs (default [`TOLERANCES`]).
    pub tolerances: Vec<f64>,
    /// Whether the compressed runs use shadowed blocks
    /// ([`CompressionOptions::shadowed_blocks`]).
    pub shadowed_blocks: bool,
}

/// Runs the study of `series`, every operator built on `backend` (the GPU: the compressed
/// operator's entries by its pair kernel). With `ranks` (a distributed run: every rank calls
/// this) the compressed operators are spread over them and the dense references run at rank 0
/// alone, whose rows are the study's.
pub fn run_compression(
    series: &CompressionSeries,
    backend: Backend,
    progress: &ProgressSink,
    ranks: Option<&Ranks>,
) -> Result<CompressionStudy> {
    let is_root = ranks.is_none_or(|r| r.rank() == 0);
    let max_n = series.max_n.unwrap_or(DEFAULT_MAX_N);
    for &t in &series.tolerances {
        CompressionOptions { tolerance: t, ..Default::default() }.validate()?;
    }
    let paper = SceneSource::Builtin(BuiltinScene::FivePiece);
    let source = series.scene.clone().unwrap_or(paper);
    // The first refinement and n = n_0 4^refine: n_0 from the scene's coarsest mesh.
    let (name, methods, first_refine, n0) = match &series.scene {
        None => {
            let methods = vec![Method::Centroid, Method::linear(Method::PAPER_ALPHA)?];
            ("five-piece".to_string(), methods, FIRST_REFINE, 10)
        }
        Some(scene) => {
            let built = in_stage(&**progress, "scene", || scene.build(Default::default()))?;
            let n0 = Mesh::new(&built, &MeshKind::Uniform, 0)?.len();
            let first = (0..12).find(|&r| n0 * 4usize.pow(r) >= SCENE_MIN_N.min(max_n));
            (built.name.clone(), vec![Method::Centroid], first.unwrap_or(12), n0)
        }
    };
    let mut rows = Vec::new();
    let mut left_out = Vec::new();
    for method in methods {
        for refine in (first_refine..=12).take_while(|&r| n0 * 4usize.pow(r) <= max_n) {
            let dof = n0 * 4usize.pow(refine) * method.nodes_per_element();
            let config = |operator, tolerance| {
                let mut c = RunConfig::paper(BuiltinScene::FivePiece, refine);
                c.scene = source.clone();
                // The paper's true solution on its surfaces; elsewhere the scene's emission.
                c.solution = c.solution.filter(|_| source.is_paper_surface());
                c.method = method;
                c.backend = backend;
                c.operator = operator;
                // The plain plan unless asked for: a series compares one plan across sizes.
                let shadowed_blocks = series.shadowed_blocks.into();
                c.compression =
                    CompressionOptions { tolerance, shadowed_blocks, ..Default::default() };
                c.solver = SolverOptions::with(SolverChoice::Auto);
                c.progress = progress.clone();
                c.ranks =
                    (operator == OperatorChoice::Compressed).then(|| ranks.cloned()).flatten();
                c
            };
            let dense = if dof <= DENSE_LIMIT && is_root {
                progress.note(&format!("compression study: {method}, dof = {dof}, dense"));
                let r = pipeline::run(&config(OperatorChoice::Dense, DEFAULT_TOLERANCE))?;
                let row = row_of(&r, None, None);
                rows.push(row);
                Some(r.u)
            } else {
                None
            };
            for &tolerance in &series.tolerances {
                progress.note(&format!(
                    "compression study: {method}, dof = {dof}, tolerance {tolerance:.0e}"
                ));
                match pipeline::run(&config(OperatorChoice::Compressed, tolerance)) {
                    Ok(r) => {
                        let difference = dense.as_ref().map(|d| relative_difference(&r.u, d));
                        rows.push(row_of(&r, Some(tolerance), difference));
                    }
                    // A run that does not fit in memory is reported, and the rest of the
                    // study goes on (smaller tolerances need more memory still).
                    // (Not over ranks: each rank's guard sees its own share, so they would not
                    // agree on leaving the run out; the error stops them all.)
                    Err(e @ Error::OperatorTooLarge { .. }) if ranks.is_none() => {
                        let note = format!("{method}, dof = {dof}, tolerance {tolerance:.0e}: {e}");
                        progress.note(&format!("compression study: left out: {note}"));
                        left_out.push(note);
                        break;
                    }
                    Err(e) => return Err(e),
                }
            }
        }
    }
    let fits = growth_fits(&rows);
    Ok(CompressionStudy {
        study: "compression",
        scene: name,
        shadowed_blocks: series.shadowed_blocks,
        rows,
        fits,
        left_out,
        figures: Vec::new(),
    })
}

fn row_of(
    r: &pipeline::RunReport,
    tolerance: Option<f64>,
    difference: Option<f64>,
) -> CompressionRow {
    CompressionRow {
        method: r.label.method,
        n: r.label.n,
        dof: r.label.dof,
        operator: r.operator,
        backend: r.label.backend,
        compression_tolerance: tolerance,
        error: r.error,
        difference_from_dense: difference,
        setup_seconds: r.setup_seconds,
        solve_seconds: r.solve_seconds,
        operator_bytes: r.operator_bytes,
        peak_rss_bytes: r.peak_rss_bytes,
        max_rank: r.blocks.map(|b| b.max_rank),
        iterations: r.iterations,
        ranks: r.distributed.as_ref().map(|d| d.ranks),
    }
}

/// `max |a - b| / max |b|`.
fn relative_difference(a: &[f64], b: &[f64]) -> f64 {
    let d = a.iter().zip(b).fold(0.0f64, |m, (x, y)| m.max((x - y).abs()));
    d / b.iter().fold(0.0f64, |m, y| m.max(y.abs())).max(f64::MIN_POSITIVE)
}

/// Least-squares slopes of log time and log memory against log n, per method and tolerance,
/// where at least two sizes ran.
fn growth_fits(rows: &[CompressionRow]) -> Vec<GrowthFit> {
    let mut keys: Vec<(&'static str, Option<f64>)> =
        rows.iter().map(|r| (r.method, r.compression_tolerance)).collect();
    keys.dedup();
    keys.sort_by(|a, b| a.0.cmp(b.0).then(a.1.partial_cmp(&b.1).expect("finite")));
    keys.dedup();
    keys.into_iter()
        .filter_map(|(method, tolerance)| {
            let series: Vec<&CompressionRow> = rows
                .iter()
                .filter(|r| r.method == method && r.compression_tolerance == tolerance)
                .collect();
            (series.len() >= 2).then(|| {
                let x: Vec<f64> = series.iter().map(|r| (r.n as f64).ln()).collect();
                let time: Vec<f64> =
                    series.iter().map(|r| (r.setup_seconds + r.solve_seconds).ln()).collect();
                let memory: Vec<f64> =
                    series.iter().map(|r| (r.operator_bytes as f64).ln()).collect();
                GrowthFit {
                    method,
                    compression_tolerance: tolerance,
                    time_exponent: slope(&x, &time),
                    memory_exponent: slope(&x, &memory),
                    n_range: [series[0].n, series[series.len() - 1].n],
                }
            })
        })
        .collect()
}

/// Least-squares slope of y against x.
fn slope(x: &[f64], y: &[f64]) -> f64 {
    let n = x.len() as f64;
    let (mx, my) = (x.iter().sum::<f64>() / n, y.iter().sum::<f64>() / n);
    let sxy: f64 = x.iter().zip(y).map(|(a, b)| (a - mx) * (b - my)).sum();
    let sxx: f64 = x.iter().map(|a| (a - mx) * (a - mx)).sum();
    sxy / sxx
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn slopes_of_power_laws_are_their_exponents() {
        let x: Vec<f64> = [1.0f64, 2.0, 4.0, 8.0].iter().map(|v| v.ln()).collect();
        let y: Vec<f64> =
            [1.0f64, 2.0, 4.0, 8.0].iter().map(|v| (3.0 * v.powf(1.25)).ln()).collect();
        assert!((slope(&x, &y) - 1.25).abs() < 1e-12);
    }
}
