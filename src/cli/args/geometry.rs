//! The scene and its mesh (`SceneArgs`), the collocation method and its quadrature
//! (`CollocationArgs`), and both together (`GeometryArgs`), which every command that builds a
//! collocation problem flattens; `viewfactors` takes the scene and its mesh alone.

use clap::{Args, ValueEnum};

use super::import::ImportArgs;

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
pub(crate) enum QuadratureArg {
    Exact,
    SevenPoint,
    Gauss,
}

/// The scene, its mesh and the collocation method: every command that builds a collocation
/// problem flattens it.
#[derive(Args)]
pub(crate) struct GeometryArgs {
    #[command(flatten)]
    pub(crate) scene: SceneArgs,
    #[command(flatten)]
    pub(crate) collocation: CollocationArgs,
}

/// The scene and its mesh (all that `viewfactors` takes of the geometry).
#[derive(Args)]
pub(crate) struct SceneArgs {
    /// Scene: four-piece, five-piece, cube, baffled-box, a generated city (city:NXxNY, or
    /// city:NXxNY:lit under an emitting sky panel), or a scene file (.toml, .obj, .stl)
    #[arg(long)]
    pub(crate) scene: String,
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
    #[command(flatten)]
    pub(crate) import: ImportArgs,
}

/// The collocation method and how its integrals are evaluated.
#[derive(Args)]
pub(crate) struct CollocationArgs {
    /// Collocation method
    #[arg(long, value_enum, default_value_t = MethodArg::Centroid)]
    pub(crate) method: MethodArg,
    /// Node parameter alpha of the linear method, in [0, 1/3) (default 1/6)
    #[arg(long)]
    pub(crate) alpha: Option<f64>,
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
}
