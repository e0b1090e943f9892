//! Assembly of the collocation matrix K of (2.43): `K[i][c] = rho_i/π ∫_{Δ_j} V G φ_c dS` for node i
//! and basis function c of element j, over the pair plan of [`crate::visibility`].
//!
//! Rows are independent and assembled in parallel; for each (node, face) the face view is computed
//! once, and elements of unobstructed faces skip all visibility work.

mod matrix;
mod memory;
mod options;
mod pairs;
mod problem;

pub use matrix::CollocationMatrix;
pub use memory::{
    MEMORY_SHARE, allowance_source, available_memory, check_fits, memory_allowance, memory_limit,
    resident_bytes, set_memory_limit, size_text,
};
pub use options::{AssemblyOptions, Quadrature};
pub use pairs::{CpuPairs, PairEvaluation, PairTask};
pub use problem::Problem;

use std::f64::consts::PI;
use std::ops::Range;

use glam::DVec2;
use rayon::prelude::*;

use crate::discretization::{Discretization, ElementFrame, Method, Node};
use crate::error::Result;
use crate::kernels::far_field::FarFieldRule;
use crate::kernels::graded::GradedRule;
use crate::kernels::{Affine2, Observer, exact, lanes};
use crate::mesh::Mesh;
use crate::progress::Progress;
use crate::quadrature::ImtRule;
use crate::visibility::{
    ElementBoxes, FaceSight, PairPlanner, PairStats, PartSight, RecentHiders, Views, Visibility,
    by_face,
};

/// Evaluates the collocation integrals of one (node, element) pair.
pub struct PairIntegrator {
    method: Method,
    imt: ImtRule,
    far_field: Option<FarFieldRule>,
    graded: Option<GradedRule>,
    /// For thin elements ([`far_field::is_thin`]) under the exact method, unless the closed forms
    /// are asked for everywhere (`far_field` off).
    subdivision: Option<FarFieldRule>,
    /// Whether fully visible elements may be evaluated in lanes ([`PairIntegrator::full_pair`]).
    lanes: bool,
}

/// How a node's integrals over an element are evaluated ([`PairIntegrator::lane_observer`]).
pub(crate) enum LaneObserver {
    /// Not at all: the node is not above the element's plane, and they vanish.
    Unseen,
    /// By [`PairIntegrator::integrate`] (another rule than the closed form).
    Scalar,
    /// The centroid method's closed form in lanes, for this observer.
    Lane(Observer),
}

/// A fully visible element's integrals, or what to evaluate with others in lanes.
pub(crate) enum FullPair {
    /// Already evaluated (another rule than the closed form, or nothing to see).
    Values([f64; 3]),
    /// The centroid method's closed form for this observer and triangle (element units).
    Lane(Observer, [DVec2; 3]),
}

impl PairIntegrator {
    /// An integrator for `method`.
    pub fn new(method: Method, options: &AssemblyOptions) -> Self {
        let graded = options.quadrature.graded_rule();
        let far_field = (graded.is_none() && options.far_field)
            .then(|| FarFieldRule::for_weights(method.nodes_per_element()));
        Self {
            method,
            imt: ImtRule::new(options.imt_nodes.max(2)),
            far_field,
            graded,
            subdivision: options.far_field.then(FarFieldRule::standard),
            lanes: options.lanes
                && method == Method::Centroid
                && options.quadrature.graded_rule().is_none(),
        }
    }

    /// As [`PairIntegrator::new`], for values kept in single precision: the centroid method's
    /// closed form at every distance, in lanes. Its far band
    /// ([`crate::kernels::far_field::CONSTANT_WEIGHT_BANDS`]) keeps the last digits of f64
    /// beyond 100 radii, where the closed form loses about 1e-12 of its value (at 2e4 radii),
    /// which an f32 value does not hold, and its 25-point rule is evaluated pair by pair, not
    /// in lanes, so the closed form in lanes is both accurate enough and faster there. The
    /// linear method keeps its bands, which are also its fast path.
    pub fn for_single_precision(method: Method, options: &AssemblyOptions) -> Self {
        let mut integrator = Self::new(method, options);
        if method == Method::Centroid {
            integrator.far_field = None;
        }
        integrator
    }

    /// As [`PairIntegrator::integrate`] for a fully visible element, except that where the
    /// centroid method's closed form applies, the observer and triangle are handed back to be
    /// evaluated in lanes ([`crate::kernels::lanes`]).
    #[inline(always)]
    pub(crate) fn full_pair(
        &self,
        el: &ElementFrame,
        basis: &[Affine2; 3],
        p: glam::DVec3,
        normal: glam::DVec3,
    ) -> FullPair {
        match self.lane_observer(el, p, normal) {
            LaneObserver::Unseen => FullPair::Values([0.0; 3]),
            LaneObserver::Scalar => {
                FullPair::Values(self.integrate(el, basis, p, normal, &Visibility::Full))
            }
            LaneObserver::Lane(obs) => FullPair::Lane(obs, el.scaled),
        }
    }

    /// The integrals over element `el` seen as `visibility` from a node at `p` (unit normal
    /// `normal`): returned where they are evaluated at once, or handed to `batch` with `tag`
    /// where the centroid method's closed form applies, the element whole or each visible
    /// piece as the fan of triangles from its first corner, whose values `sink` must add up.
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    pub(crate) fn integrate_or_batch<T: Copy>(
        &self,
        el: &ElementFrame,
        basis: &[Affine2; 3],
        p: glam::DVec3,
        normal: glam::DVec3,
        visibility: &Visibility,
        (tag, batch): (T, &mut lanes::Batch<T>),
        mut sink: impl FnMut(T, f64),
    ) -> Option<[f64; 3]> {
        let pieces = match visibility {
            Visibility::Skip(_) => return Some([0.0; 3]),
            Visibility::Full => match self.full_pair(el, basis, p, normal) {
                FullPair::Values(values) => return Some(values),
                FullPair::Lane(obs, tri) => {
                    batch.push(tag, obs, tri, sink);
                    return None;
                }
            },
            Visibility::Partial(pieces) => pieces,
        };
        match self.lane_observer(el, p, normal) {
            LaneObserver::Unseen => Some([0.0; 3]),
            LaneObserver::Scalar => Some(self.integrate(el, basis, p, normal, visibility)),
            LaneObserver::Lane(obs) => {
                for piece in pieces {
                    push_fan(el, obs, piece, (tag, batch), &mut sink);
                }
                None
            }
        }
    }

    /// Whether the centroid method's closed form over (any part of) element `el`, seen from a
    /// node at `p` with unit normal `normal`, may be evaluated in lanes, and the observer to
    /// give them with triangles in the element's units ([`ElementFrame::to_scaled`]).
    #[inline(always)]
    pub(crate) fn lane_observer(
        &self,
        el: &ElementFrame,
        p: glam::DVec3,
        normal: glam::DVec3,
    ) -> LaneObserver {
        if !self.lanes {
            return LaneObserver::Scalar;
        }
        let Some(obs) = self.observer(el, p, normal) else {
            return LaneObserver::Unseen;
        };
        let thin = self.subdivision.is_some() && el.thin;
        let banded =
            self.far_field.as_ref().is_some_and(|rule| rule.band(&obs, el.scaled_radius).is_some());
        if thin || banded { LaneObserver::Scalar } else { LaneObserver::Lane(obs) }
    }

    /// The node seen from the element's frame in the element's units ([`ElementFrame::unit`]),
    /// or `None` when the node is not above the element's plane.
    #[inline(always)]
    fn observer(&self, el: &ElementFrame, p: glam::DVec3, normal: glam::DVec3) -> Option<Observer> {
        let obs = Observer {
            position: el.frame.to_local(p) * el.unit,
            normal: el.frame.dir_to_local(normal),
        };
        // The pair plan decided the node is above the face's plane in the face's frame; in the
        // element's frame (origin at its centroid) the height carries another rounding, and a
        // face that is planar only to within its tolerance (1e-9 of its size) can put the node
        // on the other side. Such a node is in the plane as far as the data can tell: G = 0.
        if obs.position.z.is_nan() || obs.position.z <= 0.0 {
            return None;
        }
        Some(obs)
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
        if let Visibility::Skip(_) = visibility {
            return [0.0; 3];
        }
        let Some(obs) = self.observer(el, p, normal) else {
            return [0.0; 3];
        };
        let unit = el.unit;
        let basis = basis.map(|b| Affine2 { c0: b.c0, cx: b.cx / unit, cy: b.cy / unit });
        match visibility {
            Visibility::Partial(pieces) => {
                let shifted: Vec<Vec<DVec2>> = pieces
                    .iter()
                    .map(|piece| piece.iter().map(|&q| el.to_scaled(q)).collect())
                    .collect();
                let loops: Vec<&[DVec2]> = shifted.iter().map(Vec::as_slice).collect();
                self.integrate_loops(&obs, el, &loops, &basis)
            }
            _ => self.integrate_loops(&obs, el, &[&el.scaled[..]], &basis),
        }
    }

    /// `∫ G φ_l` over `loops`: the visible convex pieces of element `el`, counter-clockwise, in
    /// its local coordinates and units ([`ElementFrame::scaled`]).
    fn integrate_loops(
        &self,
        obs: &Observer,
        el: &ElementFrame,
        loops: &[&[DVec2]],
        basis: &[Affine2; 3],
    ) -> [f64; 3] {
        if let Some(rule) = &self.graded {
            return rule.integrate(obs, &el.scaled, loops, basis);
        }
        if let Some(rule) = self.subdivision.as_ref().filter(|_| el.thin) {
            let near = |piece: &[DVec2; 3]| self.closed_forms(obs, &[&piece[..]], basis);
            return integrate_fan(loops, |tri| rule.integrate_subdivided(obs, tri, basis, near));
        }
        if let Some(band) =
            self.far_field.as_ref().and_then(|rule| rule.band(obs, el.scaled_radius))
        {
            return integrate_fan(loops, |tri| obs.integrate_by_rule(&band.rule, tri, basis));
        }
        self.closed_forms(obs, loops, basis)
    }

    /// The exact method's closed forms (and IMT quadrature) over `loops`.
    fn closed_forms(&self, obs: &Observer, loops: &[&[DVec2]], basis: &[Affine2; 3]) -> [f64; 3] {
        let loops = loops.iter().copied();
        match self.method {
            Method::Centroid => [exact::constant_weight(obs, loops), 0.0, 0.0],
            Method::Linear { .. } => exact::affine_weights(obs, loops, basis, &self.imt),
        }
    }
}

/// The sum of `part` over the fan triangles of every loop.
fn integrate_fan(loops: &[&[DVec2]], part: impl Fn(&[DVec2; 3]) -> [f64; 3]) -> [f64; 3] {
    let mut sum = [0.0; 3];
    for piece in loops {
        for k in 1..piece.len() - 1 {
            let values = part(&[piece[0], piece[k], piece[k + 1]]);
            sum.iter_mut().zip(values).for_each(|(s, v)| *s += v);
        }
    }
    sum
}

/// The assembled matrix and the pair counts.
#[derive(Clone, Debug)]
pub struct Assembly {
    /// K (including rho/π), row-major.
    pub matrix: CollocationMatrix,
    /// Pair classes met.
    pub stats: PairStats,
}

/// Assembles K on the CPU. `progress` advances by the rows finished (from worker
/// threads).
pub fn assemble(
    problem: &Problem,
    options: &AssemblyOptions,
    progress: &dyn Progress,
) -> Result<Assembly> {
    let Problem { mesh, disc, planner, .. } = problem;
    options.quadrature.validate()?;
    let dof = disc.dof();
    let mut matrix = CollocationMatrix::zeros(dof)?;
    let integrator = PairIntegrator::new(disc.method, options);
    let boxes = face_boxes(mesh, disc);
    let stats = matrix
        .rows_mut()
        .enumerate()
        .map_init(RecentHiders::default, |hiders, (i, row)| {
            let surface = (mesh, disc, boxes.as_slice());
            let s = assemble_row(&disc.nodes[i], row, surface, planner, &integrator, hiders);
            progress.advance(1);
            s
        })
        .reduce(PairStats::default, |mut a, b| {
            a += b;
            a
        });
    Ok(Assembly { matrix, stats })
}

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
            (0..disc.elements.len()).filter(|&j| disc.elements[j].thin).collect();
        if elements.is_empty() || !options.far_field {
            return None;
        }
        let by_face =
            by_face(elements.iter().enumerate().map(|(k, &j)| (disc.elements[j].face, k)));
        let boxes = by_face
            .iter()
            .map(|(_, list)| {
                ElementBoxes::new(
                    list.iter().map(|&k| disc.elements[elements[k]].in_face()).collect(),
                )
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
        let node = &disc.nodes[i];
        let scale = node.rho / PI;
        let mut put = |k: usize, vis: &Visibility| {
            let j = self.elements[k];
            let el = &disc.elements[j];
            let values =
                self.integrator.integrate(el, &disc.bases[j], node.position, node.normal, vis);
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

/// `(K u)(P)` at arbitrary points of S (the operator of (1.4) applied to the collocation solution
/// `u` of `disc`, seen from each point), without storing K.
pub fn apply_at(
    points: &[Node],
    problem: &Problem,
    options: &AssemblyOptions,
    u: &[f64],
) -> Result<Vec<f64>> {
    let Problem { mesh, disc, planner, .. } = problem;
    options.quadrature.validate()?;
    let integrator = PairIntegrator::new(disc.method, options);
    let boxes = face_boxes(mesh, disc);
    Ok(points
        .par_iter()
        .map_init(
            || (vec![0.0; disc.dof()], RecentHiders::default()),
            |(row, hiders), point| {
                row.fill(0.0);
                let surface = (mesh, disc, boxes.as_slice());
                assemble_row(point, row, surface, planner, &integrator, hiders);
                row.iter().zip(u).map(|(k, v)| k * v).sum()
            },
        )
        .collect())
}

/// Hands the convex `piece` of element `el` (face coordinates, counter-clockwise) to `batch`
/// for the observer `obs`, as the fan of triangles from its first corner in the element's units,
/// each with `tag`: the values `sink` receives add up to the piece's closed form.
pub(crate) fn push_fan<T: Copy>(
    el: &ElementFrame,
    obs: Observer,
    piece: &[DVec2],
    (tag, batch): (T, &mut lanes::Batch<T>),
    mut sink: impl FnMut(T, f64),
) {
    let first = el.to_scaled(piece[0]);
    for m in 1..piece.len().saturating_sub(1) {
        let tri = [first, el.to_scaled(piece[m]), el.to_scaled(piece[m + 1])];
        batch.push(tag, obs, tri, &mut sink);
    }
}

/// The row of K for a point `node` of S against every element (entries of elements it does not
/// see are left as they are).
pub(crate) fn assemble_row(
    node: &Node,
    row: &mut [f64],
    (mesh, disc, boxes): (&Mesh, &Discretization, &[ElementBoxes]),
    planner: &PairPlanner,
    integrator: &PairIntegrator,
    hiders: &mut RecentHiders,
) -> PairStats {
    let scale = node.rho / PI;
    let mut batch = lanes::Batch::default();
    let faces = (0..mesh.face_count()).map(|face| (face, mesh.face_range(face)));
    let stats =
        planner.walk_row(&node.viewer(), faces, Views::Fresh(hiders), |face, range, sight| {
            let visible = match sight {
                FaceSight::Hidden(_) => return,
                FaceSight::Whole => None,
                FaceSight::Part(part) => Some((part, &boxes[face])),
            };
            fill_row(range, visible, node, disc, integrator, row, &mut batch);
        });
    batch.flush(|j, v| row[j] += scale * v);
    stats
}

/// The entries of the elements `range` of one face in `node`'s row (zero before): all whole, or
/// each as `part` sees it (the face's elements with the boxes of their halves). Whole elements
/// and visible pieces wait in `batch` where the centroid method's closed form applies, and add
/// into their entries.
fn fill_row(
    range: Range<usize>,
    part: Option<(PartSight<'_>, &ElementBoxes)>,
    node: &Node,
    disc: &Discretization,
    integrator: &PairIntegrator,
    row: &mut [f64],
    batch: &mut lanes::Batch<usize>,
) {
    let per = disc.method.nodes_per_element();
    // The lanes add into the entries: written first, since a fresh matrix's untouched page read
    // maps the zero page, and the write after it faults again and flushes every core's TLB,
    // which would cost more than the assembly's arithmetic.
    row[range.start * per..range.end * per].fill(0.0);
    match part {
        None => {
            for j in range {
                fill_entry(j, &Visibility::Full, node, disc, integrator, row, batch);
            }
        }
        Some((mut part, boxes)) => part.elements(boxes, |k, vis| {
            if !matches!(vis, Visibility::Skip(_)) {
                fill_entry(range.start + k, &vis, node, disc, integrator, row, batch)
            }
        }),
    }
}

/// Element j's entries in `node`'s row as `vis` says it is seen. (A function of its own, with
/// every reference a parameter, so that the compiler knows the row's stores leave the
/// discretization alone: as a closure over them, the loop took a sixth longer on the five-piece
/// surface.)
fn fill_entry(
    j: usize,
    vis: &Visibility,
    node: &Node,
    disc: &Discretization,
    integrator: &PairIntegrator,
    row: &mut [f64],
    batch: &mut lanes::Batch<usize>,
) {
    let per = disc.method.nodes_per_element();
    let scale = node.rho / PI;
    let el = &disc.elements[j];
    let sink = |j: usize, v: f64| row[j] += scale * v;
    let Some(values) = integrator.integrate_or_batch(
        el,
        &disc.bases[j],
        node.position,
        node.normal,
        vis,
        (j, batch),
        sink,
    ) else {
        return;
    };
    for (c, v) in values.iter().take(per).enumerate() {
        row[j * per + c] = scale * v;
    }
}

/// Each face's elements with the boxes of their halves ([`ElementBoxes`]), for the rows that
/// see the face in part. A face's elements are its refined triangles four by four, so the
/// halves of its list lie apart.
pub(crate) fn face_boxes(mesh: &Mesh, disc: &Discretization) -> Vec<ElementBoxes> {
    (0..mesh.face_count())
        .map(|face| {
            let range = mesh.face_range(face);
            ElementBoxes::new(disc.elements[range].iter().map(|el| el.in_face()).collect())
        })
        .collect()
}

#[cfg(test)]
mod tests;
