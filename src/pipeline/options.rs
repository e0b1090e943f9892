//! A run's options as users name them (the command line's flags, Python's keywords), with their
//! defaults, and the one place where they become a [`RunConfig`]: both front ends fill
//! [`RunOptions`] and call [`RunOptions::config`], so that the same words give the same run.

use std::path::PathBuf;

use super::{Backend, MeshChoice, RunConfig, SceneSource};
use crate::assembly::{AssemblyOptions, QuadratureRule};
use crate::discretization::{Method, MethodName};
use crate::error::{Error, Result};
use crate::gpu::Precision;
use crate::kernels::graded;
use crate::mesh::{LineExtent, S5Diagonals};
use crate::operator::{self, OperatorChoice, ShadowedBlocks};
use crate::problems::{SolutionName, TrueSolution};
use crate::scene::SurfaceParameters;
use crate::solve::{self, SolverChoice, SolverOptions};

crate::vocabulary::named_options! {
    /// The meshes by name; [`MeshChoice`] carries what each needs.
    #[derive(Clone, Copy, Debug, PartialEq, Eq)]
    pub enum MeshName as "mesh" {
        /// Faces split by their diagonals, then refined
        Uniform = "uniform",
        /// The paper's hand-built discontinuity mesh (four-piece, five-piece)
        Discontinuity = "discontinuity",
        /// The same, with S5's cells split by the uniform mesh's diagonal instead of the paper's
        DiscontinuityUniformDiagonals = "discontinuity-uniform-diagonals",
        /// Shadow lines found automatically, faces triangulated along them (any scene)
        AutoDiscontinuity = "auto-discontinuity",
    }
}

crate::vocabulary::named_options! {
    /// Where the collocation matrix is assembled, by name; [`Backend`] carries the precision.
    #[derive(Clone, Copy, Debug, PartialEq, Eq)]
    pub enum BackendName as "backend" {
        /// Plain Rust on all cores (the reference)
        Cpu = "cpu",
        /// WGSL compute shaders through wgpu
        Gpu = "gpu",
    }
}

impl MeshChoice {
    /// Name used in reports and on the command line.
    pub fn name(&self) -> &'static str {
        match self {
            Self::Uniform => MeshName::Uniform.name(),
            Self::Discontinuity(S5Diagonals::Paper) => MeshName::Discontinuity.name(),
            Self::Discontinuity(S5Diagonals::AsUniform) => {
                MeshName::DiscontinuityUniformDiagonals.name()
            }
            Self::AutoDiscontinuity(LineExtent::Chords) => MeshName::AutoDiscontinuity.name(),
            Self::AutoDiscontinuity(LineExtent::Segments) => "auto-discontinuity-segments",
        }
    }

    /// The mesh named `name`; `lines` is the shadow lines' extent of `auto-discontinuity`.
    pub fn named(name: MeshName, lines: LineExtent) -> Self {
        match name {
            MeshName::Uniform => Self::Uniform,
            MeshName::Discontinuity => Self::Discontinuity(S5Diagonals::Paper),
            MeshName::DiscontinuityUniformDiagonals => Self::Discontinuity(S5Diagonals::AsUniform),
            MeshName::AutoDiscontinuity => Self::AutoDiscontinuity(lines),
        }
    }
}

impl Backend {
    /// `cpu` or `gpu`.
    pub fn name(&self) -> &'static str {
        match self {
            Self::Cpu => BackendName::Cpu.name(),
            Self::Gpu(_) => BackendName::Gpu.name(),
        }
    }

    /// The backend named `name`; `precision` is the GPU kernels'.
    pub fn named(name: BackendName, precision: Precision) -> Self {
        match name {
            BackendName::Cpu => Self::Cpu,
            BackendName::Gpu => Self::Gpu(precision),
        }
    }
}

/// A run's options by the names users give them; [`Default`] gives every default (those of
/// `radiosity solve` and of the Python package).
#[derive(Clone, Debug)]
pub struct RunOptions {
    /// (A, B, C) of the paper's surfaces.
    pub params: SurfaceParameters,
    /// The mesh.
    pub mesh: MeshName,
    /// How far the shadow lines of `auto-discontinuity` reach.
    pub shadow_lines: LineExtent,
    /// Refinement levels.
    pub refine: u32,
    /// Edges the mesh is graded toward (`FACE:K`).
    pub grade: Vec<String>,
    /// The grading exponent q.
    pub grading: f64,
    /// The collocation method.
    pub method: MethodName,
    /// α of the linear method (`None`: the paper's 1/6).
    pub alpha: Option<f64>,
    /// The rule for the collocation integrals.
    pub quadrature: QuadratureRule,
    /// MaxLev of the graded rules.
    pub max_level: u32,
    /// IBase of the graded Gauss rule.
    pub ibase: u32,
    /// The graded rules' level is MaxLev within this many element diameters of the node.
    pub near_ratio: f64,
    /// IMT subintervals of the linear method's 1-D integrals.
    pub imt_nodes: usize,
    /// Whether far and thin pairs use the far-field expansion and the thin-element path.
    pub far_field: bool,
    /// The true solution; `None`: x2y2 on the paper's surfaces, none elsewhere.
    pub solution: Option<SolutionName>,
    /// β of the shadow or edge solution.
    pub beta: Option<f64>,
    /// γ of the shadow solution.
    pub gamma: Option<f64>,
    /// Where K is assembled.
    pub backend: BackendName,
    /// The GPU kernels' precision.
    pub precision: Precision,
    /// Precision of a dense K kept in the GPU's memory (`--backend gpu --solver iterative`).
    pub storage: Precision,
    /// Which operator is stored.
    pub operator: OperatorChoice,
    /// The compressed operator's tolerance.
    pub compression_tolerance: f64,
    /// Whether the compressed operator has shadowed blocks.
    pub shadowed_blocks: ShadowedBlocks,
    /// Most memory the run may hold resident, in bytes; `None`: each large structure may take
    /// [`crate::assembly::MEMORY_SHARE`] of the memory available when it is built.
    pub memory_limit: Option<u64>,
    /// The linear solver.
    pub solver: SolverChoice,
    /// The iterative solver's relative residual.
    pub tolerance: f64,
    /// Colour bands (`rgb`, `r,g`, `grey`).
    pub bands: String,
    /// Read the operator from this file instead of building it.
    pub operator_file: Option<PathBuf>,
}

impl Default for RunOptions {
    fn default() -> Self {
        let assembly = AssemblyOptions::default();
        Self {
            params: SurfaceParameters::default(),
            mesh: MeshName::Uniform,
            shadow_lines: LineExtent::Segments,
            refine: 2,
            grade: Vec::new(),
            grading: 2.0,
            method: MethodName::Centroid,
            alpha: None,
            quadrature: QuadratureRule::Exact,
            max_level: 3,
            ibase: 1,
            near_ratio: graded::DEFAULT_NEAR,
            imt_nodes: assembly.imt_nodes,
            far_field: assembly.far_field,
            solution: None,
            beta: None,
            gamma: None,
            backend: BackendName::Cpu,
            precision: Precision::F64,
            storage: Precision::F64,
            operator: OperatorChoice::Auto,
            compression_tolerance: operator::DEFAULT_TOLERANCE,
            shadowed_blocks: ShadowedBlocks::Auto,
            memory_limit: None,
            solver: SolverChoice::Auto,
            tolerance: solve::DEFAULT_TOLERANCE,
            bands: crate::scene::BandSet::Grey.name().into(),
            operator_file: None,
        }
    }
}

impl RunOptions {
    /// The configuration of these options on `scene`, every combination checked: α with the
    /// linear method only, β and γ with the solutions that take them, the quadrature's levels,
    /// the compression tolerance and the memory limit in range.
    pub fn config(&self, scene: SceneSource) -> Result<RunConfig> {
        self.params.validate()?;
        if self.memory_limit == Some(0) {
            return Err(Error::InvalidParameter {
                name: "memory-limit",
                value: "0".into(),
                reason: "the limit must be at least one byte".into(),
            });
        }
        if self.imt_nodes < 2 {
            return Err(Error::InvalidParameter {
                name: "imt-nodes",
                value: self.imt_nodes.to_string(),
                reason: "the IMT rule needs at least 2 subintervals".into(),
            });
        }
        let quadrature = crate::assembly::Quadrature::named(
            self.quadrature,
            self.ibase,
            self.max_level,
            self.near_ratio,
        )?;
        let default_solution = match scene.is_paper_surface() {
            true => SolutionName::X2y2,
            false => SolutionName::None,
        };
        let solution = self.solution.unwrap_or(default_solution);
        let mut config = RunConfig {
            params: self.params,
            mesh: MeshChoice::named(self.mesh, self.shadow_lines),
            refine: self.refine,
            grade: self.grade.clone(),
            grading_exponent: self.grading,
            method: Method::named(self.method, self.alpha)?,
            solution: TrueSolution::named(solution, self.beta, self.gamma)?,
            assembly: AssemblyOptions {
                quadrature,
                imt_nodes: self.imt_nodes,
                far_field: self.far_field,
                ..Default::default()
            },
            backend: Backend::named(self.backend, self.precision),
            storage: self.storage,
            operator: self.operator,
            memory_limit: self.memory_limit,
            solver: SolverOptions { choice: self.solver, tolerance: self.tolerance },
            bands: crate::scene::parse_bands(&self.bands)?,
            operator_file: self.operator_file.clone(),
            ..RunConfig::of(scene)
        };
        config.compression.tolerance = self.compression_tolerance;
        config.compression.shadowed_blocks = self.shadowed_blocks;
        config.compression.validate()?;
        Ok(config)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::BuiltinScene;

    #[test]
    fn the_defaults_give_the_paper_run_on_its_surfaces_and_no_solution_elsewhere() {
        let paper = RunOptions::default().config(SceneSource::Builtin(BuiltinScene::FivePiece));
        assert_eq!(paper.unwrap().solution, Some(TrueSolution::X2Y2));
        let cube = RunOptions::default().config(SceneSource::Builtin(BuiltinScene::Cube)).unwrap();
        assert_eq!(cube.solution, None);
        assert_eq!(cube.method, Method::Centroid);
        assert_eq!(cube.operator, OperatorChoice::Auto);
    }

    #[test]
    fn combinations_that_do_not_belong_together_are_refused() {
        let cube = || SceneSource::Builtin(BuiltinScene::Cube);
        let alpha = RunOptions { alpha: Some(0.1), ..Default::default() };
        assert!(alpha.config(cube()).unwrap_err().to_string().contains("linear"));
        let beta = RunOptions { beta: Some(1.0), ..Default::default() };
        assert!(beta.config(cube()).is_err());
        let tolerance = RunOptions { compression_tolerance: 2.0, ..Default::default() };
        assert!(tolerance.config(cube()).is_err());
        let nothing = RunOptions { memory_limit: Some(0), ..Default::default() };
        assert!(nothing.config(cube()).unwrap_err().to_string().contains("memory-limit"));
        let linear = RunOptions { method: MethodName::Linear, ..Default::default() };
        let method = linear.config(cube()).unwrap().method;
        assert_eq!(method, Method::linear(Method::PAPER_ALPHA).unwrap());
    }
}
