//! The compressed operator as built: its blocks (exact, sparse, low-rank, shadowed) in the
//! cluster trees' orders, and its products with vectors.

use std::ops::Range;

use rayon::prelude::*;

use super::estimate::MemoryEstimate;
use super::stats::OperatorStats;
use super::stored::{self, BlockData, Precision};
use crate::distributed::Ranks;
use crate::visibility::PairStats;

/// A block of K: rows `rows` of the node order, columns of the elements `cols` of the element
/// order (each with its basis functions).
#[derive(Clone, Debug)]
pub(super) struct Block {
    /// Rows and element columns as u32 (four bytes less each than usize: an operator keeps a
    /// million blocks and more).
    pub(super) rows: Range<u32>,
    pub(super) cols: Range<u32>,
    pub(super) data: BlockData,
}

/// K as exact near blocks and low-rank far blocks.
#[derive(Clone, Debug)]
pub struct CompressedOperator {
    pub(super) dof: usize,
    pub(super) per: usize,
    /// `node_order[k]`: the node at row k of the blocks (the node cluster tree's order).
    pub(super) node_order: Vec<usize>,
    /// `element_order[k]`: the element at column group k (the element cluster tree's order).
    pub(super) element_order: Vec<usize>,
    pub(super) blocks: Vec<Block>,
    /// Statistics of the blocks.
    pub stats: OperatorStats,
    /// Pair classes of the exact blocks.
    pub pairs: PairStats,
    /// Rows of nodes that reflect nothing (rho = 0): zero, u = E there.
    pub zero_rows: usize,
    /// The GPU that evaluated the entries (name and backend), if one did.
    pub device: Option<String>,
    /// In a distributed run, this rank's part: it holds only its blocks, and the products sum
    /// every rank's. `stats` and `pairs` are then the whole operator's.
    pub share: Option<RankShare>,
    /// What its build was estimated to hold at its peak before it began (none for an operator
    /// read from a file).
    pub memory_estimate: Option<Box<MemoryEstimate>>,
}

/// A rank's part of a distributed compressed operator.
#[derive(Clone, Debug)]
pub struct RankShare {
    /// The ranks the operator is spread over.
    pub ranks: Ranks,
    /// Bytes of this rank's blocks.
    pub operator_bytes: u64,
    /// Time of the build this rank spent waiting for the others in collectives.
    pub waited_seconds: f64,
    /// What the rank holds whatever its share: its resident memory when the build began (the
    /// scene, mesh, discretization and occluder index, the same on every rank), the cluster
    /// trees, the whole block plan (while its share is taken) and the orders.
    pub replicated_bytes: u64,
}

impl CompressedOperator {
    /// Number of unknowns.
    pub fn dof(&self) -> usize {
        self.dof
    }

    /// `K x`: the blocks in parallel, each adding into its rows.
    pub fn apply(&self, x: &[f64]) -> Vec<f64> {
        let mut y = self.products(&[x], |data, x, y| data.apply_add(x, y));
        y.pop().expect("one product")
    }

    /// `K x` for every `x` in `xs` together: each block is read once for all of them (many
    /// right-hand sides cost the operator's memory traffic once per round, not once per
    /// vector). Each product equals [`CompressedOperator::apply`]'s up to the order of sums.
    pub fn apply_many(&self, xs: &[&[f64]]) -> Vec<Vec<f64>> {
        let m = xs.len();
        if m <= 1 {
            return xs.iter().map(|x| self.apply(x)).collect();
        }
        self.products(xs, |data, x, y| data.apply_add_many(x, y, m))
    }

    /// `K x` for every `x` in `xs`, the vectors interleaved in the blocks' orders (`x[k * m +
    /// v]`: vector v at column k, m vectors) and each block adding its part by `add(data, x, y)`
    /// into its rows, the blocks in parallel.
    pub(super) fn products(
        &self,
        xs: &[&[f64]],
        add: impl Fn(&BlockData, &[f64], &mut [f64]) + Sync,
    ) -> Vec<Vec<f64>> {
        let (m, per, dof) = (xs.len(), self.per, self.dof);
        let mut xp = vec![0.0; dof * m];
        for (k, &e) in self.element_order.iter().enumerate() {
            for q in 0..per {
                let column = k * per + q;
                for (v, x) in xs.iter().enumerate() {
                    xp[column * m + v] = x[e * per + q];
                }
            }
        }
        // Each run of blocks adds into its own rows in block order, and the runs' rows are summed
        // in run order: a product repeats to the bit on a given number of threads (a rayon fold
        // would group the sums as its work stealing falls). Several runs a thread
        // ([`RUNS_PER_THREAD`]) let the threads share the work as it comes; a run holds only the
        // rows its blocks span (blocks follow the block tree, so a run's rows are mostly near one
        // another).
        let runs = block_runs(&self.blocks, RUNS_PER_THREAD * rayon::current_num_threads());
        let partial: Vec<(Range<usize>, Vec<f64>)> = runs
            .par_iter()
            .map(|run| {
                let blocks = &self.blocks[run.clone()];
                let start = blocks.iter().map(|b| b.row_range().start).min().unwrap_or(0);
                let end = blocks.iter().map(|b| b.row_range().end).max().unwrap_or(0);
                let mut y = vec![0.0; (end - start) * m];
                for b in blocks {
                    let (rows, cols) = (b.row_range(), b.col_range());
                    let xs = &xp[cols.start * per * m..cols.end * per * m];
                    add(&b.data, xs, &mut y[(rows.start - start) * m..(rows.end - start) * m]);
                }
                (start * m..end * m, y)
            })
            .collect();
        let mut yp = vec![0.0; dof * m];
        yp.par_chunks_mut(SUM_CHUNK).enumerate().for_each(|(c, out)| {
            let at = c * SUM_CHUNK..c * SUM_CHUNK + out.len();
            for (span, y) in &partial {
                let (lo, hi) = (span.start.max(at.start), span.end.min(at.end));
                if lo < hi {
                    let part = &y[lo - span.start..hi - span.start];
                    out[lo - at.start..hi - at.start]
                        .iter_mut()
                        .zip(part)
                        .for_each(|(a, b)| *a += b);
                }
            }
        });
        // The columns are read: their n values need not wait beside the rows' for the sums.
        drop(xp);
        if let Some(share) = &self.share {
            share.ranks.sum(&mut yp);
        }
        let mut ys = vec![vec![0.0; dof]; m];
        for (k, &i) in self.node_order.iter().enumerate() {
            for (v, y) in ys.iter_mut().enumerate() {
                y[i] = yp[k * m + v];
            }
        }
        ys
    }

    /// Largest `max_i |(K_c x - K x)_i| / max_i |(K x)_i|` against a reference product
    /// `x -> K x` (the dense matrix's, or another compressed operator's) over three vectors:
    /// ones (the row sums), one of one sign, one of both signs.
    pub fn max_product_difference(&self, reference: &dyn Fn(&[f64]) -> Vec<f64>) -> f64 {
        let n = self.dof;
        let vectors: [Vec<f64>; 3] = [
            vec![1.0; n],
            (0..n).map(|i| 1.0 + (i as f64 * 0.37).sin()).collect(),
            (0..n).map(|i| (i as f64 * 1.3).cos()).collect(),
        ];
        vectors
            .iter()
            .map(|x| {
                let (a, b) = (self.apply(x), reference(x));
                let diff = a.iter().zip(&b).fold(0.0f64, |m, (p, q)| m.max((p - q).abs()));
                diff / b.iter().fold(0.0f64, |m, v| m.max(v.abs())).max(f64::MIN_POSITIVE)
            })
            .fold(0.0, f64::max)
    }
}

/// Entries of a product's sum added by one task.
const SUM_CHUNK: usize = 1 << 14;

/// Runs of blocks per thread in a product.
const RUNS_PER_THREAD: usize = 16;

/// `blocks` cut into at most `count` (at least one) contiguous runs of about equal stored bytes,
/// which the products' work follows: the runs depend on the blocks and `count` alone.
pub(super) fn block_runs(blocks: &[Block], count: usize) -> Vec<Range<usize>> {
    let total: u64 = blocks.iter().map(|b| b.data.bytes()).sum();
    let count = count.clamp(1, blocks.len().max(1)) as u64;
    let mut runs = Vec::with_capacity(count as usize);
    let (mut start, mut seen) = (0, 0u64);
    for (k, b) in blocks.iter().enumerate() {
        seen += b.data.bytes();
        // Run r ends once the bytes seen reach r + 1 shares of the total.
        if seen * count >= (runs.len() as u64 + 1) * total && runs.len() + 1 < count as usize {
            runs.push(start..k + 1);
            start = k + 1;
        }
    }
    runs.push(start..blocks.len());
    runs
}

impl Block {
    /// Block `rows` × `cols` holding `data`.
    pub(super) fn new(rows: Range<usize>, cols: Range<usize>, data: BlockData) -> Self {
        // An operator of 2^32 unknowns would take far more memory than any machine has.
        let narrow = |r: Range<usize>| -> Range<u32> {
            let fit = |v: usize| u32::try_from(v).expect("fewer than 2^32 rows and columns");
            fit(r.start)..fit(r.end)
        };
        Block { rows: narrow(rows), cols: narrow(cols), data }
    }

    /// A block of no rows holding nothing (a slot before its block is built).
    pub(super) fn nothing() -> Self {
        Block::new(0..0, 0..0, BlockData::exact(Vec::new()))
    }

    /// Its rows, in the node order.
    pub(super) fn row_range(&self) -> Range<usize> {
        self.rows.start as usize..self.rows.end as usize
    }

    /// Its columns, in the element order (elements, each with its basis functions).
    pub(super) fn col_range(&self) -> Range<usize> {
        self.cols.start as usize..self.cols.end as usize
    }

    /// Stores an exact block by what it holds, as soon as it is built, in `precision`:
    /// nothing where every pair is hidden (it is then counted empty and left out), its
    /// non-zero entries alone where that takes fewer bytes (hidden pairs in a block seen
    /// through slats or between buildings), so that memory follows the pairs that are seen.
    pub(super) fn compact(&mut self, precision: Precision) {
        let data = std::mem::replace(&mut self.data, BlockData::exact(Vec::new()));
        self.data = data.compacted(self.row_range().len(), precision);
    }

    /// Bytes of its stored values (and of the column indices of a sparse block).
    pub(super) fn bytes(&self) -> u64 {
        self.data.bytes()
    }
}

/// What `blocks` themselves tell of an operator: blocks and entries by kind, the largest rank,
/// and the bytes they take with their index (a shadowed block's shared factors once).
pub(super) fn block_stats(blocks: &[Block], per: usize) -> OperatorStats {
    let mut stats = OperatorStats::default();
    let index_bytes = std::mem::size_of::<Block>() as u64;
    let mut shared = std::collections::HashSet::new();
    let mut count_factors =
        |stats: &mut OperatorStats, factors: &std::sync::Arc<stored::Factors>| {
            if shared.insert(std::sync::Arc::as_ptr(factors)) {
                let bytes = factors.u.bytes() + factors.v.bytes();
                stats.operator_bytes += bytes;
                stats.low_rank_bytes += bytes;
                stats.max_rank = stats.max_rank.max(factors.rank());
            }
        };
    for block in blocks {
        match &block.data {
            BlockData::Dense(d) => {
                stats.near_blocks += 1;
                stats.near_entries += d.len() as u64;
            }
            BlockData::Sparse(rows) => {
                stats.near_blocks += 1;
                stats.near_entries += rows.values.len() as u64;
            }
            BlockData::LowRank(f) => {
                stats.far_blocks += 1;
                stats.far_entries += (block.row_range().len() * f.columns()) as u64;
                stats.max_rank = stats.max_rank.max(f.rank());
                stats.low_rank_bytes += block.bytes();
            }
            BlockData::Seen(slice) => {
                stats.far_blocks += 1;
                stats.far_entries +=
                    (block.row_range().len() * block.col_range().len() * per) as u64;
                count_factors(&mut stats, &slice.factors);
            }
            BlockData::Leaf(leaf) => {
                stats.near_blocks += 1;
                stats.near_entries += leaf.partial.values.len() as u64;
                stats.far_entries += leaf.whole_entries();
                count_factors(&mut stats, &leaf.slice.factors);
            }
        }
        stats.operator_bytes += block.bytes() + index_bytes;
    }
    stats.shadowed_blocks = shared.len() as u64;
    stats
}
