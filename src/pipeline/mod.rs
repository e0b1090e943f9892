//! One solve from end to end (ARCHITECTURE.md): scene -> mesh -> discretization -> pair plan ->
//! assembly -> emissivity -> solve -> errors, with the time of each stage.
//!
//! [`RunConfig`] says what to run; [`Problem`] holds what is built once from it (the scene, its
//! mesh, the discretization and the pair plan), which every later stage and every command works
//! on (built by [`build`]); [`run`] takes a configuration through all stages to a [`RunReport`].

mod backend;
mod bands;
mod built;
mod cases;
mod choice;
mod config;
mod device;
mod operator;
mod options;
mod report;
mod saved;
mod summary;

pub use crate::assembly::Problem;
pub use crate::assembly::peak_rss_bytes;
pub use backend::{Assembler, assemble_on, cpu_and_found_gpus};
pub use built::{BuiltOperator, TimedAssembly, distributed_report};
pub use choice::{OperatorKind, operator_kind};
pub use config::{Backend, MeshChoice, REPEAT_BELOW_SECONDS, RunConfig, SceneSource};
pub use device::compressed_on_device;
pub use operator::{build_compressed, build_operator};
pub use options::{BackendName, MeshName, RunOptions};
pub use report::{BandReport, CaseReport, RunLabel, RunReport};
pub use saved::{OperatorHeader, load_operator, save_operator};
pub use summary::{DeviceTransfers, OperatorSummary};

use std::time::Instant;

use crate::discretization::Discretization;
use crate::error::{Error, Result};
use crate::mesh::{Grading, Mesh, MeshKind, Sources, paper_discontinuity_cuts, shadow_lines};
use crate::problems::emission_at;
use crate::progress::in_stage;
use crate::scene::{CHANNELS, Scene};
use crate::solution::{BandValues, CaseValues};
use crate::solve;
use crate::surface_error::surface_errors;
use crate::visibility::PairPlanner;
use bands::{mean_outcome, solve_bands, solve_bands_by_products};
use cases::solve_cases;
use report::range;

/// Relative error estimate of E above which `solve` warns: 1e3 times the quadrature's relative
/// tolerance (1e-12): the sum of per-triangle estimates is pessimistic by about that much.
const EMISSION_WARNING: f64 = 1e-9;

/// The mesh of `config` on `scene` (whose occluders are in `planner`, for the shadow lines of an
/// automatic discontinuity mesh).
fn mesh_of(config: &RunConfig, scene: &Scene, planner: &PairPlanner) -> Result<Mesh> {
    let kind = match config.mesh {
        MeshChoice::Uniform => MeshKind::Uniform,
        MeshChoice::Discontinuity(s5) => {
            MeshKind::Discontinuity(paper_discontinuity_cuts(scene, &config.params, s5)?)
        }
        MeshChoice::AutoDiscontinuity(extent) => {
            // With a true solution every face carries light (E is computed from it everywhere).
            let sources = if config.solution.is_some() { Sources::All } else { Sources::Emitting };
            MeshKind::Constrained(shadow_lines(scene, planner, sources, extent))
        }
    };
    let mut mesh = Mesh::new(scene, &kind, config.refine)?;
    if !config.grade.is_empty() {
        mesh.grade(scene, &Grading::parse(scene, &config.grade, config.grading_exponent)?)?;
    }
    Ok(mesh)
}

/// The problem of `config`: its scene, the pair planner, the mesh and the discretization on it.
pub fn build(config: &RunConfig) -> Result<Problem> {
    let scene = in_stage(&*config.progress, "scene", || config.scene.build(config.params))?;
    build_on(config, scene)
}

/// The problem of `config` on a scene built already (`config.scene` is not read). Every run
/// starts here, so here its memory limit is installed for the checks made before each large
/// allocation ([`crate::assembly::check_fits`], the compressed operator's guard), which read it
/// deep below the configuration.
pub fn build_on(config: &RunConfig, scene: Scene) -> Result<Problem> {
    crate::assembly::set_memory_limit(config.memory_limit);
    let progress = &*config.progress;
    let (planner, plan_seconds) = in_stage(progress, "occluders", || Problem::plan(&scene));
    let (mesh, disc) = in_stage(progress, "mesh", || {
        let mesh = mesh_of(config, &scene, &planner)?;
        let disc = Discretization::new(&scene, &mesh, config.method)?;
        Ok::<_, Error>((mesh, disc))
    })?;
    Ok(Problem::with_planner(scene, mesh, disc, planner, plan_seconds))
}

/// A finished run with what it was computed on (for outputs such as VTK files and pictures).
#[derive(Clone, Debug)]
pub struct Run {
    /// The report.
    pub report: RunReport,
    /// The scene.
    pub scene: Scene,
    /// The mesh.
    pub mesh: Mesh,
    /// Nodes and method.
    pub disc: Discretization,
    /// E at the nodes.
    pub emission: Vec<f64>,
    /// The colour bands' solutions (empty for a grey run).
    pub bands: Vec<BandValues>,
    /// The emission cases' solutions (empty unless cases were given).
    pub cases: Vec<CaseValues>,
}

impl Run {
    /// The solution as the outputs see it.
    pub fn field(&self) -> crate::solution::SolutionField<'_> {
        crate::solution::SolutionField {
            scene: &self.scene,
            mesh: &self.mesh,
            disc: &self.disc,
            u: &self.report.u,
            emission: &self.emission,
            bands: &self.bands,
            cases: &self.cases,
        }
    }
}

/// What the user should be told about a scene before trusting its solution.
fn run_warnings(scene: &Scene, emission: &[f64]) -> Vec<String> {
    let mut warnings = Vec::new();
    if emission.iter().all(|&e| e == 0.0) {
        warnings.push(format!(
            "no face of '{}' emits (E = 0 everywhere), so the solution is zero: give a light \
             source `emission = ...` in the scene file (per face, group or material; OBJ: Ke)",
            scene.name
        ));
    }
    for (a, b, area) in scene.faces_in_contact() {
        warnings.push(format!(
            "faces '{a}' and '{b}' lie on one another facing each other (shared area {area:.3e}) \
             without covering each other as the two sides of a plate do: no light passes between \
             them, and the part of the larger one under the smaller stays dark; lift one off the \
             other if they should exchange light"
        ));
    }
    warnings
}

/// Runs one configuration.
pub fn run(config: &RunConfig) -> Result<RunReport> {
    Ok(run_keeping_mesh(config)?.report)
}

/// Runs one configuration and keeps the scene, mesh and emissivity.
pub fn run_keeping_mesh(config: &RunConfig) -> Result<Run> {
    check_lighting(config)?;
    run_problem(config, build(config)?)
}

/// Colour bands are lit by the scene's own emission, not by a true solution; emission cases
/// replace both.
fn check_lighting(config: &RunConfig) -> Result<()> {
    let bands = || config.bands.iter().map(|&c| CHANNELS[c]).collect::<Vec<_>>().join(",");
    if !config.bands.is_empty() && config.solution.is_some() {
        return Err(Error::InvalidParameter {
            name: "bands",
            value: bands(),
            reason: "colour bands are lit by the scene's own emission: use --solution none".into(),
        });
    }
    if config.cases.is_some() && (config.solution.is_some() || !config.bands.is_empty()) {
        return Err(Error::InvalidParameter {
            name: "emission-file",
            value: if config.bands.is_empty() { "with a true solution".into() } else { bands() },
            reason: "emission cases give E themselves: use --solution none and grey bands".into(),
        });
    }
    Ok(())
}

/// Runs `config` on its `problem`, built already ([`build`]).
pub fn run_problem(config: &RunConfig, problem: Problem) -> Result<Run> {
    check_lighting(config)?;
    let cases = match &config.cases {
        Some(cases) => Some(cases.at_nodes(&problem.scene, &problem.disc)?),
        None => None,
    };
    let u_faces = match &config.solution {
        Some(sol) => Some(sol.on_faces(&problem.scene, &config.params)?),
        None => None,
    };
    let built = build_operator(config, &problem)?;

    let started = Instant::now();
    let (rhs, emission_error_estimate) = match &cases {
        // The cases' mean: the emission whose solution is the cases' mean u.
        Some(cases) => (mean(cases), None),
        None => emission(config, &problem, u_faces.as_deref()),
    };
    let emission_seconds = started.elapsed().as_secs_f64();
    let mut warnings = run_warnings(&problem.scene, &rhs);
    if let Some(estimate) = emission_error_estimate.filter(|&e| e > EMISSION_WARNING) {
        warnings.push(format!(
            "the emissivity of the true solution is uncertain to {estimate:.1e} (relative), above \
             {EMISSION_WARNING:.0e}: the adaptive quadrature ran out of subdivisions; E_n below \
             that level is not meaningful"
        ));
    }

    let started = Instant::now();
    let (outcome, bands, band_reports, cases, case_reports) =
        in_stage(&*config.progress, "solve", || match (&config.cases, cases) {
            (Some(given), Some(columns)) => {
                let (outcome, values, reports) =
                    solve_cases(config, &problem, &built, &given.names, columns)?;
                Ok((outcome, Vec::new(), Vec::new(), values, reports))
            }
            _ => {
                let (outcome, bands, reports) = solve_built(config, &problem, &built, &rhs)?;
                Ok::<_, Error>((outcome, bands, reports, Vec::new(), Vec::new()))
            }
        })?;
    let solve_seconds = started.elapsed().as_secs_f64();
    let u = outcome.u;
    let summary = built.summary(config);
    let distributed = built.distributed_report();

    let Problem { scene, disc, .. } = &problem;
    let error = u_faces.as_ref().map(|uf| {
        disc.nodes()
            .zip(&u)
            .map(|(node, value)| (uf[node.face()].eval(node.position) - value).abs())
            .fold(0.0, f64::max)
    });
    let over_surface = match (&u_faces, config.surface_lattice) {
        (Some(truth), Some(lattice)) => {
            Some(surface_errors(&problem, truth, &u, &config.assembly, &config.emission, lattice)?)
        }
        _ => None,
    };
    let report = RunReport {
        label: RunLabel::new(config, &problem),
        grading: (!config.grade.is_empty()).then_some(config.grading_exponent),
        device: summary.device,
        solver: outcome.solver,
        iterations: outcome.iterations,
        condition_estimate: outcome.condition_estimate,
        refinement_steps: outcome.refinement_steps,
        rows_eliminated: outcome.rows_eliminated,
        warnings,
        notes: scene.notes.clone(),
        bands: band_reports,
        cases: case_reports,
        error,
        setup_seconds: summary.setup_seconds,
        preparation_seconds: summary.preparation_seconds,
        emission_error_estimate,
        emission_seconds,
        solve_seconds,
        residual: outcome.residual,
        pairs: summary.pairs,
        operator: summary.operator,
        compression_tolerance: summary.compression_tolerance,
        operator_bytes: summary.operator_bytes,
        memory_estimate_bytes: summary.memory_estimate_bytes,
        blocks: summary.blocks,
        transfers: summary.transfers.map(|t| t.over(summary.setup_seconds + solve_seconds)),
        peak_rss_bytes: peak_rss_bytes(),
        solution_range: range(&u),
        distributed,
        over_surface,
        u,
    };
    let Problem { scene, mesh, disc, .. } = problem;
    Ok(Run { report, scene, mesh, disc, emission: rhs, bands, cases })
}

/// The mean of equally long vectors.
fn mean(columns: &[Vec<f64>]) -> Vec<f64> {
    let count = columns.len() as f64;
    (0..columns[0].len()).map(|i| columns.iter().map(|c| c[i]).sum::<f64>() / count).collect()
}

/// E at the nodes, from the true solution `u_faces` when there is one (with the estimate of its
/// relative error), else the faces' emissivities.
fn emission(
    config: &RunConfig,
    problem: &Problem,
    u_faces: Option<&[crate::problems::FaceFunction]>,
) -> (Vec<f64>, Option<f64>) {
    let Problem { scene, disc, planner, .. } = problem;
    match u_faces {
        Some(u) => {
            let progress = &*config.progress;
            progress.start("emission", disc.dof());
            let e = emission_at(scene, disc.par_nodes(), planner, u, &config.emission, progress);
            progress.finish();
            (e.values, Some(e.error_estimate))
        }
        None => (disc.nodes().map(|n| scene.faces[n.face()].emission).collect(), None),
    }
}

/// Solves with the built operator for `rhs`, or for each colour band of `config` (then the
/// outcome is the bands' mean, with each band's values and report).
fn solve_built(
    config: &RunConfig,
    problem: &Problem,
    built: &BuiltOperator,
    rhs: &[f64],
) -> Result<(solve::SolveOutcome, Vec<BandValues>, Vec<BandReport>)> {
    let (scene, disc) = (&problem.scene, &problem.disc);
    let bands = &config.bands;
    let per_band = match (built, built.products(config)) {
        _ if bands.is_empty() => None,
        (BuiltOperator::Dense(timed), _) => {
            Some(solve_bands(&timed.assembled.matrix, scene, disc, bands, config.solver)?)
        }
        (_, Some((op, tolerance))) => {
            Some(solve_bands_by_products(op, scene, disc, bands, config.solver, tolerance)?)
        }
        (_, None) => unreachable!("every operator but the host's matrix is known by products"),
    };
    if let Some(per_band) = per_band {
        let (mut values, mut reports, mut outcomes) = (Vec::new(), Vec::new(), Vec::new());
        for (v, r, o) in per_band {
            values.push(v);
            reports.push(r);
            outcomes.push(o);
        }
        return Ok((mean_outcome(outcomes), values, reports));
    }
    let outcome = built.solve_many(config, problem, &[rhs])?.pop().expect("one outcome");
    Ok((outcome, Vec::new(), Vec::new()))
}
