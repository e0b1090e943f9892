//! The arguments into the library's `RunConfig`: the geometry's configuration, a solve's, the
//! operator's choices, and the backend.

use radiosity::assembly::{AssemblyOptions, Quadrature};
use radiosity::discretization::Method;
use radiosity::error::{Error, Result};
use radiosity::gpu::Precision;
use radiosity::mesh::{LineExtent, S5Diagonals};
use radiosity::operator::{OperatorChoice, ShadowedBlocks};
use radiosity::pipeline::{Backend, MeshChoice, RunConfig, SceneSource};
use radiosity::problems::{EmissionCases, TrueSolution};
use radiosity::solve::{SolverChoice, SolverOptions};

use crate::cli::progress;
use crate::cli::ranks::{is_root, world};

use super::commands::{SolveArgs, SolverArg};
use super::device::{BackendArg, PrecisionArg};
use super::geometry::{
    CollocationArgs, GeometryArgs, MeshArg, MethodArg, QuadratureArg, SceneArgs, ShadowLinesArg,
};
use super::operator::{OperatorArg, OperatorArgs};
use super::values::parse_params;

pub(crate) fn backend(b: BackendArg, p: PrecisionArg) -> Backend {
    match b {
        BackendArg::Cpu => Backend::Cpu,
        BackendArg::Gpu => Backend::Gpu(match p {
            PrecisionArg::F64 => Precision::F64,
            PrecisionArg::F32 => Precision::F32,
        }),
    }
}

impl CollocationArgs {
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

    /// The method and the options of its integrals.
    fn method_and_assembly(&self) -> Result<(Method, AssemblyOptions)> {
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
        let assembly = AssemblyOptions {
            quadrature: self.quadrature()?,
            imt_nodes: self.imt_nodes,
            far_field: !self.no_far_field,
            ..Default::default()
        };
        Ok((method, assembly))
    }
}

impl SceneArgs {
    /// A configuration of the scene and its mesh alone (`viewfactors`, which integrates its own
    /// way): the centroid method and the default options of its integrals, unused there.
    pub(crate) fn config(&self) -> Result<RunConfig> {
        self.config_with(None)
    }

    /// A configuration with the paper's x2y2 solution on the paper's surfaces, none elsewhere;
    /// the method and its integrals from `collocation`, or the defaults.
    fn config_with(&self, collocation: Option<&CollocationArgs>) -> Result<RunConfig> {
        let scene = SceneSource::parse(&self.scene)?.with_import(self.import.options());
        let (method, assembly) = match collocation {
            Some(c) => c.method_and_assembly()?,
            None => (Method::Centroid, AssemblyOptions::default()),
        };
        let solution = scene.is_paper_surface().then_some(TrueSolution::X2Y2);
        Ok(RunConfig {
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
            assembly,
            progress: if is_root() { progress::on_stderr() } else { Default::default() },
            ranks: world(),
            ..RunConfig::of(scene)
        })
    }
}

impl GeometryArgs {
    /// A configuration of the scene, its mesh and the collocation method.
    pub(crate) fn config(&self) -> Result<RunConfig> {
        self.scene.config_with(Some(&self.collocation))
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
