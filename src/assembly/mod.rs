//! Assembly of the collocation matrix K of (2.43): `K[i][c] = rho_i/π ∫_{Δ_j} V G φ_c dS` for node i
//! and basis function c of element j, over the pair plan of [`crate::visibility`].
//!
//! Rows are independent and assembled in parallel; for each (node, face) the face view is computed
//! once, and elements of unobstructed faces skip all visibility work.

mod matrix;

pub use matrix::CollocationMatrix;

use std::f64::consts::PI;

use glam::DVec2;
use rayon::prelude::*;

use crate::discretization::{Discretization, ElementFrame, Method};
use crate::error::Result;
use crate::kernels::far_field::{self, FarFieldRule};
use crate::kernels::{Affine2, Observer, exact};
use crate::mesh::Mesh;
use crate::quadrature::ImtRule;
use crate::visibility::{FaceView, PairPlanner, PairStats, Visibility};

/// How the collocation integrals are evaluated.
#[derive(Clone, Debug, PartialEq)]
pub struct AssemblyOptions {
    /// Subintervals of the IMT rule for the one non-elementary moment (paper: 128).
    pub imt_nodes: usize,
    /// Use the far-field rule ([`FarFieldRule::standard`]) for elements (and visible pieces) far from
    /// the node in the linear method. Off: the paper's exact method everywhere.
    pub far_field: bool,
}

impl Default for AssemblyOptions {
    /// The exact method with 128 IMT nodes, and the far-field rule for the linear method.
    fn default() -> Self {
        Self { imt_nodes: ImtRule::PAPER_NODES, far_field: true }
    }
}

/// Evaluates the collocation integrals of one (node, element) pair.
pub struct PairIntegrator {
    method: Method,
    imt: ImtRule,
    far_field: Option<FarFieldRule>,
}

impl PairIntegrator {
    /// An integrator for `method`.
    pub fn new(method: Method, options: &AssemblyOptions) -> Self {
        let far_field =
            (options.far_field && method.nodes_per_element() == 3).then(FarFieldRule::standard);
        Self { method, imt: ImtRule::new(options.imt_nodes.max(2)), far_field }
    }

    /// `∫ G φ_l` over the visible part of element `el` for each of its basis functions, seen from a
    /// node at `p` with unit normal `normal`. Entries past the method's basis count are zero.
    pub fn integrate(
        &self,
        el: &ElementFrame,
        basis: &[Affine2; 3],
        p: glam::DVec3,
        normal: glam::DVec3,
        visibility: &Visibility,
    ) -> [f64; 3] {
        let obs =
            Observer { position: el.frame.to_local(p), normal: el.frame.dir_to_local(normal) };
        if let Some(rule) = &self.far_field {
            if let Some(band) = rule.band(&obs, far_field::radius(&el.local)) {
                return match visibility {
                    Visibility::Skip(_) => [0.0; 3],
                    Visibility::Full => FarFieldRule::integrate(band, &obs, &el.local, basis),
                    Visibility::Partial(pieces) => {
                        let mut sum = [0.0; 3];
                        for piece in pieces {
                            let local: Vec<DVec2> =
                                piece.iter().map(|&q| q - el.centroid_in_face).collect();
                            for k in 1..local.len() - 1 {
                                let tri = [local[0], local[k], local[k + 1]];
                                let part = FarFieldRule::integrate(band, &obs, &tri, basis);
                                sum.iter_mut().zip(part).for_each(|(s, p)| *s += p);
                            }
                        }
                        sum
                    }
                };
            }
        }
        let shifted: Vec<Vec<DVec2>>;
        let loops: Vec<&[DVec2]> = match visibility {
            Visibility::Skip(_) => return [0.0; 3],
            Visibility::Full => vec![&el.local[..]],
            Visibility::Partial(pieces) => {
                shifted = pieces
                    .iter()
                    .map(|piece| piece.iter().map(|&q| q - el.centroid_in_face).collect())
                    .collect();
                shifted.iter().map(Vec::as_slice).collect()
            }
        };
        match self.method {
            Method::Centroid => [exact::constant_weight(&obs, loops), 0.0, 0.0],
            Method::Linear { .. } => exact::affine_weights(&obs, loops, basis, &self.imt),
        }
    }
}

/// The assembled matrix and the pair counts.
#[derive(Clone, Debug)]
pub struct Assembly {
    /// K (including rho/π), row-major.
    pub matrix: CollocationMatrix,
    /// Pair classes met.
    pub stats: PairStats,
}

/// Assembles K on the CPU. `progress` is called with the number of rows finished (from worker
/// threads).
pub fn assemble(
    mesh: &Mesh,
    disc: &Discretization,
    planner: &PairPlanner,
    options: &AssemblyOptions,
    progress: &(dyn Fn(usize) + Sync),
) -> Result<Assembly> {
    let dof = disc.dof();
    let mut matrix = CollocationMatrix::zeros(dof)?;
    let integrator = PairIntegrator::new(disc.method, options);
    let stats = matrix
        .rows_mut()
        .enumerate()
        .map(|(i, row)| {
            let s = assemble_row(i, row, mesh, disc, planner, &integrator);
            progress(1);
            s
        })
        .reduce(PairStats::default, |mut a, b| {
            a += b;
            a
        });
    Ok(Assembly { matrix, stats })
}

/// Row i of K (node i against every element).
fn assemble_row(
    i: usize,
    row: &mut [f64],
    mesh: &Mesh,
    disc: &Discretization,
    planner: &PairPlanner,
    integrator: &PairIntegrator,
) -> PairStats {
    let node = &disc.nodes[i];
    let per = disc.method.nodes_per_element() as u64;
    let scale = node.rho / PI;
    let mut stats = PairStats::default();
    for face in 0..mesh.face_count() {
        let range = mesh.face_range(face);
        let view = planner.face_view(node.position, node.normal, node.face, face);
        if let FaceView::Skip(reason) = view {
            stats.record(&Visibility::Skip(reason), range.len() as u64);
            continue;
        }
        let unobstructed = view.is_unobstructed();
        for j in range {
            let el = &disc.elements[j];
            let vis =
                if unobstructed { Visibility::Full } else { planner.visible(&view, &el.in_face()) };
            stats.record(&vis, 1);
            if matches!(vis, Visibility::Skip(_)) {
                continue;
            }
            let values = integrator.integrate(el, &disc.bases[j], node.position, node.normal, &vis);
            let l = per as usize;
            for (c, v) in values.iter().take(l).enumerate() {
                row[j * l + c] = scale * v;
            }
        }
    }
    stats
}

#[cfg(test)]
mod tests;
