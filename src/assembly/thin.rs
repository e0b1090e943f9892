//! The thin elements' columns of K, computed on the CPU: the GPU kernels evaluate closed forms
//! only, which cancel on such elements, so a K built on the GPU has them recomputed here
//! ([`recompute_thin_columns`]) or, where K stays on the GPU, takes them from the host
//! ([`ThinColumns`]).

use std::f64::consts::PI;

use rayon::prelude::*;

use crate::visibility::{ElementBoxes, FaceSight, RecentHiders, Views, Visibility, by_face};

use super::integrator::PairIntegrator;
use super::options::AssemblyOptions;
use super::problem::Problem;
use super::rows::Assembly;

/// Recomputes on the CPU the columns of the thin elements ([`far_field::is_thin`]): the GPU kernels
/// evaluate closed forms only, which cancel on such elements. Nothing is done (and nothing is
/// planned) when the mesh has no thin element, as in the paper's meshes, or when the closed forms
/// are asked for everywhere (`far_field` off).
pub fn recompute_thin_columns(
    assembly: &mut Assembly,
    problem: &Problem,
    options: &AssemblyOptions,
) {
    let Some(thin) = ThinElements::new(problem, options) else {
        return;
    };
    let per = thin.per;
    assembly.matrix.rows_mut().enumerate().for_each_init(
        RecentHiders::default,
        |hiders, (i, row)| {
            thin.row(problem, i, hiders, |k, values| {
                let j = thin.elements[k];
                row[j * per..(j + 1) * per].copy_from_slice(&values[..per]);
            })
        },
    );
}

/// The thin elements of a problem and how their entries are computed on the CPU.
struct ThinElements {
    elements: Vec<usize>,
    per: usize,
    integrator: PairIntegrator,
    /// Positions in `elements` by face, as the row walk takes them.
    by_face: Vec<(usize, Vec<usize>)>,
    /// The elements of each of those faces with the boxes of their halves.
    boxes: Vec<ElementBoxes>,
}

impl ThinElements {
    /// `None` where there is no thin element or the closed forms are asked for everywhere.
    fn new(problem: &Problem, options: &AssemblyOptions) -> Option<Self> {
        let disc = &problem.disc;
        let elements: Vec<usize> =
            (0..disc.element_count()).filter(|&j| disc.placed(j).thin).collect();
        if elements.is_empty() || !options.far_field {
            return None;
        }
        let by_face = by_face(elements.iter().enumerate().map(|(k, &j)| (disc.face_of(j), k)));
        let boxes = by_face
            .iter()
            .map(|(_, list)| {
                ElementBoxes::new(list.iter().map(|&k| disc.in_face(elements[k])).collect())
            })
            .collect();
        Some(Self {
            per: disc.method.nodes_per_element(),
            integrator: PairIntegrator::new(disc.method, options),
            by_face,
            boxes,
            elements,
        })
    }

    /// Row i's entries of the thin elements: `write(k, values)` for the k-th of them (values
    /// scaled by rho/π, zero where it is hidden).
    fn row(
        &self,
        problem: &Problem,
        i: usize,
        hiders: &mut RecentHiders,
        mut write: impl FnMut(usize, [f64; 3]),
    ) {
        let Problem { disc, planner, .. } = problem;
        let node = &disc.node(i);
        let scale = node.rho / PI;
        let mut put = |k: usize, vis: &Visibility| {
            let j = self.elements[k];
            let el = &disc.placed(j);
            let values =
                self.integrator.integrate(el, disc.basis(j), node.position, node.normal, vis);
            write(k, values.map(|v| scale * v));
        };
        let faces = self.by_face.iter().map(|(face, list)| (*face, list.iter().copied()));
        planner.walk_row(&node.viewer(), faces, Views::Fresh(hiders), |face, list, sight| {
            match sight {
                FaceSight::Hidden(reason) => list.for_each(|k| put(k, &Visibility::Skip(reason))),
                FaceSight::Whole => list.for_each(|k| put(k, &Visibility::Full)),
                FaceSight::Part(mut part) => {
                    let g = self.by_face.iter().position(|(f, _)| *f == face).expect("a face");
                    part.elements(&self.boxes[g], |at, vis| put(self.by_face[g].1[at], &vis))
                }
            }
        });
    }
}

/// The columns of K of the thin elements, computed on the CPU (see
/// [`recompute_thin_columns`]): what a K built on the GPU and kept there takes from the host.
#[derive(Clone, Debug)]
pub struct ThinColumns {
    /// The columns (element × basis function), ascending.
    pub columns: Vec<usize>,
    /// Row-major, dof × `columns.len()`.
    pub values: Vec<f64>,
}

impl ThinColumns {
    /// The thin columns of `problem`'s K, or `None` where there are none or the closed forms
    /// are asked for everywhere (`far_field` off).
    pub fn new(problem: &Problem, options: &AssemblyOptions) -> Option<Self> {
        let thin = ThinElements::new(problem, options)?;
        let per = thin.per;
        let columns: Vec<usize> =
            thin.elements.iter().flat_map(|&j| (0..per).map(move |c| j * per + c)).collect();
        let width = columns.len();
        let mut values = vec![0.0; problem.disc.dof() * width];
        values.par_chunks_mut(width).enumerate().for_each_init(
            RecentHiders::default,
            |hiders, (i, row)| {
                thin.row(problem, i, hiders, |k, v| {
                    row[k * per..(k + 1) * per].copy_from_slice(&v[..per])
                })
            },
        );
        Some(Self { columns, values })
    }

    /// `y += T x`, T these columns of K.
    pub fn apply_add(&self, x: &[f64], y: &mut [f64]) {
        let width = self.columns.len();
        for (yi, row) in y.iter_mut().zip(self.values.chunks_exact(width)) {
            *yi += self.columns.iter().zip(row).map(|(&c, v)| v * x[c]).sum::<f64>();
        }
    }
}
