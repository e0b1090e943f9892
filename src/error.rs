//! Errors of the library: each variant carries the values that explain it.

use thiserror::Error;

/// Everything that can go wrong in the library.
#[derive(Debug, Error)]
pub enum Error {
    /// A vertex coordinate is NaN or infinite.
    #[error("face '{face}': vertex {vertex} has a non-finite coordinate ({x}, {y}, {z})")]
    NonFiniteVertex {
        /// Face name.
        face: String,
        /// Vertex index within the face.
        vertex: usize,
        /// Coordinates as given.
        x: f64,
        /// Coordinates as given.
        y: f64,
        /// Coordinates as given.
        z: f64,
    },
    /// A vertex coordinate is too large for the kernels' arithmetic.
    #[error(
        "face '{face}': vertex {vertex} has a coordinate of magnitude {magnitude:e}, beyond \
         {limit:e}; rescale the scene (the results do not depend on its unit of length)"
    )]
    CoordinateOutOfRange {
        /// Face name.
        face: String,
        /// Vertex index within the face.
        vertex: usize,
        /// Largest |coordinate| of the vertex.
        magnitude: f64,
        /// The limit.
        limit: f64,
    },
    /// A scene whose faces span too many orders of magnitude.
    #[error(
        "scene '{scene}': face '{face}' has size {size:e} while coordinates reach {magnitude:e}; \
         a ratio beyond {limit:e} cannot be integrated in f64"
    )]
    ScaleRange {
        /// Scene name.
        scene: String,
        /// The smallest face.
        face: String,
        /// Its size.
        size: f64,
        /// Largest |coordinate| in the scene.
        magnitude: f64,
        /// Largest ratio allowed.
        limit: f64,
    },
    /// A vertex lies on the line through its two neighbours.
    #[error(
        "face '{face}': vertex {vertex} lies on the line through its neighbours; remove it (the \
         face's triangulation would contain a triangle without area)"
    )]
    CollinearVertex {
        /// Face name.
        face: String,
        /// Vertex index within the face.
        vertex: usize,
    },
    /// A face whose triangulation contains a triangle without area.
    #[error(
        "face '{face}': its triangulation has a triangle of area {area:e} against size {size:e} \
         (three vertices nearly collinear across a diagonal); move the vertex or split the face"
    )]
    DegenerateElement {
        /// Face name.
        face: String,
        /// Area of the triangle.
        area: f64,
        /// Its diameter.
        size: f64,
    },
    /// Two faces in one plane, facing the same way, overlap.
    #[error(
        "faces '{first}' and '{second}' lie in one plane, face the same way and overlap (area \
         {area:e}): each point there would be counted twice"
    )]
    OverlappingFaces {
        /// First face.
        first: String,
        /// Second face.
        second: String,
        /// Common area.
        area: f64,
    },
    /// A face has fewer than three vertices.
    #[error("face '{face}': a face needs at least 3 vertices, got {count}")]
    TooFewVertices {
        /// Face name.
        face: String,
        /// Number of vertices given.
        count: usize,
    },
    /// A face has (nearly) zero area.
    #[error("face '{face}': degenerate polygon (area {area:e} against size {size:e})")]
    DegenerateFace {
        /// Face name.
        face: String,
        /// Area of the polygon.
        area: f64,
        /// Diameter of the polygon.
        size: f64,
    },
    /// A face's vertices do not lie in one plane.
    #[error(
        "face '{face}': not planar: vertex {vertex} lies {distance:e} from the face's plane (tolerance {tolerance:e})"
    )]
    NonPlanarFace {
        /// Face name.
        face: String,
        /// Offending vertex.
        vertex: usize,
        /// Its distance from the best plane.
        distance: f64,
        /// Allowed distance.
        tolerance: f64,
    },
    /// A face's polygon crosses itself.
    #[error("face '{face}': the polygon's edges {first} and {second} cross each other")]
    SelfIntersectingFace {
        /// Face name.
        face: String,
        /// One edge index.
        first: usize,
        /// The other edge index.
        second: usize,
    },
    /// A given normal disagrees with the vertex order or is zero.
    #[error(
        "face '{face}': normal ({x}, {y}, {z}) is zero or not perpendicular to the face (vertex order gives the normal {expected:?})"
    )]
    InconsistentNormal {
        /// Face name.
        face: String,
        /// Normal as given.
        x: f64,
        /// Normal as given.
        y: f64,
        /// Normal as given.
        z: f64,
        /// The normal implied by the vertex order.
        expected: [f64; 3],
    },
    /// Reflectivity outside [0, 1] or not finite.
    #[error("face '{face}': reflectivity rho = {rho} is outside [0, 1]")]
    ReflectivityOutOfRange {
        /// Face name.
        face: String,
        /// Value given.
        rho: f64,
    },
    /// Emissivity not finite or negative.
    #[error("face '{face}': emissivity E = {value} must be finite and non-negative")]
    InvalidEmission {
        /// Face name.
        face: String,
        /// Value given.
        value: f64,
    },
    /// Parameters of the paper's surfaces that violate (3.1).
    #[error(
        "surface parameters (A, B, C) = ({a}, {b}, {c}) must be finite and positive with C < B and 2B < A (paper (3.1))"
    )]
    InvalidSurfaceParameters {
        /// A.
        a: f64,
        /// B.
        b: f64,
        /// C.
        c: f64,
    },
    /// Collocation parameter outside [0, 1/3).
    #[error("alpha = {alpha} is outside [0, 1/3)")]
    InvalidAlpha {
        /// Value given.
        alpha: f64,
    },
    /// A parameter out of its range.
    #[error("{name} = {value} is invalid: {reason}")]
    InvalidParameter {
        /// Parameter name.
        name: &'static str,
        /// Value given, as text.
        value: String,
        /// What is required.
        reason: String,
    },
    /// An unknown name (scene, method, solution, study...).
    #[error("unknown {kind} '{name}'; expected one of: {expected}")]
    UnknownName {
        /// What kind of name.
        kind: &'static str,
        /// The name given.
        name: String,
        /// The names accepted.
        expected: String,
    },
    /// A true solution that is defined only on some scenes.
    #[error(
        "true solution '{solution}' is defined on the four-piece and five-piece surfaces, not on '{scene}'"
    )]
    SolutionNeedsPaperSurface {
        /// Solution name.
        solution: String,
        /// Scene name.
        scene: String,
    },
    /// A dense matrix that cannot fit in memory.
    #[error(
        "a dense {dof} x {dof} matrix needs {needed_gib:.1} GiB but only {available_gib:.1} GiB may be used \
         (--memory-limit, or 80 % of the available memory; the iterative solver also keeps the matrix); use a coarser mesh (fewer refinement levels: each \
         level multiplies the memory by 16) or a machine with more memory"
    )]
    TooLarge {
        /// Unknowns.
        dof: usize,
        /// Memory the matrix needs.
        needed_gib: f64,
        /// Memory allowed.
        available_gib: f64,
    },
    /// A compressed operator that cannot fit in memory: refused before its build, where the
    /// estimate of what the build holds exceeds what may be used, or stopped during it.
    #[error("{what}; {advice}")]
    OperatorTooLarge {
        /// Unknowns.
        dof: usize,
        /// Memory needed: the estimate (above `available_gib`), or what the build had taken
        /// when it was stopped (a lower bound, above the share of `available_gib` it may take).
        needed_gib: f64,
        /// Memory that may be used.
        available_gib: f64,
        /// What was needed against what may be used, and where that came from.
        what: String,
        /// What would fit instead.
        advice: String,
    },
    /// The linear system is singular or too ill-conditioned to solve.
    #[error(
        "the system I - K is singular or nearly singular ({reason}; estimated condition number \
         {condition:e}): a closed surface with rho = 1 has no unique solution (lower rho or open \
         the surface)"
    )]
    SingularSystem {
        /// Estimated 1-norm condition number (infinite when exactly singular).
        condition: f64,
        /// What showed it.
        reason: String,
    },
    /// The iterative solver stopped without reaching the residual asked for.
    #[error(
        "the iterative solver (GMRES) stopped: {reason}; relative residual {residual:.2e} after \
         {iterations} iterations. Ask for a larger tolerance if that residual is enough, or use \
         the LU solver where the matrix fits in memory twice"
    )]
    NotConverged {
        /// Why it stopped.
        reason: IterationFailure,
        /// Relative residual reached (2-norm).
        residual: f64,
        /// Matrix-vector products done.
        iterations: usize,
    },
    /// GPU backend failures.
    #[error("GPU: {0}")]
    Gpu(String),
    /// Input/output.
    /// A scene or mesh file that cannot be read or understood.
    #[error("{path}: {reason}")]
    SceneFile {
        /// The file.
        path: String,
        /// What is wrong, with the line where known.
        reason: String,
    },
    /// A data file (emission cases, a saved operator) that cannot be read or does not fit the
    /// run it is given to.
    #[error("{path}: {reason}")]
    DataFile {
        /// The file.
        path: String,
        /// What is wrong, with the line where known.
        reason: String,
    },
    /// Reading or writing a file failed.
    #[error(transparent)]
    Io(#[from] std::io::Error),
}

/// Why an iterative solve stopped short.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum IterationFailure {
    /// A whole restart cycle failed to halve the residual: the tolerance lies below what f64
    /// reaches for this system, or the system is (nearly) singular.
    Stagnation,
    /// The iteration limit was reached while the residual was still falling.
    IterationLimit,
    /// The residual is no longer a finite number.
    NotFinite,
}

impl std::fmt::Display for IterationFailure {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Self::Stagnation => "stagnation (a restart cycle did not halve the residual)",
            Self::IterationLimit => "iteration limit reached while the residual was still falling",
            Self::NotFinite => "the residual is not finite",
        })
    }
}

/// Result alias of the library.
pub type Result<T> = std::result::Result<T, Error>;
