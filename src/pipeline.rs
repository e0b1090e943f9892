//! One solve from end to end (DESIGN.md sec. 2): scene -> mesh -> discretization -> pair plan ->
//! assembly -> emissivity -> solve -> errors, with the time of each stage.

use std::path::PathBuf;
use std::time::Instant;

use rayon::prelude::*;
use serde::Serialize;

use crate::assembly::CollocationMatrix;
use crate::assembly::{self, Assembly, AssemblyOptions, Quadrature};
use crate::discretization::{Discretization, Method};
use crate::error::{Error, Result};
use crate::gpu::{self, GpuAssembler, GpuTimings, Precision};
use crate::mesh::{
    Grading, LineExtent, Mesh, MeshKind, S5Diagonals, Sources, paper_discontinuity_cuts,
    shadow_lines,
};
use crate::operator::{CompressedOperator, CompressionOptions, OperatorChoice, OperatorStats};
use crate::problems::{EmissionOptions, TrueSolution, emission_at};
use crate::progress::ProgressSink;
use crate::scene::{BuiltinScene, CHANNELS, ImportOptions, Scene, SurfaceParameters};
use crate::solution::BandValues;
use crate::solve::{self, SolveOutcome, SolverOptions};
use crate::surface_error::{SurfaceErrors, surface_errors};
use crate::visibility::{PairPlanner, PairStats};

/// Which mesh to build.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum MeshChoice {
    /// Faces split by their diagonals, then refined.
    Uniform,
    /// The paper's discontinuity mesh (sec. 3.1), built by hand for its surfaces, with the given
    /// split of S5's cells.
    Discontinuity(S5Diagonals),
    /// Automatic discontinuity mesh: every face triangulated along its shadow lines
    /// ([`crate::mesh::shadow_lines`]), kept as segments or extended to chords.
    AutoDiscontinuity(LineExtent),
}

impl MeshChoice {
    /// Name used in reports and on the command line.
    pub fn name(&self) -> &'static str {
        match self {
            Self::Uniform => "uniform",
            Self::Discontinuity(S5Diagonals::Paper) => "discontinuity",
            Self::Discontinuity(S5Diagonals::AsUniform) => "discontinuity-uniform-diagonals",
            Self::AutoDiscontinuity(LineExtent::Chords) => "auto-discontinuity",
            Self::AutoDiscontinuity(LineExtent::Segments) => "auto-discontinuity-segments",
        }
    }
}

/// Where the collocation matrix is assembled.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Backend {
    /// Plain Rust on all cores (the reference path).
    Cpu,
    /// WGSL compute shaders through wgpu, in the given precision.
    Gpu(Precision),
}

impl Backend {
    /// `cpu` or `gpu`.
    pub fn name(&self) -> &'static str {
        match self {
            Self::Cpu => "cpu",
            Self::Gpu(_) => "gpu",
        }
    }

    /// Precision of the matrix entries (`f64` on the CPU).
    pub fn precision(&self) -> Precision {
        match self {
            Self::Cpu => Precision::F64,
            Self::Gpu(p) => *p,
        }
    }
}

/// A backend ready to assemble K: on the GPU, the kernels compiled once (the one-time cost that
/// timings of the assembly leave out). Every command that assembles goes through it, so `bench`
/// times the very matrix `solve` uses.
pub enum Assembler {
    /// Plain Rust on all cores.
    Cpu,
    /// The GPU's compiled kernels.
    Gpu(GpuAssembler<'static>),
}

impl Assembler {
    /// Prepares `backend` for `method` and `quadrature` (the GPU evaluates the exact method only).
    pub fn new(backend: Backend, method: Method, quadrature: Quadrature) -> Result<Self> {
        match backend {
            Backend::Cpu => Ok(Self::Cpu),
            Backend::Gpu(_) if quadrature != Quadrature::Exact => Err(Error::InvalidParameter {
                name: "quadrature",
                value: quadrature.name().into(),
                reason: "the GPU backend evaluates the exact method only; use the CPU backend"
                    .into(),
            }),
            Backend::Gpu(precision) => {
                let ctx = gpu::context_for(precision)?;
                Ok(Self::Gpu(GpuAssembler::new(ctx, precision, method)?))
            }
        }
    }

    /// The GPU adapter's name and backend, for reports.
    pub fn device(&self) -> Option<String> {
        match self {
            Self::Cpu => None,
            Self::Gpu(g) => {
                let a = &g.context().adapter;
                Some(format!("{} ({})", a.name, a.backend))
            }
        }
    }

    /// Where the GPU's last assembly spent its time.
    pub fn last_timings(&self) -> Option<GpuTimings> {
        match self {
            Self::Cpu => None,
            Self::Gpu(g) => Some(g.last_timings()),
        }
    }

    /// Assembles K. On the GPU the columns of thin elements, where the closed forms cancel, are
    /// recomputed on the CPU ([`assembly::recompute_thin_columns`]).
    pub fn assemble(
        &self,
        scene: &Scene,
        mesh: &Mesh,
        disc: &Discretization,
        planner: &PairPlanner,
        options: &AssemblyOptions,
        progress: &(dyn Fn(usize) + Sync),
    ) -> Result<Assembly> {
        match self {
            Self::Cpu => assembly::assemble(mesh, disc, planner, options, progress),
            Self::Gpu(g) => {
                let mut a = g.assemble(scene, mesh, disc, planner, options, progress)?;
                assembly::recompute_thin_columns(&mut a, disc, planner, options);
                Ok(a)
            }
        }
    }
}

/// Assembles K on `backend` once (kernels compiled for it); returns the device's name for the GPU.
pub fn assemble_on(
    backend: Backend,
    scene: &Scene,
    mesh: &Mesh,
    disc: &Discretization,
    planner: &PairPlanner,
    options: &AssemblyOptions,
    progress: &(dyn Fn(usize) + Sync),
) -> Result<(Assembly, Option<String>)> {
    let assembler = Assembler::new(backend, disc.method, options.quadrature)?;
    let a = assembler.assemble(scene, mesh, disc, planner, options, progress)?;
    Ok((a, assembler.device()))
}

/// Where a study's series run.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum StudyDevice {
    /// CPU, plus the studies' GPU series where an adapter is found.
    Auto,
    /// CPU only; GPU series are left out.
    Cpu,
    /// Everything that can run on the GPU runs there, in this precision (GPU series keep theirs);
    /// a missing adapter is an error.
    Gpu(Precision),
}

/// Where the scene comes from.
#[derive(Clone, Debug, PartialEq)]
pub enum SceneSource {
    /// A built-in scene.
    Builtin(BuiltinScene),
    /// A `.toml` scene file or an `.obj` / `.stl` mesh ([`crate::scene::load_with`]), and what
    /// to do with its imperfections.
    File(PathBuf, ImportOptions),
    /// `city:NXxNY`: the generated city of NX x NY buildings ([`crate::scene::city`]).
    City(usize, usize),
}

impl SceneSource {
    /// A built-in scene's name, or a path ending in `.toml`, `.obj` or `.stl`.
    pub fn parse(name: &str) -> Result<Self> {
        if crate::scene::is_scene_file(name) {
            Ok(Self::File(PathBuf::from(name), ImportOptions::default()))
        } else if let Some(size) = name.strip_prefix("city:") {
            let parsed =
                size.split_once('x').and_then(|(a, b)| Some((a.parse().ok()?, b.parse().ok()?)));
            let (nx, ny) = parsed.ok_or_else(|| Error::InvalidParameter {
                name: "scene",
                value: name.into(),
                reason: "expected city:NXxNY, e.g. city:35x36".into(),
            })?;
            Ok(Self::City(nx, ny))
        } else {
            Ok(Self::Builtin(name.parse()?))
        }
    }

    /// Builds or loads the scene; `params` is used by the paper's surfaces only.
    pub fn build(&self, params: SurfaceParameters) -> Result<Scene> {
        match self {
            Self::Builtin(b) => b.build(params),
            Self::File(path, import) => crate::scene::load_with(path, *import),
            Self::City(nx, ny) => crate::scene::city(*nx, *ny),
        }
    }

    /// The same source with these import options (they concern scene files only).
    pub fn with_import(self, import: ImportOptions) -> Self {
        match self {
            Self::File(path, _) => Self::File(path, import),
            other => other,
        }
    }

    /// Whether the scene comes from an OBJ file (whose convention is y up).
    pub fn is_obj(&self) -> bool {
        matches!(self, Self::File(path, _)
            if path.extension().is_some_and(|e| e.eq_ignore_ascii_case("obj")))
    }

    /// Whether this is one of the paper's built-in surfaces.
    pub fn is_paper_surface(&self) -> bool {
        matches!(self, Self::Builtin(b) if b.is_paper_surface())
    }
}

/// Everything that defines one run.
#[derive(Clone, Debug)]
pub struct RunConfig {
    /// The scene.
    pub scene: SceneSource,
    /// (A, B, C) for the paper's surfaces.
    pub params: SurfaceParameters,
    /// Mesh kind.
    pub mesh: MeshChoice,
    /// Refinement levels (n = n_0 4^refine).
    pub refine: u32,
    /// Edges to grade the mesh toward (`FACE:K`, [`crate::mesh::Grading`]), and the exponent.
    pub grade: Vec<String>,
    /// Grading exponent q.
    pub grading_exponent: f64,
    /// Collocation method.
    pub method: Method,
    /// A true solution (its E is computed), or `None` to use the faces' emissivities.
    pub solution: Option<TrueSolution>,
    /// Collocation-integral options.
    pub assembly: AssemblyOptions,
    /// Emissivity-integral options.
    pub emission: EmissionOptions,
    /// Where the matrix is assembled.
    pub backend: Backend,
    /// Linear solver and its tolerance.
    pub solver: SolverOptions,
    /// Where progress goes (nowhere by default).
    pub progress: ProgressSink,
    /// Assemble up to this many times and report the fastest (timings of small runs are noisy);
    /// repetition stops once one assembly has taken over [`REPEAT_BELOW_SECONDS`].
    pub setup_repeats: usize,
    /// Also measure the errors over all of S at the sample points of this lattice
    /// ([`crate::surface_error`]), when a true solution is known.
    pub surface_lattice: Option<usize>,
    /// Which operator to store: dense, compressed, or by size.
    pub operator: OperatorChoice,
    /// How the compressed operator is built.
    pub compression: CompressionOptions,
    /// Colour channels (indices into [`CHANNELS`]) to solve for, each with its own rho and E on
    /// the one assembled operator; empty: the grey problem (the channels' means).
    pub bands: Vec<usize>,
}

/// Relative error estimate of E above which `solve` warns: 1e3 times the quadrature's relative
/// tolerance (1e-12): the sum of per-triangle estimates is pessimistic by about that much.
const EMISSION_WARNING: f64 = 1e-9;

/// Assemblies slower than this are not repeated for timing.
pub const REPEAT_BELOW_SECONDS: f64 = 2.0;

impl RunConfig {
    /// The paper's setup for a scene: uniform mesh, centroid method, u = x² + y².
    pub fn paper(scene: BuiltinScene, refine: u32) -> Self {
        Self {
            scene: SceneSource::Builtin(scene),
            params: SurfaceParameters::default(),
            mesh: MeshChoice::Uniform,
            refine,
            grade: Vec::new(),
            grading_exponent: 2.0,
            method: Method::Centroid,
            solution: Some(TrueSolution::X2Y2),
            assembly: AssemblyOptions::default(),
            emission: EmissionOptions::default(),
            backend: Backend::Cpu,
            solver: SolverOptions::default(),
            progress: ProgressSink::default(),
            setup_repeats: 1,
            surface_lattice: None,
            operator: OperatorChoice::Dense,
            compression: CompressionOptions::default(),
            bands: Vec::new(),
        }
    }
}

/// Results of one run.
#[derive(Clone, Debug, Serialize)]
pub struct RunReport {
    /// Scene name.
    pub surface: String,
    /// Mesh kind.
    pub mesh: &'static str,
    /// Grading exponent q, when the mesh is graded toward edges.
    pub grading: Option<f64>,
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
    /// Number of elements.
    pub n: usize,
    /// Number of unknowns.
    pub dof: usize,
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
    /// Block statistics of the compressed operator (`near_entries`, `far_blocks`, `max_rank`,
    /// ...).
    #[serde(flatten)]
    pub blocks: Option<OperatorStats>,
    /// Peak resident memory of the whole process so far, from the OS (Linux), in bytes.
    pub peak_rss_bytes: Option<u64>,
    /// Smallest, mean and largest nodal value of the solution.
    pub solution_range: [f64; 3],
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

/// K for colour channel `channel` from the grey K: node i's row scaled by rho_channel / rho
/// (K includes rho/π per row, and rho = 0 only where every channel is 0).
fn band_matrix(
    grey: &CollocationMatrix,
    scene: &Scene,
    disc: &Discretization,
    channel: usize,
) -> CollocationMatrix {
    let mut k = grey.clone();
    k.rows_mut().zip(disc.nodes.par_iter()).for_each(|(row, node)| {
        let face = &scene.faces[node.face];
        let scale = if face.rho == 0.0 { 0.0 } else { face.channel(channel).0 / face.rho };
        if scale != 1.0 {
            row.iter_mut().for_each(|x| *x *= scale);
        }
    });
    k
}

/// Solves each band in `channels` on the grey K: one scaled copy of K at a time.
fn solve_bands(
    grey: &CollocationMatrix,
    scene: &Scene,
    disc: &Discretization,
    channels: &[usize],
    options: SolverOptions,
) -> Result<Vec<(BandValues, BandReport, SolveOutcome)>> {
    channels
        .iter()
        .map(|&channel| {
            let emission: Vec<f64> =
                disc.nodes.iter().map(|n| scene.faces[n.face].channel(channel).1).collect();
            let k = band_matrix(grey, scene, disc, channel);
            let started = Instant::now();
            let outcome = solve::solve(&k, &emission, options)?;
            let report = BandReport {
                band: CHANNELS[channel],
                solver: outcome.solver,
                iterations: outcome.iterations,
                residual: outcome.residual,
                condition_estimate: outcome.condition_estimate,
                solve_seconds: started.elapsed().as_secs_f64(),
                solution_range: range(&outcome.u),
            };
            let values = BandValues { channel, u: outcome.u.clone(), emission };
            Ok((values, report, outcome))
        })
        .collect()
}

/// Smallest, mean and largest value.
fn range(u: &[f64]) -> [f64; 3] {
    let (lo, hi, sum) =
        u.iter().fold((f64::INFINITY, f64::NEG_INFINITY, 0.0), |(lo, hi, s), &v| {
            (lo.min(v), hi.max(v), s + v)
        });
    [lo, sum / u.len() as f64, hi]
}

/// The scene, mesh and discretization of a configuration.
pub fn build(config: &RunConfig) -> Result<(Scene, Mesh, Discretization)> {
    let scene = config.scene.build(config.params)?;
    let kind = match config.mesh {
        MeshChoice::Uniform => MeshKind::Uniform,
        MeshChoice::Discontinuity(s5) => {
            MeshKind::Discontinuity(paper_discontinuity_cuts(&scene, &config.params, s5)?)
        }
        MeshChoice::AutoDiscontinuity(extent) => {
            // With a true solution every face carries light (E is computed from it everywhere).
            let sources = if config.solution.is_some() { Sources::All } else { Sources::Emitting };
            MeshKind::Constrained(shadow_lines(&scene, sources, extent))
        }
    };
    let mut mesh = Mesh::new(&scene, &kind, config.refine)?;
    if !config.grade.is_empty() {
        mesh.grade(&scene, &Grading::parse(&scene, &config.grade, config.grading_exponent)?)?;
    }
    let disc = Discretization::new(&scene, &mesh, config.method)?;
    Ok((scene, mesh, disc))
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
        }
    }
}

/// Assembles K for `config` up to `config.setup_repeats` times (fewer once one assembly takes over
/// [`REPEAT_BELOW_SECONDS`]), each with a pair plan of its own, with one prepared backend.
fn assemble_timed(
    config: &RunConfig,
    scene: &Scene,
    mesh: &Mesh,
    disc: &Discretization,
) -> Result<TimedAssembly> {
    let started = Instant::now();
    let assembler = Assembler::new(config.backend, disc.method, config.assembly.quadrature)?;
    let preparation_seconds = started.elapsed().as_secs_f64();
    let progress = &config.progress;
    let mut timed = None;
    let mut setup_seconds = f64::INFINITY;
    for _ in 0..config.setup_repeats.max(1) {
        progress.start("assembly", disc.dof());
        let started = Instant::now();
        let planner = PairPlanner::new(scene);
        let assembled =
            assembler.assemble(scene, mesh, disc, &planner, &config.assembly, &|k| {
                progress.advance(k)
            })?;
        let seconds = started.elapsed().as_secs_f64();
        setup_seconds = setup_seconds.min(seconds);
        timed = Some(assembled);
        progress.finish();
        if seconds > REPEAT_BELOW_SECONDS {
            break;
        }
    }
    let assembled = timed.expect("at least one assembly");
    Ok(TimedAssembly { assembled, device: assembler.device(), setup_seconds, preparation_seconds })
}

/// An assembly with its timings.
struct TimedAssembly {
    assembled: Assembly,
    device: Option<String>,
    /// The fastest assembly (pair plan included).
    setup_seconds: f64,
    /// One-time preparation (GPU: compiling the kernels), not part of `setup_seconds`.
    preparation_seconds: f64,
}

/// The operator a run solves with.
enum BuiltOperator {
    Dense(TimedAssembly),
    Compressed { op: CompressedOperator, setup_seconds: f64, preparation_seconds: f64 },
}

/// What a report says of the operator.
struct OperatorSummary {
    operator: &'static str,
    device: Option<String>,
    setup_seconds: f64,
    preparation_seconds: f64,
    pairs: PairStats,
    compression_tolerance: Option<f64>,
    operator_bytes: u64,
    blocks: Option<OperatorStats>,
}

impl BuiltOperator {
    fn summary(&self, config: &RunConfig, dof: usize) -> OperatorSummary {
        match self {
            Self::Dense(t) => OperatorSummary {
                operator: "dense",
                device: t.device.clone(),
                setup_seconds: t.setup_seconds,
                preparation_seconds: t.preparation_seconds,
                pairs: t.assembled.stats,
                compression_tolerance: None,
                operator_bytes: 8 * (dof as u64) * (dof as u64),
                blocks: None,
            },
            Self::Compressed { op, setup_seconds, preparation_seconds } => OperatorSummary {
                operator: "compressed",
                device: op.device.clone(),
                setup_seconds: *setup_seconds,
                preparation_seconds: *preparation_seconds,
                pairs: op.pairs,
                compression_tolerance: Some(config.compression.tolerance),
                operator_bytes: op.stats.operator_bytes,
                blocks: Some(op.stats),
            },
        }
    }
}

/// The compressed operator of `config` for a built scene with `planner`, its entries evaluated
/// by `assembler` (the CPU, or the GPU's pair kernel in batches); refused where the
/// configuration needs the dense matrix (LU, colour bands).
pub fn build_compressed(
    config: &RunConfig,
    assembler: &Assembler,
    scene: &Scene,
    mesh: &Mesh,
    disc: &Discretization,
    planner: &PairPlanner,
) -> Result<CompressedOperator> {
    if !config.bands.is_empty() {
        return Err(Error::InvalidParameter {
            name: "bands",
            value: format!("{} bands", config.bands.len()),
            reason: "colour bands scale the rows of the dense matrix; choose the dense operator"
                .into(),
        });
    }
    if config.solver.choice == solve::SolverChoice::Lu {
        return Err(Error::InvalidParameter {
            name: "solver",
            value: "lu".into(),
            reason: "LU needs the dense matrix; the compressed operator is solved by GMRES \
                     (the iterative solver), or choose the dense operator"
                .into(),
        });
    }
    let device = match assembler {
        Assembler::Cpu => None,
        Assembler::Gpu(g) => Some(gpu::PairEvaluator::new(g, scene, disc, &config.assembly)?),
    };
    let mut op = CompressedOperator::build(
        scene,
        mesh,
        disc,
        planner,
        &config.assembly,
        &config.compression,
        device.as_ref().map(|d| d as &dyn crate::assembly::PairEvaluation),
        &*config.progress,
    )?;
    op.device = assembler.device();
    Ok(op)
}

/// The dense matrix (timed as [`assemble_timed`]) or, when `config.operator` asks for it at this
/// size, the compressed operator (built once, its pair planner included in the setup time, as
/// the dense assembly's is).
fn build_operator(
    config: &RunConfig,
    scene: &Scene,
    mesh: &Mesh,
    disc: &Discretization,
) -> Result<BuiltOperator> {
    if !compresses(config, disc.dof()) {
        return Ok(BuiltOperator::Dense(assemble_timed(config, scene, mesh, disc)?));
    }
    let started = Instant::now();
    let assembler = Assembler::new(config.backend, disc.method, config.assembly.quadrature)?;
    let preparation_seconds = started.elapsed().as_secs_f64();
    let started = Instant::now();
    let op = build_compressed(config, &assembler, scene, mesh, disc, &PairPlanner::new(scene))?;
    let setup_seconds = started.elapsed().as_secs_f64();
    Ok(BuiltOperator::Compressed { op, setup_seconds, preparation_seconds })
}

/// Whether `config` stores the compressed operator for `dof` unknowns: when asked for, or under
/// [`OperatorChoice::Auto`] above its size unless LU or colour bands (which need the dense
/// matrix) are asked for.
pub fn compresses(config: &RunConfig, dof: usize) -> bool {
    match config.operator {
        OperatorChoice::Auto => {
            config.operator.compresses(dof)
                && config.solver.choice != solve::SolverChoice::Lu
                && config.bands.is_empty()
        }
        choice => choice.compresses(dof),
    }
}

/// Peak resident set size of this process (`VmHWM` of /proc/self/status), in bytes.
pub fn peak_rss_bytes() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib * 1024)
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
    if !config.bands.is_empty() && config.solution.is_some() {
        return Err(Error::InvalidParameter {
            name: "bands",
            value: config.bands.iter().map(|&c| CHANNELS[c]).collect::<Vec<_>>().join(","),
            reason: "colour bands are lit by the scene's own emission: use --solution none".into(),
        });
    }
    let (scene, mesh, disc) = build(config)?;
    let u_faces = match &config.solution {
        Some(sol) => Some(sol.on_faces(&scene, &config.params)?),
        None => None,
    };
    let planner = PairPlanner::new(&scene);
    let built = build_operator(config, &scene, &mesh, &disc)?;

    let started = Instant::now();
    let (rhs, emission_error_estimate) = match &u_faces {
        Some(u) => {
            let progress = &config.progress;
            progress.start("emission", disc.dof());
            let e = emission_at(&scene, &disc.nodes, &planner, u, &config.emission, &|k| {
                progress.advance(k)
            });
            progress.finish();
            (e.values, Some(e.error_estimate))
        }
        None => (disc.nodes.iter().map(|n| scene.faces[n.face].emission).collect(), None),
    };
    let emission_seconds = started.elapsed().as_secs_f64();
    let mut warnings = run_warnings(&scene, &rhs);
    if let Some(estimate) = emission_error_estimate.filter(|&e| e > EMISSION_WARNING) {
        warnings.push(format!(
            "the emissivity of the true solution is uncertain to {estimate:.1e} (relative), above \
             {EMISSION_WARNING:.0e}: the adaptive quadrature ran out of subdivisions; E_n below \
             that level is not meaningful"
        ));
    }

    let started = Instant::now();
    let (outcome, bands, band_reports) = match &built {
        BuiltOperator::Dense(timed) if !config.bands.is_empty() => {
            let (mut values, mut reports, mut outcomes) = (Vec::new(), Vec::new(), Vec::new());
            for (v, r, o) in
                solve_bands(&timed.assembled.matrix, &scene, &disc, &config.bands, config.solver)?
            {
                values.push(v);
                reports.push(r);
                outcomes.push(o);
            }
            (mean_outcome(outcomes), values, reports)
        }
        BuiltOperator::Dense(timed) => {
            (solve::solve(&timed.assembled.matrix, &rhs, config.solver)?, Vec::new(), Vec::new())
        }
        BuiltOperator::Compressed { op, .. } => {
            let rho: Vec<f64> = disc.nodes.iter().map(|n| n.rho).collect();
            let tolerance = config.compression.tolerance;
            let outcome = solve::solve_compressed(op, &rhs, &rho, config.solver, tolerance)?;
            (outcome, Vec::new(), Vec::new())
        }
    };
    let solve_seconds = started.elapsed().as_secs_f64();
    let u = outcome.u;
    let summary = built.summary(config, disc.dof());

    let error = u_faces.as_ref().map(|uf| {
        disc.nodes
            .iter()
            .zip(&u)
            .map(|(node, value)| (uf[node.face].eval(node.position) - value).abs())
            .fold(0.0, f64::max)
    });
    let over_surface = match (&u_faces, config.surface_lattice) {
        (Some(truth), Some(lattice)) => Some(surface_errors(
            &scene,
            &mesh,
            &disc,
            &planner,
            truth,
            &u,
            &config.assembly,
            &config.emission,
            lattice,
        )?),
        _ => None,
    };
    let report = RunReport {
        surface: scene.name.clone(),
        mesh: config.mesh.name(),
        grading: (!config.grade.is_empty()).then_some(config.grading_exponent),
        method: config.method.name(),
        alpha: config.method.alpha(),
        quadrature: config.assembly.quadrature,
        backend: config.backend.name(),
        precision: config.backend.precision().name(),
        device: summary.device,
        solver: outcome.solver,
        iterations: outcome.iterations,
        condition_estimate: outcome.condition_estimate,
        refinement_steps: outcome.refinement_steps,
        rows_eliminated: outcome.rows_eliminated,
        warnings,
        notes: scene.notes.clone(),
        bands: band_reports,
        n: mesh.len(),
        dof: disc.dof(),
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
        blocks: summary.blocks,
        peak_rss_bytes: peak_rss_bytes(),
        solution_range: range(&u),
        over_surface,
        u,
    };
    Ok(Run { report, scene, mesh, disc, emission: rhs, bands })
}

/// The bands' solves as one: u their mean, iterations summed, the worst residual, condition
/// and refinement.
fn mean_outcome(outcomes: Vec<SolveOutcome>) -> SolveOutcome {
    let count = outcomes.len() as f64;
    let mut mean = outcomes[0].clone();
    mean.u.iter_mut().for_each(|x| *x = 0.0);
    mean.iterations = 0;
    for o in &outcomes {
        mean.u.iter_mut().zip(&o.u).for_each(|(m, x)| *m += x / count);
        mean.iterations += o.iterations;
        mean.residual = mean.residual.max(o.residual);
        mean.refinement_steps = mean.refinement_steps.max(o.refinement_steps);
        mean.condition_estimate = match (mean.condition_estimate, o.condition_estimate) {
            (Some(a), Some(b)) => Some(a.max(b)),
            (a, b) => a.or(b),
        };
    }
    mean
}
