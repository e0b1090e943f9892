//! Emissivity at points of S from a true solution: `E(P) = u(P) - (rho/π) Σ_F ∫_{F visible from P} u G dS`.
//!
//! The integrals respect visibility exactly (the visible part of each face from the pair plan) and
//! the kinks of u (faces are cut along them). Quadratic u are integrated in closed form up to one
//! IMT quadrature per edge; other u by iterated adaptive Gauss–Kronrod over the pieces, whose edges
//! carry the kinks and singular lines of u where bisection resolves them.

use std::f64::consts::PI;

use glam::{DVec2, DVec3};
use rayon::prelude::*;

use super::FaceFunction;
use crate::discretization::Node;
use crate::geometry::{HalfPlane, PlaneFrame, clip_convex};
use crate::kernels::{Observer, Quadratic2, exact};
use crate::progress::Progress;
use crate::quadrature::{ImtRule, Tolerance, integrate_triangle};
use crate::scene::Scene;
use crate::visibility::{FaceSight, PairPlanner, RecentHiders, Views, Visibility};

/// Accuracy settings for the emissivity integrals.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EmissionOptions {
    /// IMT subintervals for quadratic u (default 128).
    pub imt_nodes: usize,
    /// Relative tolerance of the adaptive quadrature for general u (default 1e-12).
    pub relative_tolerance: f64,
}

impl Default for EmissionOptions {
    fn default() -> Self {
        Self { imt_nodes: ImtRule::PAPER_NODES, relative_tolerance: 1e-12 }
    }
}

/// E at points of S, with how far the adaptive quadrature may be off.
#[derive(Clone, Debug, PartialEq)]
pub struct Emission {
    /// E at each point.
    pub values: Vec<f64>,
    /// The largest error estimate of an E value, relative to the largest |E| (0 when every
    /// integral is in closed form, as for quadratic u).
    pub error_estimate: f64,
}

/// `E` at `points` of S (the collocation nodes, or any other points with their face's normal and
/// rho) for the true solution given face by face in `u`.
pub fn emission_at(
    scene: &Scene,
    points: impl IndexedParallelIterator<Item = Node>,
    planner: &PairPlanner,
    u: &[FaceFunction],
    options: &EmissionOptions,
    progress: &dyn Progress,
) -> Emission {
    let imt = ImtRule::new(options.imt_nodes.max(2));
    let per_point: Vec<(f64, f64)> = points
        .map_init(RecentHiders::default, |hiders, node| {
            let (mut integral, mut error) = (0.0, 0.0);
            // Each face is one item of the walk: its visible part is found whole.
            let faces = (0..scene.faces.len()).map(|k| (k, std::iter::once(k)));
            planner.walk_row(&node.viewer(), faces, Views::Fresh(hiders), |k, _, sight| {
                let pieces = match sight {
                    FaceSight::Hidden(_) => return,
                    FaceSight::Whole => planner.convex_parts(k),
                    FaceSight::Part(mut part) => planner
                        .convex_parts(k)
                        .into_iter()
                        .flat_map(|piece| match part.element(&piece) {
                            Visibility::Skip(_) => vec![],
                            Visibility::Full => vec![piece],
                            Visibility::Partial(pieces) => pieces,
                        })
                        .collect(),
                };
                if pieces.is_empty() {
                    return;
                }
                let face = &scene.faces[k];
                let obs = Observer {
                    position: face.frame.to_local(node.position),
                    normal: face.frame.dir_to_local(node.normal),
                };
                let (value, estimate) =
                    face_integral(&obs, &face.frame, &pieces, &u[k], &imt, options);
                integral += value;
                error += estimate;
            });
            progress.advance(1);
            (u[node.face()].eval(node.position) - node.rho / PI * integral, node.rho / PI * error)
        })
        .collect();
    let largest = per_point.iter().fold(0.0f64, |m, (e, _)| m.max(e.abs()));
    let worst = per_point.iter().fold(0.0f64, |m, (_, err)| m.max(*err));
    Emission {
        values: per_point.iter().map(|(e, _)| *e).collect(),
        error_estimate: if worst == 0.0 { 0.0 } else { worst / largest.max(f64::MIN_POSITIVE) },
    }
}

/// `∫ u G` over the convex `pieces` (face coordinates) of one face, and its error estimate (0 in
/// closed form).
fn face_integral(
    obs: &Observer,
    frame: &PlaneFrame,
    pieces: &[Vec<DVec2>],
    u: &FaceFunction,
    imt: &ImtRule,
    options: &EmissionOptions,
) -> (f64, f64) {
    match u {
        FaceFunction::Quadratic { a, b, c } => {
            let q = restrict(frame, a, *b, *c);
            (exact::quadratic_weight(obs, pieces.iter().map(Vec::as_slice), &q, imt), 0.0)
        }
        FaceFunction::General { f, kinks, magnitude } => {
            let mut parts: Vec<Vec<DVec2>> = pieces.to_vec();
            for &(m, offset) in kinks {
                let hp = HalfPlane {
                    normal: DVec2::new(m.dot(frame.e1), m.dot(frame.e2)),
                    offset: m.dot(frame.origin) - offset,
                };
                if hp.normal.length() <= 1e-12 * m.length() {
                    continue; // the kink plane is parallel to the face
                }
                parts = parts
                    .iter()
                    .flat_map(|p| [clip_convex(p, &hp), clip_convex(p, &hp.flipped())])
                    .flatten()
                    .collect();
            }
            let tol = Tolerance {
                absolute: 1e-3 * options.relative_tolerance * magnitude,
                relative: options.relative_tolerance,
                max_intervals: 4000,
            };
            parts
                .iter()
                .flat_map(|p| (1..p.len() - 1).map(move |k| [p[0], p[k], p[k + 1]]))
                .map(|tri| integrate_triangle(|x| f(frame.to_global(x)) * obs.kernel(x), tri, tol))
                .fold((0.0, 0.0), |(v, e), (dv, de)| (v + dv, e + de))
        }
    }
}

/// A global quadratic `x·A x + b·x + c` restricted to the plane of `frame`, in its 2-D coordinates.
fn restrict(frame: &PlaneFrame, a: &[[f64; 3]; 3], b: DVec3, c: f64) -> Quadratic2 {
    let mul = |v: DVec3| {
        DVec3::new(
            a[0][0] * v.x + a[0][1] * v.y + a[0][2] * v.z,
            a[1][0] * v.x + a[1][1] * v.y + a[1][2] * v.z,
            a[2][0] * v.x + a[2][1] * v.y + a[2][2] * v.z,
        )
    };
    let (o, e1, e2) = (frame.origin, frame.e1, frame.e2);
    let mut q = Quadratic2::default();
    q.c[0][0] = o.dot(mul(o)) + b.dot(o) + c;
    q.c[1][0] = 2.0 * e1.dot(mul(o)) + b.dot(e1);
    q.c[0][1] = 2.0 * e2.dot(mul(o)) + b.dot(e2);
    q.c[2][0] = e1.dot(mul(e1));
    q.c[1][1] = 2.0 * e1.dot(mul(e2));
    q.c[0][2] = e2.dot(mul(e2));
    q
}

#[cfg(test)]
mod tests {
    use std::sync::Arc;

    use super::*;
    use crate::discretization::{Discretization, Method};
    use crate::mesh::{Mesh, MeshKind};
    use crate::problems::{SolutionName, TrueSolution};
    use crate::scene::{SurfaceParameters, five_piece, four_piece};

    fn setup(scene: &Scene, refine: u32) -> (Discretization, PairPlanner) {
        let mesh = Mesh::new(scene, &MeshKind::Uniform, refine).unwrap();
        let disc = Discretization::new(scene, &mesh, Method::Centroid).unwrap();
        (disc, PairPlanner::new(scene))
    }

    #[test]
    fn closed_form_and_adaptive_emissivity_agree_for_x2_plus_y2() {
        let p = SurfaceParameters::default();
        for scene in [four_piece(p).unwrap(), five_piece(p).unwrap()] {
            let (disc, planner) = setup(&scene, 1);
            let exact_u = TrueSolution::X2Y2.on_faces(&scene, &p).unwrap();
            let general_u: Vec<FaceFunction> = exact_u
                .iter()
                .map(|u| {
                    let u = u.clone();
                    FaceFunction::General {
                        f: Arc::new(move |x| u.eval(x)),
                        kinks: vec![],
                        magnitude: 50.0,
                    }
                })
                .collect();
            let opts = EmissionOptions::default();
            let e1 = emission_at(
                &scene,
                disc.par_nodes(),
                &planner,
                &exact_u,
                &opts,
                &crate::progress::Silent,
            );
            let e2 = emission_at(
                &scene,
                disc.par_nodes(),
                &planner,
                &general_u,
                &opts,
                &crate::progress::Silent,
            );
            for (i, (a, b)) in e1.values.iter().zip(&e2.values).enumerate() {
                let scale = disc.node(i).position.truncate().length_squared().max(1.0);
                assert!((a - b).abs() < 1e-10 * scale, "{} node {i}: {a} vs {b}", scene.name);
            }
        }
    }

    #[test]
    fn adaptive_emissivity_is_converged_for_kinks_and_singularities() {
        let p = SurfaceParameters::default();
        let scene = five_piece(p).unwrap();
        let (disc, planner) = setup(&scene, 1);
        for sol in
            [TrueSolution::Shadow { beta: 0.5, gamma: 1.5 }, TrueSolution::Edge { beta: 0.5 }]
        {
            let u = sol.on_faces(&scene, &p).unwrap();
            let loose = EmissionOptions { relative_tolerance: 1e-10, ..Default::default() };
            let tight = EmissionOptions { relative_tolerance: 1e-13, ..Default::default() };
            let a = emission_at(
                &scene,
                disc.par_nodes(),
                &planner,
                &u,
                &loose,
                &crate::progress::Silent,
            );
            let b = emission_at(
                &scene,
                disc.par_nodes(),
                &planner,
                &u,
                &tight,
                &crate::progress::Silent,
            );
            for (i, (x, y)) in a.values.iter().zip(&b.values).enumerate() {
                assert!((x - y).abs() < 1e-10 * y.abs().max(1.0), "{sol}: node {i}: {x} vs {y}");
            }
            // The loose run's own estimate covers its difference from the tight one.
            let scale = b.values.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            let diff =
                a.values.iter().zip(&b.values).fold(0.0f64, |m, (x, y)| m.max((x - y).abs()));
            assert!(
                diff <= a.error_estimate * scale + 1e-15,
                "{sol}: {diff:e} vs {:e}",
                a.error_estimate
            );
            assert!(b.error_estimate < 1e-9, "{sol}: tight estimate {:e}", b.error_estimate);
        }
    }

    #[test]
    fn solutions_3_3_and_3_4_need_the_paper_surfaces() {
        let e = TrueSolution::Edge { beta: 0.5 }
            .on_faces(&crate::scene::cube().unwrap(), &SurfaceParameters::default())
            .unwrap_err();
        assert!(e.to_string().contains("cube"), "{e}");
        assert!(TrueSolution::named(SolutionName::Edge, Some(-1.0), None).is_err());
        assert!(TrueSolution::named(SolutionName::Edge, None, Some(1.0)).is_err());
        assert!(TrueSolution::named(SolutionName::None, Some(1.0), None).is_err());
        assert_eq!(TrueSolution::named(SolutionName::None, None, None).unwrap(), None);
    }
}
