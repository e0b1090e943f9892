//! What a run reports: its label, the solver's outcome, timings, pair classes and memory.

use serde::Serialize;

use super::summary::DeviceTransfers;
use super::{Problem, RunConfig};
use crate::assembly::Quadrature;
use crate::distributed::DistributedReport;
use crate::operator::OperatorStats;
use crate::surface_error::SurfaceErrors;
use crate::visibility::PairStats;

/// What a run was: the scene, mesh, method and backend, and its size. The reports of runs (a
/// run's, a study's rows) carry it flattened: its keys stand beside theirs in JSON.
#[derive(Clone, Debug, Serialize)]
pub struct RunLabel {
    /// Scene name.
    pub surface: String,
    /// Mesh kind.
    pub mesh: &'static str,
    /// Method name.
    pub method: &'static str,
    /// α of the linear method.
    pub alpha: Option<f64>,
    /// Quadrature of the collocation integrals (`quadrature` and its parameters).
    #[serde(flatten)]
    pub quadrature: Quadrature,
    /// Backend that assembled the matrix.
    pub backend: &'static str,
    /// Precision of the matrix entries.
    pub precision: &'static str,
    /// Number of elements.
    pub n: usize,
    /// Number of unknowns.
    pub dof: usize,
}

impl RunLabel {
    /// The label of `config` run on `problem`.
    pub fn new(config: &RunConfig, problem: &Problem) -> Self {
        Self {
            surface: problem.scene.name.clone(),
            mesh: config.mesh.name(),
            method: config.method.name(),
            alpha: config.method.alpha(),
            quadrature: config.assembly.quadrature,
            backend: config.backend.name(),
            precision: config.backend.precision().name(),
            n: problem.mesh.len(),
            dof: problem.disc.dof(),
        }
    }
}

/// Results of one run.
#[derive(Clone, Debug, Serialize)]
pub struct RunReport {
    /// What was run: scene, mesh, method, quadrature, backend, precision, n and dof.
    #[serde(flatten)]
    pub label: RunLabel,
    /// Grading exponent q, when the mesh is graded toward edges.
    pub grading: Option<f64>,
    /// The GPU adapter, when the GPU assembled the matrix.
    pub device: Option<String>,
    /// Linear solver used (`lu` or `gmres`).
    pub solver: &'static str,
    /// Iterations of the iterative solver.
    pub iterations: usize,
    /// Estimated 1-norm condition number of I - K (LU only).
    pub condition_estimate: Option<f64>,
    /// Steps of iterative refinement after LU.
    pub refinement_steps: usize,
    /// Estimated relative error of E computed from a true solution by adaptive quadrature (0 in
    /// closed form; `None` when E comes from the scene's emitters).
    pub emission_error_estimate: Option<f64>,
    /// One-time preparation of the backend (GPU: compiling its kernels), not in `setup_seconds`.
    pub preparation_seconds: f64,
    /// Unknowns known without solving (zero rows of K: rho = 0 or nothing in view; u = E).
    pub rows_eliminated: usize,
    /// What the user should know about the scene or the run (no emitter, faces lying on one
    /// another); the binary prints them as warnings.
    pub warnings: Vec<String>,
    /// What the loader repaired in the scene file ([`Scene::notes`]).
    pub notes: Vec<String>,
    /// Per colour band, when bands were solved (then `u`, `solution_range` and the solver's
    /// fields above are of the bands' mean, summed or worst over the bands).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub bands: Vec<BandReport>,
    /// Per emission case, when cases were given (then `u`, `solution_range` and the solver's
    /// fields above are of the cases' mean, summed or worst over the cases).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub cases: Vec<CaseReport>,
    /// Max error at the nodes `max_i |u(P_i) - u_n(P_i)|`, when a true solution is known.
    pub error: Option<f64>,
    /// Time to plan and assemble the matrix.
    pub setup_seconds: f64,
    /// Time to compute the emissivity at the nodes.
    pub emission_seconds: f64,
    /// Time to solve the linear system.
    pub solve_seconds: f64,
    /// Relative residual of the solve.
    pub residual: f64,
    /// Pair classes (of the exact blocks, for the compressed operator).
    pub pairs: PairStats,
    /// `dense` or `compressed`.
    pub operator: &'static str,
    /// Relative tolerance of the low-rank blocks (compressed operator).
    pub compression_tolerance: Option<f64>,
    /// Memory of the stored operator, in bytes.
    pub operator_bytes: u64,
    /// What the compressed operator's build was estimated to hold at its peak before it began.
    pub memory_estimate_bytes: Option<u64>,
    /// Block statistics of the compressed operator (`near_entries`, `far_blocks`, `max_rank`,
    /// ...).
    #[serde(flatten)]
    pub blocks: Option<OperatorStats>,
    /// Where a dense K assembled on the GPU is kept and what crossed (`operator_location`,
    /// `bytes_uploaded`, `bytes_read_back`, `gpu_submissions`, `device_idle_fraction`).
    #[serde(flatten, skip_serializing_if = "Option::is_none")]
    pub transfers: Option<DeviceTransfers>,
    /// Peak resident memory of the whole process so far, from the OS (Linux), in bytes.
    pub peak_rss_bytes: Option<u64>,
    /// Smallest, mean and largest nodal value of the solution.
    pub solution_range: [f64; 3],
    /// The ranks of a distributed run (`ranks`, `per_rank`, `communication_seconds`,
    /// `communication_bytes`, `load_imbalance`).
    #[serde(flatten, skip_serializing_if = "Option::is_none")]
    pub distributed: Option<DistributedReport>,
    /// Errors over all of S at sample points (`surface_error`, `iterated_error`, `surface_points`),
    /// when asked for and a true solution is known.
    #[serde(flatten)]
    pub over_surface: Option<SurfaceErrors>,
    /// Nodal values of the computed solution.
    #[serde(skip)]
    pub u: Vec<f64>,
}

/// The solve of one colour band.
#[derive(Clone, Debug, Serialize)]
pub struct BandReport {
    /// Band name (`r`, `g`, `b`).
    pub band: &'static str,
    /// Linear solver used.
    pub solver: &'static str,
    /// Iterations of the iterative solver.
    pub iterations: usize,
    /// Relative residual.
    pub residual: f64,
    /// Estimated condition number of I - K_band (LU only).
    pub condition_estimate: Option<f64>,
    /// Time to solve this band.
    pub solve_seconds: f64,
    /// Smallest, mean and largest nodal value.
    pub solution_range: [f64; 3],
}

/// The solve of one emission case.
#[derive(Clone, Debug, Serialize)]
pub struct CaseReport {
    /// Case name (the column's header, or its number from 1).
    pub case: String,
    /// Linear solver used.
    pub solver: &'static str,
    /// Iterations of the iterative solver.
    pub iterations: usize,
    /// Relative residual.
    pub residual: f64,
    /// Smallest, mean and largest nodal value.
    pub solution_range: [f64; 3],
}

/// Smallest, mean and largest value.
pub(super) fn range(u: &[f64]) -> [f64; 3] {
    let (lo, hi, sum) =
        u.iter().fold((f64::INFINITY, f64::NEG_INFINITY, 0.0), |(lo, hi, s), &v| {
            (lo.min(v), hi.max(v), s + v)
        });
    [lo, sum / u.len() as f64, hi]
}
