//! Sparse matrices as files, only their non-zero entries: SciPy's CSR `.npz` (what
//! `scipy.sparse.save_npz` writes and `scipy.sparse.load_npz` reads) and Matrix Market `.mtx`
//! (coordinate, real, general; `scipy.io.mmread`, MATLAB, Julia).

use std::io::Write;

use crate::error::Result;
use crate::viewfactors::ViewFactors;

/// A sparse matrix by rows, borrowed from where it is kept (the view factors' own arrays):
/// the files below are written from it without a copy of its entries.
#[derive(Clone, Copy, Debug)]
pub struct CsrRows<'a> {
    /// Rows.
    pub rows: usize,
    /// Columns.
    pub cols: usize,
    /// Where each row starts in `indices` and `data`, and where the last ends (rows + 1 values).
    pub indptr: &'a [usize],
    /// Column of each stored entry, increasing within a row.
    pub indices: &'a [u32],
    /// Value of each stored entry.
    pub data: &'a [f64],
}

impl<'a> CsrRows<'a> {
    /// The non-zero view factors F_ij, as they are stored.
    pub fn of_view_factors(f: &'a ViewFactors) -> Self {
        Self {
            rows: f.len(),
            cols: f.len(),
            indptr: &f.row_starts,
            indices: &f.columns,
            data: &f.values,
        }
    }
}

/// The header of a NumPy `.npy` file (format 1.0): `descr` the dtype, `shape` the dimensions
/// (none: a scalar); the data, little-endian, follows it.
fn npy_header(descr: &str, shape: &[usize]) -> Vec<u8> {
    let dims = match shape {
        [] => "()".to_string(),
        [n] => format!("({n},)"),
        _ => format!("({})", shape.iter().map(usize::to_string).collect::<Vec<_>>().join(", ")),
    };
    let mut header = format!("{{'descr': '{descr}', 'fortran_order': False, 'shape': {dims}, }}");
    // Magic (6), version (2) and length (2), then the header padded so that the data starts on
    // a multiple of 64 bytes, ending in a newline.
    let unpadded = 10 + header.len() + 1;
    header.push_str(&" ".repeat(unpadded.next_multiple_of(64) - unpadded));
    header.push('\n');
    let mut out = b"\x93NUMPY\x01\x00".to_vec();
    out.extend_from_slice(&(header.len() as u16).to_le_bytes());
    out.extend_from_slice(header.as_bytes());
    out
}

/// Writes `values` little-endian, a block at a time (a large matrix's arrays are not copied
/// whole into bytes).
fn write_le<T: Copy, const N: usize>(
    out: &mut impl Write,
    values: &[T],
    to_le: impl Fn(T) -> [u8; N],
) -> std::io::Result<()> {
    let mut bytes = Vec::with_capacity(N * WRITE_BLOCK);
    for block in values.chunks(WRITE_BLOCK) {
        bytes.clear();
        bytes.extend(block.iter().flat_map(|&v| to_le(v)));
        out.write_all(&bytes)?;
    }
    Ok(())
}

/// Entries converted to bytes at a time by [`write_le`].
const WRITE_BLOCK: usize = 1 << 16;

/// Writes `m` as SciPy's sparse `.npz` (an uncompressed zip of `data`, `indices`, `indptr`,
/// `format` and `shape`), and the named f64 arrays `beside` it (which `scipy.sparse.load_npz`
/// leaves alone; `numpy.load` reads them), streamed: memory beyond the matrix's stays a few
/// blocks.
pub fn write_npz(path: &str, m: CsrRows<'_>, beside: &[(&str, &[f64])]) -> Result<()> {
    let as_i64 = |k: usize| i64::try_from(k).expect("an index fits in i64");
    let file = std::io::BufWriter::new(std::fs::File::create(path)?);
    let mut zip = zip::ZipWriter::new(file);
    let options = zip::write::SimpleFileOptions::default()
        .compression_method(zip::CompressionMethod::Stored)
        .large_file(8 * m.data.len() > u32::MAX as usize / 2);
    let start = |zip: &mut zip::ZipWriter<_>, name: &str, descr: &str, shape: &[usize]| {
        zip.start_file(name, options).map_err(std::io::Error::from)?;
        zip.write_all(&npy_header(descr, shape))
    };
    start(&mut zip, "data.npy", "<f8", &[m.data.len()])?;
    write_le(&mut zip, m.data, f64::to_le_bytes)?;
    start(&mut zip, "indices.npy", "<i8", &[m.indices.len()])?;
    write_le(&mut zip, m.indices, |j| i64::from(j).to_le_bytes())?;
    start(&mut zip, "indptr.npy", "<i8", &[m.indptr.len()])?;
    write_le(&mut zip, m.indptr, |k| as_i64(k).to_le_bytes())?;
    start(&mut zip, "format.npy", "|S3", &[])?;
    zip.write_all(b"csr")?;
    start(&mut zip, "shape.npy", "<i8", &[2])?;
    write_le(&mut zip, &[m.rows, m.cols], |k| as_i64(k).to_le_bytes())?;
    for (name, values) in beside {
        start(&mut zip, &format!("{name}.npy"), "<f8", &[values.len()])?;
        write_le(&mut zip, values, f64::to_le_bytes)?;
    }
    zip.finish().map_err(std::io::Error::from)?;
    Ok(())
}

/// Writes `m` as a Matrix Market coordinate file (1-based indices, values that read back to
/// the same f64).
pub fn write_mtx(path: &str, m: CsrRows<'_>, comment: &str) -> Result<()> {
    let mut out = std::io::BufWriter::new(std::fs::File::create(path)?);
    writeln!(out, "%%MatrixMarket matrix coordinate real general")?;
    for line in comment.lines() {
        writeln!(out, "% {line}")?;
    }
    writeln!(out, "{} {} {}", m.rows, m.cols, m.data.len())?;
    for i in 0..m.rows {
        for k in m.indptr[i]..m.indptr[i + 1] {
            writeln!(out, "{} {} {:e}", i + 1, m.indices[k] + 1, m.data[k])?;
        }
    }
    out.flush()?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// 3 x 4 with an empty row, a negative entry, and a value that needs all 17 digits, stored
    /// as the view factors store theirs. (The `.npz` is read back, through the binary, in
    /// `tests/suite/scenes.rs`.)
    fn example() -> (Vec<usize>, Vec<u32>, Vec<f64>) {
        let dense = [0.0, 1.5, 0.0, -2.0, 0.0, 0.0, 0.0, 0.0, 0.1 + 0.2, 0.0, 0.0, 7e-300];
        let (mut indptr, mut indices, mut data) = (vec![0], Vec::new(), Vec::new());
        for row in dense.chunks(4) {
            for (j, &v) in row.iter().enumerate().filter(|(_, v)| **v != 0.0) {
                indices.push(j as u32);
                data.push(v);
            }
            indptr.push(data.len());
        }
        (indptr, indices, data)
    }

    #[test]
    fn npy_headers_end_on_64_bytes() {
        for shape in [&[][..], &[7], &[123_456_789]] {
            let bytes = npy_header("<f8", shape);
            assert_eq!(bytes.len() % 64, 0, "{shape:?}");
            assert_eq!(bytes.last(), Some(&b'\n'));
        }
    }

    #[test]
    fn blocks_written_little_endian_are_the_values_in_order() {
        let values: Vec<u32> = (0..3 * WRITE_BLOCK as u32 / 2).collect();
        let mut out = Vec::new();
        write_le(&mut out, &values, |v| i64::from(v).to_le_bytes()).unwrap();
        let back: Vec<u32> =
            out.chunks(8).map(|b| i64::from_le_bytes(b.try_into().unwrap()) as u32).collect();
        assert_eq!(back, values);
    }

    #[test]
    fn matrix_market_lists_each_entry_once_one_based_and_exact() {
        let (indptr, indices, data) = example();
        let m = CsrRows { rows: 3, cols: 4, indptr: &indptr, indices: &indices, data: &data };
        let path =
            std::env::temp_dir().join(format!("radiosity-sparse-{}.mtx", std::process::id()));
        let path = path.to_str().unwrap();
        write_mtx(path, m, "view factors").unwrap();
        let text = std::fs::read_to_string(path).unwrap();
        let lines: Vec<&str> = text.lines().collect();
        assert_eq!(lines[0], "%%MatrixMarket matrix coordinate real general");
        assert_eq!(lines[1], "% view factors");
        assert_eq!(lines[2], "3 4 4");
        let entries: Vec<(usize, usize, f64)> = lines[3..]
            .iter()
            .map(|l| {
                let f: Vec<&str> = l.split(' ').collect();
                (f[0].parse().unwrap(), f[1].parse().unwrap(), f[2].parse().unwrap())
            })
            .collect();
        assert_eq!(entries, vec![(1, 2, 1.5), (1, 4, -2.0), (3, 1, 0.1 + 0.2), (3, 4, 7e-300)]);
        std::fs::remove_file(path).unwrap();
    }
}
