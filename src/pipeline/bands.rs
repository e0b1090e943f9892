//! Colour bands on one assembled operator: each band's K is the grey K with its rows scaled by
//! the band's reflectivity, solved in turn, and the bands' solves are reported as one.

use std::time::Instant;

use rayon::prelude::*;

use super::BandReport;
use super::report::range;
use crate::assembly::CollocationMatrix;
use crate::discretization::Discretization;
use crate::error::Result;
use crate::scene::{CHANNELS, Scene};
use crate::solution::BandValues;
use crate::solve::{self, Products, SolveOutcome, SolverOptions};

/// K for colour channel `channel` from the grey K: node i's row scaled by rho_channel / rho
/// (K includes rho/π per row, and rho = 0 only where every channel is 0).
fn band_matrix(
    grey: &CollocationMatrix,
    scene: &Scene,
    disc: &Discretization,
    channel: usize,
) -> CollocationMatrix {
    let mut k = grey.clone();
    k.rows_mut().zip(disc.par_nodes()).for_each(|(row, node)| {
        let face = &scene.faces[node.face()];
        let scale = if face.rho == 0.0 { 0.0 } else { face.channel(channel).0 / face.rho };
        if scale != 1.0 {
            row.iter_mut().for_each(|x| *x *= scale);
        }
    });
    k
}

/// Solves each band in `channels` on the grey K: one scaled copy of K at a time.
pub(super) fn solve_bands(
    grey: &CollocationMatrix,
    scene: &Scene,
    disc: &Discretization,
    channels: &[usize],
    options: SolverOptions,
) -> Result<Vec<(BandValues, BandReport, SolveOutcome)>> {
    solve_each_band(scene, disc, channels, |channel, emission| {
        solve::solve(&band_matrix(grey, scene, disc, channel), emission, options)
    })
}

/// Solves each band in `channels` on the grey operator known by its products (compressed, or
/// on the device), its rows scaled per band in every product (no copy).
pub(super) fn solve_bands_by_products(
    grey: &dyn Products,
    scene: &Scene,
    disc: &Discretization,
    channels: &[usize],
    options: SolverOptions,
    compression_tolerance: f64,
) -> Result<Vec<(BandValues, BandReport, SolveOutcome)>> {
    let grey_rho: Vec<f64> = disc.nodes().map(|n| n.rho).collect();
    solve_each_band(scene, disc, channels, |channel, emission| {
        let rho: Vec<f64> =
            disc.nodes().map(|n| scene.faces[n.face()].channel(channel).0).collect();
        let rho = (rho.as_slice(), grey_rho.as_slice());
        solve::solve_by_products(grey, emission, rho, options, compression_tolerance)
    })
}

/// Each band's solve by `solve(channel, emission)`, with its report.
fn solve_each_band(
    scene: &Scene,
    disc: &Discretization,
    channels: &[usize],
    solve: impl Fn(usize, &[f64]) -> Result<SolveOutcome>,
) -> Result<Vec<(BandValues, BandReport, SolveOutcome)>> {
    channels
        .iter()
        .map(|&channel| {
            let emission: Vec<f64> =
                disc.nodes().map(|n| scene.faces[n.face()].channel(channel).1).collect();
            let started = Instant::now();
            let outcome = solve(channel, &emission)?;
            let report = BandReport {
                band: CHANNELS[channel],
                solver: outcome.solver,
                iterations: outcome.iterations,
                residual: outcome.residual,
                condition_estimate: outcome.condition_estimate,
                solve_seconds: started.elapsed().as_secs_f64(),
                solution_range: range(&outcome.u),
            };
            let values = BandValues { channel, u: outcome.u.clone(), emission };
            Ok((values, report, outcome))
        })
        .collect()
}

/// The bands' solves as one: u their mean, iterations summed, the worst residual, condition
/// and refinement.
pub(super) fn mean_outcome(outcomes: Vec<SolveOutcome>) -> SolveOutcome {
    let count = outcomes.len() as f64;
    let mut mean = outcomes[0].clone();
    mean.u.iter_mut().for_each(|x| *x = 0.0);
    mean.iterations = 0;
    for o in &outcomes {
        mean.u.iter_mut().zip(&o.u).for_each(|(m, x)| *m += x / count);
        mean.iterations += o.iterations;
        mean.residual = mean.residual.max(o.residual);
        mean.refinement_steps = mean.refinement_steps.max(o.refinement_steps);
        mean.condition_estimate = match (mean.condition_estimate, o.condition_estimate) {
            (Some(a), Some(b)) => Some(a.max(b)),
            (a, b) => a.or(b),
        };
    }
    mean
}
