//! The scene and its mesh (`SceneArgs`), the collocation method and its quadrature
//! (`CollocationArgs`), and both together (`GeometryArgs`), which every command that builds a
//! collocation problem flattens; `viewfactors` takes the scene and its mesh alone.

use clap::Args;
use radiosity::assembly::QuadratureRule;
use radiosity::discretization::MethodName;
use radiosity::mesh::LineExtent;
use radiosity::pipeline::{MeshName, RunOptions};

use super::named::named;

use super::import::ImportArgs;

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
    #[arg(long, value_parser = named::<MeshName>(), default_value_t = RunOptions::default().mesh)]
    pub(crate) mesh: MeshName,
    /// Extent of the shadow lines of --mesh auto-discontinuity: chords give the paper's mesh on
    /// its surfaces, segments far fewer elements in scenes with many occluders
    #[arg(
        long,
        value_parser = named::<LineExtent>(),
        default_value_t = RunOptions::default().shadow_lines
    )]
    pub(crate) shadow_lines: LineExtent,
    /// Grade the mesh toward an edge of a face: FACE:K names the edge from vertex K to K+1
    /// (repeatable; e.g. S1:2 and S5:3, the common edge of the five-piece surface)
    #[arg(long, value_name = "FACE:K")]
    pub(crate) grade: Vec<String>,
    /// Grading exponent q: a point at distance d from a graded edge moves to D (d/D)^q
    #[arg(long, default_value_t = RunOptions::default().grading)]
    pub(crate) grading: f64,
    /// Refinement levels: n = n0 * 4^refine
    #[arg(long, default_value_t = RunOptions::default().refine)]
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
    #[arg(long, value_parser = named::<MethodName>(), default_value_t = RunOptions::default().method)]
    pub(crate) method: MethodName,
    /// Node parameter alpha of the linear method, in [0, 1/3) (default 1/6)
    #[arg(long)]
    pub(crate) alpha: Option<f64>,
    /// How the collocation integrals are evaluated: closed forms (+ IMT), or the paper's graded
    /// 7-point or collapsed-Gauss rules (sec. 4.2)
    #[arg(
        long,
        value_parser = named::<QuadratureRule>(),
        default_value_t = RunOptions::default().quadrature
    )]
    pub(crate) quadrature: QuadratureRule,
    /// MaxLev of the seven-point and gauss quadratures: 4^MaxLev subtriangles, or 2^(IBase+MaxLev)
    /// Gauss points per dimension, next to the node
    #[arg(long, default_value_t = RunOptions::default().max_level)]
    pub(crate) max_level: u32,
    /// IBase of the gauss quadrature: 2^IBase points per dimension far from the node
    #[arg(long, default_value_t = RunOptions::default().ibase)]
    pub(crate) ibase: u32,
    /// The quadrature level is MaxLev within this many element diameters of the node, and falls by
    /// one per doubling of the distance
    #[arg(long, default_value_t = RunOptions::default().near_ratio)]
    pub(crate) near_ratio: f64,
    /// IMT subintervals for the linear method's 1-D integrals
    #[arg(long, default_value_t = RunOptions::default().imt_nodes)]
    pub(crate) imt_nodes: usize,
    /// Use the paper's closed forms for every pair, also far from the node and on thin elements
    /// (slower, and less accurate there, where the closed forms cancel)
    #[arg(long)]
    pub(crate) no_far_field: bool,
}
