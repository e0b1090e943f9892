//! The compressed operator packed into flat arrays for a device to apply
//! (`shaders/blocks.wgsl` reads this layout; the GPU's side is `gpu::DeviceBlocks`).

use super::compressed::{Block, CompressedOperator};
use super::stored::BlockData;

/// Fields of a block's descriptor, in order.
pub mod field {
    /// [`super::DENSE`], [`super::SPARSE`] or [`super::LOW_RANK`].
    pub const KIND: usize = 0;
    /// First row (node-order position) and the number of rows.
    pub const ROWS_START: usize = 1;
    /// Number of rows.
    pub const ROWS: usize = 2;
    /// First column (element-order position × basis functions) and the number of columns.
    pub const COLS_START: usize = 3;
    /// Number of columns.
    pub const COLS: usize = 4;
    /// Rank of a low-rank block.
    pub const RANK: usize = 5;
    /// Where its values start in `values`: dense, row-major; sparse, row by row; low-rank,
    /// U (rows × rank) then V (columns × rank), both row-major.
    pub const VALUES_AT: usize = 6;
    /// Where a sparse block's row starts (rows + 1) then its columns start in `indices`.
    pub const INDEX_AT: usize = 7;
    /// Where a low-rank block's `V^T x` (rank values) goes in the scratch buffer.
    pub const T_AT: usize = 8;
    /// Where the block's rows of its product go in the scratch buffer.
    pub const PARTIAL_AT: usize = 9;
}

/// u32 per descriptor.
pub const DESCRIPTOR: usize = 12;
/// Block kinds.
pub const DENSE: u32 = 0;
/// A block stored by its non-zero entries row by row.
pub const SPARSE: u32 = 1;
/// A block stored as U V^T.
pub const LOW_RANK: u32 = 2;

/// The blocks of a compressed operator as flat arrays. `indices` holds the descriptors
/// ([`DESCRIPTOR`] u32 each, fields in [`field`]), the sparse blocks' row starts and columns,
/// then the low-rank blocks' numbers (`low_rank_at`), then per row of the block order the
/// range of its contributions (`row_starts_at`, dof + 1 values) and the contributions
/// themselves (scratch positions, `contributions_at`), so that a row's sum is taken in block
/// order, the same every time.
#[derive(Clone, Debug, Default)]
pub struct PackedBlocks {
    /// Number of blocks.
    pub blocks: usize,
    /// Number of low-rank blocks.
    pub low_rank: usize,
    /// Values of every block.
    pub values: Vec<f64>,
    /// Descriptors and index data.
    pub indices: Vec<u32>,
    /// Where the low-rank blocks' numbers start in `indices`.
    pub low_rank_at: usize,
    /// Where the rows' contribution ranges start in `indices`.
    pub row_starts_at: usize,
    /// Where the contributions start in `indices`.
    pub contributions_at: usize,
    /// f64 values of scratch the product needs (the low-rank blocks' `V^T x` and every
    /// block's rows).
    pub scratch: usize,
}

impl CompressedOperator {
    /// The blocks packed for a device in one part ([`PackedBlocks`]), or `None` in a
    /// distributed run (each rank holds a part) or where an offset passes what u32 holds.
    pub fn packed(&self) -> Option<PackedBlocks> {
        if self.share.is_some() {
            return None;
        }
        self.pack(&self.blocks)
    }

    /// The blocks packed in consecutive parts whose values, indices and scratch each take at
    /// most `max_bytes` (a device's largest binding), so that the product is the sum of the
    /// parts' products, taken in part order; `None` where [`Self::packed`] gives none or one
    /// block alone passes `max_bytes`.
    pub fn packed_parts(&self, max_bytes: u64) -> Option<Vec<PackedBlocks>> {
        if self.share.is_some() {
            return None;
        }
        // Bytes of each array in a part: the rows' contribution ranges are in every part.
        let fixed = [0, 4 * (self.dof as u64 + 1), 0];
        let mut parts = Vec::new();
        let (mut start, mut bytes) = (0, fixed);
        for (b, block) in self.blocks.iter().enumerate() {
            let rows = block.row_range().len() as u64;
            let width = block.col_range().len() * self.per;
            let (values, index, rank) = match block.data.standalone(rows as usize, width).as_ref() {
                BlockData::Dense(values) => (values.len(), 0, 0),
                BlockData::Sparse(s) => {
                    (s.values.len(), block.row_range().len() + 1 + s.values.len(), 0)
                }
                BlockData::LowRank(lr) => (lr.u.len() + lr.v.len(), 1, lr.rank()),
                BlockData::Seen(_) | BlockData::Leaf(_) => unreachable!("packed standalone"),
            };
            let own = [
                8 * values as u64,
                4 * (DESCRIPTOR as u64 + index as u64 + rows),
                8 * (rank as u64 + rows),
            ];
            if (0..3).any(|a| fixed[a] + own[a] > max_bytes) {
                return None;
            }
            if (0..3).any(|a| bytes[a] + own[a] > max_bytes) {
                parts.push(self.pack(&self.blocks[start..b])?);
                (start, bytes) = (b, fixed);
            }
            (0..3).for_each(|a| bytes[a] += own[a]);
        }
        parts.push(self.pack(&self.blocks[start..])?);
        Some(parts)
    }

    /// `blocks` packed as one part.
    fn pack(&self, blocks: &[Block]) -> Option<PackedBlocks> {
        let mut p = PackedBlocks { blocks: blocks.len(), ..Default::default() };
        let mut descriptors = vec![0u32; DESCRIPTOR * blocks.len()];
        let mut sparse_index = Vec::new();
        let mut low_rank = Vec::new();
        let mut scratch = 0usize;
        let fits = |v: usize| u32::try_from(v).ok();
        for (b, block) in blocks.iter().enumerate() {
            let d = &mut descriptors[b * DESCRIPTOR..(b + 1) * DESCRIPTOR];
            d[field::ROWS_START] = fits(block.row_range().start)?;
            d[field::ROWS] = fits(block.row_range().len())?;
            d[field::COLS_START] = fits(block.col_range().start * self.per)?;
            d[field::COLS] = fits(block.col_range().len() * self.per)?;
            d[field::VALUES_AT] = fits(p.values.len())?;
            let width = block.col_range().len() * self.per;
            match block.data.standalone(block.row_range().len(), width).as_ref() {
                BlockData::Dense(values) => {
                    d[field::KIND] = DENSE;
                    values.extend_f64(&mut p.values);
                }
                BlockData::Sparse(rows) => {
                    d[field::KIND] = SPARSE;
                    d[field::INDEX_AT] = fits(sparse_index.len())?;
                    let (starts, columns) = rows.csr(width);
                    sparse_index.extend_from_slice(&starts);
                    sparse_index.extend_from_slice(&columns);
                    rows.values.extend_f64(&mut p.values);
                }
                BlockData::LowRank(lr) => {
                    d[field::KIND] = LOW_RANK;
                    d[field::RANK] = fits(lr.rank())?;
                    d[field::T_AT] = fits(scratch)?;
                    scratch += lr.rank();
                    lr.u.extend_f64(&mut p.values);
                    lr.v.extend_f64(&mut p.values);
                    low_rank.push(fits(b)?);
                }
                BlockData::Seen(_) | BlockData::Leaf(_) => unreachable!("packed standalone"),
            }
            d[field::PARTIAL_AT] = fits(scratch)?;
            scratch += block.row_range().len();
        }
        // Sparse blocks' index data follows the descriptors.
        let base = fits(descriptors.len())?;
        for d in descriptors.chunks_exact_mut(DESCRIPTOR) {
            if d[field::KIND] == SPARSE {
                d[field::INDEX_AT] = d[field::INDEX_AT].checked_add(base)?;
            }
        }
        // Each row's contributions in block order.
        let mut count = vec![0u32; self.dof + 1];
        for block in blocks {
            block.row_range().clone().for_each(|r| count[r + 1] += 1);
        }
        for r in 0..self.dof {
            count[r + 1] += count[r];
        }
        let mut contributions = vec![0u32; count[self.dof] as usize];
        let mut next = count.clone();
        for (b, block) in blocks.iter().enumerate() {
            let at = descriptors[b * DESCRIPTOR + field::PARTIAL_AT] as usize;
            for (k, r) in block.row_range().clone().enumerate() {
                contributions[next[r] as usize] = fits(at + k)?;
                next[r] += 1;
            }
        }
        p.indices = descriptors;
        p.indices.extend_from_slice(&sparse_index);
        p.low_rank_at = p.indices.len();
        p.low_rank = low_rank.len();
        p.indices.extend_from_slice(&low_rank);
        p.row_starts_at = p.indices.len();
        p.indices.extend_from_slice(&count);
        p.contributions_at = p.indices.len();
        p.indices.extend_from_slice(&contributions);
        p.scratch = scratch;
        fits(p.indices.len())?;
        fits(p.values.len())?;
        Some(p)
    }

    /// Basis functions per element (columns per element of the blocks).
    pub fn per_element(&self) -> usize {
        self.per
    }

    /// `node_order[k]`: the node at row k of the blocks.
    pub fn node_order(&self) -> &[usize] {
        &self.node_order
    }

    /// `element_order[k]`: the element at column group k of the blocks.
    pub fn element_order(&self) -> &[usize] {
        &self.element_order
    }
}
