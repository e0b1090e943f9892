//! K on the CPU, row by row: [`assemble`] fills the whole matrix in parallel, [`apply_at`]
//! applies K at arbitrary points without storing it, both through [`assemble_row`], which walks
//! a node's row face by face over the pair plan and integrates each visible element (the
//! faces' element boxes, [`face_boxes`], let a row take a run of elements at once).

use std::f64::consts::PI;
use std::ops::Range;

use rayon::prelude::*;

use crate::discretization::{Discretization, Node};
use crate::error::Result;
use crate::kernels::lanes;
use crate::mesh::Mesh;
use crate::progress::Progress;
use crate::visibility::{
    ElementBoxes, FaceSight, PairPlanner, PairStats, PartSight, RecentHiders, Views, Visibility,
};

use super::integrator::PairIntegrator;
use super::matrix::CollocationMatrix;
use super::options::AssemblyOptions;
use super::problem::Problem;

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
            let s = assemble_row(&disc.node(i), row, surface, planner, &integrator, hiders);
            progress.advance(1);
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
    points: impl IndexedParallelIterator<Item = Node>,
    problem: &Problem,
    options: &AssemblyOptions,
    u: &[f64],
) -> Result<Vec<f64>> {
    let Problem { mesh, disc, planner, .. } = problem;
    options.quadrature.validate()?;
    let integrator = PairIntegrator::new(disc.method, options);
    let boxes = face_boxes(mesh, disc);
    Ok(points
        .map_init(
            || (vec![0.0; disc.dof()], RecentHiders::default()),
            |(row, hiders), point| {
                row.fill(0.0);
                let surface = (mesh, disc, boxes.as_slice());
                assemble_row(&point, row, surface, planner, &integrator, hiders);
                row.iter().zip(u).map(|(k, v)| k * v).sum()
            },
        )
        .collect())
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
/// discretization alone: a closure capturing them hides that, and the values are loaded again
/// after every store.)
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
    let el = &disc.placed(j);
    let sink = |j: usize, v: f64| row[j] += scale * v;
    let Some(values) = integrator.integrate_or_batch(
        el,
        disc.basis(j),
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
            ElementBoxes::new(range.map(|j| disc.in_face(j)).collect())
        })
        .collect()
}
