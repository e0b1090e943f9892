//! Each command's own arguments: the groups of flags it flattens, and its own flags.

use clap::Args;
use radiosity::gpu::Precision;
use radiosity::pipeline::{BackendName, RunOptions};
use radiosity::problems::SolutionName;
use radiosity::solve::SolverChoice;

use super::colour::ColourArgs;
use super::device::DeviceArgs;
use super::geometry::{GeometryArgs, SceneArgs};
use super::named::named;
use super::operator::OperatorArgs;
use super::outputs::OutputArgs;

/// Where `study` writes its plots unless `--figures` says.
pub(crate) const DEFAULT_FIGURES: &str = "figures";

/// `radiosity study`'s arguments: every study's, each of which takes only its own
/// (`cli::study`'s table, which `radiosity study ID --help` shows).
#[derive(Args)]
pub(crate) struct StudyArgs {
    /// Study id
    pub(crate) id: String,
    /// Largest number of elements n to run (default: the paper's largest; `study cities`: the
    /// cities of 4 to 32 blocks a side)
    #[arg(long)]
    pub(crate) max_n: Option<usize>,
    /// Where to assemble: cpu (GPU series left out), gpu (everything that can runs on the
    /// GPU); default: the CPU, plus the study's GPU series where an adapter is found
    #[arg(long, value_parser = named::<BackendName>())]
    pub(crate) backend: Option<BackendName>,
    /// Precision of the GPU kernels with --backend gpu [default: f64]
    #[arg(long, value_parser = named::<Precision>())]
    pub(crate) precision: Option<Precision>,
    /// Directory for the plots (PNG and SVG) of the figure and error-vs-time studies [default:
    /// figures]
    #[arg(long, value_name = "DIR")]
    pub(crate) figures: Option<String>,
    /// Also write JSON to PATH; `-`: JSON on standard output instead of the text table
    #[arg(long, value_name = "PATH")]
    pub(crate) json: Option<String>,
    /// Print Markdown tables instead of aligned text
    #[arg(long)]
    pub(crate) markdown: bool,
    /// `study compression` on this scene (built-in name, city:NXxNY[:lit], or a .toml, .obj or
    /// .stl file) instead of the five-piece surface: centroid method, the scene's own emission;
    /// `study estimates`: scenes checked beside the generated ones (repeatable) [default:
    /// city:4x4]
    #[arg(long)]
    pub(crate) scene: Vec<String>,
    /// `study compression`'s tolerances, comma-separated [default: 1e-3,1e-6,1e-9];
    /// `study estimates`' [default: 1e-4,1e-6,1e-8]
    #[arg(long, value_delimiter = ',')]
    pub(crate) tolerances: Option<Vec<f64>>,
    /// `study estimates`: seeds 0..N of each generated family [default: 8]
    #[arg(long, value_name = "N")]
    pub(crate) seeds: Option<u64>,
    /// `study compression` with shadowed blocks (as `solve --shadowed-blocks`)
    #[arg(long)]
    pub(crate) shadowed_blocks: bool,
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
    #[arg(long, value_parser = named::<Precision>(), default_value_t = Precision::F64)]
    pub(crate) storage: Precision,
    #[command(flatten)]
    pub(crate) operator: OperatorArgs,
    /// True solution [default: x2y2 on the paper's surfaces, none elsewhere]
    #[arg(long, value_parser = named::<SolutionName>())]
    pub(crate) solution: Option<SolutionName>,
    /// beta of the shadow (3.3) or edge (3.4) solution
    #[arg(long)]
    pub(crate) beta: Option<f64>,
    /// gamma of the shadow solution (3.3)
    #[arg(long)]
    pub(crate) gamma: Option<f64>,
    /// Linear solver (auto: LU up to 6000 unknowns, GMRES beyond)
    #[arg(
        long,
        value_parser = named::<SolverChoice>(),
        default_value_t = RunOptions::default().solver
    )]
    pub(crate) solver: SolverChoice,
    /// Relative residual ||E - (I - K) u||_2 / ||E||_2 at which the iterative solver stops
    #[arg(long, default_value_t = RunOptions::default().tolerance)]
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

#[derive(Args)]
pub(crate) struct BenchArgs {
    #[command(flatten)]
    pub(crate) geometry: GeometryArgs,
    #[command(flatten)]
    pub(crate) operator: OperatorArgs,
    /// Backends to run, comma separated [default: cpu, and gpu where an adapter can run the
    /// precision asked for]
    #[arg(long, value_parser = named::<BackendName>(), value_delimiter = ',')]
    pub(crate) backends: Option<Vec<BackendName>>,
    /// Precision of the GPU kernels
    #[arg(long, value_parser = named::<Precision>(), default_value_t = Precision::F64)]
    pub(crate) precision: Precision,
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
    pub(crate) scene: SceneArgs,
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
    /// Write each element's sky view factor (1 - Σ_j F_ij, after --condition and
    /// --drop-below) to FILE: .csv (element, face, area, sky_view_factor) or .npy
    #[arg(long, value_name = "FILE")]
    pub(crate) sky_view_factors: Option<String>,
    /// Condition F for models that need closure: reciprocity made exact, rows above 1 scaled to
    /// 1 (every sky view factor at least 0), no entry moved by more than the run's error
    /// estimate (refused, naming the entry, where one would be)
    #[arg(long)]
    pub(crate) condition: bool,
    /// Drop each pair whose F_ij and F_ji are both below V (after --condition, so reciprocity
    /// holds for what stays); the summary says how many went and the largest row sum dropped,
    /// which the sky view factors then count as sky
    #[arg(long, value_name = "V")]
    pub(crate) drop_below: Option<f64>,
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

#[derive(Args)]
pub(crate) struct SunArgs {
    #[command(flatten)]
    pub(crate) scene: SceneArgs,
    /// The sun's angle from the zenith, degrees (0 overhead, 90 on the horizon; beyond, no
    /// direct light). Without it and --sun-positions, the scene file's [sun] and [sky] tables
    #[arg(
        long,
        allow_negative_numbers = true,
        requires_all = ["azimuth", "direct_normal"],
        conflicts_with = "sun_positions"
    )]
    pub(crate) zenith: Option<f64>,
    /// The sun's compass azimuth, degrees clockwise from north
    #[arg(
        long,
        allow_negative_numbers = true,
        requires_all = ["zenith", "direct_normal"],
        conflicts_with = "sun_positions"
    )]
    pub(crate) azimuth: Option<f64>,
    /// The compass direction of the scene's +x, degrees clockwise from north (90: +x east and
    /// +y north, z up)
    #[arg(long, allow_negative_numbers = true, default_value_t = radiosity::sun::DEFAULT_X_AZIMUTH)]
    pub(crate) x_azimuth: f64,
    /// Direct normal irradiance of the sun (W/m²; every flux comes out in its unit)
    #[arg(
        long,
        allow_negative_numbers = true,
        requires_all = ["zenith", "azimuth"],
        conflicts_with = "sun_positions"
    )]
    pub(crate) direct_normal: Option<f64>,
    /// Diffuse horizontal irradiance of an isotropic sky, in the same unit (default 0)
    #[arg(long, allow_negative_numbers = true, conflicts_with = "sun_positions")]
    pub(crate) diffuse_horizontal: Option<f64>,
    /// A day of sun positions instead of one sun: a CSV file with the columns time, zenith,
    /// azimuth, direct_normal, diffuse_horizontal (one row per time), each solved on the same
    /// view factors
    #[arg(long, value_name = "FILE.csv")]
    pub(crate) sun_positions: Option<String>,
    /// Absolute tolerance on each view factor F_ij, which carry the sky light (the sky view
    /// factor 1 - Σ_j F_ij) and the reflections
    #[arg(long, default_value_t = 1e-6)]
    pub(crate) tolerance: f64,
    /// Direct sunlight alone, for the largest scenes and many sun positions: no view factors,
    /// so no sky light and reflections not followed (the sky view factors are NaN, all
    /// reflected light counts as escaped; --export writes facetarea and Sdir.txt only)
    #[arg(long, conflicts_with_all = ["diffuse_horizontal", "condition"])]
    pub(crate) direct_only: bool,
    /// Condition the view factors before they carry light (reciprocity exact, rows + sky = 1,
    /// no entry moved beyond the estimate; `viewfactors --condition`)
    #[arg(long)]
    pub(crate) condition: bool,
    /// Write each face's fluxes (area averages over its elements) to FILE.csv (a first column
    /// `time` with --sun-positions)
    #[arg(long, value_name = "FILE.csv")]
    pub(crate) csv: Option<String>,
    /// Write each element's fluxes to FILE.csv
    #[arg(long, value_name = "FILE.csv")]
    pub(crate) element_csv: Option<String>,
    /// Write the files of an urban LES's preprocessing (uDALES: facetarea.inp, svf.inp,
    /// netsw.inp or timedepsw.inp, Sdir.txt, vfsparse.inp) to DIR, one value per facet: the
    /// triangles of an .stl scene in its order (at --refine 0). The view factors are then
    /// conditioned and their pairs below 5e-7 dropped, and the light computed on them
    #[arg(long, value_name = "DIR")]
    pub(crate) export: Option<String>,
    /// Write each element's fluxes (those of --element-csv) as VTK cell data to FILE.vtu (one
    /// sun, or the first time of a day), for ParaView
    #[arg(long, value_name = "FILE.vtu")]
    pub(crate) vtu: Option<String>,
    /// Render the scene coloured by each element's absorbed flux (one sun, or the first time
    /// of a day), seen from the south-west, above
    #[arg(long, value_name = "FILE.png")]
    pub(crate) png: Option<String>,
    /// Picture size in pixels
    #[arg(long, value_name = "WxH", default_value = "1200x800")]
    pub(crate) png_size: String,
    /// The experiment number appended to the exported files' names (e.g. 001)
    #[arg(long, value_name = "N", requires = "export")]
    pub(crate) expnr: Option<String>,
    /// Write the summary as JSON to PATH (`-` for standard output) instead of text
    #[arg(long, value_name = "PATH")]
    pub(crate) json: Option<String>,
}
