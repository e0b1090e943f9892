//! Errors over all of S, not only at the nodes (paper sec. 2.5 and Fig. 3.7): at sample points inside
//! every element, of the collocation solution u_n itself (piecewise constant or linear) and of the
//! iterated solution `ũ_n = E + K u_n`, each against the true u.
//!
//! At a node, `ũ_n = u_n` by the collocation equations (2.16); between nodes the two differ, and
//! for piecewise linear collocation u_n converges only at O(h²) overall (with discontinuity
//! meshing) while its nodal values converge faster (2.41)–(2.42).

use glam::DVec3;
use rayon::prelude::*;
use serde::Serialize;

use crate::assembly::{self, AssemblyOptions, Problem};
use crate::discretization::{Discretization, Node};
use crate::error::Result;
use crate::mesh::Mesh;
use crate::problems::{EmissionOptions, FaceFunction, emission_at};
use crate::scene::Scene;

/// Default lattice of sample points: spacing 1/9 in barycentric coordinates, 28 points per element.
pub const DEFAULT_LATTICE: usize = 9;

/// Maximum errors over the sample points.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct SurfaceErrors {
    /// `max |u - u_n|`.
    #[serde(rename = "surface_error")]
    pub interpolant: f64,
    /// `max |u - ũ_n|`, `ũ_n = E + K u_n`.
    #[serde(rename = "iterated_error")]
    pub iterated: f64,
    /// Number of sample points.
    #[serde(rename = "surface_points")]
    pub points: usize,
}

/// The interior points `(i, j, k)/m` (i, j, k >= 1, i + j + k = m) of the barycentric lattice of
/// spacing 1/m in every element, as points of S with their face's normal and rho. Points on element
/// edges are left out: there u_n has two values, and on the edges of S the normal is undefined.
pub fn sample_points(scene: &Scene, mesh: &Mesh, lattice: usize) -> Vec<Node> {
    let m = lattice.max(3);
    let mut points = Vec::new();
    for (element, e) in mesh.elements().iter().enumerate() {
        let face = &scene.faces[e.face];
        for i in 1..m - 1 {
            for j in 1..m - i {
                let k = m - i - j;
                let w = DVec3::new(i as f64, j as f64, k as f64) / m as f64;
                points.push(Node::new(
                    e.vertices[0] * w.x + e.vertices[1] * w.y + e.vertices[2] * w.z,
                    face.frame.normal,
                    e.face,
                    element,
                    face.rho,
                ));
            }
        }
    }
    points
}

/// The collocation solution `u` (nodal values of `disc`) at a point of its element.
pub fn interpolant_at(disc: &Discretization, u: &[f64], point: &Node) -> f64 {
    let j = point.element();
    let per = disc.method.nodes_per_element();
    let q = disc.placed(j).frame.to_plane(point.position);
    (0..per).map(|l| u[j * per + l] * disc.basis(j)[l].eval(q)).sum()
}

/// The errors of `u` (the collocation solution) against the true solution `truth` (face by face)
/// at the sample points of `lattice`.
pub fn surface_errors(
    problem: &Problem,
    truth: &[FaceFunction],
    u: &[f64],
    assembly: &AssemblyOptions,
    emission: &EmissionOptions,
    lattice: usize,
) -> Result<SurfaceErrors> {
    let Problem { scene, mesh, disc, planner, .. } = problem;
    let points = sample_points(scene, mesh, lattice);
    let e = emission_at(
        scene,
        points.par_iter().copied(),
        planner,
        truth,
        emission,
        &crate::progress::Silent,
    )
    .values;
    let ku = assembly::apply_at(points.par_iter().copied(), problem, assembly, u)?;
    let (mut interpolant, mut iterated) = (0.0f64, 0.0f64);
    for ((p, e), ku) in points.iter().zip(e).zip(ku) {
        let exact = truth[p.face()].eval(p.position);
        interpolant = interpolant.max((exact - interpolant_at(disc, u, p)).abs());
        iterated = iterated.max((exact - (e + ku)).abs());
    }
    Ok(SurfaceErrors { interpolant, iterated, points: points.len() })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::discretization::Method;
    use crate::mesh::MeshKind;
    use crate::problems::TrueSolution;
    use crate::scene::{SurfaceParameters, five_piece};
    use crate::solve::{SolverChoice, SolverOptions, solve};

    #[test]
    fn lattice_points_lie_inside_their_elements() {
        let scene = five_piece(SurfaceParameters::default()).unwrap();
        let mesh = Mesh::new(&scene, &MeshKind::Uniform, 0).unwrap();
        let points = sample_points(&scene, &mesh, 9);
        assert_eq!(points.len(), 28 * mesh.len());
        for p in &points {
            let e = &mesh.elements()[p.element()];
            let d = p.position - e.vertices[0];
            assert!(d.dot(p.normal).abs() < 1e-12, "off the face's plane");
        }
    }

    /// At the nodes the iterated solution equals u_n (the collocation equations), so evaluating
    /// `E + K u_n` at the nodes checks emission, `apply_at` and the interpolant together.
    #[test]
    fn the_iterated_solution_equals_the_collocation_solution_at_the_nodes() {
        let params = SurfaceParameters::default();
        let scene = five_piece(params).unwrap();
        let mesh = Mesh::new(&scene, &MeshKind::Uniform, 1).unwrap();
        for method in [Method::Centroid, Method::linear(1.0 / 6.0).unwrap()] {
            let disc = Discretization::new(&scene, &mesh, method).unwrap();
            let problem = Problem::new(scene.clone(), mesh.clone(), disc);
            let Problem { disc, planner, .. } = &problem;
            let options = AssemblyOptions::default();
            let truth =
                TrueSolution::Shadow { beta: 1.0, gamma: 1.5 }.on_faces(&scene, &params).unwrap();
            let emission = EmissionOptions::default();
            let k = assembly::assemble(&problem, &options, &crate::progress::Silent).unwrap();
            let e = emission_at(
                &scene,
                disc.par_nodes(),
                planner,
                &truth,
                &emission,
                &crate::progress::Silent,
            )
            .values;
            let u = solve(&k.matrix, &e, SolverOptions::with(SolverChoice::Lu)).unwrap().u;
            let ku = assembly::apply_at(disc.par_nodes(), &problem, &options, &u).unwrap();
            let scale = u.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            for (i, node) in disc.nodes().enumerate() {
                let iterated = e[i] + ku[i];
                assert!((iterated - u[i]).abs() < 1e-12 * scale, "{}: node {i}", method.name());
                let interpolated = interpolant_at(disc, &u, &node);
                assert!((interpolated - u[i]).abs() < 1e-12 * scale, "{}: node {i}", method.name());
            }
        }
    }
}
