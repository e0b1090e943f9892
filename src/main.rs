//! `radiosity`: command-line front end. Parses arguments, calls the library, prints.

use std::process::ExitCode;

use clap::{Args, Parser, Subcommand, ValueEnum};
use serde::Serialize;

use radiosity::assembly::AssemblyOptions;
use radiosity::discretization::Method;
use radiosity::error::{Error, Result};
use radiosity::pipeline::{self, MeshChoice, RunConfig, RunReport};
use radiosity::problems::{EmissionOptions, TrueSolution};
use radiosity::report;
use radiosity::scene::{BuiltinScene, SurfaceParameters};
use radiosity::study::{self, StudyOptions};
use radiosity::visibility::PairPlanner;

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
    /// Reproduce a table of the paper (ids: table-3.1, table-3.4)
    Study {
        /// Study id
        id: String,
        /// Largest number of elements n to run (default: the paper's largest)
        #[arg(long)]
        max_n: Option<usize>,
        /// Where the collocation matrix is assembled
        #[arg(long, value_enum, default_value_t = BackendArg::Cpu)]
        backend: BackendArg,
        /// Write JSON to PATH (`-` for standard output) instead of the text table
        #[arg(long, value_name = "PATH")]
        json: Option<String>,
    },
    /// Solve one problem and report its error and timings
    Solve(ProblemArgs),
    /// Matrix statistics: row sums of K/rho and pair-class counts
    Inspect(ProblemArgs),
}

#[derive(Clone, Copy, ValueEnum)]
enum MethodArg {
    Centroid,
    Linear,
}

#[derive(Clone, Copy, ValueEnum)]
enum MeshArg {
    Uniform,
    Discontinuity,
}

#[derive(Clone, Copy, PartialEq, Eq, ValueEnum)]
enum BackendArg {
    Cpu,
}

#[derive(Clone, Copy, ValueEnum)]
enum QuadratureArg {
    Exact,
}

#[derive(Args)]
struct ProblemArgs {
    /// Scene: four-piece, five-piece, cube, baffled-box
    #[arg(long)]
    scene: String,
    /// Collocation method
    #[arg(long, value_enum, default_value_t = MethodArg::Centroid)]
    method: MethodArg,
    /// Node parameter alpha of the linear method, in [0, 1/3)
    #[arg(long, default_value_t = Method::PAPER_ALPHA)]
    alpha: f64,
    /// Mesh
    #[arg(long, value_enum, default_value_t = MeshArg::Uniform)]
    mesh: MeshArg,
    /// Refinement levels: n = n0 * 4^refine
    #[arg(long, default_value_t = 2)]
    refine: u32,
    /// True solution (x2y2, shadow, edge, none); default x2y2 on the paper's surfaces, none elsewhere
    #[arg(long)]
    solution: Option<String>,
    /// beta of the shadow (3.3) or edge (3.4) solution
    #[arg(long)]
    beta: Option<f64>,
    /// gamma of the shadow solution (3.3)
    #[arg(long)]
    gamma: Option<f64>,
    /// Surface parameters A,B,C of the paper's surfaces
    #[arg(long, value_name = "A,B,C", default_value = "5,2,1")]
    params: String,
    /// How the collocation integrals are evaluated
    #[arg(long, value_enum, default_value_t = QuadratureArg::Exact)]
    quadrature: QuadratureArg,
    /// IMT subintervals for the linear method's 1-D integrals
    #[arg(long, default_value_t = 128)]
    imt_nodes: usize,
    /// Where the collocation matrix is assembled
    #[arg(long, value_enum, default_value_t = BackendArg::Cpu)]
    backend: BackendArg,
    /// Write JSON to PATH (`-` for standard output) instead of text
    #[arg(long, value_name = "PATH")]
    json: Option<String>,
}

fn parse_params(text: &str) -> Result<SurfaceParameters> {
    let values: Vec<f64> = text
        .split(',')
        .map(|s| s.trim().parse::<f64>())
        .collect::<std::result::Result<_, _>>()
        .map_err(|_| Error::InvalidParameter {
            name: "params",
            value: text.into(),
            reason: "expected three numbers A,B,C".into(),
        })?;
    let [a, b, c] = values[..] else {
        return Err(Error::InvalidParameter {
            name: "params",
            value: text.into(),
            reason: "expected three numbers A,B,C".into(),
        });
    };
    let p = SurfaceParameters { a, b, c };
    p.validate()?;
    Ok(p)
}

impl ProblemArgs {
    fn config(&self) -> Result<RunConfig> {
        let scene: BuiltinScene = self.scene.parse()?;
        let method = match self.method {
            MethodArg::Centroid => Method::Centroid,
            MethodArg::Linear => Method::linear(self.alpha)?,
        };
        let default_solution = if scene.is_paper_surface() {
            "x2y2"
        } else {
            "none"
        };
        let name = self.solution.as_deref().unwrap_or(default_solution);
        let solution = if name == "none" {
            None
        } else {
            Some(TrueSolution::parse(name, self.beta, self.gamma)?)
        };
        if self.imt_nodes < 2 {
            return Err(Error::InvalidParameter {
                name: "imt-nodes",
                value: self.imt_nodes.to_string(),
                reason: "the IMT rule needs at least 2 subintervals".into(),
            });
        }
        Ok(RunConfig {
            scene,
            params: parse_params(&self.params)?,
            mesh: match self.mesh {
                MeshArg::Uniform => MeshChoice::Uniform,
                MeshArg::Discontinuity => MeshChoice::Discontinuity,
            },
            refine: self.refine,
            method,
            solution,
            assembly: AssemblyOptions {
                imt_nodes: self.imt_nodes,
            },
            emission: EmissionOptions::default(),
            progress: true,
        })
    }
}

/// What `inspect` prints.
#[derive(Serialize)]
struct Inspection {
    surface: String,
    mesh: &'static str,
    method: &'static str,
    alpha: Option<f64>,
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

fn inspect(args: &ProblemArgs) -> Result<()> {
    let config = args.config()?;
    let (scene, mesh, disc) = pipeline::build(&config)?;
    let started = std::time::Instant::now();
    let planner = PairPlanner::new(&scene);
    let assembled =
        radiosity::assembly::assemble(&mesh, &disc, &planner, &config.assembly, &|_| {})?;
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
    match &args.json {
        Some(target) => report::write_json(&out, target),
        None => {
            println!(
                "{} ({} mesh, {} method): n = {}, dof = {}",
                out.surface, out.mesh, out.method, out.n, out.dof
            );
            println!(
                "row sums of K/rho: min {:.15}, max {:.15}",
                out.row_sum_min, out.row_sum_max
            );
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
            println!("setup {:.3} s", out.setup_seconds);
            Ok(())
        }
    }
}

fn print_run(r: &RunReport) {
    println!(
        "{} ({} mesh, {} method{}): n = {}, dof = {}",
        r.surface,
        r.mesh,
        r.method,
        r.alpha
            .map(|a| format!(", alpha = {a}"))
            .unwrap_or_default(),
        r.n,
        r.dof
    );
    if let Some(e) = r.error {
        println!("max error at the nodes E_n = {e:.6e}");
    }
    println!(
        "solution at the nodes: min {:.6}, mean {:.6}, max {:.6}",
        r.solution_range[0], r.solution_range[1], r.solution_range[2]
    );
    println!(
        "setup {:.3} s, emissivity {:.3} s, solve {:.3} s (relative residual {:.1e})",
        r.setup_seconds, r.emission_seconds, r.solve_seconds, r.residual
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

fn run(cli: Cli) -> Result<()> {
    match cli.command {
        Command::Study {
            id,
            max_n,
            backend: _,
            json,
        } => {
            let result = study::run_study(
                &id,
                &StudyOptions {
                    max_n,
                    progress: true,
                },
            )?;
            match json {
                Some(target) => report::write_json(&result, &target),
                None => {
                    print!("{}", report::study_table(&result));
                    Ok(())
                }
            }
        }
        Command::Solve(args) => {
            let config = args.config()?;
            let r = pipeline::run(&config)?;
            match &args.json {
                Some(target) => report::write_json(&r, target),
                None => {
                    print_run(&r);
                    Ok(())
                }
            }
        }
        Command::Inspect(args) => inspect(&args),
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
