//! Element-to-element view factors `F_ij = (1/A_i) ∫_{T_i} (1/π) ∫_{T_j, visible from P} G dA_Q dA_P`.
//!
//! The inner integral is the exact point-to-element integral of the collocation matrix (closed
//! forms over the exactly visible pieces, [`crate::assembly::PairIntegrator`]). The outer one is
//! chosen per pair, as View3D chooses its method by separation, but kept exact:
//!
//! - visibility first, per pair of faces and then of elements: no occluder between the faces, or
//!   none in the shaft of the two elements ([`PairPlanner::shaft_occluders`]), and the whole
//!   element is seen from every point, with no per-point visibility work; one occluder across the
//!   whole shaft, and F_ij = 0;
//! - otherwise T_i is cut along the planes where the visible part of T_j changes shape (each
//!   occluder's plane, and the vertex–edge event planes between T_j and the occluders and between
//!   occluders, the EV and VE events of `mesh/shadow_lines.rs`, each only across the pieces
//!   that its segment of T_i reaches), and where it crosses T_j's plane, so that the integrand
//!   is smooth on every piece. An event at an edge that two
//!   occluders share, seen on its plane from the same side of both (inside a solid's shadow),
//!   changes nothing and is not cut along, nor one at a vertex all of whose edges are such.
//!   Where a corner of T_j lies on T_i (a contact along part of an edge, a point contact), or
//!   an edge of T_j crosses an edge of T_i that lies in T_j's plane (where that contact ends),
//!   T_i is also cut across there, so that the contact's ends are corners of pieces;
//! - each piece keeps only the pair's occluders in its own shaft to T_j
//!   ([`PairPlanner::polygon_shaft`]), less those that a convex solid among them hides from the
//!   whole piece (a city's buildings behind a nearer one): none, and it sees T_j whole; one
//!   across that shaft, and it sees nothing; otherwise each point's view is shadowed by those
//!   alone ([`PairPlanner::part_view_among`], no search);
//! - each piece is covered by quadrilaterals and triangles (`patch.rs`), integrated by Gauss
//!   rules (tensor through the bilinear map, collapsed on a triangle) of an order fitted to
//!   their separation from T_j and from the poles of the shadow corners the piece has (the
//!   Bernstein-ellipse bound), and again with one order more, whose difference is the error
//!   estimate; the nested tensor tanh-sinh rule takes the triangles that touch T_j (d log d
//!   behaviour beside a common edge) or a point where an occluder's edge meets T_i (where the
//!   shadow's limit depends on the direction), collapsed at the corner nearest either, with
//!   Bailey's estimate from its last three levels (`kept_error`); where T_j reaches behind
//!   T_i's plane, or the views from nine probe points differ in shape, the triangle's four
//!   quarters are integrated too, their sum kept and its difference from the whole's counted
//!   in the estimate (the levels of one rule can agree while missing the integral). The pair
//!   is globally adaptive: the patch with the largest estimate is split in four until the
//!   estimates together are within `--tolerance` on F_ij. The estimates also find what the a
//!   priori order does not see: the curved events of three mutually skew edges, which are not
//!   cut along.
//!
//! Each pair is integrated once, over the element of smaller area: F_ji = A_i F_ij / A_j then
//! has the error of F_ij times A_i / A_j <= 1 (as View3D computes A_i F_ij once per pair). With
//! [`ViewFactorOptions::each_direction`] both are integrated, and reciprocity measures the
//! accuracy (1e-12 on the paper's surfaces, 1e-9 on the occluded box).

use rayon::prelude::*;
use serde::Serialize;

use crate::assembly::{AssemblyOptions, PairIntegrator};
use crate::discretization::{Discretization, Method};
use crate::error::{Error, Result};
use crate::geometry::bounding_box_3d;
use crate::mesh::{Element, Mesh};
use crate::progress::Progress;
use crate::scene::Scene;
use crate::visibility::{OccluderUnit, PairPlanner};

mod check;
mod events;
mod opening;
mod outer;
mod pair;
mod patch;
mod poles;
mod sight;
pub use check::EstimateCheck;
use pair::OuterRules;

/// Accuracy settings.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ViewFactorOptions {
    /// Absolute tolerance on each F_ij: the sum of its patches' error estimates (default 1e-10);
    /// on each touching triangle, also the tanh-sinh rule's on the mean of its integrand.
    pub tolerance: f64,
    /// Finest tanh-sinh level: step 2^-max_level (default 3).
    pub max_level: u32,
    /// Most times a touching part is split into four when the levels disagree (default 0).
    pub max_depth: u32,
    /// Integrate F_ij and F_ji each, so that reciprocity checks the accuracy (twice the work);
    /// otherwise each pair once, over the element of smaller area (default).
    pub each_direction: bool,
}

impl Default for ViewFactorOptions {
    fn default() -> Self {
        Self { tolerance: 1e-10, max_level: 3, max_depth: 0, each_direction: false }
    }
}

impl ViewFactorOptions {
    /// Refuses a tolerance that is not positive and a split depth beyond 6.
    pub fn validate(&self) -> Result<()> {
        if !(self.tolerance.is_finite() && self.tolerance > 0.0) {
            return Err(Error::InvalidParameter {
                name: "tolerance",
                value: self.tolerance.to_string(),
                reason: "must be positive".into(),
            });
        }
        if self.max_depth > 6 {
            return Err(Error::InvalidParameter {
                name: "max-depth",
                value: self.max_depth.to_string(),
                reason: "at most 6 (4^6 parts of an element)".into(),
            });
        }
        Ok(())
    }
}

/// Most rounds of splitting an outer patch: deeper, it is settled with its estimate (which
/// the reported `error_estimate` then shows).
pub const MAX_SPLITS: u32 = 6;

/// The view factor matrix (its non-zero entries, row by row: memory follows what is seen, not
/// n²) and its checks.
#[derive(Clone, Debug)]
pub struct ViewFactors {
    /// Where row i's entries start in `columns` and `values`, and where the last row's end
    /// (n + 1 offsets).
    pub row_starts: Vec<usize>,
    /// Column j of each non-zero F_ij, increasing within a row.
    pub columns: Vec<u32>,
    /// F_ij of each entry.
    pub values: Vec<f64>,
    /// Element areas A_i.
    pub areas: Vec<f64>,
    /// Largest estimated error of an entry F_ij: the sum of its patches' estimates (the
    /// difference of two Gauss orders, the error of the coarser one where the finer one's value
    /// is kept; or Bailey's estimate from the last three tanh-sinh levels). Above the tolerance
    /// only where patches reached [`MAX_SPLITS`].
    pub error_estimate: f64,
    /// Point-to-element integrals evaluated.
    pub evaluations: u64,
    /// Whether F_ij and F_ji were integrated each ([`ViewFactorOptions::each_direction`]);
    /// otherwise reciprocity holds by construction, to rounding.
    pub each_direction: bool,
    /// Entries whose integral came out below zero by rounding, stored as zero.
    pub clamped: usize,
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
    /// Point-to-element integrals evaluated.
    pub evaluations: u64,
    /// Whether F_ij and F_ji were integrated each, so that `reciprocity_error` measures the
    /// accuracy; otherwise each pair once, and reciprocity holds by construction.
    pub each_direction: bool,
    /// Entries F_ij that are not zero (what a sparse output stores).
    pub nonzeros: usize,
    /// Entries that came out below zero by rounding and were stored as zero.
    pub clamped_negative: usize,
    /// Wall time.
    pub seconds: f64,
}

impl ViewFactors {
    /// Number of elements.
    pub fn len(&self) -> usize {
        self.areas.len()
    }

    /// The summary of these view factors of scene `surface`, computed in `seconds`.
    pub fn summary(&self, surface: &str, seconds: f64) -> ViewFactorSummary {
        let (row_sum_min, row_sum_max) = self.row_sum_range();
        ViewFactorSummary {
            surface: surface.to_string(),
            n: self.len(),
            row_sum_min,
            row_sum_max,
            reciprocity_error: self.reciprocity_error(),
            error_estimate: self.error_estimate,
            evaluations: self.evaluations,
            each_direction: self.each_direction,
            nonzeros: self.nonzeros(),
            clamped_negative: self.clamped,
            seconds,
        }
    }

    /// Entries that are not zero.
    pub fn nonzeros(&self) -> usize {
        self.values.len()
    }

    /// Whether there are no elements.
    pub fn is_empty(&self) -> bool {
        self.areas.is_empty()
    }

    /// Row i's non-zero entries: their columns and values.
    pub fn row(&self, i: usize) -> (&[u32], &[f64]) {
        let range = self.row_starts[i]..self.row_starts[i + 1];
        (&self.columns[range.clone()], &self.values[range])
    }

    /// F_ij.
    pub fn get(&self, i: usize, j: usize) -> f64 {
        let (columns, values) = self.row(i);
        columns.binary_search(&(j as u32)).map_or(0.0, |k| values[k])
    }

    /// F as a dense row-major n x n matrix (n² values: for small scenes and dense outputs).
    pub fn to_dense(&self) -> Vec<f64> {
        let n = self.len();
        let mut dense = vec![0.0; n * n];
        for i in 0..n {
            let (columns, values) = self.row(i);
            for (&j, &v) in columns.iter().zip(values) {
                dense[i * n + j as usize] = v;
            }
        }
        dense
    }

    /// Smallest and largest row sum.
    pub fn row_sum_range(&self) -> (f64, f64) {
        (0..self.len())
            .map(|i| self.row(i).1.iter().sum::<f64>())
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), s| (lo.min(s), hi.max(s)))
    }

    /// max |A_i F_ij - A_j F_ji| relative to the largest A_i F_ij: over the stored entries, as
    /// a pair with both entries zero adds nothing.
    pub fn reciprocity_error(&self) -> f64 {
        let (mut worst, mut scale) = (0.0f64, 0.0f64);
        for i in 0..self.len() {
            let (columns, values) = self.row(i);
            for (&j, &v) in columns.iter().zip(values) {
                let j = j as usize;
                let (a, b) = (self.areas[i] * v, self.areas[j] * self.get(j, i));
                worst = worst.max((a - b).abs());
                scale = scale.max(a.abs());
            }
        }
        if scale > 0.0 { worst / scale } else { 0.0 }
    }

    /// Face-to-face view factors: F_ab = (1/A_a) Σ_{i in a} A_i Σ_{j in b} F_ij.
    pub fn by_face(&self, mesh: &Mesh) -> Vec<Vec<f64>> {
        let faces = mesh.face_count();
        let mut sums = vec![vec![0.0; faces]; faces];
        let mut face_areas = vec![0.0; faces];
        for (i, e) in mesh.elements().iter().enumerate() {
            face_areas[e.face] += self.areas[i];
            let (columns, values) = self.row(i);
            for (&j, &v) in columns.iter().zip(values) {
                sums[e.face][mesh.elements()[j as usize].face] += self.areas[i] * v;
            }
        }
        for (row, area) in sums.iter_mut().zip(face_areas) {
            row.iter_mut().for_each(|s| *s /= area);
        }
        sums
    }
}

/// Computes the element-to-element view factors of `mesh`.
pub fn view_factors(
    scene: &Scene,
    mesh: &Mesh,
    planner: &PairPlanner,
    options: &ViewFactorOptions,
    progress: &dyn Progress,
) -> Result<ViewFactors> {
    let disc = Discretization::new(scene, mesh, Method::Centroid)?;
    let integrator = PairIntegrator::new(Method::Centroid, &AssemblyOptions::default());
    let rules = OuterRules::new(options);
    let context = Context { scene, mesh, disc: &disc, planner, integrator: &integrator, options };
    let n = mesh.len();
    let faces = mesh.face_count();
    let areas: Vec<f64> = mesh.elements().iter().map(Element::area).collect();
    // Row i integrates F_ij where T_i is the smaller of the two (by index between equals).
    let integrated = |i: usize, j: usize| {
        options.each_direction || areas[i].total_cmp(&areas[j]).then(i.cmp(&j)).is_lt()
    };
    let rows: Vec<(Vec<(u32, f64)>, Tally)> = (0..n)
        .into_par_iter()
        .map(|i| {
            let mut row = Vec::new();
            let mut tally = Tally::default();
            // What may come between element i and each face: found once per face, where a
            // pair needs it.
            let mut between: Vec<Option<Between>> = (0..faces).map(|_| None).collect();
            for j in (0..n).filter(|&j| integrated(i, j)) {
                let other = &mut between[mesh.elements()[j].face];
                let value = context.pair(i, j, other, &rules, &mut tally);
                // A view factor is not negative: where rounding of the signed pieces leaves
                // one below 0 (a pair seen through a hair's width), it is 0, and counted.
                if value < 0.0 {
                    tally.clamped += 1;
                } else if value != 0.0 {
                    row.push((j as u32, value));
                }
            }
            progress.advance(1);
            // The row's growth slack freed now: the rows wait for one another, a large city's
            // tens of millions of entries.
            row.shrink_to_fit();
            (row, tally)
        })
        .collect();
    let mirrored = !options.each_direction;
    // Each row's length, its own entries and, where F_ji = A_i F_ij / A_j is taken from row i
    // (its error is F_ij's times A_i / A_j <= 1), those that the other rows give it; then every
    // entry put in place, the rows dropped one by one, and each row sorted by column. Memory:
    // the rows computed and the final arrays, no copy of either.
    let mut row_starts = vec![0; n + 1];
    for (i, (row, _)) in rows.iter().enumerate() {
        row_starts[i + 1] += row.len();
        if mirrored {
            row.iter().for_each(|&(j, _)| row_starts[j as usize + 1] += 1);
        }
    }
    for i in 0..n {
        row_starts[i + 1] += row_starts[i];
    }
    let nonzeros = row_starts[n];
    let (mut columns, mut values) = (vec![0u32; nonzeros], vec![0.0; nonzeros]);
    let mut next = row_starts[..n].to_vec();
    let mut put = |i: usize, j: u32, v: f64| {
        columns[next[i]] = j;
        values[next[i]] = v;
        next[i] += 1;
    };
    let (mut error_estimate, mut evaluations, mut clamped) = (0.0f64, 0, 0);
    for (i, (row, tally)) in rows.into_iter().enumerate() {
        for (j, v) in row {
            put(i, j, v);
            if mirrored {
                put(j as usize, i as u32, areas[i] * v / areas[j as usize]);
            }
        }
        error_estimate = error_estimate.max(tally.error);
        evaluations += tally.evaluations;
        clamped += tally.clamped;
    }
    let mut entries = Vec::new();
    for i in 0..n {
        let range = row_starts[i]..row_starts[i + 1];
        entries.clear();
        entries.extend(
            columns[range.clone()].iter().copied().zip(values[range.clone()].iter().copied()),
        );
        entries.sort_unstable_by_key(|&(j, _)| j);
        for (k, (j, v)) in range.zip(entries.iter().copied()) {
            columns[k] = j;
            values[k] = v;
        }
    }
    let each_direction = options.each_direction;
    Ok(ViewFactors {
        row_starts,
        columns,
        values,
        areas,
        error_estimate,
        evaluations,
        each_direction,
        clamped,
    })
}

/// What the pairs of one computation share.
struct Context<'a> {
    scene: &'a Scene,
    mesh: &'a Mesh,
    disc: &'a Discretization,
    planner: &'a PairPlanner,
    integrator: &'a PairIntegrator,
    options: &'a ViewFactorOptions,
}

/// What may come between the element of a row and the elements of one face, found once per row
/// and face from the shaft between the element and the whole face (each pair's shaft lies
/// inside it).
pub(super) enum Between {
    /// No occluder.
    Nothing,
    /// A building hides the whole face from the element.
    Hidden,
    /// These occluder units, each pair's searched among them.
    Among(Vec<OccluderUnit>),
    /// More units than a pair's search of the scene costs: each pair searches it.
    Search,
}

/// The most occluder units a row keeps for a face ([`Between::Among`]): scanning a list of
/// them costs a box test each, where a search of the scene's tree goes down from its root.
const UNITS_KEPT: usize = 64;

impl Context<'_> {
    /// What may come between element `i` and face `face` ([`Between`]).
    fn between(&self, i: usize, face: usize) -> Between {
        let own = self.mesh.elements()[i].face;
        if self.planner.candidates(own, face).is_empty() {
            return Between::Nothing;
        }
        let from = bounding_box_3d(&self.mesh.elements()[i].vertices);
        let to = bounding_box_3d(&self.scene.faces[face].vertices);
        let units = self.planner.shaft_candidates(from, to, None);
        if units.is_empty() {
            Between::Nothing
        } else if self.planner.solid_among_hides(own, face, from, to, &units) {
            Between::Hidden
        } else if units.len() > UNITS_KEPT {
            Between::Search
        } else {
            Between::Among(units)
        }
    }
}

/// Point-to-element integrals evaluated, the largest error estimate and the entries clamped at
/// zero of a row.
#[derive(Default)]
struct Tally {
    evaluations: u64,
    error: f64,
    clamped: usize,
}

#[cfg(test)]
mod tests;
