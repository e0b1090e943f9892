//! The arguments into the library's `RunOptions`, and from there (`RunOptions::config`, the
//! one place Python's keywords go too) into a `RunConfig`; then what only the command line
//! sets: progress on standard error, the ranks, `solve`'s emission cases and surface lattice.

use radiosity::error::{Error, Result};
use radiosity::pipeline::{RunConfig, RunOptions, SceneSource};
use radiosity::problems::{EmissionCases, SolutionName};

use crate::cli::progress;
use crate::cli::ranks::{is_root, world};

use super::commands::SolveArgs;
use super::geometry::{CollocationArgs, GeometryArgs, SceneArgs};
use super::values::parse_params;

impl CollocationArgs {
    /// The method's options, into `options`.
    fn fill(&self, options: &mut RunOptions) {
        options.method = self.method;
        options.alpha = self.alpha;
        options.quadrature = self.quadrature;
        options.max_level = self.max_level;
        options.ibase = self.ibase;
        options.near_ratio = self.near_ratio;
        options.imt_nodes = self.imt_nodes;
        options.far_field = !self.no_far_field;
    }
}

impl SceneArgs {
    /// The scene's and its mesh's options, the others at their defaults.
    fn options(&self) -> Result<RunOptions> {
        Ok(RunOptions {
            params: parse_params(&self.params)?,
            mesh: self.mesh,
            shadow_lines: self.shadow_lines,
            refine: self.refine,
            grade: self.grade.clone(),
            grading: self.grading,
            ..RunOptions::default()
        })
    }

    /// A configuration of the scene and its mesh alone (`viewfactors`, which integrates its own
    /// way): the centroid method and the default options of its integrals, unused there.
    pub(crate) fn config(&self) -> Result<RunConfig> {
        self.config_of(&self.options()?)
    }

    /// The configuration of `options` on this scene, progress on standard error (the root
    /// rank's) and the ranks of `mpirun`.
    pub(crate) fn config_of(&self, options: &RunOptions) -> Result<RunConfig> {
        let scene = SceneSource::parse(&self.scene)?.with_import(self.import.options());
        Ok(RunConfig {
            progress: if is_root() { progress::on_stderr() } else { Default::default() },
            ranks: world(),
            ..options.config(scene)?
        })
    }
}

impl GeometryArgs {
    /// The scene's, its mesh's and the method's options.
    pub(crate) fn options(&self) -> Result<RunOptions> {
        let mut options = self.scene.options()?;
        self.collocation.fill(&mut options);
        Ok(options)
    }
}

impl SolveArgs {
    pub(crate) fn config(&self) -> Result<RunConfig> {
        let mut options = self.geometry.options()?;
        self.device.fill(&mut options);
        options.storage = self.storage;
        self.operator.fill(&mut options);
        // Emission cases give E: no true solution unless one is asked for (and then refused).
        let cases_without_solution = self.emission_file.is_some() && self.solution.is_none();
        options.solution =
            if cases_without_solution { Some(SolutionName::None) } else { self.solution };
        options.beta = self.beta;
        options.gamma = self.gamma;
        options.solver = self.solver;
        options.tolerance = self.tolerance;
        options.bands = self.colour.bands.clone();
        options.operator_file = self.operator_file.as_ref().map(std::path::PathBuf::from);
        let mut config = self.geometry.scene.config_of(&options)?;
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
        if let Some(path) = &self.emission_file {
            config.cases = Some(EmissionCases::read_csv(std::path::Path::new(path))?);
        }
        Ok(config)
    }
}
