//! The command line: the arguments (clap), and one module per command with what it prints.

pub(crate) mod assemble;
pub(crate) mod bench;
pub(crate) mod bench_plan;
pub(crate) mod gpu_check;
pub(crate) mod inspect;
pub(crate) mod output;
pub(crate) mod progress;
pub(crate) mod solve;
pub(crate) mod study;
pub(crate) mod viewfactors;

use clap::{Args, Parser, Subcommand, ValueEnum};

use std::sync::OnceLock;

use radiosity::assembly::{AssemblyOptions, Quadrature};
use radiosity::discretization::Method;
use radiosity::distributed::Ranks;
use radiosity::error::{Error, Result};
use radiosity::gpu::Precision;
use radiosity::mesh::{LineExtent, S5Diagonals};
use radiosity::operator::{CompressionOptions, OperatorChoice, ShadowedBlocks};
use radiosity::pipeline::{Backend, MeshChoice, RunConfig, SceneSource};
use radiosity::problems::{EmissionCases, EmissionOptions, TrueSolution};
use radiosity::report::Tone;
use radiosity::scene::{Coplanar, Duplicates, ImportOptions, NonPlanar, SurfaceParameters};
use radiosity::solve::{SolverChoice, SolverOptions};

#[derive(Parser)]
#[command(
    name = "radiosity",
    version,
    about = "Collocation solver for the occluded radiosity equation (Atkinson, Chien & Seol 2000)"
)]
pub(crate) struct Cli {
    #[command(subcommand)]
    pub(crate) command: Command,
}

#[derive(Subcommand)]
pub(crate) enum Command {
    /// Reproduce a table or figure of the paper, or run a study (ids: table-3.1 .. table-3.5,
    /// table-4.1, table-4.2, figure-3.4 .. figure-3.7, error-vs-time, grading)
    Study(StudyArgs),
    /// Solve one problem and report its error and timings
    Solve(SolveArgs),
    /// Matrix statistics: row sums of K/rho and pair-class counts
    Inspect(SolveArgs),
    /// Assemble the same matrix on several backends: timings, pairs per second, differences
    Bench(BenchArgs),
    /// Assemble the collocation matrix K and write it as a NumPy .npy file
    Assemble(AssembleArgs),
    /// Element-to-element view factors F_ij, with reciprocity and closure checks
    Viewfactors(ViewFactorArgs),
    /// Time the pair plan (views of sampled nodes against every face) with and without the
    /// occluder index (R*-tree), and check that both give the same views
    BenchPlan {
        /// Scene (e.g. city:35x36, about 10 000 faces)
        #[arg(long, default_value = "city:35x36")]
        scene: String,
        /// Nodes sampled (face centres spread over the scene)
        #[arg(long, default_value_t = 100)]
        nodes: usize,
        /// Write JSON to PATH (`-` for standard output) instead of text
        #[arg(long, value_name = "PATH")]
        json: Option<String>,
    },
    /// The GPU adapter, its f64 support, and the worst errors (ulp) of the WGSL math library
    GpuCheck {
        /// Samples per function
        #[arg(long, default_value_t = 1_000_000)]
        samples: usize,
        /// Precision of the math library to test
        #[arg(long, value_enum, default_value_t = PrecisionArg::F64)]
        precision: PrecisionArg,
        /// Write JSON to PATH (`-` for standard output) instead of text
        #[arg(long, value_name = "PATH")]
        json: Option<String>,
    },
}

/// `radiosity study`'s arguments.
#[derive(Args)]
pub(crate) struct StudyArgs {
    /// Study id
    pub(crate) id: String,
    /// Largest number of elements n to run (default: the paper's largest)
    #[arg(long)]
    pub(crate) max_n: Option<usize>,
    /// Where to assemble: cpu (GPU series left out), gpu (everything that can runs on the
    /// GPU); default: the CPU, plus the study's GPU series where an adapter is found
    #[arg(long, value_enum)]
    pub(crate) backend: Option<BackendArg>,
    /// Precision of the GPU kernels with --backend gpu
    #[arg(long, value_enum, default_value_t = PrecisionArg::F64)]
    pub(crate) precision: PrecisionArg,
    /// Directory for the plots (PNG and SVG) of the figure and error-vs-time studies
    #[arg(long, value_name = "DIR", default_value = "figures")]
    pub(crate) figures: String,
    /// Also write JSON to PATH; `-`: JSON on standard output instead of the text table
    #[arg(long, value_name = "PATH")]
    pub(crate) json: Option<String>,
    /// Print Markdown tables instead of aligned text
    #[arg(long)]
    pub(crate) markdown: bool,
    /// `study compression` on this scene (built-in name, city:NXxNY[:lit], or a .toml, .obj or
    /// .stl file) instead of the five-piece surface: centroid method, the scene's own emission
    #[arg(long)]
    pub(crate) scene: Option<String>,
    /// `study compression`'s tolerances, comma-separated [default: 1e-3,1e-6,1e-9]
    #[arg(long, value_delimiter = ',')]
    pub(crate) tolerances: Option<Vec<f64>>,
    /// `study compression` with shadowed blocks (as `solve --shadowed-blocks`)
    #[arg(long)]
    pub(crate) shadowed_blocks: bool,
}

#[derive(Clone, Copy, ValueEnum)]
pub(crate) enum MethodArg {
    Centroid,
    Linear,
}

#[derive(Clone, Copy, ValueEnum)]
pub(crate) enum MeshArg {
    /// Faces split by their diagonals, then refined
    Uniform,
    /// The paper's hand-built discontinuity mesh (four-piece, five-piece)
    Discontinuity,
    /// The same, with S5's cells split by the uniform mesh's diagonal instead of the paper's
    DiscontinuityUniformDiagonals,
    /// Shadow lines found automatically, faces triangulated along them (any scene)
    AutoDiscontinuity,
}

#[derive(Clone, Copy, ValueEnum)]
pub(crate) enum ShadowLinesArg {
    /// Each shadow line extended across its face (as the paper's mesh)
    Chords,
    /// Only where the visibility events are
    Segments,
}

#[derive(Clone, Copy, PartialEq, Eq, ValueEnum)]
pub(crate) enum BackendArg {
    Cpu,
    Gpu,
}

#[derive(Clone, Copy, PartialEq, Eq, ValueEnum)]
pub(crate) enum PrecisionArg {
    F64,
    F32,
}

#[derive(Clone, Copy, PartialEq, Eq, ValueEnum)]
pub(crate) enum SolverArg {
    Auto,
    Lu,
    Iterative,
}

#[derive(Clone, Copy, PartialEq, Eq, ValueEnum)]
pub(crate) enum QuadratureArg {
    Exact,
    SevenPoint,
    Gauss,
}

/// The scene, its mesh and the collocation method.
#[derive(Args)]
pub(crate) struct GeometryArgs {
    /// Scene: four-piece, five-piece, cube, baffled-box, a generated city (city:NXxNY, or
    /// city:NXxNY:lit under an emitting sky panel), or a scene file (.toml, .obj, .stl)
    #[arg(long)]
    pub(crate) scene: String,
    /// Collocation method
    #[arg(long, value_enum, default_value_t = MethodArg::Centroid)]
    pub(crate) method: MethodArg,
    /// Node parameter alpha of the linear method, in [0, 1/3) (default 1/6)
    #[arg(long)]
    pub(crate) alpha: Option<f64>,
    /// Mesh
    #[arg(long, value_enum, default_value_t = MeshArg::Uniform)]
    pub(crate) mesh: MeshArg,
    /// Extent of the shadow lines of --mesh auto-discontinuity: chords give the paper's mesh on
    /// its surfaces, segments far fewer elements in scenes with many occluders
    #[arg(long, value_enum, default_value_t = ShadowLinesArg::Segments)]
    pub(crate) shadow_lines: ShadowLinesArg,
    /// Grade the mesh toward an edge of a face: FACE:K names the edge from vertex K to K+1
    /// (repeatable; e.g. S1:2 and S5:3, the common edge of the five-piece surface)
    #[arg(long, value_name = "FACE:K")]
    pub(crate) grade: Vec<String>,
    /// Grading exponent q: a point at distance d from a graded edge moves to D (d/D)^q
    #[arg(long, default_value_t = 2.0)]
    pub(crate) grading: f64,
    /// Refinement levels: n = n0 * 4^refine
    #[arg(long, default_value_t = 2)]
    pub(crate) refine: u32,
    /// Surface parameters A,B,C of the paper's surfaces
    #[arg(long, value_name = "A,B,C", default_value = "5,2,1")]
    pub(crate) params: String,
    /// How the collocation integrals are evaluated: closed forms (+ IMT), or the paper's graded
    /// 7-point or collapsed-Gauss rules (sec. 4.2)
    #[arg(long, value_enum, default_value_t = QuadratureArg::Exact)]
    pub(crate) quadrature: QuadratureArg,
    /// MaxLev of the seven-point and gauss quadratures: 4^MaxLev subtriangles, or 2^(IBase+MaxLev)
    /// Gauss points per dimension, next to the node
    #[arg(long, default_value_t = 3)]
    pub(crate) max_level: u32,
    /// IBase of the gauss quadrature: 2^IBase points per dimension far from the node
    #[arg(long, default_value_t = 1)]
    pub(crate) ibase: u32,
    /// The quadrature level is MaxLev within this many element diameters of the node, and falls by
    /// one per doubling of the distance
    #[arg(long, default_value_t = radiosity::kernels::graded::DEFAULT_NEAR)]
    pub(crate) near_ratio: f64,
    /// IMT subintervals for the linear method's 1-D integrals
    #[arg(long, default_value_t = 128)]
    pub(crate) imt_nodes: usize,
    /// Use the paper's closed forms for every pair, also far from the node and on thin elements
    /// (slower, and less accurate there, where the closed forms cancel)
    #[arg(long)]
    pub(crate) no_far_field: bool,
    #[command(flatten)]
    pub(crate) import: ImportArgs,
}

/// Where the matrix is assembled.
#[derive(Args)]
pub(crate) struct DeviceArgs {
    /// Where the collocation matrix is assembled
    #[arg(long, value_enum, default_value_t = BackendArg::Cpu)]
    pub(crate) backend: BackendArg,
    /// Precision of the GPU kernels
    #[arg(long, value_enum, default_value_t = PrecisionArg::F64)]
    pub(crate) precision: PrecisionArg,
}

/// Which operator to store, and how to compress it.
#[derive(Args)]
pub(crate) struct OperatorArgs {
    /// Operator: dense (every entry stored; the reference), compressed (exact blocks near,
    /// low-rank blocks far), or auto (compressed above 12 000 unknowns)
    #[arg(long, value_enum, default_value_t = OperatorArg::Auto)]
    pub(crate) operator: OperatorArg,
    /// Relative error of each low-rank block of the compressed operator, in (0, 1): its cross
    /// approximation's, and half as much again from its recompression
    #[arg(long, value_name = "T", default_value_t = radiosity::operator::DEFAULT_TOLERANCE)]
    pub(crate) compression_tolerance: f64,
    /// Compress the blocks that occluders or tangent planes cut once, without occlusion, and
    /// keep only their partly visible pairs exact: less memory and setup where faces hold many
    /// elements [default: where they hold at least 512 on average]
    #[arg(long, conflicts_with = "no_shadowed_blocks")]
    pub(crate) shadowed_blocks: bool,
    /// Never make shadowed blocks: split the blocks that occluders or tangent planes cut down
    /// to exact leaves and low-rank blocks
    #[arg(long)]
    pub(crate) no_shadowed_blocks: bool,
    /// Most memory the run may hold resident (bytes, or with K, M, G or T: powers of 1024); a
    /// matrix that would pass it is refused before it is built, a compressed operator before
    /// its build where the estimate of its peak (from a sample of its blocks) cannot fit, or
    /// else where its build reaches it [default: 80 % of the available memory for each large
    /// structure]
    #[arg(long, value_name = "BYTES", value_parser = parse_bytes)]
    pub(crate) memory_limit: Option<u64>,
}

/// A size in bytes: digits, optionally with K, M, G or T (powers of 1024; `B` or `iB` may
/// follow).
fn parse_bytes(text: &str) -> std::result::Result<u64, String> {
    let t = text.trim();
    let t = t.strip_suffix("iB").or_else(|| t.strip_suffix('B')).unwrap_or(t);
    let (digits, shift) = match t.char_indices().last() {
        Some((k, c)) if c.is_ascii_alphabetic() => {
            let shift = match c.to_ascii_uppercase() {
                'K' => 10,
                'M' => 20,
                'G' => 30,
                'T' => 40,
                _ => return Err(format!("'{text}': the unit must be K, M, G or T")),
            };
            (&t[..k], shift)
        }
        _ => (t, 0),
    };
    let value: f64 = digits.trim().parse().map_err(|_| format!("'{text}' is no size in bytes"))?;
    let bytes = value * (1u64 << shift) as f64;
    if !(bytes.is_finite() && bytes >= 1.0 && bytes < u64::MAX as f64) {
        return Err(format!("'{text}': the limit must be at least one byte"));
    }
    Ok(bytes as u64)
}

#[derive(Clone, Copy, Debug, ValueEnum)]
pub(crate) enum OperatorArg {
    Auto,
    Dense,
    Compressed,
}

impl OperatorArgs {
    /// Sets the operator of `config`, refusing a tolerance outside (0, 1).
    pub(crate) fn apply(&self, config: &mut RunConfig) -> Result<()> {
        config.operator = match self.operator {
            OperatorArg::Auto => OperatorChoice::Auto,
            OperatorArg::Dense => OperatorChoice::Dense,
            OperatorArg::Compressed => OperatorChoice::Compressed,
        };
        config.compression.tolerance = self.compression_tolerance;
        config.compression.shadowed_blocks = match (self.shadowed_blocks, self.no_shadowed_blocks) {
            (true, _) => ShadowedBlocks::On,
            (_, true) => ShadowedBlocks::Off,
            _ => ShadowedBlocks::Auto,
        };
        radiosity::assembly::set_memory_limit(self.memory_limit);
        config.compression.validate()
    }
}

#[derive(Args)]
pub(crate) struct SolveArgs {
    #[command(flatten)]
    pub(crate) geometry: GeometryArgs,
    #[command(flatten)]
    pub(crate) device: DeviceArgs,
    /// Precision of the dense matrix kept in the GPU's memory (`--backend gpu --solver
    /// iterative`): f32 halves its memory and the products' reads; the error it adds is
    /// measured on every entry and reported
    #[arg(long, value_enum, default_value_t = PrecisionArg::F64)]
    pub(crate) storage: PrecisionArg,
    #[command(flatten)]
    pub(crate) operator: OperatorArgs,
    /// True solution (x2y2, shadow, edge, none); default x2y2 on the paper's surfaces, none elsewhere
    #[arg(long)]
    pub(crate) solution: Option<String>,
    /// beta of the shadow (3.3) or edge (3.4) solution
    #[arg(long)]
    pub(crate) beta: Option<f64>,
    /// gamma of the shadow solution (3.3)
    #[arg(long)]
    pub(crate) gamma: Option<f64>,
    /// Linear solver: LU up to 6000 unknowns and GMRES beyond (auto), or forced
    #[arg(long, value_enum, default_value_t = SolverArg::Auto)]
    pub(crate) solver: SolverArg,
    /// Relative residual ||E - (I - K) u||_2 / ||E||_2 at which the iterative solver stops
    #[arg(long, default_value_t = radiosity::solve::DEFAULT_TOLERANCE)]
    pub(crate) tolerance: f64,
    /// Read the operator from this file (written by `assemble --save`) instead of building it;
    /// refused if it was built for another scene, mesh, method or tolerance
    #[arg(long, value_name = "OP.bin")]
    pub(crate) operator_file: Option<String>,
    /// Solve one emission case per column of this CSV file on the one operator (one row per
    /// face, in the scene's order, or one per node; a header row may name the cases); outputs
    /// get u and E per case
    #[arg(long, value_name = "E.csv")]
    pub(crate) emission_file: Option<String>,
    /// Also report the largest errors over all of S, of u_n and of the iterated solution E + K u_n,
    /// at the interior points of a barycentric lattice of spacing 1/M in every element
    #[arg(long, value_name = "M")]
    pub(crate) surface_lattice: Option<usize>,
    /// Write JSON to PATH (`-` for standard output) instead of text
    #[arg(long, value_name = "PATH")]
    pub(crate) json: Option<String>,
    #[command(flatten)]
    pub(crate) outputs: OutputArgs,
    #[command(flatten)]
    pub(crate) colour: ColourArgs,
}

/// Files written from a solution.
#[derive(Args)]
pub(crate) struct OutputArgs {
    /// Write the mesh with u, E, rho per element and u at the vertices as VTK (.vtu, for ParaView)
    #[arg(long, value_name = "FILE.vtu")]
    pub(crate) vtu: Option<String>,
    /// Write the nodal values (position, face, rho, E, u) as CSV
    #[arg(long, value_name = "FILE.csv")]
    pub(crate) csv: Option<String>,
    /// Render a false-colour picture of u (back faces culled: a closed room seen from outside
    /// shows its inside)
    #[arg(long, value_name = "FILE.png")]
    pub(crate) png: Option<String>,
    /// Picture size in pixels
    #[arg(long, value_name = "WxH", default_value = "1200x800")]
    pub(crate) png_size: String,
    /// Eye position of the picture (default: outside the scene, from the south-west, above)
    #[arg(long, value_name = "X,Y,Z")]
    pub(crate) eye: Option<String>,
    /// Point the picture looks at (default: the centre of the scene)
    #[arg(long, value_name = "X,Y,Z")]
    pub(crate) target: Option<String>,
}

#[derive(Args)]
pub(crate) struct BenchArgs {
    #[command(flatten)]
    pub(crate) geometry: GeometryArgs,
    #[command(flatten)]
    pub(crate) operator: OperatorArgs,
    /// Backends to run, comma separated [default: cpu, and gpu where an adapter can run the
    /// precision asked for]
    #[arg(long, value_enum, value_delimiter = ',')]
    pub(crate) backends: Option<Vec<BackendArg>>,
    /// Precision of the GPU kernels
    #[arg(long, value_enum, default_value_t = PrecisionArg::F64)]
    pub(crate) precision: PrecisionArg,
    /// Repetitions per backend (the best time counts)
    #[arg(long, default_value_t = 3)]
    pub(crate) repeats: usize,
    /// Write JSON to PATH (`-` for standard output) instead of text
    #[arg(long, value_name = "PATH")]
    pub(crate) json: Option<String>,
}

#[derive(Args)]
pub(crate) struct ViewFactorArgs {
    #[command(flatten)]
    pub(crate) geometry: GeometryArgs,
    /// Absolute tolerance on each F_ij: the outer integral is refined where its error estimates
    /// (two Gauss orders, or two tanh-sinh levels where elements touch) add up to more
    #[arg(long, default_value_t = 1e-10)]
    pub(crate) tolerance: f64,
    /// Most times a touching part is split into four where the tanh-sinh levels disagree; each
    /// split costs up to 4x its time (the finest level is far more accurate than the level
    /// difference says: on the paper's surface, reciprocity is 5e-11 without splitting)
    #[arg(long, default_value_t = 0)]
    pub(crate) max_depth: u32,
    /// Integrate F_ij and F_ji each, so that reciprocity checks the accuracy (twice the time);
    /// by default each pair is integrated once, over the smaller element, and the other entry
    /// is A_i F_ij / A_j
    #[arg(long)]
    pub(crate) each_direction: bool,
    /// Write F (n x n, row-major) to FILE: NumPy .npy or .csv (dense), or only its non-zero
    /// entries as SciPy sparse CSR .npz (scipy.sparse.load_npz) or Matrix Market .mtx
    #[arg(long, value_name = "FILE")]
    pub(crate) output: Option<String>,
    /// Write the summary as JSON to PATH (`-` for standard output) instead of text
    #[arg(long, value_name = "PATH")]
    pub(crate) json: Option<String>,
}

#[derive(Args)]
pub(crate) struct AssembleArgs {
    #[command(flatten)]
    pub(crate) geometry: GeometryArgs,
    #[command(flatten)]
    pub(crate) device: DeviceArgs,
    #[command(flatten)]
    pub(crate) operator: OperatorArgs,
    /// Write the dense matrix K to this NumPy file (.npy, float64, row-major dof x dof)
    #[arg(long, value_name = "FILE.npy")]
    pub(crate) output: Option<String>,
    /// Save the operator (dense or compressed, as --operator chooses) for `solve
    /// --operator-file`: a versioned binary file that records the scene, mesh and method it
    /// was built for
    #[arg(long, value_name = "OP.bin")]
    pub(crate) save: Option<String>,
}

pub(crate) fn parse_params(text: &str) -> Result<SurfaceParameters> {
    let bad = || Error::InvalidParameter {
        name: "params",
        value: text.into(),
        reason: "expected three numbers A,B,C".into(),
    };
    let values: Vec<f64> = text
        .split(',')
        .map(|s| s.trim().parse::<f64>())
        .collect::<std::result::Result<_, _>>()
        .map_err(|_| bad())?;
    let [a, b, c] = values[..] else { return Err(bad()) };
    let p = SurfaceParameters { a, b, c };
    p.validate()?;
    Ok(p)
}

pub(crate) fn backend(b: BackendArg, p: PrecisionArg) -> Backend {
    match b {
        BackendArg::Cpu => Backend::Cpu,
        BackendArg::Gpu => Backend::Gpu(match p {
            PrecisionArg::F64 => Precision::F64,
            PrecisionArg::F32 => Precision::F32,
        }),
    }
}

impl GeometryArgs {
    pub(crate) fn quadrature(&self) -> Result<Quadrature> {
        let (max_level, ibase, near_ratio) = (self.max_level, self.ibase, self.near_ratio);
        let q = match self.quadrature {
            QuadratureArg::Exact => Quadrature::Exact,
            QuadratureArg::SevenPoint => Quadrature::SevenPoint { max_level, near_ratio },
            QuadratureArg::Gauss => Quadrature::Gauss { ibase, max_level, near_ratio },
        };
        q.validate()?;
        Ok(q)
    }

    /// A configuration with the paper's x2y2 solution on the paper's surfaces, none elsewhere.
    pub(crate) fn config(&self) -> Result<RunConfig> {
        let scene = SceneSource::parse(&self.scene)?.with_import(self.import.options());
        let method = match self.method {
            MethodArg::Centroid if self.alpha.is_some() => {
                return Err(Error::InvalidParameter {
                    name: "alpha",
                    value: format!("{}", self.alpha.unwrap_or_default()),
                    reason: "alpha belongs to --method linear".into(),
                });
            }
            MethodArg::Centroid => Method::Centroid,
            MethodArg::Linear => Method::linear(self.alpha.unwrap_or(Method::PAPER_ALPHA))?,
        };
        if self.imt_nodes < 2 {
            return Err(Error::InvalidParameter {
                name: "imt-nodes",
                value: self.imt_nodes.to_string(),
                reason: "the IMT rule needs at least 2 subintervals".into(),
            });
        }
        let solution = scene.is_paper_surface().then_some(TrueSolution::X2Y2);
        Ok(RunConfig {
            scene,
            params: parse_params(&self.params)?,
            mesh: match self.mesh {
                MeshArg::Uniform => MeshChoice::Uniform,
                MeshArg::Discontinuity => MeshChoice::Discontinuity(S5Diagonals::Paper),
                MeshArg::DiscontinuityUniformDiagonals => {
                    MeshChoice::Discontinuity(S5Diagonals::AsUniform)
                }
                MeshArg::AutoDiscontinuity => {
                    MeshChoice::AutoDiscontinuity(match self.shadow_lines {
                        ShadowLinesArg::Chords => LineExtent::Chords,
                        ShadowLinesArg::Segments => LineExtent::Segments,
                    })
                }
            },
            refine: self.refine,
            grade: self.grade.clone(),
            grading_exponent: self.grading,
            method,
            solution,
            assembly: AssemblyOptions {
                quadrature: self.quadrature()?,
                imt_nodes: self.imt_nodes,
                far_field: !self.no_far_field,
                ..Default::default()
            },
            emission: EmissionOptions::default(),
            backend: Backend::Cpu,
            storage: Precision::F64,
            solver: SolverOptions::default(),
            progress: if is_root() { progress::on_stderr() } else { Default::default() },
            setup_repeats: 1,
            surface_lattice: None,
            operator: OperatorChoice::Dense,
            compression: CompressionOptions::default(),
            bands: Vec::new(),
            cases: None,
            operator_file: None,
            ranks: world(),
        })
    }
}

impl SolveArgs {
    pub(crate) fn config(&self) -> Result<RunConfig> {
        let mut config = self.geometry.config()?;
        if let Some(name) = &self.solution {
            config.solution = if name == "none" {
                None
            } else {
                Some(TrueSolution::parse(name, self.beta, self.gamma)?)
            };
        } else if let Some(TrueSolution::X2Y2) = config.solution {
            if self.beta.is_some() || self.gamma.is_some() {
                return Err(Error::InvalidParameter {
                    name: "beta/gamma",
                    value: "given".into(),
                    reason: "beta and gamma belong to --solution shadow or edge".into(),
                });
            }
        }
        config.backend = backend(self.device.backend, self.device.precision);
        config.storage = backend(BackendArg::Gpu, self.storage).precision();
        self.operator.apply(&mut config)?;
        if let Some(m) = self.surface_lattice {
            if m < 3 {
                return Err(Error::InvalidParameter {
                    name: "surface-lattice",
                    value: m.to_string(),
                    reason: "a lattice with interior points needs M >= 3".into(),
                });
            }
        }
        config.surface_lattice = self.surface_lattice;
        config.solver = SolverOptions {
            choice: match self.solver {
                SolverArg::Auto => SolverChoice::Auto,
                SolverArg::Lu => SolverChoice::Lu,
                SolverArg::Iterative => SolverChoice::Iterative,
            },
            tolerance: self.tolerance,
        };
        config.bands = self.colour.channels()?;
        config.operator_file = self.operator_file.as_ref().map(std::path::PathBuf::from);
        if let Some(path) = &self.emission_file {
            config.cases = Some(EmissionCases::read_csv(std::path::Path::new(path))?);
            // The cases give E: no true solution unless one is asked for (and then refused).
            if self.solution.is_none() {
                config.solution = None;
            }
        }
        Ok(config)
    }
}

// Imperfect scene files, colour bands and pictures.

#[derive(Clone, Copy, ValueEnum)]
pub(crate) enum NonPlanarArg {
    /// Into planar triangles: a quadrilateral along its shorter diagonal, others by ear clipping
    Split,
    Refuse,
}

#[derive(Clone, Copy, ValueEnum)]
pub(crate) enum DuplicatesArg {
    /// Keep the first of faces with the same vertices (same order) and properties
    Drop,
    Refuse,
}

#[derive(Clone, Copy, ValueEnum)]
pub(crate) enum CoplanarArg {
    /// Join them into planar faces for visibility, the triangles kept as elements
    Merge,
    /// Every triangle a face of its own
    Keep,
}

#[derive(Clone, Copy, ValueEnum)]
pub(crate) enum ToneArg {
    Linear,
    Log,
    Gamma,
}

/// How imperfect scene files are read.
#[derive(Args)]
pub(crate) struct ImportArgs {
    /// Non-planar polygons [default: split for OBJ/STL polygons, refuse for TOML faces]
    #[arg(long, value_enum)]
    pub(crate) nonplanar: Option<NonPlanarArg>,
    /// Faces that repeat an earlier face exactly [default: drop for OBJ/STL polygons, refuse
    /// for TOML faces]; partial overlaps are always refused
    #[arg(long, value_enum)]
    pub(crate) duplicates: Option<DuplicatesArg>,
    /// Coplanar triangles of OBJ/STL meshes that share edges and properties [default: merge]
    #[arg(long, value_enum)]
    pub(crate) coplanar: Option<CoplanarArg>,
}

impl ImportArgs {
    pub(crate) fn options(&self) -> ImportOptions {
        ImportOptions {
            nonplanar: self.nonplanar.map(|n| match n {
                NonPlanarArg::Split => NonPlanar::Split,
                NonPlanarArg::Refuse => NonPlanar::Refuse,
            }),
            duplicates: self.duplicates.map(|d| match d {
                DuplicatesArg::Drop => Duplicates::Drop,
                DuplicatesArg::Refuse => Duplicates::Refuse,
            }),
            coplanar: self.coplanar.map(|c| match c {
                CoplanarArg::Merge => Coplanar::Merge,
                CoplanarArg::Keep => Coplanar::Keep,
            }),
        }
    }
}

/// Colour bands, and how the picture is drawn.
#[derive(Args)]
pub(crate) struct ColourArgs {
    /// Solve per colour band on one assembled operator, each with its channel of rho and E (OBJ:
    /// Kd, Ke; grey faces the same in every band): rgb, a list such as r,g, or grey (one solve
    /// with the channels' means)
    #[arg(long, value_name = "BANDS", default_value = "grey")]
    pub(crate) bands: String,
    /// The direction that is up in the picture [default: 0,1,0 for OBJ files, 0,0,1 otherwise]
    #[arg(long, value_name = "X,Y,Z")]
    pub(crate) up: Option<String>,
    /// How u becomes colour: linear, log (three decades) or gamma (2.2)
    #[arg(long, value_enum, default_value_t = ToneArg::Gamma)]
    pub(crate) tone: ToneArg,
}

impl ColourArgs {
    /// The channels of --bands (empty: grey).
    pub(crate) fn channels(&self) -> Result<Vec<usize>> {
        radiosity::scene::parse_bands(&self.bands)
    }

    /// The tone map of --tone.
    pub(crate) fn tone(&self) -> Tone {
        match self.tone {
            ToneArg::Linear => Tone::Linear,
            ToneArg::Log => Tone::Log,
            ToneArg::Gamma => Tone::Gamma,
        }
    }

    /// The up direction of --up, or the default for `scene`.
    pub(crate) fn up(&self, scene: &SceneSource) -> Result<glam::DVec3> {
        let Some(text) = &self.up else {
            return Ok(if scene.is_obj() { glam::DVec3::Y } else { glam::DVec3::Z });
        };
        let up = solve::parse_point("up", text)?;
        if up.length() == 0.0 || !up.length().is_finite() {
            return Err(Error::InvalidParameter {
                name: "up",
                value: text.clone(),
                reason: "the up direction must be a non-zero vector".into(),
            });
        }
        Ok(up)
    }
}

/// The ranks of this process's `mpirun`, where it started several.
static WORLD: OnceLock<Ranks> = OnceLock::new();

/// Makes the runs of this process distributed over `ranks`.
#[cfg_attr(not(feature = "mpi"), allow(dead_code))]
pub(crate) fn set_world(ranks: Ranks) {
    WORLD.set(ranks).expect("the world is set once, at the start");
}

/// The ranks the runs are spread over, or `None` for one process.
pub(crate) fn world() -> Option<Ranks> {
    WORLD.get().cloned()
}

/// Whether this process prints and writes: rank 0 of a distributed run, or a lone process.
pub(crate) fn is_root() -> bool {
    WORLD.get().is_none_or(|w| w.rank() == 0)
}
