//! The computation of a scene's view factors ([`view_factors`]): each row's pairs in parallel,
//! each integrated once over the smaller element, then the sparse matrix put together with the
//! entries that reciprocity gives.

use rayon::prelude::*;

use super::context::Context;
use super::matrix::ViewFactors;
use super::options::ViewFactorOptions;
use super::outer_rules::OuterRules;
use super::row::{Between, Tally};
use crate::assembly::{AssemblyOptions, PairIntegrator};
use crate::discretization::{Discretization, Method};
use crate::error::Result;
use crate::mesh::{Element, Mesh};
use crate::progress::Progress;
use crate::scene::Scene;
use crate::visibility::PairPlanner;

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
                let mut own = Tally::default();
                let mut value = context.pair(i, j, other, &rules, &mut own);
                let mut estimate = own.error;
                tally.evaluations += own.evaluations;
                if value > 0.0 && context.close(i, j) {
                    (value, estimate) =
                        context.reconciled((i, j), (value, estimate), &rules, &mut tally);
                }
                tally.error = tally.error.max(estimate);
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
