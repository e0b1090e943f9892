//! How a block of the compressed operator holds its values, and its products: exact blocks
//! dense or by their non-zero entries, low-rank blocks by their factors, the parts of a
//! shadowed block (`shadowed.rs`) by the factors they share and, in leaves, a bit for each pair
//! seen whole and the exact partly visible entries; the values in f64, or
//! in f32 where the operator's tolerance leaves room for f32's rounding (mixed-precision
//! storage of hierarchical matrices: the low-rank blocks' error is the tolerance the user set,
//! and values rounded to f32 add 2^-24 of each entry, 16 times less at the threshold).

use std::sync::Arc;

use super::aca::{LowRank, dot};

/// The precision of a compressed operator's stored values: f64 as computed, or rounded to f32
/// (relative error at most 2^-24 each, arithmetic in f64).
pub use crate::vocabulary::Precision;

/// The smallest compression tolerance at which values are stored in f32: 16 times f32's unit
/// roundoff, so that rounding adds at most a sixteenth of the tolerance to a product. The
/// default tolerance 1e-6 is above it; at 1e-9 the values stay in f64.
pub const F32_FROM_TOLERANCE: f64 = 16.0 * f32::EPSILON as f64 / 2.0;

/// The precision an operator of compression tolerance `tolerance` stores its values in.
pub fn precision_for(tolerance: f64) -> Precision {
    if tolerance >= F32_FROM_TOLERANCE { Precision::F32 } else { Precision::F64 }
}

/// Stored values: f64, or rounded to f32 (boxed slices: a block's values do not grow, and
/// the capacity a vector would keep beside them is 8 bytes more for each of a million blocks).
#[derive(Clone, Debug, PartialEq)]
pub(super) enum Values {
    F64(Box<[f64]>),
    F32(Box<[f32]>),
}

/// `$body` with `$v` bound to the slice of `$values` in its own precision: the products are
/// generic over it, so that each block is dispatched once, not each value.
macro_rules! on_values {
    ($values:expr, $v:ident => $body:expr) => {
        match $values {
            Values::F64($v) => $body,
            Values::F32($v) => $body,
        }
    };
}

impl Values {
    /// `values` in `precision`.
    pub(super) fn new(values: Vec<f64>, precision: Precision) -> Self {
        match precision {
            Precision::F64 => Values::F64(values.into_boxed_slice()),
            Precision::F32 => Values::F32(values.into_iter().map(|v| v as f32).collect()),
        }
    }

    /// Their precision.
    #[cfg(test)]
    pub(super) fn precision(&self) -> Precision {
        match self {
            Values::F64(_) => Precision::F64,
            Values::F32(_) => Precision::F32,
        }
    }

    pub(super) fn len(&self) -> usize {
        on_values!(self, v => v.len())
    }

    pub(super) fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// A copy of the values at `range`.
    pub(super) fn range(&self, range: std::ops::Range<usize>) -> Self {
        match self {
            Values::F64(v) => Values::F64(v[range].into()),
            Values::F32(v) => Values::F32(v[range].into()),
        }
    }

    /// Bytes they take.
    pub(super) fn bytes(&self) -> u64 {
        match self {
            Values::F64(v) => 8 * v.len() as u64,
            Values::F32(v) => 4 * v.len() as u64,
        }
    }

    /// Them all in f64, appended to `out`.
    pub(super) fn extend_f64(&self, out: &mut Vec<f64>) {
        on_values!(self, v => out.extend(v.iter().map(|&x| wide(x))))
    }
}

/// A stored value in f64 (the macro's arms take both precisions through it).
#[inline]
fn wide<T: Into<f64>>(value: T) -> f64 {
    value.into()
}

/// A block's values.
#[derive(Clone, Debug)]
pub(super) enum BlockData {
    /// Row-major, rows × (elements · per).
    Dense(Values),
    /// An exact block most of whose pairs are hidden: its non-zero entries row by row.
    Sparse(SparseRows),
    /// `U V^T`.
    LowRank(Factors),
    /// A sub-block of a shadowed block that its nodes see whole: the shared factors' product.
    Seen(FactorSlice),
    /// A leaf of a shadowed block that a shadow boundary crosses.
    Leaf(Box<ShadowedLeaf>),
}

impl BlockData {
    /// An exact block as computed, row-major (stored in f64 until [`BlockData::compacted`]).
    pub(super) fn exact(values: Vec<f64>) -> Self {
        BlockData::Dense(Values::F64(values.into_boxed_slice()))
    }

    /// A low-rank block's factors in `precision`.
    pub(super) fn low_rank(lr: LowRank, precision: Precision) -> Self {
        BlockData::LowRank(Factors::from_low_rank(lr, precision))
    }

    /// The block as the kinds a saved operator and a device keep (dense, sparse, low-rank):
    /// a shadowed block's parts with their entries of the shared factors written out, for a
    /// block of `rows` × `width`.
    pub(super) fn standalone(&self, rows: usize, width: usize) -> std::borrow::Cow<'_, Self> {
        use std::borrow::Cow;
        match self {
            BlockData::Seen(slice) => Cow::Owned(BlockData::LowRank(slice.to_factors(rows, width))),
            BlockData::Leaf(leaf) => Cow::Owned(BlockData::Sparse(leaf.to_sparse(rows, width))),
            _ => Cow::Borrowed(self),
        }
    }

    /// An exact block of `rows` rows as it is worth storing, in `precision`: nothing where
    /// every entry is zero (an empty dense block), its non-zero entries alone where that takes
    /// fewer bytes (hidden pairs in a block seen through slats or between buildings), else
    /// dense. Other blocks as they are.
    pub(super) fn compacted(self, rows: usize, precision: Precision) -> Self {
        let BlockData::Dense(Values::F64(d)) = self else { return self };
        let non_zero = d.iter().filter(|&&v| v != 0.0).count();
        if non_zero == 0 {
            return BlockData::Dense(Values::F64(Box::default()));
        }
        let width = d.len() / rows;
        let masked =
            SparseRows::mask_bytes(rows, width) + (precision.bytes() as u64) * non_zero as u64;
        if masked < (precision.bytes() as u64) * d.len() as u64 {
            BlockData::Sparse(SparseRows::from_dense(&d, width, precision))
        } else {
            BlockData::Dense(Values::new(d.into_vec(), precision))
        }
    }

    /// Bytes of its values (and of the masks of a sparse block).
    pub(super) fn bytes(&self) -> u64 {
        match self {
            BlockData::Dense(d) => d.bytes(),
            BlockData::Sparse(rows) => rows.bytes(),
            BlockData::LowRank(f) => f.u.bytes() + f.v.bytes(),
            // The shared factors count once, with the shadowed block.
            BlockData::Seen(_) => 0,
            BlockData::Leaf(leaf) => leaf.bytes(),
        }
    }

    /// `y += B x`.
    pub(super) fn apply_add(&self, x: &[f64], y: &mut [f64]) {
        match self {
            BlockData::Dense(d) => on_values!(d, d => {
                for (yi, row) in y.iter_mut().zip(d.chunks_exact(x.len())) {
                    *yi += dot(row, x);
                }
            }),
            BlockData::Sparse(rows) => rows.apply_add(x, y),
            BlockData::LowRank(f) => {
                let k = f.rank();
                let mut t = vec![0.0; k];
                on_values!(&f.v, v => {
                    for (row, xj) in v.chunks_exact(k.max(1)).zip(x) {
                        t.iter_mut().zip(row).for_each(|(t, &v)| *t += wide(v) * xj);
                    }
                });
                on_values!(&f.u, u => {
                    for (yi, row) in y.iter_mut().zip(u.chunks_exact(k.max(1))) {
                        *yi += dot(row, &t);
                    }
                });
            }
            BlockData::Seen(slice) => slice.apply_add(x, y),
            BlockData::Leaf(leaf) => leaf.apply_add(x, y),
        }
    }

    /// `y += B x` for `m` vectors interleaved: `x[c * m + v]`, `y[r * m + v]`.
    pub(super) fn apply_add_many(&self, x: &[f64], y: &mut [f64], m: usize) {
        let c = x.len() / m;
        let axpy = |y: &mut [f64], a: f64, x: &[f64]| {
            y.iter_mut().zip(x).for_each(|(y, x)| *y += a * x);
        };
        match self {
            BlockData::Dense(d) => on_values!(d, d => {
                for (row, y) in d.chunks_exact(c.max(1)).zip(y.chunks_exact_mut(m)) {
                    for (&a, x) in row.iter().zip(x.chunks_exact(m)) {
                        axpy(y, wide(a), x);
                    }
                }
            }),
            BlockData::Sparse(rows) => on_values!(&rows.values, values => {
                let mut k = 0;
                for (y, row) in y.chunks_exact_mut(m).zip(rows.row_masks(c)) {
                    each_column(row, |col| {
                        axpy(y, wide(values[k]), &x[col * m..(col + 1) * m]);
                        k += 1;
                    });
                }
            }),
            BlockData::LowRank(f) => {
                // t = V^T x (k x m), then y += U t.
                let k = f.rank();
                let mut t = vec![0.0; k * m];
                on_values!(&f.v, v => {
                    for (v_row, x) in v.chunks_exact(k.max(1)).zip(x.chunks_exact(m)) {
                        for (&a, t) in v_row.iter().zip(t.chunks_exact_mut(m)) {
                            axpy(t, wide(a), x);
                        }
                    }
                });
                on_values!(&f.u, u => {
                    for (u_row, y) in u.chunks_exact(k.max(1)).zip(y.chunks_exact_mut(m)) {
                        for (&a, t) in u_row.iter().zip(t.chunks_exact(m)) {
                            axpy(y, wide(a), t);
                        }
                    }
                });
            }
            BlockData::Seen(slice) => each_vector(x, y, m, |x, y| slice.apply_add(x, y)),
            BlockData::Leaf(leaf) => each_vector(x, y, m, |x, y| leaf.apply_add(x, y)),
        }
    }
}

/// The non-zero entries of a block, row by row: bit j of row r's mask (`width.div_ceil(64)`
/// words) is set where column j holds a value, and the values follow in row-major order. For
/// the 16 or 32 columns of a leaf a row's index takes 8 bytes, not 4 per entry as column lists
/// would, so that storing a block sparse pays once an eighth of its pairs are hidden.
#[derive(Clone, Debug)]
pub(super) struct SparseRows {
    pub(super) masks: Box<[u64]>,
    pub(super) values: Values,
}

impl SparseRows {
    /// The non-zero entries of a row-major block of `width` columns, in `precision`.
    pub(super) fn from_dense(d: &[f64], width: usize, precision: Precision) -> Self {
        let words = mask_words(width);
        let mut masks = vec![0u64; d.len() / width.max(1) * words];
        let mut values = Vec::new();
        for (row, mask) in d.chunks_exact(width).zip(masks.chunks_exact_mut(words)) {
            for (c, &v) in row.iter().enumerate().filter(|(_, v)| **v != 0.0) {
                mask[c / 64] |= 1 << (c % 64);
                values.push(v);
            }
        }
        Self { masks: masks.into_boxed_slice(), values: Values::new(values, precision) }
    }

    /// The entries of an m × `width` block given row by row as compressed sparse rows (row r
    /// holds `columns[starts[r]..starts[r + 1]]`, increasing), or `None` where they are not
    /// such rows of that block.
    pub(super) fn from_csr(
        starts: &[u32],
        columns: &[u32],
        values: Values,
        m: usize,
        width: usize,
    ) -> Option<Self> {
        let words = mask_words(width);
        let fits = starts.len() == m + 1
            && starts.first() == Some(&0)
            && starts.windows(2).all(|w| w[0] <= w[1])
            && starts[m] as usize == columns.len()
            && columns.len() == values.len();
        if !fits {
            return None;
        }
        let mut masks = vec![0u64; m * words];
        for (r, mask) in masks.chunks_exact_mut(words).enumerate() {
            let row = &columns[starts[r] as usize..starts[r + 1] as usize];
            if !row.windows(2).all(|w| w[0] < w[1])
                || row.last().is_some_and(|&c| c as usize >= width)
            {
                return None;
            }
            row.iter().for_each(|&c| mask[c as usize / 64] |= 1 << (c % 64));
        }
        Some(Self { masks: masks.into_boxed_slice(), values })
    }

    /// Its entries as compressed sparse rows: where each row starts (rows + 1 values), then
    /// each entry's column, for a block of `width` columns.
    pub(super) fn csr(&self, width: usize) -> (Vec<u32>, Vec<u32>) {
        let (mut starts, mut cols) = (vec![0], Vec::with_capacity(self.values.len()));
        for row in self.row_masks(width) {
            each_column(row, |c| cols.push(c as u32));
            starts.push(cols.len() as u32);
        }
        (starts, cols)
    }

    /// `y += B x`.
    fn apply_add(&self, x: &[f64], y: &mut [f64]) {
        on_values!(&self.values, values => {
            let mut k = 0;
            for (yi, row) in y.iter_mut().zip(self.row_masks(x.len())) {
                let mut sum = 0.0;
                each_column(row, |c| {
                    sum += wide(values[k]) * x[c];
                    k += 1;
                });
                *yi += sum;
            }
        })
    }

    /// Each row's mask words, for a block of `width` columns.
    fn row_masks(&self, width: usize) -> std::slice::ChunksExact<'_, u64> {
        self.masks.chunks_exact(mask_words(width))
    }

    /// Bytes of the masks of a block of `rows` × `width`.
    fn mask_bytes(rows: usize, width: usize) -> u64 {
        8 * (rows * mask_words(width)) as u64
    }

    pub(super) fn bytes(&self) -> u64 {
        8 * self.masks.len() as u64 + self.values.bytes()
    }
}

/// Mask words of a row of `width` columns (one at least, so that rows stay apart).
pub(super) fn mask_words(width: usize) -> usize {
    width.div_ceil(64).max(1)
}

/// `f(c)` for each column c whose bit is set in a row's mask words, increasing.
#[inline]
fn each_column(mask: &[u64], mut f: impl FnMut(usize)) {
    for (w, &word) in mask.iter().enumerate() {
        let mut bits = word;
        while bits != 0 {
            f(64 * w + bits.trailing_zeros() as usize);
            bits &= bits - 1;
        }
    }
}

/// A low-rank block `U V^T`: U rows × k and V columns × k, both row-major.
#[derive(Clone, Debug)]
pub(super) struct Factors {
    /// Columns (u32, as a block's are).
    pub(super) c: u32,
    /// Rank.
    pub(super) k: u32,
    pub(super) u: Values,
    pub(super) v: Values,
}

impl Factors {
    /// `U V^T` of `c` columns and rank `k`, or `None` where either passes u32.
    pub(super) fn new(c: usize, k: usize, u: Values, v: Values) -> Option<Self> {
        Some(Self { c: c.try_into().ok()?, k: k.try_into().ok()?, u, v })
    }

    /// A cross approximation's factors in `precision`.
    pub(super) fn from_low_rank(lr: LowRank, precision: Precision) -> Self {
        let (u, v) = (Values::new(lr.u, precision), Values::new(lr.v, precision));
        Self::new(lr.c, lr.k, u, v).expect("a block's columns and rank fit u32")
    }

    /// Columns.
    pub(super) fn columns(&self) -> usize {
        self.c as usize
    }

    /// Rank.
    pub(super) fn rank(&self) -> usize {
        self.k as usize
    }
}

/// The part of a shadowed block's shared factors that one of its sub-blocks covers: from row
/// `row0` and column `col0` of the factors on (the sub-block's extent is its own).
#[derive(Clone, Debug)]
pub(super) struct FactorSlice {
    pub(super) factors: Arc<Factors>,
    pub(super) row0: u32,
    pub(super) col0: u32,
}

impl FactorSlice {
    /// `t = V^T x` over the slice's columns (`x` holds them).
    fn project(&self, x: &[f64]) -> Vec<f64> {
        let k = self.factors.rank();
        let mut t = vec![0.0; k];
        let at = self.col0 as usize * k;
        on_values!(&self.factors.v, v => {
            for (row, xj) in v[at..at + x.len() * k].chunks_exact(k.max(1)).zip(x) {
                t.iter_mut().zip(row).for_each(|(t, &v)| *t += wide(v) * xj);
            }
        });
        t
    }

    /// `y += U t` over the slice's rows (`y` holds them).
    fn expand_add(&self, t: &[f64], y: &mut [f64]) {
        let k = self.factors.rank();
        let (at, rows) = (self.row0 as usize * k, y.len());
        on_values!(&self.factors.u, u => {
            for (yi, row) in y.iter_mut().zip(u[at..at + rows * k].chunks_exact(k.max(1))) {
                *yi += dot(row, t);
            }
        });
    }

    /// `y += U V^T x` on the slice.
    pub(super) fn apply_add(&self, x: &[f64], y: &mut [f64]) {
        let t = self.project(x);
        self.expand_add(&t, y);
    }

    /// The slice of `rows` × `columns` as a low-rank block of its own.
    pub(super) fn to_factors(&self, rows: usize, columns: usize) -> Factors {
        let k = self.factors.rank();
        let (r, c) = (self.row0 as usize * k, self.col0 as usize * k);
        let u = self.factors.u.range(r..r + rows * k);
        let v = self.factors.v.range(c..c + columns * k);
        Factors::new(columns, k, u, v).expect("a block's columns and rank fit u32")
    }
}

thread_local! {
    /// A thread's scratch for [`ShadowedLeaf::apply_add`]: the prefix sums of a leaf's columns
    /// and a row's sum of runs, kept from one leaf to the next.
    static PREFIX: std::cell::RefCell<Vec<f64>> = const { std::cell::RefCell::new(Vec::new()) };
}

/// A leaf of a shadowed block that a shadow boundary crosses.
#[derive(Clone, Debug)]
pub(super) struct ShadowedLeaf {
    pub(super) slice: FactorSlice,
    /// Row by row (mask words of the leaf's columns): the columns of the elements the node
    /// sees whole, whose entries the factors give.
    pub(super) whole: Box<[u64]>,
    /// The exact entries of the elements the node sees in part.
    pub(super) partial: SparseRows,
}

impl ShadowedLeaf {
    /// `y += B x`: per row, the factors' product summed over each run of columns seen whole
    /// (prefix sums of `V_q x_q`, one difference per run), then the partly visible entries.
    pub(super) fn apply_add(&self, x: &[f64], y: &mut [f64]) {
        PREFIX.with_borrow_mut(|scratch| {
            on_values!(&self.slice.factors.v, v => on_values!(&self.slice.factors.u, u => {
                #[cfg(target_arch = "x86_64")]
                if std::arch::is_x86_feature_detected!("avx2")
                    && std::arch::is_x86_feature_detected!("fma")
                {
                    // SAFETY: AVX2 and FMA were detected at run time just above.
                    return unsafe { self.whole_add_avx2(u, v, x, y, scratch) };
                }
                self.whole_add(u, v, x, y, scratch)
            }))
        });
        self.partial.apply_add(x, y);
    }

    /// [`Self::whole_add`] compiled for AVX2 and FMA (four rank terms at a time).
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,fma")]
    fn whole_add_avx2<U: Copy + Into<f64>, V: Copy + Into<f64>>(
        &self,
        u: &[U],
        v: &[V],
        x: &[f64],
        y: &mut [f64],
        scratch: &mut Vec<f64>,
    ) {
        self.whole_add(u, v, x, y, scratch)
    }

    /// `y += B x` over the pairs seen whole, with the factors `u` and `v` and the prefix sums in
    /// `scratch`. A row whose mask is its predecessor's reuses its sum of runs (neighbouring
    /// nodes mostly see the same elements whole).
    #[inline(always)]
    fn whole_add<U: Copy + Into<f64>, V: Copy + Into<f64>>(
        &self,
        u: &[U],
        v: &[V],
        x: &[f64],
        y: &mut [f64],
        scratch: &mut Vec<f64>,
    ) {
        let k = self.slice.factors.rank();
        if k == 0 {
            return;
        }
        let c = x.len();
        // Only the first prefix row needs zeros: the others are written before they are read,
        // and the sum is cleared before its first row.
        scratch.resize((c + 2) * k, 0.0);
        let (prefix, sum) = scratch.split_at_mut((c + 1) * k);
        prefix[..k].fill(0.0);
        let at = self.slice.col0 as usize * k;
        for (q, (row, &xq)) in v[at..at + c * k].chunks_exact(k).zip(x).enumerate() {
            let (before, after) = prefix.split_at_mut((q + 1) * k);
            let (before, after) = (&before[q * k..], &mut after[..k]);
            for ((a, &b), &vl) in after.iter_mut().zip(before).zip(row) {
                *a = b + vl.into() * xq;
            }
        }
        let words = mask_words(c);
        let row0 = self.slice.row0 as usize;
        let mut last: Option<&[u64]> = None;
        for (r, (yi, mask)) in y.iter_mut().zip(self.whole.chunks_exact(words)).enumerate() {
            if mask.iter().all(|&w| w == 0) {
                continue;
            }
            if last != Some(mask) {
                sum.fill(0.0);
                each_run(mask, |a, b| {
                    let (hi, lo) = (&prefix[b * k..(b + 1) * k], &prefix[a * k..(a + 1) * k]);
                    for ((s, &h), &l) in sum.iter_mut().zip(hi).zip(lo) {
                        *s += h - l;
                    }
                });
                last = Some(mask);
            }
            *yi += dot(&u[(row0 + r) * k..(row0 + r + 1) * k], sum);
        }
    }

    /// The leaf as the non-zero entries of a block of its own, of `rows` × `width`: the
    /// factors' entries where a node sees an element whole, the exact ones elsewhere. In f64
    /// whatever the factors' precision, so that its products are the leaf's to rounding.
    pub(super) fn to_sparse(&self, rows: usize, width: usize) -> SparseRows {
        let factors = &self.slice.factors;
        let k = factors.rank();
        let mut dense = vec![0.0; rows * width];
        let (starts, columns) = self.partial.csr(width);
        let mut values = Vec::new();
        self.partial.values.extend_f64(&mut values);
        for r in 0..rows {
            for e in starts[r] as usize..starts[r + 1] as usize {
                dense[r * width + columns[e] as usize] = values[e];
            }
        }
        let (u, v) = (factors.u.range(0..factors.u.len()), &factors.v);
        let (row0, col0) = (self.slice.row0 as usize, self.slice.col0 as usize);
        let words = mask_words(width);
        let (mut ur, mut vq) = (Vec::with_capacity(k), Vec::with_capacity(k));
        for (r, mask) in self.whole.chunks_exact(words).enumerate() {
            ur.clear();
            u.range((row0 + r) * k..(row0 + r + 1) * k).extend_f64(&mut ur);
            each_run(mask, |a, b| {
                for q in a..b {
                    vq.clear();
                    v.range((col0 + q) * k..(col0 + q + 1) * k).extend_f64(&mut vq);
                    dense[r * width + q] = dot(&ur, &vq);
                }
            });
        }
        SparseRows::from_dense(&dense, width, Precision::F64)
    }

    /// Bytes of its masks and exact entries (the factors are the shadowed block's).
    pub(super) fn bytes(&self) -> u64 {
        8 * self.whole.len() as u64 + self.partial.bytes()
    }

    /// Entries that the factors give.
    pub(super) fn whole_entries(&self) -> u64 {
        self.whole.iter().map(|w| u64::from(w.count_ones())).sum()
    }
}

/// `f(a, b)` for each run `a..b` of set bits in a row's mask words, increasing.
fn each_run(mask: &[u64], mut f: impl FnMut(usize, usize)) {
    let mut start = None;
    for (w, &word) in mask.iter().enumerate() {
        let mut at = 0u32;
        while at < 64 {
            let rest = word >> at;
            match start {
                None => {
                    if rest == 0 {
                        break;
                    }
                    at += rest.trailing_zeros();
                    start = Some(64 * w + at as usize);
                }
                Some(a) => {
                    // The shift brought in zeros, so the ones counted stop at the word's end.
                    at += (!rest).trailing_zeros().min(64 - at);
                    if at < 64 {
                        f(a, 64 * w + at as usize);
                        start = None;
                    }
                }
            }
        }
    }
    if let Some(a) = start {
        f(a, 64 * mask.len());
    }
}

/// `y += B x` for `m` vectors interleaved (`x[c * m + v]`, `y[r * m + v]`), one vector at a
/// time through `apply`.
fn each_vector(x: &[f64], y: &mut [f64], m: usize, apply: impl Fn(&[f64], &mut [f64])) {
    let (c, rows) = (x.len() / m, y.len() / m);
    let (mut xv, mut yv) = (vec![0.0; c], vec![0.0; rows]);
    for v in 0..m {
        xv.iter_mut().enumerate().for_each(|(q, xq)| *xq = x[q * m + v]);
        yv.fill(0.0);
        apply(&xv, &mut yv);
        yv.iter().enumerate().for_each(|(r, yr)| y[r * m + v] += yr);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A block stored in f32 gives the products of its f64 values to f32's rounding, and
    /// takes half the bytes.
    #[test]
    fn values_in_f32_give_the_products_of_f64_to_their_rounding() {
        let (m, c) = (5, 7);
        let values: Vec<f64> =
            (0..m * c).map(|k| if k % 3 == 0 { 0.0 } else { 1.0 / (1.0 + k as f64) }).collect();
        let x: Vec<f64> = (0..c).map(|j| (j as f64 * 0.7).cos()).collect();
        let lr = LowRank {
            m,
            c,
            k: 2,
            u: (0..2 * m).map(|k| (k as f64).sin()).collect(),
            v: (0..2 * c).map(|k| (k as f64 * 0.3).cos()).collect(),
        };
        let blocks = |p: Precision| {
            [
                BlockData::exact(values.clone()).compacted(m, p),
                BlockData::Sparse(SparseRows::from_dense(&values, c, p)),
                BlockData::low_rank(lr.clone(), p),
            ]
        };
        for (wide, narrow) in blocks(Precision::F64).iter().zip(&blocks(Precision::F32)) {
            assert!(narrow.bytes() < wide.bytes());
            let (mut a, mut b) = (vec![0.0; m], vec![0.0; m]);
            wide.apply_add(&x, &mut a);
            narrow.apply_add(&x, &mut b);
            let scale = a.iter().fold(0.0f64, |s, v| s.max(v.abs()));
            let worst = a.iter().zip(&b).fold(0.0f64, |s, (p, q)| s.max((p - q).abs()));
            assert!(worst > 0.0 && worst <= 4.0 * f32::EPSILON as f64 * scale, "{worst}");
            // Two vectors at once give each one's product.
            let xx: Vec<f64> = x.iter().flat_map(|&v| [v, 2.0 * v]).collect();
            let mut yy = vec![0.0; 2 * m];
            narrow.apply_add_many(&xx, &mut yy, 2);
            for r in 0..m {
                assert!((yy[2 * r] - b[r]).abs() <= 1e-15 * scale);
                assert!((yy[2 * r + 1] - 2.0 * b[r]).abs() <= 1e-15 * scale);
            }
        }
        assert_eq!(precision_for(1e-6), Precision::F32);
    }

    /// Sparse rows of one or several mask words give the dense block's product to rounding, and
    /// go to compressed sparse rows and back.
    #[test]
    fn sparse_rows_give_the_dense_product() {
        let sizes = [(3, 1), (16, 16), (5, 40), (7, 64), (4, 70), (3, 130)];
        // About a third hidden, scattered; or a band of each row hidden, and the rest in long
        // runs (whole mask words of 64 among them).
        let scattered = |k: usize, _: usize| (k * 7 + k / 5).is_multiple_of(3);
        let band = |k: usize, width: usize| (width / 3..width / 2).contains(&(k % width));
        let hidden: [&dyn Fn(usize, usize) -> bool; 2] = [&scattered, &band];
        for ((m, width), hidden) in sizes.into_iter().flat_map(|s| hidden.map(|h| (s, h))) {
            let d: Vec<f64> = (0..m * width)
                .map(|k| if hidden(k, width) { 0.0 } else { 0.1 + (k as f64).sin().abs() })
                .collect();
            let x: Vec<f64> = (0..width).map(|j| (j as f64 * 0.9).cos()).collect();
            for precision in [Precision::F64, Precision::F32] {
                let rows = SparseRows::from_dense(&d, width, precision);
                // The values as stored, so that only the order of sums differs.
                let mut stored = Vec::new();
                rows.values.extend_f64(&mut stored);
                let mut at = stored.iter();
                let dense: Vec<f64> = d
                    .chunks(width)
                    .map(|row| {
                        row.iter()
                            .zip(&x)
                            .filter(|(v, _)| **v != 0.0)
                            .map(|(_, xj)| at.next().unwrap() * xj)
                            .sum::<f64>()
                    })
                    .collect();
                let mut y = vec![1.0; m];
                rows.apply_add(&x, &mut y);
                for (a, c) in y.iter().zip(&dense) {
                    assert!((a - 1.0 - c).abs() <= 1e-14, "{a} {c}");
                }
                let (starts, cols) = rows.csr(width);
                let back = SparseRows::from_csr(&starts, &cols, rows.values.clone(), m, width);
                assert_eq!(back.map(|b| b.masks), Some(rows.masks.clone()));
                // Columns out of order or past the block are refused.
                if cols.len() >= 2 && starts[1] >= 2 {
                    let mut swapped = cols.clone();
                    swapped.swap(0, 1);
                    assert!(
                        SparseRows::from_csr(&starts, &swapped, rows.values.clone(), m, width)
                            .is_none()
                    );
                }
                if width > 1 {
                    let narrower = SparseRows::from_csr(&starts, &cols, rows.values.clone(), m, 1);
                    assert!(narrower.is_none());
                }
                // A block of no columns (a damaged file's) holds nothing, and no row of it does.
                let none = SparseRows::from_csr(&starts, &cols, rows.values.clone(), m, 0);
                assert!(none.is_none());
                let empty = SparseRows::from_csr(
                    &vec![0; m + 1],
                    &[],
                    Values::new(vec![], precision),
                    m,
                    0,
                );
                assert!(empty.is_some_and(|e| e.masks.iter().all(|&w| w == 0)));
            }
        }
        assert_eq!(precision_for(1e-9), Precision::F64);
    }

    /// The runs of set bits, within and across mask words.
    #[test]
    fn runs_of_set_bits_are_found_within_and_across_words() {
        let runs = |mask: &[u64]| {
            let mut out = Vec::new();
            each_run(mask, |a, b| out.push((a, b)));
            out
        };
        assert_eq!(runs(&[0]), vec![]);
        assert_eq!(runs(&[0b1011_0110]), vec![(1, 3), (4, 6), (7, 8)]);
        assert_eq!(runs(&[u64::MAX]), vec![(0, 64)]);
        assert_eq!(runs(&[1 << 63, 1]), vec![(63, 65)]);
        assert_eq!(runs(&[u64::MAX << 60, u64::MAX, 0b101]), vec![(60, 129), (130, 131)]);
        assert_eq!(runs(&[0, 1 << 5]), vec![(69, 70)]);
    }
}
