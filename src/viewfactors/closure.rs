//! Closure for open scenes, as urban and building models need it: each element's sky view
//! factor (1 - Σ_j F_ij, the share of its hemisphere that no element fills:
//! [`ViewFactors::sky_view_factors`]), the matrix conditioned so that reciprocity is exact and no
//! row exceeds 1 with no entry moved by more than the run's error estimate
//! ([`ViewFactors::condition`]), and entries below a threshold dropped in pairs
//! ([`ViewFactors::drop_below`]).

use serde::Serialize;

use super::matrix::ViewFactors;
use crate::error::{Error, Result};

/// What [`ViewFactors::condition`] changed.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Conditioning {
    /// The largest change of an entry: reciprocity made exact, then rows above 1 scaled.
    pub largest_change: f64,
    /// Rows whose sum exceeded 1 and were scaled to it.
    pub rows_scaled: usize,
}

/// What [`ViewFactors::drop_below`] removed.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Dropped {
    /// The threshold: F_ij and F_ji both below it are dropped.
    pub below: f64,
    /// Entries dropped.
    pub entries: usize,
    /// The largest sum of a row's dropped entries: what its sky view factor then counts as sky.
    pub largest_row_sum: f64,
}

impl ViewFactors {
    /// Each element's sky view factor, 1 - Σ_j F_ij: what of its hemisphere no element fills
    /// (0 for an element of a closed scene, to the entries' estimates).
    pub fn sky_view_factors(&self) -> Vec<f64> {
        (0..self.len()).map(|i| 1.0 - self.row(i).1.iter().sum::<f64>()).collect()
    }

    /// Conditions F in place for models that need closure: each pair's A_i F_ij and A_j F_ji
    /// replaced by their mean (reciprocity exact: where each pair was integrated once it already
    /// is, to rounding), then every pair of a row whose sum exceeds 1 scaled by the smaller
    /// of its two rows' factors `1 / sum` (symmetric, so reciprocity stays exact, and no row
    /// exceeds 1: every sky view factor is at least 0). Refuses, naming the entry and leaving
    /// F unchanged, where an entry would move by more than the run's error estimate: the
    /// entries are then not accurate enough for closure (a tighter tolerance is).
    pub fn condition(&mut self) -> Result<Conditioning> {
        let n = self.len();
        let allowed = self.error_estimate;
        let mut moved = 0.0f64;
        let refuse =
            |(i, j): (usize, u32), from: f64, to: f64, why: &str| Error::InvalidParameter {
                name: "condition",
                value: format!("F({i}, {j}) = {from:e}"),
                reason: format!(
                    "{why} would move it to {to:e}, by more than the run's error estimate \
                 {allowed:.2e}: tighten --tolerance"
                ),
            };
        // Reciprocity: every pair of the union of both rows' entries, both ways.
        let mut rows: Vec<Vec<(u32, f64)>> = vec![Vec::new(); n];
        for i in 0..n {
            let (columns, values) = self.row(i);
            for (&j, &f_ij) in columns.iter().zip(values) {
                let ju = j as usize;
                let f_ji = self.get(ju, i);
                // Each pair once: from its first row, or from row i where row j lacks it.
                if ju < i && f_ji != 0.0 {
                    continue;
                }
                let shared = 0.5 * (self.areas[i] * f_ij + self.areas[ju] * f_ji);
                let (to_ij, to_ji) = (shared / self.areas[i], shared / self.areas[ju]);
                for (at, from, to) in [((i, j), f_ij, to_ij), ((ju, i as u32), f_ji, to_ji)] {
                    if (to - from).abs() > allowed {
                        return Err(refuse(at, from, to, "making reciprocity exact"));
                    }
                }
                rows[i].push((j, to_ij));
                if ju != i {
                    rows[ju].push((i as u32, to_ji));
                }
            }
        }
        // Rows above 1, each by a factor that leaves its rounded sum at most 1: a sum of k
        // terms is off by at most (k - 1) ulp of it.
        let factors: Vec<f64> = rows
            .iter()
            .map(|row| {
                let sum: f64 = row.iter().map(|&(_, v)| v).sum();
                let margin = 1.0 + (row.len() + 1) as f64 * f64::EPSILON;
                if sum * margin > 1.0 { 1.0 / (sum * margin) } else { 1.0 }
            })
            .collect();
        for (i, row) in rows.iter_mut().enumerate() {
            for (j, v) in row.iter_mut() {
                let scaled = *v * factors[i].min(factors[*j as usize]);
                let from = self.get(i, *j as usize);
                if (from - scaled).abs() > allowed {
                    return Err(refuse((i, *j), from, scaled, "scaling its row's sum to 1"));
                }
                moved = moved.max((from - scaled).abs());
                *v = scaled;
            }
            row.sort_unstable_by_key(|&(j, _)| j);
        }
        self.set_rows(rows);
        Ok(Conditioning {
            largest_change: moved,
            rows_scaled: factors.iter().filter(|&&c| c < 1.0).count(),
        })
    }

    /// Drops each pair whose entries F_ij and F_ji are both below `threshold` (so that what
    /// stays keeps reciprocity), and says how many and how much of a row's sum went.
    pub fn drop_below(&mut self, threshold: f64) -> Dropped {
        let n = self.len();
        let mut lost = vec![0.0f64; n];
        let mut rows: Vec<Vec<(u32, f64)>> = Vec::with_capacity(n);
        for (i, lost) in lost.iter_mut().enumerate() {
            let (columns, values) = self.row(i);
            let mut row = Vec::with_capacity(columns.len());
            for (&j, &v) in columns.iter().zip(values) {
                if v < threshold && self.get(j as usize, i) < threshold {
                    *lost += v;
                } else {
                    row.push((j, v));
                }
            }
            rows.push(row);
        }
        let before = self.nonzeros();
        self.set_rows(rows);
        Dropped {
            below: threshold,
            entries: before - self.nonzeros(),
            largest_row_sum: lost.into_iter().fold(0.0, f64::max),
        }
    }

    /// Replaces the entries by `rows`, each sorted by column.
    fn set_rows(&mut self, rows: Vec<Vec<(u32, f64)>>) {
        self.row_starts = std::iter::once(0)
            .chain(rows.iter().scan(0, |end, row| {
                *end += row.len();
                Some(*end)
            }))
            .collect();
        self.columns = rows.iter().flatten().map(|&(j, _)| j).collect();
        self.values = rows.iter().flatten().map(|&(_, v)| v).collect();
    }
}
