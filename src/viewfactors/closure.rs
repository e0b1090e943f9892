//! Closure for open scenes, as urban and building models need it: each element's sky view
//! factor (1 - Σ_j F_ij, the share of its hemisphere that no element fills:
//! [`ViewFactors::sky_view_factors`]), the matrix conditioned so that reciprocity is exact and no
//! row exceeds 1 with no entry moved by more than the run's error estimate
//! ([`ViewFactors::condition`]), and entries below a threshold dropped in pairs
//! ([`ViewFactors::drop_below`]).

use serde::Serialize;

use super::matrix::ViewFactors;
use crate::error::{Error, Result};

/// The closure a caller asks for (`viewfactors --condition --drop-below V`).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ClosureOptions {
    /// Condition the matrix ([`ViewFactors::condition`]).
    pub condition: bool,
    /// Then drop the pairs below this threshold ([`ViewFactors::drop_below`]).
    pub drop_below: Option<f64>,
}

impl ClosureOptions {
    /// Refuses a threshold outside (0, 1], before the work that computes the matrix.
    pub fn validate(&self) -> Result<()> {
        self.drop_below.map(check_threshold).transpose().map(|_| ())
    }
}

/// What closure changed: each part where it was asked for.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct Closure {
    /// What conditioning changed ([`ViewFactors::condition`]).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub conditioning: Option<Conditioning>,
    /// What the threshold dropped ([`ViewFactors::drop_below`]).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub dropped: Option<Dropped>,
}

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

    /// Closes F as `options` ask: conditioned, then its small pairs dropped.
    pub fn close(&mut self, options: &ClosureOptions) -> Result<Closure> {
        let conditioning = if options.condition { Some(self.condition()?) } else { None };
        let dropped = options.drop_below.map(|threshold| self.drop_below(threshold)).transpose()?;
        Ok(Closure { conditioning, dropped })
    }

    /// Conditions F in place for models that need closure: each pair's A_i F_ij and A_j F_ji
    /// replaced by their mean (reciprocity exact: where each pair was integrated once it already
    /// is, to rounding), then every pair of a row whose sum exceeds 1 scaled by the smaller
    /// of its two rows' factors `1 / sum` (symmetric, so reciprocity stays exact, and no row
    /// exceeds 1: every sky view factor is at least 0). Refuses, naming the entry and leaving
    /// F unchanged, where an entry would move by more than the run's error estimate: the
    /// entries are then not accurate enough for closure (a tighter tolerance is).
    pub fn condition(&mut self) -> Result<Conditioning> {
        let allowed = self.error_estimate;
        self.store_both_entries_of_each_pair();
        let n = self.len();
        let refuse =
            |(i, j): (usize, usize), from: f64, to: f64, why: &str| Error::InvalidParameter {
                name: "condition",
                value: format!("F({i}, {j}) = {from:e}"),
                reason: format!(
                    "{why} would move it to {to:e}, by more than the run's error estimate \
                 {allowed:.2e}: tighten --tolerance"
                ),
            };
        // The rows' sums once reciprocity is exact, and the factor that leaves each at most 1
        // (a sum of k terms rounds by at most k - 1 ulp of it).
        let mut factors = vec![1.0; n];
        for (i, factor) in factors.iter_mut().enumerate() {
            let range = self.row_starts[i]..self.row_starts[i + 1];
            let mut sum = 0.0;
            for k in range.clone() {
                let [(at, _, to), _] = self.conditioned_pair(i, k, 1.0);
                if (to - self.values[k]).abs() > allowed {
                    return Err(refuse(at, self.values[k], to, "making reciprocity exact"));
                }
                sum += to;
            }
            let margin = 1.0 + (range.len() + 1) as f64 * f64::EPSILON;
            if sum * margin > 1.0 {
                *factor = 1.0 / (sum * margin);
            }
        }
        // Each pair once, from its entry above the diagonal; every pair checked before any is
        // written, so that a refusal leaves F as it was.
        let factor_of =
            |f: &Self, i: usize, k: usize| factors[i].min(factors[f.columns[k] as usize]);
        for i in 0..n {
            for k in self.above_the_diagonal(i) {
                for (at, place, to) in self.conditioned_pair(i, k, factor_of(self, i, k)) {
                    if (to - self.values[place]).abs() > allowed {
                        return Err(refuse(
                            at,
                            self.values[place],
                            to,
                            "scaling its row's sum to 1",
                        ));
                    }
                }
            }
        }
        let mut largest_change = 0.0f64;
        for i in 0..n {
            for k in self.above_the_diagonal(i) {
                for (_, place, to) in self.conditioned_pair(i, k, factor_of(self, i, k)) {
                    largest_change = largest_change.max((to - self.values[place]).abs());
                    self.values[place] = to;
                }
            }
        }
        Ok(Conditioning {
            largest_change,
            rows_scaled: factors.iter().filter(|&&c| c < 1.0).count(),
        })
    }

    /// The pair of the entry `k` of row `i` (F_ij), both its entries: each one's (row,
    /// column), place among the values and value once reciprocity is exact (the mean of
    /// A_i F_ij and A_j F_ji, over each area) and scaled by `factor`.
    fn conditioned_pair(
        &self,
        i: usize,
        k: usize,
        factor: f64,
    ) -> [((usize, usize), usize, f64); 2] {
        let j = self.columns[k] as usize;
        let (columns, _) = self.row(j);
        let m = self.row_starts[j] + columns.binary_search(&(i as u32)).expect("a stored mirror");
        let mean = 0.5 * (self.areas[i] * self.values[k] + self.areas[j] * self.values[m]);
        [((i, j), k, mean / self.areas[i] * factor), ((j, i), m, mean / self.areas[j] * factor)]
    }

    /// The places among the values of row i's entries above the diagonal (F_ij with j > i).
    fn above_the_diagonal(&self, i: usize) -> std::ops::Range<usize> {
        let (columns, _) = self.row(i);
        let first = columns.partition_point(|&j| j as usize <= i);
        self.row_starts[i] + first..self.row_starts[i + 1]
    }

    /// The columns j of row i whose F_ji is not stored.
    fn unmirrored(&self, i: usize) -> impl Iterator<Item = u32> + '_ {
        let (columns, _) = self.row(i);
        columns
            .iter()
            .copied()
            .filter(move |&j| self.row(j as usize).0.binary_search(&(i as u32)).is_err())
    }

    /// Stores F_ji = 0 where F_ij is stored and F_ji is not (with each direction integrated,
    /// one may have come out zero), so that every pair has both its entries.
    fn store_both_entries_of_each_pair(&mut self) {
        let n = self.len();
        if (0..n).all(|i| self.unmirrored(i).next().is_none()) {
            return;
        }
        let mut rows: Vec<Vec<(u32, f64)>> = (0..n)
            .map(|i| {
                let (columns, values) = self.row(i);
                columns.iter().copied().zip(values.iter().copied()).collect()
            })
            .collect();
        for i in 0..n {
            for j in self.unmirrored(i) {
                rows[j as usize].push((i as u32, 0.0));
            }
        }
        rows.iter_mut().for_each(|row| row.sort_unstable_by_key(|&(j, _)| j));
        self.set_rows(rows);
    }

    /// Drops each pair whose entries F_ij and F_ji are both below `threshold` (so that what
    /// stays keeps reciprocity), and says how many and how much of a row's sum went. Refuses a
    /// threshold outside (0, 1].
    pub fn drop_below(&mut self, threshold: f64) -> Result<Dropped> {
        check_threshold(threshold)?;
        let n = self.len();
        // Which entries go, decided on the whole matrix before any moves.
        let f: &Self = self;
        let keep: Vec<bool> = (0..n)
            .flat_map(|i| {
                let (columns, values) = f.row(i);
                columns
                    .iter()
                    .zip(values)
                    .map(move |(&j, &v)| v >= threshold || f.get(j as usize, i) >= threshold)
            })
            .collect();
        let (mut lost, mut kept) = (vec![0.0f64; n], 0);
        for (i, lost) in lost.iter_mut().enumerate() {
            let range = self.row_starts[i]..self.row_starts[i + 1];
            self.row_starts[i] = kept;
            for k in range {
                if keep[k] {
                    (self.columns[kept], self.values[kept]) = (self.columns[k], self.values[k]);
                    kept += 1;
                } else {
                    *lost += self.values[k];
                }
            }
        }
        let before = self.nonzeros();
        self.row_starts[n] = kept;
        self.columns.truncate(kept);
        self.values.truncate(kept);
        Ok(Dropped {
            below: threshold,
            entries: before - kept,
            largest_row_sum: lost.into_iter().fold(0.0, f64::max),
        })
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

/// Refuses a threshold for [`ViewFactors::drop_below`] outside (0, 1].
fn check_threshold(threshold: f64) -> Result<()> {
    if threshold > 0.0 && threshold <= 1.0 {
        return Ok(());
    }
    Err(Error::InvalidParameter {
        name: "drop-below",
        value: threshold.to_string(),
        reason: "a view factor threshold in (0, 1]".into(),
    })
}
