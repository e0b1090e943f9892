//! What defines one run: the scene's source, the mesh, the backend, and every option of the
//! stages ([`RunConfig`]).

use std::path::PathBuf;

use serde::Serialize;

use crate::assembly::AssemblyOptions;
use crate::discretization::Method;
use crate::distributed::Ranks;
use crate::error::{Error, Result};
use crate::gpu::Precision;
use crate::mesh::{LineExtent, S5Diagonals};
use crate::operator::{CompressionOptions, OperatorChoice};
use crate::problems::{EmissionCases, EmissionOptions, TrueSolution};
use crate::progress::ProgressSink;
use crate::scene::{BuiltinScene, ImportOptions, Scene, SurfaceParameters};
use crate::solve::SolverOptions;

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

/// Where the collocation matrix is assembled.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Backend {
    /// Plain Rust on all cores (the reference path).
    Cpu,
    /// WGSL compute shaders through wgpu, in the given precision.
    Gpu(Precision),
}

impl Backend {
    /// Precision of the matrix entries (`f64` on the CPU).
    pub fn precision(&self) -> Precision {
        match self {
            Self::Cpu => Precision::F64,
            Self::Gpu(p) => *p,
        }
    }
}

/// Where the scene comes from.
#[derive(Clone, Debug)]
pub enum SceneSource {
    /// A built-in scene.
    Builtin(BuiltinScene),
    /// A `.toml` scene file or an `.obj` / `.stl` mesh ([`crate::scene::load_with`]), and what
    /// to do with its imperfections.
    File(PathBuf, ImportOptions),
    /// `city:NXxNY`: the generated city of NX x NY buildings ([`crate::scene::city`]), or with
    /// `:lit` under an emitting sky panel ([`crate::scene::lit_city`]).
    City(usize, usize, bool),
    /// A scene built already (from arrays, by the Python package).
    Given(std::sync::Arc<Scene>),
}

impl SceneSource {
    /// A built-in scene's name, or a path ending in `.toml`, `.obj` or `.stl`.
    pub fn parse(name: &str) -> Result<Self> {
        if crate::scene::is_scene_file(name) {
            Ok(Self::File(PathBuf::from(name), ImportOptions::default()))
        } else if let Some(size) = name.strip_prefix("city:") {
            let (size, lit) = match size.strip_suffix(":lit") {
                Some(size) => (size, true),
                None => (size, false),
            };
            let parsed =
                size.split_once('x').and_then(|(a, b)| Some((a.parse().ok()?, b.parse().ok()?)));
            let (nx, ny) = parsed.ok_or_else(|| Error::InvalidParameter {
                name: "scene",
                value: name.into(),
                reason: "expected city:NXxNY or city:NXxNY:lit, e.g. city:35x36".into(),
            })?;
            Ok(Self::City(nx, ny, lit))
        } else {
            Ok(Self::Builtin(name.parse()?))
        }
    }

    /// Builds or loads the scene; `params` is used by the paper's surfaces only.
    pub fn build(&self, params: SurfaceParameters) -> Result<Scene> {
        match self {
            Self::Builtin(b) => b.build(params),
            Self::File(path, import) => crate::scene::load_with(path, *import),
            Self::City(nx, ny, false) => crate::scene::city(*nx, *ny),
            Self::City(nx, ny, true) => crate::scene::lit_city(*nx, *ny),
            Self::Given(scene) => Ok(Scene::clone(scene)),
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
    /// Precision of a dense K kept in the GPU's memory (`--storage`): f64, or f32 on request
    /// (half the memory and the products' reads; the error it adds is measured and reported).
    pub storage: Precision,
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
    /// Most memory the run may hold resident, in bytes (`None`: a share of what is available
    /// for each large structure); installed for the run's allocations by [`super::build_on`].
    pub memory_limit: Option<u64>,
    /// Colour channels (indices into [`CHANNELS`]) to solve for, each with its own rho and E on
    /// the one assembled operator; empty: the grey problem (the channels' means).
    pub bands: Vec<usize>,
    /// Emission cases solved on the one operator instead of the scene's emission (then the
    /// solution must be `None` and the bands grey).
    pub cases: Option<EmissionCases>,
    /// Read the operator from this file (`assemble --save`) instead of building it.
    pub operator_file: Option<PathBuf>,
    /// The ranks of a distributed run (`mpirun -np N`, N > 1), or `None` for one process:
    /// the compressed operator is then spread over them ([`crate::distributed`]).
    pub ranks: Option<Ranks>,
}

/// Assemblies slower than this are not repeated for timing.
pub const REPEAT_BELOW_SECONDS: f64 = 2.0;

impl RunConfig {
    /// The paper's setup for a scene: uniform mesh, centroid method, u = x² + y².
    pub fn paper(scene: BuiltinScene, refine: u32) -> Self {
        Self { refine, solution: Some(TrueSolution::X2Y2), ..Self::of(SceneSource::Builtin(scene)) }
    }

    /// The defaults for `scene`: refine 0, uniform mesh, centroid method with the default
    /// options of its integrals, no true solution, dense operator on the CPU, one process.
    pub fn of(scene: SceneSource) -> Self {
        Self {
            scene,
            params: SurfaceParameters::default(),
            mesh: MeshChoice::Uniform,
            refine: 0,
            grade: Vec::new(),
            grading_exponent: 2.0,
            method: Method::Centroid,
            solution: None,
            assembly: AssemblyOptions::default(),
            emission: EmissionOptions::default(),
            backend: Backend::Cpu,
            storage: Precision::F64,
            solver: SolverOptions::default(),
            progress: ProgressSink::default(),
            setup_repeats: 1,
            surface_lattice: None,
            operator: OperatorChoice::Dense,
            compression: CompressionOptions::default(),
            memory_limit: None,
            bands: Vec::new(),
            cases: None,
            operator_file: None,
            ranks: None,
        }
    }
}
