//! Assembly of the collocation matrix K of (2.43): `K[i][c] = rho_i/π ∫_{Δ_j} V G φ_c dS` for node i
//! and basis function c of element j, over the pair plan of [`crate::visibility`].
//!
//! Rows are independent and assembled in parallel; for each (node, face) the face view is computed
//! once, and elements of unobstructed faces skip all visibility work.

mod matrix;
mod options;

pub use matrix::CollocationMatrix;
pub use options::{AssemblyOptions, Quadrature};

use std::f64::consts::PI;

use glam::DVec2;
use rayon::prelude::*;

use crate::discretization::{Discretization, ElementFrame, Method, Node};
use crate::error::Result;
use crate::kernels::far_field::{self, FarFieldRule};
use crate::kernels::graded::GradedRule;
use crate::kernels::{Affine2, Observer, exact};
use crate::mesh::Mesh;
use crate::quadrature::ImtRule;
use crate::visibility::{FaceView, PairPlanner, PairStats, Visibility};

/// Evaluates the collocation integrals of one (node, element) pair.
pub struct PairIntegrator {
    method: Method,
    imt: ImtRule,
    far_field: Option<FarFieldRule>,
    graded: Option<GradedRule>,
}

impl PairIntegrator {
    /// An integrator for `method`.
    pub fn new(method: Method, options: &AssemblyOptions) -> Self {
        let graded = options.quadrature.graded_rule();
        let far_field = (graded.is_none() && options.far_field && method.nodes_per_element() == 3)
            .then(FarFieldRule::standard);
        Self { method, imt: ImtRule::new(options.imt_nodes.max(2)), far_field, graded }
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
        match visibility {
            Visibility::Skip(_) => [0.0; 3],
            Visibility::Full => self.integrate_loops(&obs, el, &[&el.local[..]], basis),
            Visibility::Partial(pieces) => {
                let shifted: Vec<Vec<DVec2>> = pieces
                    .iter()
                    .map(|piece| piece.iter().map(|&q| q - el.centroid_in_face).collect())
                    .collect();
                let loops: Vec<&[DVec2]> = shifted.iter().map(Vec::as_slice).collect();
                self.integrate_loops(&obs, el, &loops, basis)
            }
        }
    }

    /// `∫ G φ_l` over `loops`: the visible convex pieces of `el`, counter-clockwise, in its local
    /// coordinates.
    fn integrate_loops(
        &self,
        obs: &Observer,
        el: &ElementFrame,
        loops: &[&[DVec2]],
        basis: &[Affine2; 3],
    ) -> [f64; 3] {
        if let Some(rule) = &self.graded {
            return rule.integrate(obs, &el.local, loops, basis);
        }
        if let Some(band) =
            self.far_field.as_ref().and_then(|rule| rule.band(obs, far_field::radius(&el.local)))
        {
            let mut sum = [0.0; 3];
            for piece in loops {
                for k in 1..piece.len() - 1 {
                    let tri = [piece[0], piece[k], piece[k + 1]];
                    let part = obs.integrate_by_rule(&band.rule, &tri, basis);
                    sum.iter_mut().zip(part).for_each(|(s, p)| *s += p);
                }
            }
            return sum;
        }
        let loops = loops.iter().copied();
        match self.method {
            Method::Centroid => [exact::constant_weight(obs, loops), 0.0, 0.0],
            Method::Linear { .. } => exact::affine_weights(obs, loops, basis, &self.imt),
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
    options.quadrature.validate()?;
    let dof = disc.dof();
    let mut matrix = CollocationMatrix::zeros(dof)?;
    let integrator = PairIntegrator::new(disc.method, options);
    let stats = matrix
        .rows_mut()
        .enumerate()
        .map(|(i, row)| {
            let s = assemble_row(&disc.nodes[i], row, mesh, disc, planner, &integrator);
            progress(1);
            s
        })
        .reduce(PairStats::default, |mut a, b| {
            a += b;
            a
        });
    Ok(Assembly { matrix, stats })
}

/// `(K u)(P)` at arbitrary points of S (the operator of (1.4) applied to the collocation solution
/// `u` of `disc`, seen from each point), without storing K.
pub fn apply_at(
    points: &[Node],
    mesh: &Mesh,
    disc: &Discretization,
    planner: &PairPlanner,
    options: &AssemblyOptions,
    u: &[f64],
) -> Result<Vec<f64>> {
    options.quadrature.validate()?;
    let integrator = PairIntegrator::new(disc.method, options);
    Ok(points
        .par_iter()
        .map_init(
            || vec![0.0; disc.dof()],
            |row, point| {
                row.fill(0.0);
                assemble_row(point, row, mesh, disc, planner, &integrator);
                row.iter().zip(u).map(|(k, v)| k * v).sum()
            },
        )
        .collect())
}

/// The row of K for a point `node` of S against every element.
fn assemble_row(
    node: &Node,
    row: &mut [f64],
    mesh: &Mesh,
    disc: &Discretization,
    planner: &PairPlanner,
    integrator: &PairIntegrator,
) -> PairStats {
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
