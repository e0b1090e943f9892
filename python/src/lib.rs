//! `radiosity._native`: the library's scenes, solves, operators and view factors for Python
//! (PyO3, NumPy arrays in and out). The package `radiosity` (python/radiosity) wraps it in the
//! classes users see: results as objects, the operator as a SciPy `LinearOperator`, view
//! factors as a SciPy sparse matrix.
//!
//! Options are the command line's, by the same names and defaults (`refine`, `method`,
//! `operator`, ...), so that a Python run and a `radiosity solve` run are the same run.

use std::sync::Mutex;
use std::sync::atomic::{AtomicUsize, Ordering};

use glam::DVec3;
use numpy::ndarray::Array2;
use numpy::{IntoPyArray, PyArray1, PyArray2, PyReadonlyArray1, PyReadonlyArray2};
use pyo3::create_exception;
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;

use radiosity::discretization::MethodName;
use radiosity::gpu::Precision;
use radiosity::mesh::LineExtent;
use radiosity::operator::{OperatorChoice, ShadowedBlocks};
use radiosity::pipeline::{
    self, BackendName, BuiltOperator, MeshName, Problem, RunConfig, SceneSource,
};
use radiosity::problems::{EmissionCases, SolutionName};
use radiosity::progress::{Progress, ProgressSink};
use radiosity::scene::{Coplanar, Duplicates, ImportOptions, NonPlanar};
use radiosity::scene::{Scene, SurfaceParameters};
use radiosity::solve::SolverChoice;
use radiosity::viewfactors::{
    ClosureOptions, ViewFactorOptions, view_factors as compute_view_factors,
};
use radiosity::vocabulary::Named;

create_exception!(
    _native,
    RadiosityError,
    PyValueError,
    "What the library refused or could not do, with its message (the culprit named)."
);

/// The library's error as a Python exception.
fn raised(e: radiosity::Error) -> PyErr {
    RadiosityError::new_err(e.to_string())
}

/// The Python keyword of the option `T` (the command line's flag with `_` for `-`).
fn keyword<T: Named>() -> String {
    T::OPTION.replace('-', "_")
}

/// The value named `value` of the option `T`, or an error naming the names it accepts (the
/// library's table: this crate spells no option value).
fn pick<T: Named>(value: &str) -> PyResult<T> {
    pick_as(&keyword::<T>(), value)
}

/// [`pick`] for an option named `keyword` whose values are `T`'s (`storage`: a precision).
fn pick_as<T: Named>(keyword: &str, value: &str) -> PyResult<T> {
    T::parse(value).map_err(|_| {
        let names: Vec<&str> = T::names().collect();
        let expected = match names.split_last() {
            Some((last, [])) => last.to_string(),
            Some((last, rest)) => format!("{} or {last}", rest.join(", ")),
            None => String::new(),
        };
        RadiosityError::new_err(format!("{keyword} '{value}' is not known: expected {expected}"))
    })
}

/// The names an option accepts, under its keyword.
fn vocabulary<T: Named>() -> (String, Vec<&'static str>) {
    (keyword::<T>(), T::names().collect())
}

/// Every option with a fixed vocabulary and the names it accepts, from the library's tables
/// (for the package's tests and tools).
#[pyfunction]
fn option_values() -> std::collections::BTreeMap<String, Vec<&'static str>> {
    [
        vocabulary::<NonPlanar>(),
        vocabulary::<Duplicates>(),
        vocabulary::<Coplanar>(),
        vocabulary::<MethodName>(),
        vocabulary::<MeshName>(),
        vocabulary::<LineExtent>(),
        vocabulary::<SolutionName>(),
        vocabulary::<BackendName>(),
        vocabulary::<Precision>(),
        ("storage".into(), Precision::names().collect()),
        vocabulary::<OperatorChoice>(),
        vocabulary::<ShadowedBlocks>(),
        vocabulary::<SolverChoice>(),
    ]
    .into_iter()
    .collect()
}

/// The library's defaults of the run options (those of `radiosity solve`), by the keywords and
/// in the order of `RunOptions` below.
#[pyfunction]
fn default_options(py: Python<'_>) -> PyResult<Bound<'_, pyo3::types::PyDict>> {
    let d = pipeline::RunOptions::default();
    let out = pyo3::types::PyDict::new(py);
    out.set_item("refine", d.refine)?;
    out.set_item("method", d.method.name())?;
    out.set_item("alpha", d.alpha)?;
    out.set_item("mesh", d.mesh.name())?;
    out.set_item("shadow_lines", d.shadow_lines.name())?;
    out.set_item("solution", d.solution.map(SolutionName::name))?;
    out.set_item("beta", d.beta)?;
    out.set_item("gamma", d.gamma)?;
    out.set_item("backend", d.backend.name())?;
    out.set_item("precision", d.precision.name())?;
    out.set_item("storage", d.storage.name())?;
    out.set_item("operator", d.operator.name())?;
    out.set_item("compression_tolerance", d.compression_tolerance)?;
    out.set_item("shadowed_blocks", d.shadowed_blocks.name())?;
    out.set_item("memory_limit", d.memory_limit)?;
    out.set_item("solver", d.solver.name())?;
    out.set_item("tolerance", d.tolerance)?;
    out.set_item("operator_file", d.operator_file)?;
    out.set_item("bands", d.bands)?;
    Ok(out)
}

/// A scene, from a file, a built-in name or arrays.
#[pyclass(name = "Scene", module = "radiosity", frozen)]
struct PyScene {
    /// Shared with `source` where that is the scene itself (arrays).
    scene: std::sync::Arc<Scene>,
    /// Where it came from (the paper's surfaces default to their x2y2 solution).
    source: SceneSource,
    params: SurfaceParameters,
}

#[pymethods]
impl PyScene {
    /// A scene file (.toml, .obj, .stl), read as `radiosity solve --scene PATH` reads it.
    #[staticmethod]
    #[pyo3(signature = (path, nonplanar=None, duplicates=None, coplanar=None))]
    fn load(
        py: Python<'_>,
        path: std::path::PathBuf,
        nonplanar: Option<&str>,
        duplicates: Option<&str>,
        coplanar: Option<&str>,
    ) -> PyResult<Self> {
        let options = import_options(nonplanar, duplicates, coplanar)?;
        let scene = py.detach(|| radiosity::scene::load_with(&path, options)).map_err(raised)?;
        let source = SceneSource::File(path, options);
        Ok(Self { scene: scene.into(), source, params: SurfaceParameters::default() })
    }

    /// A built-in scene (four-piece, five-piece, cube, baffled-box) or a generated city
    /// (`city:NXxNY`, `city:NXxNY:lit`); `params` are (A, B, C) of the paper's surfaces.
    #[staticmethod]
    #[pyo3(signature = (name, params=(5.0, 2.0, 1.0)))]
    fn builtin(py: Python<'_>, name: &str, params: (f64, f64, f64)) -> PyResult<Self> {
        let source = match SceneSource::parse(name).map_err(raised)? {
            SceneSource::File(..) => {
                return Err(RadiosityError::new_err(format!(
                    "built-in scene '{name}' is not known: expected a built-in name; files: \
                     Scene.load"
                )));
            }
            source => source,
        };
        let params = SurfaceParameters { a: params.0, b: params.1, c: params.2 };
        params.validate().map_err(raised)?;
        let scene = py.detach(|| source.build(params)).map_err(raised)?.into();
        Ok(Self { scene, source, params })
    }

    /// A triangle mesh: `vertices` (m x 3), `triangles` (t x 3 vertex indices), `rho` and
    /// `emission` per triangle; read as an STL file is (coplanar triangles merged into faces
    /// for visibility unless `coplanar="keep"`).
    #[staticmethod]
    #[pyo3(signature = (vertices, triangles, rho, emission, name="mesh", coplanar=None))]
    fn from_arrays(
        py: Python<'_>,
        vertices: PyReadonlyArray2<'_, f64>,
        triangles: PyReadonlyArray2<'_, i64>,
        rho: PyReadonlyArray1<'_, f64>,
        emission: PyReadonlyArray1<'_, f64>,
        name: &str,
        coplanar: Option<&str>,
    ) -> PyResult<Self> {
        let (vertices, triangles) = (vertices.as_array(), triangles.as_array());
        if vertices.ncols() != 3 || triangles.ncols() != 3 {
            return Err(RadiosityError::new_err(format!(
                "vertices must be m x 3 and triangles t x 3; got {:?} and {:?}",
                vertices.shape(),
                triangles.shape()
            )));
        }
        let points: Vec<DVec3> =
            vertices.rows().into_iter().map(|v| DVec3::new(v[0], v[1], v[2])).collect();
        let mut corners = Vec::with_capacity(triangles.nrows());
        for (k, t) in triangles.rows().into_iter().enumerate() {
            let index = |i: i64| {
                usize::try_from(i).map_err(|_| {
                    RadiosityError::new_err(format!("triangle {k}: negative vertex index {i}"))
                })
            };
            corners.push([index(t[0])?, index(t[1])?, index(t[2])?]);
        }
        let (rho, emission) = (rho.as_array().to_vec(), emission.as_array().to_vec());
        let options = import_options(None, None, coplanar)?;
        let scene = py
            .detach(|| {
                radiosity::scene::from_triangles(name, &points, &corners, &rho, &emission, options)
            })
            .map_err(raised)?;
        let scene = std::sync::Arc::new(scene);
        let source = SceneSource::Given(scene.clone());
        Ok(Self { scene, source, params: SurfaceParameters::default() })
    }

    /// The scene's name.
    #[getter]
    fn name(&self) -> String {
        self.scene.name.clone()
    }

    /// The faces' names, in the order of per-face arrays (emission cases).
    #[getter]
    fn face_names(&self) -> Vec<String> {
        self.scene.faces.iter().map(|f| f.name.clone()).collect()
    }

    /// What the loader repaired or merged (the notes `solve` prints).
    #[getter]
    fn notes(&self) -> Vec<String> {
        self.scene.notes.clone()
    }

    fn __len__(&self) -> usize {
        self.scene.faces.len()
    }

    fn __repr__(&self) -> String {
        format!("Scene('{}', {} faces)", self.scene.name, self.scene.faces.len())
    }
}

/// How imperfect meshes are read, by the command line's names.
fn import_options(
    nonplanar: Option<&str>,
    duplicates: Option<&str>,
    coplanar: Option<&str>,
) -> PyResult<ImportOptions> {
    Ok(ImportOptions {
        nonplanar: nonplanar.map(pick).transpose()?,
        duplicates: duplicates.map(pick).transpose()?,
        coplanar: coplanar.map(pick).transpose()?,
    })
}

/// The run options `solve` and `operator` take, by the command line's names and defaults.
#[derive(FromPyObject)]
#[pyo3(from_item_all)]
struct RunOptions {
    refine: u32,
    method: String,
    alpha: Option<f64>,
    mesh: String,
    shadow_lines: String,
    solution: Option<String>,
    beta: Option<f64>,
    gamma: Option<f64>,
    backend: String,
    precision: String,
    storage: String,
    operator: String,
    compression_tolerance: f64,
    shadowed_blocks: String,
    memory_limit: Option<Size>,
    solver: String,
    tolerance: f64,
    operator_file: Option<std::path::PathBuf>,
    bands: String,
}

/// A size in bytes: a number, or text as `--memory-limit` takes it (`"4G"`, `"512M"`).
#[derive(FromPyObject)]
enum Size {
    Bytes(u64),
    Text(String),
}

impl Size {
    /// The bytes, or the command line's refusal of the text.
    fn bytes(&self) -> PyResult<u64> {
        match self {
            Self::Bytes(b) => Ok(*b),
            Self::Text(t) => radiosity::assembly::parse_size(t)
                .map_err(|why| RadiosityError::new_err(format!("memory_limit: {why}"))),
        }
    }
}

impl RunOptions {
    /// The configuration of these options on `scene`, progress going to `progress`: the
    /// library's options by their names, made a configuration where the command line's are.
    fn config(&self, scene: &PyScene, progress: ProgressSink) -> PyResult<RunConfig> {
        let options = pipeline::RunOptions {
            params: scene.params,
            refine: self.refine,
            method: pick(&self.method)?,
            alpha: self.alpha,
            mesh: pick(&self.mesh)?,
            shadow_lines: pick(&self.shadow_lines)?,
            solution: self.solution.as_deref().map(pick).transpose()?,
            beta: self.beta,
            gamma: self.gamma,
            backend: pick(&self.backend)?,
            precision: pick(&self.precision)?,
            storage: pick_as("storage", &self.storage)?,
            operator: pick(&self.operator)?,
            compression_tolerance: self.compression_tolerance,
            shadowed_blocks: pick(&self.shadowed_blocks)?,
            memory_limit: self.memory_limit.as_ref().map(Size::bytes).transpose()?,
            solver: pick(&self.solver)?,
            tolerance: self.tolerance,
            operator_file: self.operator_file.clone(),
            bands: self.bands.clone(),
            ..Default::default()
        };
        let config = options.config(scene.source.clone()).map_err(raised)?;
        Ok(RunConfig { progress, ..config })
    }
}

/// Progress reported to a Python callable `callback(stage, done, total)` (total 0: a stage
/// whose length is not known; a note comes as `callback("note: TEXT", 0, 0)`), about a hundred
/// calls per stage. An exception in the callback is printed and not raised again.
struct Callback {
    callback: Py<PyAny>,
    stage: Mutex<(String, usize)>,
    done: AtomicUsize,
    reported: AtomicUsize,
}

impl Callback {
    fn call(&self, stage: &str, done: usize, total: usize) {
        Python::attach(|py| {
            if let Err(e) = self.callback.call1(py, (stage, done, total)) {
                e.print(py);
            }
        });
    }
}

impl Progress for Callback {
    fn start(&self, stage: &str, len: usize) {
        *self.stage.lock().expect("progress lock") = (stage.to_string(), len);
        self.done.store(0, Ordering::Relaxed);
        self.reported.store(0, Ordering::Relaxed);
        self.call(stage, 0, len);
    }

    fn advance(&self, steps: usize) {
        let done = self.done.fetch_add(steps, Ordering::Relaxed) + steps;
        let (stage, len) = self.stage.lock().expect("progress lock").clone();
        let step = (len / 100).max(1);
        let last = self.reported.load(Ordering::Relaxed);
        if done >= last + step
            && self
                .reported
                .compare_exchange(last, done, Ordering::Relaxed, Ordering::Relaxed)
                .is_ok()
        {
            self.call(&stage, done, len);
        }
    }

    fn finish(&self) {
        let (stage, len) = self.stage.lock().expect("progress lock").clone();
        self.call(&stage, len, len);
    }

    fn note(&self, text: &str) {
        self.call(&format!("note: {text}"), 0, 0);
    }
}

/// Progress to `callback`, or nowhere.
fn progress_to(callback: Option<Py<PyAny>>) -> ProgressSink {
    match callback {
        None => ProgressSink::default(),
        Some(callback) => ProgressSink(std::sync::Arc::new(Callback {
            callback,
            stage: Mutex::new((String::new(), 0)),
            done: AtomicUsize::new(0),
            reported: AtomicUsize::new(0),
        })),
    }
}

/// Columns of emission values (one per face or per node) from a 1-D or 2-D array: a 2-D array
/// holds one case per column.
fn emission_columns(emission: &Bound<'_, PyAny>) -> PyResult<(Vec<Vec<f64>>, bool)> {
    if let Ok(one) = emission.extract::<PyReadonlyArray1<'_, f64>>() {
        return Ok((vec![one.as_array().to_vec()], false));
    }
    let many: PyReadonlyArray2<'_, f64> = emission.extract().map_err(|_| {
        RadiosityError::new_err(
            "emission must be a 1-D or 2-D array of float64 (one column per case)",
        )
    })?;
    let many = many.as_array();
    Ok((many.columns().into_iter().map(|c| c.to_vec()).collect(), true))
}

/// The positions of `nodes` in the user's coordinates (the scene's local frame moved back by
/// `origin`) as a dof x 3 array, and their faces.
fn nodes_array<'py>(
    py: Python<'py>,
    nodes: &[radiosity::discretization::Node],
    origin: DVec3,
) -> (Bound<'py, PyArray2<f64>>, Bound<'py, PyArray1<usize>>) {
    let positions = Array2::from_shape_fn((nodes.len(), 3), |(i, k)| {
        (nodes[i].position + origin).to_array()[k]
    });
    let faces: Vec<usize> = nodes.iter().map(|n| n.face()).collect();
    (positions.into_pyarray(py), faces.into_pyarray(py))
}

/// One run, as `radiosity solve` does it; `emission` (1-D or 2-D: one case per column, one row
/// per face or per node) replaces the scene's emission. Returns a dict with `u`, `nodes`,
/// `faces`, `emission` (E at the nodes), `report` (the JSON of `solve --json`), with cases
/// `cases_u` (dof x cases), with colour bands `bands_u` (dof x bands).
#[pyfunction]
#[pyo3(signature = (scene, options, emission=None, progress=None))]
fn solve<'py>(
    py: Python<'py>,
    scene: &PyScene,
    options: RunOptions,
    emission: Option<&Bound<'py, PyAny>>,
    progress: Option<Py<PyAny>>,
) -> PyResult<Bound<'py, pyo3::types::PyDict>> {
    let mut options = options;
    if emission.is_some() && options.solution.is_none() {
        // The cases give E: no true solution unless one is asked for (and then refused).
        options.solution = Some(SolutionName::None.name().into());
    }
    let mut config = options.config(scene, progress_to(progress))?;
    if let Some(emission) = emission {
        let (columns, _) = emission_columns(emission)?;
        config.cases = Some(EmissionCases::from_columns(columns).map_err(raised)?);
    }
    let run = py
        .detach(|| {
            pipeline::run_problem(&config, pipeline::build_on(&config, Scene::clone(&scene.scene))?)
        })
        .map_err(raised)?;
    let out = pyo3::types::PyDict::new(py);
    let nodes: Vec<_> = run.disc.nodes().collect();
    let (positions, faces) = nodes_array(py, &nodes, run.scene.origin);
    out.set_item("nodes", positions)?;
    out.set_item("faces", faces)?;
    let report = serde_json::to_string(&run.report).expect("the report is JSON");
    out.set_item("report", report)?;
    out.set_item("emission", run.emission.into_pyarray(py))?;
    if !run.bands.is_empty() {
        let (dof, count) = (run.report.u.len(), run.bands.len());
        let bands = Array2::from_shape_fn((dof, count), |(i, c)| run.bands[c].u[i]);
        out.set_item("bands_u", bands.into_pyarray(py))?;
    }
    if !run.cases.is_empty() {
        let (dof, count) = (run.report.u.len(), run.cases.len());
        let cases = Array2::from_shape_fn((dof, count), |(i, c)| run.cases[c].u[i]);
        out.set_item("cases_u", cases.into_pyarray(py))?;
    }
    out.set_item("u", run.report.u.into_pyarray(py))?;
    Ok(out)
}

/// The collocation operator K of one run's problem, built once: products `K x` and solves of
/// `(I - K) u = E` for any number of right-hand sides.
#[pyclass(name = "NativeOperator", module = "radiosity", frozen)]
struct PyOperator {
    config: RunConfig,
    problem: Problem,
    built: BuiltOperator,
}

#[pymethods]
impl PyOperator {
    /// Number of unknowns.
    #[getter]
    fn dof(&self) -> usize {
        self.built.dof()
    }

    /// The operator's summary (JSON): `operator`, `setup_seconds`, `operator_bytes`, blocks.
    #[getter]
    fn report(&self) -> String {
        let summary = self.built.summary(&self.config);
        serde_json::to_string(&summary).expect("the summary is JSON")
    }

    /// The nodes' positions (dof x 3, the user's coordinates), faces and reflectivities.
    #[allow(clippy::type_complexity)]
    fn nodes<'py>(
        &self,
        py: Python<'py>,
    ) -> (Bound<'py, PyArray2<f64>>, Bound<'py, PyArray1<usize>>, Bound<'py, PyArray1<f64>>) {
        let nodes: Vec<_> = self.problem.disc.nodes().collect();
        let (positions, faces) = nodes_array(py, &nodes, self.problem.scene.origin);
        let rho: Vec<f64> = nodes.iter().map(|n| n.rho).collect();
        (positions, faces, rho.into_pyarray(py))
    }

    /// Saves the operator (as `assemble --save` does) for `operator(..., operator_file=path)`
    /// and `solve --operator-file`.
    fn save(&self, py: Python<'_>, path: std::path::PathBuf) -> PyResult<()> {
        py.detach(|| pipeline::save_operator(&path, &self.built, &self.config, &self.problem))
            .map_err(raised)
    }

    /// `K x`.
    fn matvec<'py>(
        &self,
        py: Python<'py>,
        x: PyReadonlyArray1<'py, f64>,
    ) -> PyResult<Bound<'py, PyArray1<f64>>> {
        let x = x.as_array().to_vec();
        if x.len() != self.built.dof() {
            return Err(RadiosityError::new_err(format!(
                "x has {} values; the operator has {} unknowns",
                x.len(),
                self.built.dof()
            )));
        }
        Ok(py.detach(|| self.built.apply(&x)).map_err(raised)?.into_pyarray(py))
    }

    /// Solves `(I - K) u = E` for E per face or per node, 1-D or one case per column (2-D);
    /// returns u (dof, or dof x cases) and each case's report (JSON).
    fn solve<'py>(
        &self,
        py: Python<'py>,
        emission: &Bound<'py, PyAny>,
    ) -> PyResult<(Bound<'py, PyAny>, Vec<String>)> {
        let (columns, two_d) = emission_columns(emission)?;
        let cases = EmissionCases::from_columns(columns).map_err(raised)?;
        let outcomes = py
            .detach(|| {
                let columns = cases.at_nodes(&self.problem.scene, &self.problem.disc)?;
                let rhs: Vec<&[f64]> = columns.iter().map(Vec::as_slice).collect();
                self.built.solve_many(&self.config, &self.problem, &rhs)
            })
            .map_err(raised)?;
        let reports = outcomes
            .iter()
            .map(|o| serde_json::to_string(o).expect("the outcome is JSON"))
            .collect();
        let u = if two_d {
            let (dof, count) = (self.built.dof(), outcomes.len());
            Array2::from_shape_fn((dof, count), |(i, c)| outcomes[c].u[i])
                .into_pyarray(py)
                .into_any()
        } else {
            let outcome = outcomes.into_iter().next().expect("one case");
            outcome.u.into_pyarray(py).into_any()
        };
        Ok((u, reports))
    }
}

/// Builds the operator of one run (as `solve` would, without solving).
#[pyfunction]
#[pyo3(signature = (scene, options, progress=None))]
fn operator(
    py: Python<'_>,
    scene: &PyScene,
    options: RunOptions,
    progress: Option<Py<PyAny>>,
) -> PyResult<PyOperator> {
    let mut config = options.config(scene, progress_to(progress))?;
    config.solution = None;
    if !config.bands.is_empty() {
        return Err(RadiosityError::new_err(
            "an operator is grey: solve colour bands with radiosity.solve(..., bands=...)",
        ));
    }
    py.detach(|| {
        let problem = pipeline::build_on(&config, Scene::clone(&scene.scene))?;
        let built = pipeline::build_operator(&config, &problem)?;
        Ok(PyOperator { config, problem, built })
    })
    .map_err(raised)
}

/// Element-to-element view factors of the scene's uniform mesh at `refine`, as `radiosity
/// viewfactors` computes them (with `--condition` and `--drop-below` where asked): (indptr,
/// indices, data, n, areas, sky view factors, summary JSON) of the CSR matrix of its non-zero
/// entries.
#[pyfunction]
#[pyo3(signature = (
    scene, refine, tolerance, max_depth, each_direction=false, condition=false, drop_below=None,
    progress=None
))]
#[allow(clippy::type_complexity, clippy::too_many_arguments)]
fn view_factors<'py>(
    py: Python<'py>,
    scene: &PyScene,
    refine: u32,
    tolerance: f64,
    max_depth: u32,
    each_direction: bool,
    condition: bool,
    drop_below: Option<f64>,
    progress: Option<Py<PyAny>>,
) -> PyResult<(
    Bound<'py, PyArray1<i64>>,
    Bound<'py, PyArray1<i64>>,
    Bound<'py, PyArray1<f64>>,
    usize,
    Bound<'py, PyArray1<f64>>,
    Bound<'py, PyArray1<f64>>,
    String,
)> {
    let options = ViewFactorOptions { tolerance, max_depth, each_direction, ..Default::default() };
    options.validate().map_err(raised)?;
    let closure = ClosureOptions { condition, drop_below };
    closure.validate().map_err(raised)?;
    let run = pipeline::RunOptions { refine, params: scene.params, ..Default::default() };
    let config = run.config(scene.source.clone()).map_err(raised)?;
    let config = RunConfig { progress: progress_to(progress), ..config };
    let (f, summary) = py
        .detach(|| {
            let started = std::time::Instant::now();
            let problem = pipeline::build_on(&config, Scene::clone(&scene.scene))?;
            let Problem { scene, mesh, planner, .. } = &problem;
            config.progress.start("viewfactors", mesh.len());
            let mut f = compute_view_factors(scene, mesh, planner, &options, &*config.progress)?;
            config.progress.finish();
            let closure = f.close(&closure)?;
            let mut summary = f.summary(&scene.name, started.elapsed().as_secs_f64());
            summary.closure = closure;
            Ok::<_, radiosity::Error>((f, summary))
        })
        .map_err(raised)?;
    let as_i64 = |k: usize| i64::try_from(k).expect("an index fits in i64");
    let indptr: Vec<i64> = f.row_starts.iter().map(|&k| as_i64(k)).collect();
    let indices: Vec<i64> = f.columns.iter().map(|&j| i64::from(j)).collect();
    let summary = serde_json::to_string(&summary).expect("the summary is JSON");
    let (n, sky) = (f.len(), f.sky_view_factors());
    Ok((
        indptr.into_pyarray(py),
        indices.into_pyarray(py),
        f.values.into_pyarray(py),
        n,
        f.areas.into_pyarray(py),
        sky.into_pyarray(py),
        summary,
    ))
}

/// The native part of the `radiosity` package.
#[pymodule]
fn _native(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<PyScene>()?;
    m.add_class::<PyOperator>()?;
    m.add_function(wrap_pyfunction!(solve, m)?)?;
    m.add_function(wrap_pyfunction!(operator, m)?)?;
    m.add_function(wrap_pyfunction!(view_factors, m)?)?;
    m.add_function(wrap_pyfunction!(option_values, m)?)?;
    m.add_function(wrap_pyfunction!(default_options, m)?)?;
    m.add("RadiosityError", m.py().get_type::<RadiosityError>())?;
    Ok(())
}
