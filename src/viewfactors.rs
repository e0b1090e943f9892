//! Element-to-element view factors `F_ij = (1/A_i) ∫_{T_i} (1/π) ∫_{T_j, visible from P} G dA_Q dA_P`.
//!
//! The inner integral is the exact point-to-element integral of the collocation matrix (closed
//! forms over the exactly visible pieces, [`crate::assembly::PairIntegrator`]). As a function of P
//! it is smooth inside T_i except next to an element that shares an edge with T_i (or touches
//! it), where it behaves like d log d in the distance d to that edge. The outer integral is
//! therefore a tensor double-exponential (tanh-sinh) rule on T_i collapsed onto the unit square,
//! whose points cluster exponentially toward all three edges of T_i: it integrates d log d
//! behaviour at the edges to full accuracy with a few hundred points. Levels (step 2^-l) are
//! nested and compared; where they do not agree to the tolerance (a shadow line crossing T_i makes
//! a kink inside), T_i is split into four and each part integrated the same way.

use std::collections::HashMap;
use std::f64::consts::PI;

use glam::DVec3;
use rayon::prelude::*;
use serde::Serialize;

use crate::assembly::{AssemblyOptions, PairIntegrator, assemble_row};
use crate::discretization::{Discretization, Method, Node};
use crate::error::Result;
use crate::mesh::{Element, Mesh};
use crate::scene::Scene;
use crate::visibility::PairPlanner;

/// Accuracy settings.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ViewFactorOptions {
    /// Absolute tolerance on each F_ij (default 1e-10).
    pub tolerance: f64,
    /// Finest tanh-sinh level: step 2^-max_level (default 1).
    pub max_level: u32,
    /// Most times an element is split into four when the levels disagree (default 1).
    pub max_depth: u32,
}

impl Default for ViewFactorOptions {
    fn default() -> Self {
        Self { tolerance: 1e-10, max_level: 3, max_depth: 1 }
    }
}

/// The view factor matrix and its checks.
#[derive(Clone, Debug)]
pub struct ViewFactors {
    /// F_ij, row-major n x n.
    pub matrix: Vec<f64>,
    /// Element areas A_i.
    pub areas: Vec<f64>,
    /// Largest estimated error of an entry (the level difference where it converged).
    pub error_estimate: f64,
    /// Outer quadrature points (each one row of point-to-element integrals).
    pub evaluations: u64,
}

/// Summary of a view factor computation, for reports.
#[derive(Clone, Debug, Serialize)]
pub struct ViewFactorSummary {
    /// Scene name.
    pub surface: String,
    /// Number of elements.
    pub n: usize,
    /// Smallest and largest row sum of F (1 for every element of a closed scene).
    pub row_sum_min: f64,
    /// See `row_sum_min`.
    pub row_sum_max: f64,
    /// max |A_i F_ij - A_j F_ji| / max(A_i F_ij).
    pub reciprocity_error: f64,
    /// Largest estimated quadrature error of an entry.
    pub error_estimate: f64,
    /// Outer quadrature points.
    pub evaluations: u64,
    /// Wall time.
    pub seconds: f64,
}

impl ViewFactors {
    /// Number of elements.
    pub fn len(&self) -> usize {
        self.areas.len()
    }

    /// Whether there are no elements.
    pub fn is_empty(&self) -> bool {
        self.areas.is_empty()
    }

    /// F_ij.
    pub fn get(&self, i: usize, j: usize) -> f64 {
        self.matrix[i * self.len() + j]
    }

    /// Smallest and largest row sum.
    pub fn row_sum_range(&self) -> (f64, f64) {
        let n = self.len();
        (0..n)
            .map(|i| self.matrix[i * n..(i + 1) * n].iter().sum::<f64>())
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), s| (lo.min(s), hi.max(s)))
    }

    /// max |A_i F_ij - A_j F_ji| relative to the largest A_i F_ij.
    pub fn reciprocity_error(&self) -> f64 {
        let n = self.len();
        let (mut worst, mut scale) = (0.0f64, 0.0f64);
        for i in 0..n {
            for j in 0..n {
                let (a, b) = (self.areas[i] * self.get(i, j), self.areas[j] * self.get(j, i));
                worst = worst.max((a - b).abs());
                scale = scale.max(a.abs());
            }
        }
        if scale > 0.0 { worst / scale } else { 0.0 }
    }

    /// Face-to-face view factors: F_ab = (1/A_a) Σ_{i in a} A_i Σ_{j in b} F_ij.
    pub fn by_face(&self, mesh: &Mesh) -> Vec<Vec<f64>> {
        let faces = mesh.face_count();
        (0..faces)
            .map(|a| {
                let ra = mesh.face_range(a);
                let area: f64 = ra.clone().map(|i| self.areas[i]).sum();
                (0..faces)
                    .map(|b| {
                        ra.clone()
                            .map(|i| {
                                self.areas[i]
                                    * mesh.face_range(b).map(|j| self.get(i, j)).sum::<f64>()
                            })
                            .sum::<f64>()
                            / area
                    })
                    .collect()
            })
            .collect()
    }
}

/// Computes the element-to-element view factors of `mesh`.
pub fn view_factors(
    scene: &Scene,
    mesh: &Mesh,
    planner: &PairPlanner,
    options: &ViewFactorOptions,
    progress: &(dyn Fn(usize) + Sync),
) -> Result<ViewFactors> {
    let disc = Discretization::new(scene, mesh, Method::Centroid)?;
    let integrator = PairIntegrator::new(Method::Centroid, &AssemblyOptions::default());
    let rule = TanhSinh::new(options.max_level);
    let n = mesh.len();
    let rows: Vec<(Vec<f64>, f64, u64)> = (0..n)
        .into_par_iter()
        .map(|i| {
            let el = &mesh.elements()[i];
            let sees_something = (0..mesh.face_count()).any(|b| can_see(scene, el, b));
            // The whole row of K (with rho = 1) at one point: Σ_j of it is 1 inside a closed
            // scene at every point, so the rows of F sum to 1 to rounding whatever the outer
            // rule's error.
            let integrand = |p: DVec3, out: &mut [f64]| {
                let node = Node {
                    position: p,
                    normal: scene.faces[el.face].frame.normal,
                    face: el.face,
                    element: i,
                    rho: 1.0,
                };
                out.fill(0.0);
                assemble_row(&node, out, mesh, &disc, planner, &integrator);
            };
            let mut outer = Outer { rule: &rule, options, integrand, evaluations: 0 };
            let (row, error) = if !sees_something {
                (vec![0.0; n], 0.0)
            } else {
                outer.integrate(el.vertices, n, 0)
            };
            progress(1);
            (row, error, outer.evaluations)
        })
        .collect();
    let mut matrix = Vec::with_capacity(n * n);
    let (mut error_estimate, mut evaluations) = (0.0f64, 0);
    for (row, e, k) in rows {
        matrix.extend(row);
        error_estimate = error_estimate.max(e);
        evaluations += k;
    }
    let areas = mesh.elements().iter().map(Element::area).collect();
    Ok(ViewFactors { matrix, areas, error_estimate, evaluations })
}

/// Whether some point of element `el` can see some point of face `b` (not coplanar, and neither
/// wholly behind the other's plane).
fn can_see(scene: &Scene, el: &Element, b: usize) -> bool {
    let (fa, fb) = (&scene.faces[el.face], &scene.faces[b]);
    if el.face == b || fa.is_coplanar_with(fb) {
        return false;
    }
    let tol = 1e-12 * fa.size().max(fb.size());
    fb.vertices.iter().any(|&v| fa.frame.height(v) > tol)
        && el.vertices.iter().any(|&v| fb.frame.height(v) > tol)
}

/// The tanh-sinh rule on [0, 1] at steps 2^-l, l = 0 ..= max_level, as one list of points
/// indexed on the finest grid.
struct TanhSinh {
    max_level: u32,
    /// (index on the finest grid, x, 1 - x, weight per unit step) for |t| <= T_MAX.
    points: Vec<(i64, f64, f64, f64)>,
}

/// Truncation of the t axis: the weights beyond are below 1e-20.
const T_MAX: f64 = 3.5;

impl TanhSinh {
    fn new(max_level: u32) -> Self {
        let h = (-(max_level as f64)).exp2();
        let m = (T_MAX / h).floor() as i64;
        let points = (-m..=m)
            .map(|k| {
                let t = k as f64 * h;
                let s = PI * t.sinh();
                // x = 1 / (1 + e^-s) and 1 - x = 1 / (1 + e^s), each without cancellation.
                let (x, rest) = (1.0 / (1.0 + (-s).exp()), 1.0 / (1.0 + s.exp()));
                let weight = PI * t.cosh() * x * rest;
                (k, x, rest, weight)
            })
            .collect();
        Self { max_level, points }
    }

    /// The points of level `l` (every 2^(max_level - l)-th point), with step 2^-l.
    fn level(&self, l: u32) -> impl Iterator<Item = &(i64, f64, f64, f64)> {
        let stride = 1i64 << (self.max_level - l);
        self.points.iter().filter(move |p| p.0 % stride == 0)
    }
}

/// The adaptive outer integral of a row over one element.
struct Outer<'a, F: Fn(DVec3, &mut [f64])> {
    rule: &'a TanhSinh,
    options: &'a ViewFactorOptions,
    integrand: F,
    evaluations: u64,
}

impl<F: Fn(DVec3, &mut [f64])> Outer<'_, F> {
    /// `(1/A) ∫_T g dA` for the triangle `t`, and the estimated error.
    fn integrate(&mut self, t: [DVec3; 3], len: usize, depth: u32) -> (Vec<f64>, f64) {
        let [a, b, c] = t;
        // P(u, v) = c + u (a - c) + u v (b - a); dA = 2 A u du dv.
        let mut cache: HashMap<(i64, i64), Vec<f64>> = HashMap::new();
        let mut previous: Option<Vec<f64>> = None;
        let mut value = vec![0.0; len];
        for level in 0..=self.rule.max_level {
            let step = (-(level as f64)).exp2();
            value.fill(0.0);
            let mut total_weight = 0.0;
            for &(iu, u, _, wu) in self.rule.level(level) {
                for &(iv, v, _, wv) in self.rule.level(level) {
                    let g = cache.entry((iu, iv)).or_insert_with(|| {
                        self.evaluations += 1;
                        let mut out = vec![0.0; len];
                        (self.integrand)(c + (a - c) * u + (b - a) * (u * v), &mut out);
                        out
                    });
                    let w = 2.0 * u * wu * wv * step * step;
                    total_weight += w;
                    for (s, x) in value.iter_mut().zip(g.iter()) {
                        *s += w * x;
                    }
                }
            }
            // The rule integrates 1 to within its truncation (1e-11 at the coarsest level);
            // dividing by its sum makes it exact for constants (closure to rounding).
            for s in value.iter_mut() {
                *s /= total_weight;
            }
            if let Some(prev) = &previous {
                let diff = value.iter().zip(prev).map(|(x, y)| (x - y).abs()).fold(0.0, f64::max);
                if diff <= self.options.tolerance {
                    return (value, diff);
                }
                if level == self.rule.max_level && depth < self.options.max_depth {
                    let (ab, bc, ca) = ((a + b) * 0.5, (b + c) * 0.5, (c + a) * 0.5);
                    let mut sum = vec![0.0; len];
                    let mut error = 0.0f64;
                    for child in [[a, ab, ca], [ab, b, bc], [ca, bc, c], [ab, bc, ca]] {
                        let (v, e) = self.integrate(child, len, depth + 1);
                        for (s, x) in sum.iter_mut().zip(v) {
                            *s += 0.25 * x;
                        }
                        error += 0.25 * e;
                    }
                    return (sum, error);
                }
                if level == self.rule.max_level {
                    return (value, diff);
                }
            }
            previous = Some(value.clone());
        }
        (value, f64::INFINITY)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::MeshKind;
    use crate::scene::Face;

    fn square(name: &str, z: f64, up: bool, x0: f64) -> Face {
        let mut v = vec![
            DVec3::new(x0, 0.0, z),
            DVec3::new(x0 + 1.0, 0.0, z),
            DVec3::new(x0 + 1.0, 1.0, z),
            DVec3::new(x0, 1.0, z),
        ];
        if !up {
            v.reverse();
        }
        Face::new(name, v, 0.5).unwrap()
    }

    fn compute(scene: &Scene, refine: u32) -> (Mesh, ViewFactors) {
        let mesh = Mesh::new(scene, &MeshKind::Uniform, refine).unwrap();
        let planner = PairPlanner::new(scene);
        let f = view_factors(scene, &mesh, &planner, &ViewFactorOptions::default(), &|_| {});
        (mesh, f.unwrap())
    }

    #[test]
    fn howell_c11_parallel_unit_squares() {
        // Howell's catalogue C-11: directly opposed unit squares at distance 1.
        let scene =
            Scene::new("c11", vec![square("a", 0.0, true, 0.0), square("b", 1.0, false, 0.0)])
                .unwrap();
        for refine in [0, 1] {
            let (mesh, f) = compute(&scene, refine);
            let faces = f.by_face(&mesh);
            let want = 0.199_824_895_698_387_46;
            assert!((faces[0][1] - want).abs() < 1e-10, "refine {refine}: {}", faces[0][1]);
            assert!((faces[1][0] - want).abs() < 1e-10);
            assert!(f.reciprocity_error() < 1e-10);
        }
    }

    #[test]
    fn howell_c14_perpendicular_squares_with_a_common_edge() {
        // C-14 with W = H = 1; the inner integral has d log d behaviour at the common edge.
        let wall = Face::new(
            "wall",
            vec![DVec3::ZERO, DVec3::Y, DVec3::new(0.0, 1.0, 1.0), DVec3::new(0.0, 0.0, 1.0)],
            0.5,
        )
        .unwrap();
        let scene = Scene::new("c14", vec![square("floor", 0.0, true, 0.0), wall]).unwrap();
        let (w, h): (f64, f64) = (1.0, 1.0);
        let (w2, h2) = (w * w, h * h);
        let s = (h2 + w2).sqrt();
        let log_term = ((1.0 + w2) * (1.0 + h2) / (1.0 + w2 + h2)).ln()
            + w2 * (w2 * (1.0 + w2 + h2) / ((1.0 + w2) * (w2 + h2))).ln()
            + h2 * (h2 * (1.0 + h2 + w2) / ((1.0 + h2) * (h2 + w2))).ln();
        let want = (w * (1.0 / w).atan() + h * (1.0 / h).atan() - s * (1.0 / s).atan()
            + 0.25 * log_term)
            / (PI * w);
        for refine in [0, 2] {
            let (mesh, f) = compute(&scene, refine);
            let got = f.by_face(&mesh)[0][1];
            assert!((got - want).abs() < 1e-9, "refine {refine}: {got} vs {want}");
            assert!(f.reciprocity_error() < 1e-9, "{}", f.reciprocity_error());
        }
    }

    #[test]
    fn closed_box_with_an_occluder_rows_sum_to_one() {
        // Every outer point sees the whole enclosure, so the rows sum to 1 up to the rounding of
        // the kernels at points a distance δ from an edge (ε h/δ, times a weight of order δ, at
        // each of some thousand points); shadow lines crossing the elements put kinks in the
        // integrand and limit reciprocity.
        let scene = crate::scene::baffled_box().unwrap();
        let (_, f) = compute(&scene, 0);
        let (lo, hi) = f.row_sum_range();
        assert!(lo > 1.0 - 1e-10 && hi < 1.0 + 1e-10, "{lo} {hi}");
        assert!(f.reciprocity_error() < 1e-3, "{}", f.reciprocity_error());
        assert!(f.error_estimate < 1e-3, "{}", f.error_estimate);
    }
}
