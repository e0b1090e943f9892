//! Stiff systems: rho → 1 in nearly closed and closed enclosures, where ||K|| → 1 and, for a closed
//! surface with rho = 1, I − K is singular (Lemma 2.1: K 1 = 1).
//!
//! For each scene and rho the study assembles K, takes a known discrete solution u* (an affine
//! function of position at the nodes), forms E = (I − K) u* with compensated dot products, and
//! solves: plain LU (the "before"), [`crate::solve::solve`] with LU (singularity checks,
//! condition estimate, refinement with compensated residuals) and with GMRES, checked against LU.
//! Each row of K scales with the rho of its node's face, so each scene is assembled once, with
//! rho = 1, and scaled. Scenes with a black lamp (a face with rho = 0 among faces with rho → 1)
//! check that zero rows are taken out and that GMRES survives them.

use glam::DVec3;
use serde::Serialize;

use crate::assembly::{AssemblyOptions, CollocationMatrix};
use crate::discretization::{Discretization, Method};
use crate::error::{Error, Result};
use crate::mesh::{Mesh, MeshKind};
use crate::pipeline::{Backend, Problem, assemble_on};
use crate::progress::Silent;
use crate::scene::{Face, Scene, baffled_box, cube};
use crate::solve::{LuSolution, SolverChoice, SolverOptions, compensated_residual, solve};

/// The reflectivities of the study.
pub const RHOS: [f64; 7] = [0.9, 0.99, 0.999, 0.9999, 0.999999, 0.99999999, 1.0];

/// One row: a scene at one rho.
#[derive(Clone, Debug, Serialize)]
pub struct StiffRow {
    /// Scene.
    pub case: String,
    /// `centroid` or `linear`.
    pub method: &'static str,
    /// Reflectivity of every face.
    pub rho: f64,
    /// Unknowns.
    pub dof: usize,
    /// Estimated 1-norm condition number of I − K.
    pub condition_estimate: Option<f64>,
    /// `max |u − u*| / max |u*|` of plain LU (no checks, no refinement).
    pub error_lu: Option<f64>,
    /// The same after [`solve`] (refined).
    pub error_refined: Option<f64>,
    /// Refinement steps taken.
    pub refinement_steps: Option<usize>,
    /// `max |u − u*| / max |u*|` of GMRES (default tolerance).
    pub error_gmres: Option<f64>,
    /// `max |u_GMRES − u_LU| / max |u_LU|`.
    pub gmres_vs_lu: Option<f64>,
    /// GMRES iterations (matrix-vector products).
    pub gmres_iterations: Option<usize>,
    /// Unknowns taken out as u = E (rows of the black face).
    pub rows_eliminated: usize,
    /// The bound claimed for the refined error: 4 ε, plus the effect of rounding E to f64 once,
    /// 3 κ ε ||E|| / ||u*|| (3: the condition estimate is a lower bound, usually within 3).
    pub bound: Option<f64>,
    /// `solved`, or why not.
    pub status: String,
}

/// The unit cube with a slit of width `w` along one edge of its top face (`0 < w < 1`).
pub fn slit_cube(w: f64) -> Result<Scene> {
    let mut faces = cube()?.faces;
    let s = 1.0 - w;
    let corners = [(0.0, 0.0), (0.0, s), (1.0, s), (1.0, 0.0)];
    faces[1] =
        Face::new("top", corners.iter().map(|&(x, y)| DVec3::new(x, y, 1.0)).collect(), 0.5)?;
    Scene::new(format!("cube, top {:.0}% open", 100.0 * w), faces)
}

fn with_rho(mut scene: Scene, rho: f64) -> Scene {
    for f in &mut scene.faces {
        f.rho = rho;
    }
    scene
}

/// Row scales: the row of a node on face `black` gets 0, every other row `rho`.
fn row_rhos(disc: &Discretization, black: Option<usize>, rho: f64) -> Vec<f64> {
    disc.nodes().map(|n| if Some(n.face()) == black { 0.0 } else { rho }).collect()
}

/// Runs the study on `backend` (the assembly; the solves run on the CPU).
pub fn run(backend: Backend) -> Result<Vec<StiffRow>> {
    let scenes = [
        (slit_cube(0.1)?, Method::Centroid, 2, None),
        (slit_cube(0.1)?, Method::Linear { alpha: 1.0 / 6.0 }, 1, None),
        (cube()?, Method::Centroid, 2, None),
        (baffled_box()?, Method::Centroid, 2, None),
        (cube()?, Method::Centroid, 2, Some("top")),
        (cube()?, Method::Linear { alpha: 1.0 / 6.0 }, 1, Some("top")),
    ];
    let mut rows = Vec::new();
    for (scene, method, refine, black) in scenes {
        let scene = with_rho(scene, 1.0);
        let black = black.map(|name| scene.face_index(name).expect("the black face exists"));
        let case = match black {
            Some(f) => format!("{}, black {}", scene.name, scene.faces[f].name),
            None => scene.name.clone(),
        };
        let mesh = Mesh::new(&scene, &MeshKind::Uniform, refine)?;
        let disc = Discretization::new(&scene, &mesh, method)?;
        let problem = Problem::new(scene, mesh, disc);
        let (k1, _) = assemble_on(backend, &problem, &AssemblyOptions::default(), &Silent)?;
        let disc = &problem.disc;
        let exact: Vec<f64> =
            disc.nodes().map(|n| 1.0 + n.position.dot(DVec3::new(0.5, 0.25, 0.125))).collect();
        let dof = disc.dof();
        for rho in RHOS {
            let scales = row_rhos(disc, black, rho);
            let data = k1
                .matrix
                .as_slice()
                .chunks_exact(dof)
                .zip(&scales)
                .flat_map(|(row, r)| row.iter().map(move |v| v * r))
                .collect();
            let k = CollocationMatrix::from_rows(dof, data);
            let zero = vec![0.0; dof];
            let rhs: Vec<f64> =
                compensated_residual(&k, &exact, &zero).iter().map(|v| -v).collect();
            rows.push(stiff_row(&case, method, rho, &k, &rhs, &exact)?);
        }
    }
    Ok(rows)
}

/// Solves one stiff system three ways (plain LU, the solver's LU, GMRES) against its known
/// solution `exact`.
fn stiff_row(
    case: &str,
    method: Method,
    rho: f64,
    k: &CollocationMatrix,
    rhs: &[f64],
    exact: &[f64],
) -> Result<StiffRow> {
    let dof = k.dof();
    let error_of = |u: &[f64]| relative_difference(u, exact);
    let error_lu = LuSolution::new(k, rhs, 0).ok().map(|s| error_of(&s.u));
    let mut row = StiffRow {
        case: case.to_string(),
        method: method.name(),
        rho,
        dof,
        condition_estimate: None,
        error_lu,
        error_refined: None,
        refinement_steps: None,
        error_gmres: None,
        gmres_vs_lu: None,
        gmres_iterations: None,
        rows_eliminated: 0,
        bound: None,
        status: "solved".into(),
    };
    match solve(k, rhs, SolverOptions::with(SolverChoice::Lu)) {
        Ok(s) => {
            let kappa = s.condition_estimate.unwrap_or(f64::INFINITY);
            row.condition_estimate = Some(kappa);
            row.error_refined = Some(error_of(&s.u));
            row.refinement_steps = Some(s.refinement_steps);
            row.rows_eliminated = s.rows_eliminated;
            let ratio = max_abs(rhs) / max_abs(exact);
            row.bound = Some(4.0 * f64::EPSILON + 3.0 * kappa * f64::EPSILON * ratio);
            match solve(k, rhs, SolverOptions::with(SolverChoice::Iterative)) {
                Ok(g) => {
                    row.error_gmres = Some(error_of(&g.u));
                    row.gmres_vs_lu = Some(relative_difference(&g.u, &s.u));
                    row.gmres_iterations = Some(g.iterations);
                }
                Err(e @ Error::NotConverged { .. }) => row.status = format!("LU solved; {e}"),
                Err(e) => return Err(e),
            }
        }
        Err(Error::SingularSystem { condition, reason }) => {
            row.condition_estimate = condition.is_finite().then_some(condition);
            row.status = format!("refused as singular: {reason}");
        }
        Err(e) => return Err(e),
    }
    Ok(row)
}

fn max_abs(v: &[f64]) -> f64 {
    v.iter().fold(0.0f64, |m, x| m.max(x.abs()))
}

fn relative_difference(u: &[f64], exact: &[f64]) -> f64 {
    u.iter().zip(exact).fold(0.0f64, |m, (a, b)| m.max((a - b).abs())) / max_abs(exact)
}
