//! The compressed operator in a file: its orders and blocks in a little-endian binary layout,
//! and the reader and writer that layout (and the dense matrix's, `pipeline::saved`) is made
//! of. The reader checks every length against what the file still holds and every index
//! against the operator's size, and a checksum of everything at the end, so that a truncated
//! or damaged file is refused with what is wrong, never read past or trusted.

use std::io::{Read, Write};

use super::compressed::{Block, CompressedOperator, block_stats};
use super::stats::OperatorStats;
use super::stored::BlockData;
use super::stored::{Factors, SparseRows, Values};
use crate::error::{Error, Result};
use crate::visibility::PairStats;

/// A checksum of a byte stream, word by word in four interleaved lanes (FNV-1a's step on
/// 64-bit words, with a rotation so that every bit reaches every other; four lanes so that the
/// multiplications do not wait on each other), the same however the stream is cut into calls.
#[derive(Clone, Copy, Debug)]
struct Checksum {
    lanes: [u64; 4],
    /// Words taken so far: the next goes to lane `words % 4`.
    words: u64,
    pending: [u8; 8],
    filled: usize,
}

const FNV_PRIME: u64 = 0x0000_0100_0000_01b3;

fn mix(state: u64, word: u64) -> u64 {
    (state ^ word).wrapping_mul(FNV_PRIME).rotate_left(27)
}

impl Checksum {
    fn new() -> Self {
        Self { lanes: [0xcbf2_9ce4_8422_2325; 4], words: 0, pending: [0; 8], filled: 0 }
    }

    fn word(&mut self, w: u64) {
        let lane = (self.words % 4) as usize;
        self.lanes[lane] = mix(self.lanes[lane], w);
        self.words += 1;
    }

    fn update(&mut self, mut bytes: &[u8]) {
        while self.filled > 0 && !bytes.is_empty() {
            self.pending[self.filled] = bytes[0];
            self.filled = (self.filled + 1) % 8;
            bytes = &bytes[1..];
            if self.filled == 0 {
                self.word(u64::from_le_bytes(self.pending));
            }
        }
        if bytes.is_empty() {
            return;
        }
        let word = |b: &[u8]| u64::from_le_bytes(b.try_into().expect("eight bytes"));
        while !self.words.is_multiple_of(4) && bytes.len() >= 8 {
            self.word(word(&bytes[..8]));
            bytes = &bytes[8..];
        }
        let (body, tail) = bytes.split_at(bytes.len() / 32 * 32);
        // Four words at a time; straight from the buffer where it is aligned (the arrays read
        // into their own memory are).
        let mut block = |b: [u64; 4]| {
            for (lane, w) in self.lanes.iter_mut().zip(b) {
                *lane = mix(*lane, u64::from_le(w));
            }
        };
        match bytemuck::try_cast_slice::<u8, [u64; 4]>(body) {
            Ok(blocks) => blocks.iter().for_each(|&b| block(b)),
            Err(_) => body.chunks_exact(32).for_each(|b| {
                block(bytemuck::pod_read_unaligned::<[u64; 4]>(b));
            }),
        }
        self.words += (body.len() / 8) as u64;
        let words = tail.chunks_exact(8);
        let rest = words.remainder();
        for w in words {
            self.word(word(w));
        }
        self.pending[..rest.len()].copy_from_slice(rest);
        self.filled = rest.len();
    }

    fn value(mut self) -> u64 {
        let filled = self.filled as u64;
        self.pending[self.filled..].fill(0);
        self.word(u64::from_le_bytes(self.pending));
        self.lanes.iter().fold(mix(0, filled), |s, &lane| mix(s, lane))
    }
}

/// Writes numbers little-endian, arrays with their length first, and at the end a checksum of
/// all it wrote.
pub struct BinaryWriter<W: Write> {
    out: W,
    sum: Checksum,
}

impl<W: Write> BinaryWriter<W> {
    /// A writer into `out`.
    pub fn new(out: W) -> Self {
        Self { out, sum: Checksum::new() }
    }

    /// Writes the checksum; the output, flushed.
    pub fn finish(mut self) -> Result<W> {
        self.out.write_all(&self.sum.value().to_le_bytes())?;
        self.out.flush()?;
        Ok(self.out)
    }

    /// Raw bytes, no length.
    pub fn raw(&mut self, bytes: &[u8]) -> Result<()> {
        self.sum.update(bytes);
        Ok(self.out.write_all(bytes)?)
    }

    /// One number.
    pub fn u64(&mut self, v: u64) -> Result<()> {
        self.raw(&v.to_le_bytes())
    }

    /// Bytes with their length.
    pub fn bytes(&mut self, v: &[u8]) -> Result<()> {
        self.u64(v.len() as u64)?;
        self.raw(v)
    }

    /// Numbers with their length.
    pub fn f64s(&mut self, v: &[f64]) -> Result<()> {
        self.u64(v.len() as u64)?;
        if cfg!(target_endian = "little") {
            // The values' own bytes: no copy of a large array.
            return self.raw(bytemuck::cast_slice(v));
        }
        for chunk in v.chunks(1 << 16) {
            let bytes: Vec<u8> = chunk.iter().flat_map(|x| x.to_le_bytes()).collect();
            self.raw(&bytes)?;
        }
        Ok(())
    }

    /// Numbers stored in f32, with their length.
    pub fn f32s(&mut self, v: &[f32]) -> Result<()> {
        self.u64(v.len() as u64)?;
        let bytes: Vec<u8> = v.iter().flat_map(|x| x.to_le_bytes()).collect();
        self.raw(&bytes)
    }

    /// Indices with their length.
    pub fn u32s(&mut self, v: &[u32]) -> Result<()> {
        self.u64(v.len() as u64)?;
        let bytes: Vec<u8> = v.iter().flat_map(|x| x.to_le_bytes()).collect();
        self.raw(&bytes)
    }

    /// Indices with their length, as u64.
    pub fn usizes(&mut self, v: &[usize]) -> Result<()> {
        self.u64(v.len() as u64)?;
        let bytes: Vec<u8> = v.iter().flat_map(|&x| (x as u64).to_le_bytes()).collect();
        self.raw(&bytes)
    }
}

/// Reads what [`BinaryWriter`] wrote from a file of known length, refusing any length the file
/// cannot hold (a truncated or damaged file) before allocating for it.
pub struct BinaryReader<R: Read> {
    input: R,
    path: String,
    left: u64,
    sum: Checksum,
}

impl<R: Read> BinaryReader<R> {
    /// A reader of `len` bytes from `input`, the file `path` (for messages).
    pub fn new(input: R, len: u64, path: &str) -> Self {
        Self { input, path: path.to_string(), left: len, sum: Checksum::new() }
    }

    /// Reads the checksum [`BinaryWriter::finish`] wrote and refuses a file whose bytes do not
    /// give it, or that goes on after it.
    pub fn finish(mut self) -> Result<()> {
        let expected = self.sum.value();
        let bytes = self.raw(8, "the checksum")?;
        let found = u64::from_le_bytes(bytes.try_into().expect("eight bytes"));
        if found != expected {
            return Err(self.error("damaged: the checksum does not match the contents".into()));
        }
        if self.left != 0 {
            return Err(self.error(format!("damaged: {} bytes after the checksum", self.left)));
        }
        Ok(())
    }

    /// An error about this file.
    pub fn error(&self, reason: String) -> Error {
        Error::DataFile { path: self.path.clone(), reason }
    }

    /// `n` raw bytes of `what`.
    pub fn raw(&mut self, n: u64, what: &str) -> Result<Vec<u8>> {
        self.check_left(n, what)?;
        let mut bytes = vec![0; n as usize];
        self.fill(&mut bytes, what)?;
        Ok(bytes)
    }

    /// Refuses to read `n` bytes of `what` where fewer are left.
    fn check_left(&self, n: u64, what: &str) -> Result<()> {
        if n > self.left {
            return Err(self.error(format!(
                "truncated: {what} needs {n} bytes, the file has {} left",
                self.left
            )));
        }
        Ok(())
    }

    /// Fills `bytes` from the file.
    fn fill(&mut self, bytes: &mut [u8], what: &str) -> Result<()> {
        self.check_left(bytes.len() as u64, what)?;
        self.input.read_exact(bytes)?;
        self.left -= bytes.len() as u64;
        self.sum.update(bytes);
        Ok(())
    }

    /// One number.
    pub fn u64(&mut self, what: &str) -> Result<u64> {
        let bytes = self.raw(8, what)?;
        Ok(u64::from_le_bytes(bytes.try_into().expect("eight bytes")))
    }

    /// A length of `what`, each item `item_bytes` long, that the file can hold.
    fn len(&mut self, what: &str, item_bytes: u64) -> Result<usize> {
        let len = self.u64(what)?;
        if len.saturating_mul(item_bytes) > self.left {
            return Err(self.error(format!(
                "truncated or damaged: {what} claims {len} items, the file has {} bytes left",
                self.left
            )));
        }
        Ok(len as usize)
    }

    /// Bytes with their length.
    pub fn bytes(&mut self, what: &str) -> Result<Vec<u8>> {
        let len = self.len(what, 1)?;
        self.raw(len as u64, what)
    }

    /// Numbers with their length.
    pub fn f64s(&mut self, what: &str) -> Result<Vec<f64>> {
        let len = self.len(what, 8)?;
        // Read into the values' own bytes: no second copy of a large array.
        let mut values = vec![0.0f64; len];
        self.fill(bytemuck::cast_slice_mut(&mut values), what)?;
        if cfg!(target_endian = "big") {
            values.iter_mut().for_each(|v| *v = f64::from_bits(u64::from_le(v.to_bits())));
        }
        Ok(values)
    }

    /// Numbers stored in f32, with their length.
    pub fn f32s(&mut self, what: &str) -> Result<Vec<f32>> {
        let len = self.len(what, 4)?;
        let bytes = self.raw(4 * len as u64, what)?;
        Ok(bytes.chunks_exact(4).map(|b| f32::from_le_bytes(b.try_into().expect("4"))).collect())
    }

    /// Indices with their length.
    pub fn u32s(&mut self, what: &str) -> Result<Vec<u32>> {
        let len = self.len(what, 4)?;
        let bytes = self.raw(4 * len as u64, what)?;
        Ok(bytes.chunks_exact(4).map(|b| u32::from_le_bytes(b.try_into().expect("4"))).collect())
    }

    /// Indices with their length, each below `bound`.
    pub fn usizes(&mut self, what: &str, bound: usize) -> Result<Vec<usize>> {
        let len = self.len(what, 8)?;
        let bytes = self.raw(8 * len as u64, what)?;
        let values: Vec<u64> =
            bytes.chunks_exact(8).map(|b| u64::from_le_bytes(b.try_into().expect("8"))).collect();
        match values.iter().find(|&&v| v >= bound as u64) {
            Some(v) => Err(self.error(format!("damaged: {what} holds {v}, beyond {bound}"))),
            None => Ok(values.into_iter().map(|v| v as usize).collect()),
        }
    }
}

const DENSE: u64 = 0;
const SPARSE: u64 = 1;
const LOW_RANK: u64 = 2;

impl CompressedOperator {
    /// Writes the operator (its statistics, orders and blocks).
    pub fn write<W: Write>(&self, out: &mut BinaryWriter<W>) -> Result<()> {
        if let Some(share) = &self.share {
            return Err(Error::InvalidParameter {
                name: "save",
                value: format!("{} ranks", share.ranks.size()),
                reason: "each rank holds only its blocks of a distributed operator: save it \
                         from a run of one process"
                    .into(),
            });
        }
        for v in [self.dof as u64, self.per as u64, self.zero_rows as u64] {
            out.u64(v)?;
        }
        for v in self.stats.counts().into_iter().chain(self.pairs.counts()) {
            out.u64(v)?;
        }
        out.usizes(&self.node_order)?;
        out.usizes(&self.element_order)?;
        out.u64(self.blocks.len() as u64)?;
        for b in &self.blocks {
            for v in
                [b.row_range().start, b.row_range().end, b.col_range().start, b.col_range().end]
            {
                out.u64(v as u64)?;
            }
            let width = b.col_range().len() * self.per;
            match b.data.standalone(b.row_range().len(), width).as_ref() {
                BlockData::Dense(values) => {
                    out.u64(DENSE)?;
                    write_values(out, values)?;
                }
                BlockData::Sparse(rows) => {
                    out.u64(SPARSE)?;
                    let (starts, columns) = rows.csr(width);
                    out.u32s(&starts)?;
                    out.u32s(&columns)?;
                    write_values(out, &rows.values)?;
                }
                BlockData::LowRank(lr) => {
                    out.u64(LOW_RANK)?;
                    out.u64(lr.rank() as u64)?;
                    write_values(out, &lr.u)?;
                    write_values(out, &lr.v)?;
                }
                BlockData::Seen(_) | BlockData::Leaf(_) => unreachable!("written standalone"),
            }
        }
        Ok(())
    }

    /// Reads an operator [`CompressedOperator::write`] wrote, checking every block against its
    /// size.
    pub fn read<R: Read>(input: &mut BinaryReader<R>) -> Result<Self> {
        let dof = input.u64("the number of unknowns")? as usize;
        let per = input.u64("the nodes per element")? as usize;
        if !(per == 1 || per == 3) || !dof.is_multiple_of(per) || dof > u32::MAX as usize {
            return Err(input.error(format!("damaged: {dof} unknowns with {per} per element")));
        }
        let zero_rows = input.u64("the zero rows")? as usize;
        let mut stats = [0; OperatorStats::COUNTS];
        for v in &mut stats {
            *v = input.u64("statistics")?;
        }
        let mut pairs = [0; 7];
        for v in &mut pairs {
            *v = input.u64("pair classes")?;
        }
        let (mut stats, pairs) = (OperatorStats::from_counts(stats), PairStats::from_counts(pairs));
        let node_order = input.usizes("the node order", dof)?;
        let element_order = input.usizes("the element order", dof / per)?;
        if node_order.len() != dof || element_order.len() != dof / per {
            return Err(input.error("damaged: the orders do not cover the unknowns".into()));
        }
        let count = input.u64("the number of blocks")?;
        let mut blocks = Vec::new();
        for _ in 0..count {
            let mut range = |bound: usize| -> Result<std::ops::Range<usize>> {
                let (start, end) = (input.u64("a block")? as usize, input.u64("a block")? as usize);
                if start > end || end > bound {
                    return Err(input.error(format!("damaged: a block spans {start}..{end}")));
                }
                Ok(start..end)
            };
            let rows = range(dof)?;
            let cols = range(dof / per)?;
            let (m, c) = (rows.len(), cols.len() * per);
            let data = match input.u64("a block's kind")? {
                DENSE => BlockData::Dense(read_values(input, "a dense block")?),
                SPARSE => {
                    let starts = input.u32s("a sparse block")?;
                    let columns = input.u32s("a sparse block")?;
                    let values = read_values(input, "a sparse block")?;
                    match SparseRows::from_csr(&starts, &columns, values, m, c) {
                        Some(rows) => BlockData::Sparse(rows),
                        None => {
                            return Err(input.error(format!(
                                "damaged: a sparse block of {m} x {c} holds other entries"
                            )));
                        }
                    }
                }
                LOW_RANK => {
                    let k = input.u64("a rank")? as usize;
                    let u = read_values(input, "a low-rank block")?;
                    let v = read_values(input, "a low-rank block")?;
                    match Factors::new(c, k, u, v) {
                        Some(factors) => BlockData::LowRank(factors),
                        None => return Err(input.error(format!("damaged: a rank of {k}"))),
                    }
                }
                other => return Err(input.error(format!("damaged: block kind {other}"))),
            };
            if !fits(&data, m, c) {
                return Err(input.error(format!("damaged: a block of {m} x {c} holds other sizes")));
            }
            blocks.push(Block::new(rows, cols, data));
        }
        // The bytes of the blocks as read; the counts of entries and blocks stay the build's.
        let counted = block_stats(&blocks, per);
        stats.operator_bytes = counted.operator_bytes + super::stats::order_bytes(dof, per);
        stats.low_rank_bytes = counted.low_rank_bytes;
        Ok(Self {
            dof,
            per,
            node_order,
            element_order,
            blocks,
            stats,
            pairs,
            zero_rows,
            device: None,
            share: None,
            memory_estimate: None,
        })
    }
}

/// Whether block data matches an m × c block (so that its product stays inside it).
fn fits(data: &BlockData, m: usize, c: usize) -> bool {
    match data {
        BlockData::Dense(values) => values.len() == m * c,
        // Checked as it was read.
        BlockData::Sparse(_) => true,
        BlockData::LowRank(lr) => {
            lr.columns() == c && lr.u.len() == m * lr.rank() && lr.v.len() == c * lr.rank()
        }
        // Written standalone, never read.
        BlockData::Seen(_) | BlockData::Leaf(_) => false,
    }
}

/// Stored values with their precision first (the bits of a value: 64 or 32).
fn write_values<W: Write>(out: &mut BinaryWriter<W>, values: &Values) -> Result<()> {
    match values {
        Values::F64(v) => {
            out.u64(64)?;
            out.f64s(v)
        }
        Values::F32(v) => {
            out.u64(32)?;
            out.f32s(v)
        }
    }
}

/// Values [`write_values`] wrote.
fn read_values<R: Read>(input: &mut BinaryReader<R>, what: &str) -> Result<Values> {
    match input.u64(what)? {
        64 => Ok(Values::F64(input.f64s(what)?.into())),
        32 => Ok(Values::F32(input.f32s(what)?.into())),
        bits => Err(input.error(format!("damaged: {what} of {bits}-bit values"))),
    }
}

#[cfg(test)]
mod tests {
    use super::Checksum;

    #[test]
    fn the_checksum_does_not_depend_on_how_the_stream_is_cut() {
        let bytes: Vec<u8> = (0..1000u32).map(|i| (i * 7 + i / 13) as u8).collect();
        let whole = {
            let mut c = Checksum::new();
            c.update(&bytes);
            c.value()
        };
        for cuts in [[1, 2, 3], [7, 8, 9], [31, 33, 500], [0, 64, 999]] {
            let mut c = Checksum::new();
            let mut from = 0;
            for to in cuts.into_iter().chain([bytes.len()]) {
                c.update(&bytes[from..to]);
                from = to;
            }
            assert_eq!(c.value(), whole, "{cuts:?}");
        }
        let mut changed = bytes.clone();
        changed[500] ^= 1;
        let mut c = Checksum::new();
        c.update(&changed);
        assert_ne!(c.value(), whole);
    }
}
