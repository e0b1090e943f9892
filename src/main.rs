//! `radiosity`: command-line front end. Parses arguments, calls the library, prints.

use std::process::ExitCode;

use clap::{Args, Parser, Subcommand, ValueEnum};
use serde::Serialize;

use radiosity::assembly::{Assembly, AssemblyOptions, Quadrature};
use radiosity::discretization::Discretization;
use radiosity::discretization::Method;
use radiosity::error::{Error, Result};
use radiosity::gpu::Precision;
use radiosity::mesh::{LineExtent, Mesh, S5Diagonals};
use radiosity::pipeline::{self, Backend, MeshChoice, RunConfig, RunReport, SceneSource};
use radiosity::problems::{EmissionOptions, TrueSolution};
use radiosity::report::TableFormat;
use radiosity::scene::Scene;
use radiosity::scene::SurfaceParameters;
use radiosity::solve::{SolverChoice, SolverOptions};
use radiosity::study::{self, StudyDevice, StudyOptions};
use radiosity::visibility::PairPlanner;
use radiosity::{bench, report};

#[derive(Parser)]
#[command(
    name = "radiosity",
    version,
    about = "Collocation solver for the occluded radiosity equation (Atkinson, Chien & Seol 2000)"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Reproduce a table or figure of the paper, or run a study (ids: table-3.1 .. table-3.5,
    /// table-4.1, table-4.2, figure-3.4 .. figure-3.7, error-vs-time, grading)
    Study {
        /// Study id
        id: String,
        /// Largest number of elements n to run (default: the paper's largest)
        #[arg(long)]
        max_n: Option<usize>,
        /// Where to assemble: cpu (GPU series left out), gpu (everything that can runs on the
        /// GPU); default: the CPU, plus the study's GPU series where an adapter is found
        #[arg(long, value_enum)]
        backend: Option<BackendArg>,
        /// Precision of the GPU kernels with --backend gpu
        #[arg(long, value_enum, default_value_t = PrecisionArg::F64)]
        precision: PrecisionArg,
        /// Directory for the plots (PNG and SVG) of the figure and error-vs-time studies
        #[arg(long, value_name = "DIR", default_value = "figures")]
        figures: String,
        /// Also write JSON to PATH; `-`: JSON on standard output instead of the text table
        #[arg(long, value_name = "PATH")]
        json: Option<String>,
        /// Print Markdown tables instead of aligned text
        #[arg(long)]
        markdown: bool,
    },
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

#[derive(Clone, Copy, ValueEnum)]
enum MethodArg {
    Centroid,
    Linear,
}

#[derive(Clone, Copy, ValueEnum)]
enum MeshArg {
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
enum ShadowLinesArg {
    /// Each shadow line extended across its face (as the paper's mesh)
    Chords,
    /// Only where the visibility events are
    Segments,
}

#[derive(Clone, Copy, PartialEq, Eq, ValueEnum)]
enum BackendArg {
    Cpu,
    Gpu,
}

#[derive(Clone, Copy, PartialEq, Eq, ValueEnum)]
enum PrecisionArg {
    F64,
    F32,
}

#[derive(Clone, Copy, PartialEq, Eq, ValueEnum)]
enum SolverArg {
    Auto,
    Lu,
    Iterative,
}

#[derive(Clone, Copy, PartialEq, Eq, ValueEnum)]
enum QuadratureArg {
    Exact,
    SevenPoint,
    Gauss,
}

/// The scene, its mesh and the collocation method.
#[derive(Args)]
struct GeometryArgs {
    /// Scene: four-piece, five-piece, cube, baffled-box, or a scene file (.toml, .obj, .stl)
    #[arg(long)]
    scene: String,
    /// Collocation method
    #[arg(long, value_enum, default_value_t = MethodArg::Centroid)]
    method: MethodArg,
    /// Node parameter alpha of the linear method, in [0, 1/3) (default 1/6)
    #[arg(long)]
    alpha: Option<f64>,
    /// Mesh
    #[arg(long, value_enum, default_value_t = MeshArg::Uniform)]
    mesh: MeshArg,
    /// Extent of the shadow lines of --mesh auto-discontinuity: chords give the paper's mesh on
    /// its surfaces, segments far fewer elements in scenes with many occluders
    #[arg(long, value_enum, default_value_t = ShadowLinesArg::Segments)]
    shadow_lines: ShadowLinesArg,
    /// Grade the mesh toward an edge of a face: FACE:K names the edge from vertex K to K+1
    /// (repeatable; e.g. S1:2 and S5:3, the common edge of the five-piece surface)
    #[arg(long, value_name = "FACE:K")]
    grade: Vec<String>,
    /// Grading exponent q: a point at distance d from a graded edge moves to D (d/D)^q
    #[arg(long, default_value_t = 2.0)]
    grading: f64,
    /// Refinement levels: n = n0 * 4^refine
    #[arg(long, default_value_t = 2)]
    refine: u32,
    /// Surface parameters A,B,C of the paper's surfaces
    #[arg(long, value_name = "A,B,C", default_value = "5,2,1")]
    params: String,
    /// How the collocation integrals are evaluated: closed forms (+ IMT), or the paper's graded
    /// 7-point or collapsed-Gauss rules (sec. 4.2)
    #[arg(long, value_enum, default_value_t = QuadratureArg::Exact)]
    quadrature: QuadratureArg,
    /// MaxLev of the seven-point and gauss quadratures: 4^MaxLev subtriangles, or 2^(IBase+MaxLev)
    /// Gauss points per dimension, next to the node
    #[arg(long, default_value_t = 3)]
    max_level: u32,
    /// IBase of the gauss quadrature: 2^IBase points per dimension far from the node
    #[arg(long, default_value_t = 1)]
    ibase: u32,
    /// The quadrature level is MaxLev within this many element diameters of the node, and falls by
    /// one per doubling of the distance
    #[arg(long, default_value_t = radiosity::kernels::graded::DEFAULT_NEAR)]
    near_ratio: f64,
    /// IMT subintervals for the linear method's 1-D integrals
    #[arg(long, default_value_t = 128)]
    imt_nodes: usize,
    /// Use the paper's closed forms for every pair, also far from the node and on thin elements
    /// (slower, and less accurate there, where the closed forms cancel)
    #[arg(long)]
    no_far_field: bool,
}

/// Where the matrix is assembled.
#[derive(Args)]
struct DeviceArgs {
    /// Where the collocation matrix is assembled
    #[arg(long, value_enum, default_value_t = BackendArg::Cpu)]
    backend: BackendArg,
    /// Precision of the GPU kernels
    #[arg(long, value_enum, default_value_t = PrecisionArg::F64)]
    precision: PrecisionArg,
}

#[derive(Args)]
struct SolveArgs {
    #[command(flatten)]
    geometry: GeometryArgs,
    #[command(flatten)]
    device: DeviceArgs,
    /// True solution (x2y2, shadow, edge, none); default x2y2 on the paper's surfaces, none elsewhere
    #[arg(long)]
    solution: Option<String>,
    /// beta of the shadow (3.3) or edge (3.4) solution
    #[arg(long)]
    beta: Option<f64>,
    /// gamma of the shadow solution (3.3)
    #[arg(long)]
    gamma: Option<f64>,
    /// Linear solver: LU up to 6000 unknowns and GMRES beyond (auto), or forced
    #[arg(long, value_enum, default_value_t = SolverArg::Auto)]
    solver: SolverArg,
    /// Relative residual ||E - (I - K) u||_2 / ||E||_2 at which the iterative solver stops
    #[arg(long, default_value_t = radiosity::solve::DEFAULT_TOLERANCE)]
    tolerance: f64,
    /// Also report the largest errors over all of S, of u_n and of the iterated solution E + K u_n,
    /// at the interior points of a barycentric lattice of spacing 1/M in every element
    #[arg(long, value_name = "M")]
    surface_lattice: Option<usize>,
    /// Write JSON to PATH (`-` for standard output) instead of text
    #[arg(long, value_name = "PATH")]
    json: Option<String>,
    #[command(flatten)]
    outputs: OutputArgs,
}

/// Files written from a solution.
#[derive(Args)]
struct OutputArgs {
    /// Write the mesh with u, E, rho per element and u at the vertices as VTK (.vtu, for ParaView)
    #[arg(long, value_name = "FILE.vtu")]
    vtu: Option<String>,
    /// Write the nodal values (position, face, rho, E, u) as CSV
    #[arg(long, value_name = "FILE.csv")]
    csv: Option<String>,
    /// Render a false-colour picture of u (back faces culled: a closed room seen from outside
    /// shows its inside)
    #[arg(long, value_name = "FILE.png")]
    png: Option<String>,
    /// Picture size in pixels
    #[arg(long, value_name = "WxH", default_value = "1200x800")]
    png_size: String,
    /// Eye position of the picture (default: outside the scene, from the south-west, above)
    #[arg(long, value_name = "X,Y,Z")]
    eye: Option<String>,
    /// Point the picture looks at (default: the centre of the scene)
    #[arg(long, value_name = "X,Y,Z")]
    target: Option<String>,
}

#[derive(Args)]
struct BenchArgs {
    #[command(flatten)]
    geometry: GeometryArgs,
    /// Backends to run, comma separated [default: cpu, and gpu where an adapter can run the
    /// precision asked for]
    #[arg(long, value_enum, value_delimiter = ',')]
    backends: Option<Vec<BackendArg>>,
    /// Precision of the GPU kernels
    #[arg(long, value_enum, default_value_t = PrecisionArg::F64)]
    precision: PrecisionArg,
    /// Repetitions per backend (the best time counts)
    #[arg(long, default_value_t = 3)]
    repeats: usize,
    /// Write JSON to PATH (`-` for standard output) instead of text
    #[arg(long, value_name = "PATH")]
    json: Option<String>,
}

#[derive(Args)]
struct ViewFactorArgs {
    #[command(flatten)]
    geometry: GeometryArgs,
    /// Absolute tolerance of each F_ij (outer quadrature)
    #[arg(long, default_value_t = 1e-10)]
    tolerance: f64,
    /// Most times an element is split into four where the outer rule's levels disagree (shadow
    /// lines crossing it); each split costs up to 4x the time of the element
    #[arg(long, default_value_t = 1)]
    max_depth: u32,
    /// Write F (n x n, row-major) to FILE: NumPy .npy or .csv
    #[arg(long, value_name = "FILE")]
    output: Option<String>,
    /// Write the summary as JSON to PATH (`-` for standard output) instead of text
    #[arg(long, value_name = "PATH")]
    json: Option<String>,
}

#[derive(Args)]
struct AssembleArgs {
    #[command(flatten)]
    geometry: GeometryArgs,
    #[command(flatten)]
    device: DeviceArgs,
    /// Output file (NumPy .npy, float64, row-major dof x dof)
    #[arg(long, value_name = "FILE.npy")]
    output: String,
}

/// Three comma-separated numbers.
fn parse_point(name: &'static str, text: &str) -> Result<glam::DVec3> {
    // Every component must parse: "1,x,2,3" is refused, not read as (1, 2, 3).
    let values: Option<Vec<f64>> = text.split(',').map(|s| s.trim().parse().ok()).collect();
    match values.as_deref().unwrap_or_default() {
        &[x, y, z] if x.is_finite() && y.is_finite() && z.is_finite() => {
            Ok(glam::DVec3::new(x, y, z))
        }
        _ => Err(Error::InvalidParameter {
            name,
            value: text.into(),
            reason: "expected three finite numbers X,Y,Z".into(),
        }),
    }
}

fn write_outputs(run: &pipeline::Run, out: &OutputArgs) -> Result<()> {
    let field = run.field();
    if let Some(path) = &out.vtu {
        report::write_vtu(&field, std::path::Path::new(path))?;
    }
    if let Some(path) = &out.csv {
        report::write_node_csv(&field, std::path::Path::new(path))?;
    }
    if let Some(path) = &out.png {
        let size = out
            .png_size
            .split_once('x')
            .and_then(|(w, h)| Some((w.parse().ok()?, h.parse().ok()?)))
            .ok_or_else(|| Error::InvalidParameter {
                name: "png-size",
                value: out.png_size.clone(),
                reason: "expected WIDTHxHEIGHT in pixels".into(),
            })?;
        let mut camera = report::Camera::overview(&field, report::DEFAULT_VIEW);
        // The user gives points in their coordinates; the scene is drawn in its local frame.
        let origin = run.scene.origin;
        if let Some(t) = &out.target {
            camera.target = parse_point("target", t)? - origin;
        }
        if let Some(e) = &out.eye {
            camera.eye = parse_point("eye", e)? - origin;
        }
        let r = &run.report;
        let title = format!("{}: u, {} method, n = {}", r.surface, r.method, r.n);
        report::render_png(&field, &camera, size, &title, std::path::Path::new(path))?;
    }
    Ok(())
}

fn parse_params(text: &str) -> Result<SurfaceParameters> {
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

fn backend(b: BackendArg, p: PrecisionArg) -> Backend {
    match b {
        BackendArg::Cpu => Backend::Cpu,
        BackendArg::Gpu => Backend::Gpu(match p {
            PrecisionArg::F64 => Precision::F64,
            PrecisionArg::F32 => Precision::F32,
        }),
    }
}

impl GeometryArgs {
    fn quadrature(&self) -> Result<Quadrature> {
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
    fn config(&self) -> Result<RunConfig> {
        let scene = SceneSource::parse(&self.scene)?;
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
            },
            emission: EmissionOptions::default(),
            backend: Backend::Cpu,
            solver: SolverOptions::default(),
            progress: true,
            setup_repeats: 1,
            surface_lattice: None,
        })
    }
}

impl SolveArgs {
    fn config(&self) -> Result<RunConfig> {
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
        Ok(config)
    }
}

/// What `inspect` prints.
#[derive(Serialize)]
struct Inspection {
    surface: String,
    mesh: &'static str,
    method: &'static str,
    alpha: Option<f64>,
    backend: &'static str,
    n: usize,
    dof: usize,
    row_sum_min: f64,
    row_sum_max: f64,
    pairs_total: u64,
    pairs_skipped: u64,
    pairs_full: u64,
    pairs_partial: u64,
    pairs_same_plane: u64,
    pairs_facing_away: u64,
    pairs_hidden: u64,
    occluders_possible: bool,
    setup_seconds: f64,
}

/// K for `config` on its backend.
fn assemble_without_progress(
    config: &RunConfig,
    scene: &Scene,
    mesh: &Mesh,
    disc: &Discretization,
    planner: &PairPlanner,
) -> Result<Assembly> {
    let (assembled, _) = pipeline::assemble_on(
        config.backend,
        scene,
        mesh,
        disc,
        planner,
        &config.assembly,
        &|_| {},
    )?;
    Ok(assembled)
}

fn inspect(args: &SolveArgs) -> Result<()> {
    let o = &args.outputs;
    if o.vtu.is_some() || o.csv.is_some() || o.png.is_some() {
        return Err(Error::InvalidParameter {
            name: "vtu/csv/png",
            value: "given".into(),
            reason: "inspect solves nothing; the outputs belong to solve".into(),
        });
    }
    let config = args.config()?;
    let (scene, mesh, disc) = pipeline::build(&config)?;
    let started = std::time::Instant::now();
    let planner = PairPlanner::new(&scene);
    let assembled = assemble_without_progress(&config, &scene, &mesh, &disc, &planner)?;
    let setup_seconds = started.elapsed().as_secs_f64();
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for (i, node) in disc.nodes.iter().enumerate() {
        if node.rho > 0.0 {
            let s = assembled.matrix.row(i).iter().sum::<f64>() / node.rho;
            lo = lo.min(s);
            hi = hi.max(s);
        }
    }
    let p = assembled.stats;
    let out = Inspection {
        surface: scene.name.clone(),
        mesh: config.mesh.name(),
        method: config.method.name(),
        alpha: config.method.alpha(),
        backend: config.backend.name(),
        n: mesh.len(),
        dof: disc.dof(),
        row_sum_min: lo,
        row_sum_max: hi,
        pairs_total: p.total,
        pairs_skipped: p.skipped(),
        pairs_full: p.full,
        pairs_partial: p.partial,
        pairs_same_plane: p.same_plane,
        pairs_facing_away: p.facing_away,
        pairs_hidden: p.hidden,
        occluders_possible: planner.has_occlusion(),
        setup_seconds,
    };
    if let Some(target) = &args.json {
        return report::write_json(&out, target);
    }
    println!(
        "{} ({} mesh, {} method): n = {}, dof = {}",
        out.surface, out.mesh, out.method, out.n, out.dof
    );
    println!("row sums of K/rho: min {:.15}, max {:.15}", out.row_sum_min, out.row_sum_max);
    println!(
        "pairs: {} total, {} skipped ({} same plane, {} facing away, {} hidden), {} full, {} partial",
        out.pairs_total,
        out.pairs_skipped,
        out.pairs_same_plane,
        out.pairs_facing_away,
        out.pairs_hidden,
        out.pairs_full,
        out.pairs_partial
    );
    println!("setup {:.3} s on the {}", out.setup_seconds, out.backend);
    Ok(())
}

fn print_run(r: &RunReport) {
    let alpha = r.alpha.map(|a| format!(", alpha = {a}")).unwrap_or_default();
    println!(
        "{} ({} mesh, {} method{alpha}): n = {}, dof = {}",
        r.surface, r.mesh, r.method, r.n, r.dof
    );
    if let Some(device) = &r.device {
        println!("assembled on {device} in {}", r.precision);
    }
    if let Some(e) = r.error {
        println!("max error at the nodes E_n = {e:.6e}");
    }
    if let Some(s) = &r.over_surface {
        println!(
            "max error over S ({} points): u_n {:.6e}, iterated solution E + K u_n {:.6e}",
            s.points, s.interpolant, s.iterated
        );
    }
    println!(
        "solution at the nodes: min {:.6}, mean {:.6}, max {:.6}",
        r.solution_range[0], r.solution_range[1], r.solution_range[2]
    );
    let mut iterations = match r.condition_estimate {
        Some(k) => format!(", condition ~{k:.1e}, {} refinement steps", r.refinement_steps),
        None => format!(", {} iterations", r.iterations),
    };
    if r.rows_eliminated > 0 {
        iterations += &format!(", {} unknowns known as u = E (rho = 0)", r.rows_eliminated);
    }
    println!(
        "setup {:.3} s, emissivity {:.3} s, solve {:.3} s ({}{iterations}, relative residual {:.1e})",
        r.setup_seconds, r.emission_seconds, r.solve_seconds, r.solver, r.residual
    );
    let p = &r.pairs;
    println!(
        "pairs: {} total, {} skipped, {} full, {} partial",
        p.total,
        p.skipped(),
        p.full,
        p.partial
    );
}

fn run_bench(args: &BenchArgs) -> Result<()> {
    let mut config = args.geometry.config()?;
    config.progress = false;
    let named = match &args.backends {
        Some(named) => named.clone(),
        None => {
            match radiosity::gpu::context_for(backend(BackendArg::Gpu, args.precision).precision())
            {
                Ok(_) => vec![BackendArg::Cpu, BackendArg::Gpu],
                Err(e) => {
                    eprintln!("note: the GPU is left out: {e}");
                    vec![BackendArg::Cpu]
                }
            }
        }
    };
    let mut backends: Vec<Backend> = Vec::new();
    for &b in &named {
        let b = backend(b, args.precision);
        if backends.iter().any(|x| x.name() == b.name()) {
            return Err(Error::InvalidParameter {
                name: "backends",
                value: b.name().into(),
                reason: "each backend may be named once".into(),
            });
        }
        backends.push(b);
    }
    let r = bench::run(&config, &backends, args.repeats)?;
    if let Some(target) = &args.json {
        return report::write_json(&r, target);
    }
    println!(
        "{} ({} mesh, {} method): n = {}, dof = {}, {} pairs ({} evaluated)",
        r.scene, r.mesh, r.method, r.n, r.dof, r.pairs, r.pairs_evaluated
    );
    for (name, t) in [("cpu", &r.cpu), ("gpu", &r.gpu)] {
        if let Some(t) = t {
            println!(
                "{name} ({}): setup {:.3} s, {:.3e} pairs/s (preparation {:.3} s, best of {})",
                t.precision, t.setup_seconds, t.pairs_per_second, t.preparation_seconds, r.repeats
            );
            if let Some(b) = &t.breakdown {
                println!(
                    "    {} tiles: host planning {:.3} s, waiting for the device {:.3} s, read-back {:.3} s",
                    b.tiles, b.planning_seconds, b.device_wait_seconds, b.readback_seconds
                );
            }
        }
    }
    if let Some(d) = &r.device {
        println!("device: {d}");
    }
    if let (Some(s), Some(a), Some(rel)) = (r.speedup, r.max_abs_diff, r.max_rel_diff) {
        println!(
            "speedup (cpu time / gpu time): {s:.2}; max |difference| {a:.2e}, row-relative {rel:.2e}"
        );
    }
    Ok(())
}

fn run_assemble(args: &AssembleArgs) -> Result<()> {
    let mut config = args.geometry.config()?;
    config.backend = backend(args.device.backend, args.device.precision);
    let (scene, mesh, disc) = pipeline::build(&config)?;
    let a = assemble_without_progress(&config, &scene, &mesh, &disc, &PairPlanner::new(&scene))?;
    radiosity::report::write_npy(&args.output, a.matrix.dof(), a.matrix.as_slice())?;
    eprintln!(
        "wrote K ({} x {}, float64, rho/pi included) to {}",
        a.matrix.dof(),
        a.matrix.dof(),
        args.output
    );
    Ok(())
}

fn run_viewfactors(args: &ViewFactorArgs) -> Result<()> {
    use radiosity::viewfactors::{ViewFactorOptions, ViewFactorSummary, view_factors};
    if !(args.tolerance.is_finite() && args.tolerance > 0.0) {
        return Err(Error::InvalidParameter {
            name: "tolerance",
            value: args.tolerance.to_string(),
            reason: "must be positive".into(),
        });
    }
    let config = args.geometry.config()?;
    let (scene, mesh, _) = pipeline::build(&config)?;
    let started = std::time::Instant::now();
    let planner = PairPlanner::new(&scene);
    if args.max_depth > 6 {
        return Err(Error::InvalidParameter {
            name: "max-depth",
            value: args.max_depth.to_string(),
            reason: "at most 6 (4^6 parts of an element)".into(),
        });
    }
    let options = ViewFactorOptions {
        tolerance: args.tolerance,
        max_depth: args.max_depth,
        ..Default::default()
    };
    let bar = pipeline::progress_bar(true, "viewfactors", mesh.len());
    let f = view_factors(&scene, &mesh, &planner, &options, &|k| bar.inc(k as u64))?;
    bar.finish_and_clear();
    let (row_sum_min, row_sum_max) = f.row_sum_range();
    let summary = ViewFactorSummary {
        surface: scene.name.clone(),
        n: f.len(),
        row_sum_min,
        row_sum_max,
        reciprocity_error: f.reciprocity_error(),
        error_estimate: f.error_estimate,
        evaluations: f.evaluations,
        seconds: started.elapsed().as_secs_f64(),
    };
    if let Some(path) = &args.output {
        if path.ends_with(".npy") {
            report::write_npy(path, f.len(), &f.matrix)?;
        } else if path.ends_with(".csv") {
            let text: String = f
                .matrix
                .chunks(f.len())
                .map(|row| {
                    row.iter().map(|v| format!("{v:e}")).collect::<Vec<_>>().join(",") + "\n"
                })
                .collect();
            std::fs::write(path, text)?;
        } else {
            return Err(Error::InvalidParameter {
                name: "output",
                value: path.clone(),
                reason: "expected a .npy or .csv file".into(),
            });
        }
    }
    if let Some(target) = &args.json {
        return report::write_json(&summary, target);
    }
    println!("{}: n = {} elements, {:.2} s", summary.surface, summary.n, summary.seconds);
    println!("row sums of F: min {:.15}, max {:.15}", summary.row_sum_min, summary.row_sum_max);
    println!(
        "reciprocity: max |A_i F_ij - A_j F_ji| / max A_i F_ij = {:.2e}; quadrature error estimate {:.2e}",
        summary.reciprocity_error, summary.error_estimate
    );
    if scene.faces.len() <= 12 {
        println!("face-to-face view factors (row: from):");
        for (a, row) in f.by_face(&mesh).iter().enumerate() {
            let cells: Vec<String> = row.iter().map(|v| format!("{v:.10}")).collect();
            println!("  {:>12} {}", scene.faces[a].name, cells.join(" "));
        }
    }
    Ok(())
}

/// What `gpu-check` prints.
#[derive(Serialize)]
struct GpuCheck {
    adapter: radiosity::gpu::AdapterSummary,
    functions: Vec<radiosity::gpu::math::UlpReport>,
}

fn gpu_check(samples: usize, precision: PrecisionArg, json: Option<&str>) -> Result<()> {
    let precision = match precision {
        PrecisionArg::F64 => Precision::F64,
        PrecisionArg::F32 => Precision::F32,
    };
    let ctx = radiosity::gpu::context_for(precision)?;
    let functions = radiosity::gpu::math::measure(ctx, precision, samples)?;
    let out = GpuCheck { adapter: ctx.adapter.clone(), functions };
    if let Some(target) = json {
        return report::write_json(&out, target);
    }
    let a = &out.adapter;
    println!("adapter: {} ({}, {}), SHADER_F64: {}", a.name, a.backend, a.device_type, a.f64);
    println!(
        "math library in {}, {} samples per function, against Rust's f64 functions:",
        precision.name(),
        samples
    );
    for r in &out.functions {
        println!(
            "  {:<6} worst {:>6.2} ulp at {:?}",
            format!("{:?}", r.function).to_lowercase(),
            r.worst_ulp,
            r.worst_at
        );
    }
    Ok(())
}

/// A study's result: JSON to `json` when given, and the table unless the JSON goes to stdout.
fn emit<T: Serialize>(
    result: &T,
    json: Option<&str>,
    table: impl FnOnce() -> String,
) -> Result<()> {
    if let Some(target) = json {
        report::write_json(result, target)?;
    }
    if json != Some("-") {
        print!("{}", table());
    }
    Ok(())
}

fn run(cli: Cli) -> Result<()> {
    match cli.command {
        Command::Study { id, max_n, backend: device, precision, figures, json, markdown } => {
            let device = match (device, backend(BackendArg::Gpu, precision)) {
                (None, _) => StudyDevice::Auto,
                (Some(BackendArg::Cpu), _) => StudyDevice::Cpu,
                (Some(BackendArg::Gpu), b) => StudyDevice::Gpu(b.precision()),
            };
            let format = if markdown { TableFormat::Markdown } else { TableFormat::Text };
            let json = json.as_deref();
            match id.as_str() {
                "stability" => {
                    let result = radiosity::stability::run_stability(device)?;
                    emit(&result, json, || report::stability_table(&result, format))
                }
                "stiff" => {
                    let result = radiosity::stability::run_stiff(device)?;
                    emit(&result, json, || report::stiff_table(&result, format))
                }
                _ => {
                    let options = StudyOptions { max_n, device, progress: true };
                    let mut result = study::run_study(&id, &options)?;
                    result.figures =
                        report::write_study_figures(&result, std::path::Path::new(&figures))?;
                    emit(&result, json, || report::study_table(&result, format))
                }
            }
        }
        Command::Solve(args) => {
            let run = pipeline::run_keeping_mesh(&args.config()?)?;
            write_outputs(&run, &args.outputs)?;
            let r = &run.report;
            for w in &r.warnings {
                eprintln!("warning: {w}");
            }
            match &args.json {
                Some(target) => report::write_json(&r, target),
                None => {
                    print_run(r);
                    Ok(())
                }
            }
        }
        Command::Inspect(args) => inspect(&args),
        Command::Bench(args) => run_bench(&args),
        Command::Assemble(args) => run_assemble(&args),
        Command::Viewfactors(args) => run_viewfactors(&args),
        Command::BenchPlan { scene, nodes, json } => {
            let scene = SceneSource::parse(&scene)?.build(SurfaceParameters::default())?;
            let b = radiosity::visibility::bench_plan(&scene, nodes);
            if let Some(target) = json {
                return report::write_json(&b, &target);
            }
            println!(
                "{}: {} faces, {} occluders; {} nodes x {} faces = {} views ({} shadowed or hidden)",
                b.scene, b.faces, b.occluders, b.nodes, b.faces, b.views, b.shadowed_views
            );
            for t in &b.timings {
                println!(
                    "  {:>8}: planner built in {:.3} s, views {:.3} s",
                    serde_json::to_value(t.acceleration)
                        .unwrap_or_default()
                        .as_str()
                        .unwrap_or("?"),
                    t.build_seconds,
                    t.plan_seconds
                );
            }
            println!(
                "R*-tree with the view pyramid: {:.1}x faster than the core solver's plan (box-scan), {:.1}x faster than scanning every occluder with the pyramid; same visible parts: {}",
                b.speedup, b.speedup_over_scan, b.identical
            );
            println!(
                "complete plan (one node per face), projected: the core solver's pair lists alone {:.0} s; with its views {:.1}x the tree's time",
                b.pair_lists_seconds_projected, b.complete_plan_speedup
            );
            Ok(())
        }
        Command::GpuCheck { samples, precision, json } => {
            gpu_check(samples, precision, json.as_deref())
        }
    }
}

fn main() -> ExitCode {
    match run(Cli::parse()) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::FAILURE
        }
    }
}
