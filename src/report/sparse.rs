//! Sparse matrices as files, only their non-zero entries: SciPy's CSR `.npz` (what
//! `scipy.sparse.save_npz` writes and `scipy.sparse.load_npz` reads) and Matrix Market `.mtx`
//! (coordinate, real, general; `scipy.io.mmread`, MATLAB, Julia).

use std::io::Write;

use crate::error::Result;
use crate::viewfactors::ViewFactors;

/// A matrix in compressed sparse rows: row i's entries are `data[indptr[i]..indptr[i + 1]]`, in
/// the columns `indices[...]`, increasing.
#[derive(Clone, Debug, PartialEq)]
pub struct Csr {
    /// Rows.
    pub rows: usize,
    /// Columns.
    pub cols: usize,
    /// Where each row starts in `indices` and `data`, and where the last ends (rows + 1 values).
    pub indptr: Vec<i64>,
    /// Column of each stored entry.
    pub indices: Vec<i64>,
    /// Value of each stored entry.
    pub data: Vec<f64>,
}

impl Csr {
    /// The non-zero entries of the row-major `rows` × `cols` matrix `values`.
    #[cfg(test)]
    fn from_dense(rows: usize, cols: usize, values: &[f64]) -> Self {
        assert_eq!(values.len(), rows * cols, "a {rows} x {cols} matrix");
        let mut csr = Self { rows, cols, indptr: vec![0], indices: Vec::new(), data: Vec::new() };
        for row in values.chunks(cols.max(1)).take(rows) {
            for (j, &v) in row.iter().enumerate().filter(|(_, v)| **v != 0.0) {
                csr.indices.push(j as i64);
                csr.data.push(v);
            }
            csr.indptr.push(csr.data.len() as i64);
        }
        csr
    }

    /// The non-zero view factors F_ij, as they are stored.
    pub fn from_view_factors(f: &ViewFactors) -> Self {
        let to_i64 = |k: usize| i64::try_from(k).expect("an index fits in i64");
        Self {
            rows: f.len(),
            cols: f.len(),
            indptr: f.row_starts.iter().map(|&k| to_i64(k)).collect(),
            indices: f.columns.iter().map(|&j| i64::from(j)).collect(),
            data: f.values.clone(),
        }
    }

    /// Stored (non-zero) entries.
    pub fn nonzeros(&self) -> usize {
        self.data.len()
    }
}

/// One NumPy `.npy` file (format 1.0): `descr` the dtype, `shape` the dimensions (none: a
/// scalar), `data` the little-endian bytes.
fn npy(descr: &str, shape: &[usize], data: &[u8]) -> Vec<u8> {
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
    out.extend_from_slice(data);
    out
}

fn le_bytes<T: Copy, const N: usize>(values: &[T], to_le: impl Fn(T) -> [u8; N]) -> Vec<u8> {
    values.iter().flat_map(|&v| to_le(v)).collect()
}

/// Writes `csr` as SciPy's sparse `.npz` (an uncompressed zip of `data`, `indices`, `indptr`,
/// `format` and `shape`).
pub fn write_npz(path: &str, csr: &Csr) -> Result<()> {
    let shape = [csr.rows as i64, csr.cols as i64];
    let arrays = [
        ("data.npy", npy("<f8", &[csr.data.len()], &le_bytes(&csr.data, f64::to_le_bytes))),
        (
            "indices.npy",
            npy("<i8", &[csr.indices.len()], &le_bytes(&csr.indices, i64::to_le_bytes)),
        ),
        ("indptr.npy", npy("<i8", &[csr.indptr.len()], &le_bytes(&csr.indptr, i64::to_le_bytes))),
        ("format.npy", npy("|S3", &[], b"csr")),
        ("shape.npy", npy("<i8", &[2], &le_bytes(&shape, i64::to_le_bytes))),
    ];
    let file = std::io::BufWriter::new(std::fs::File::create(path)?);
    let mut zip = zip::ZipWriter::new(file);
    let options = zip::write::SimpleFileOptions::default()
        .compression_method(zip::CompressionMethod::Stored)
        .large_file(arrays[0].1.len() > u32::MAX as usize / 2);
    for (name, bytes) in arrays {
        zip.start_file(name, options).map_err(std::io::Error::from)?;
        zip.write_all(&bytes)?;
    }
    zip.finish().map_err(std::io::Error::from)?;
    Ok(())
}

/// Writes `csr` as a Matrix Market coordinate file (1-based indices, values that read back to
/// the same f64).
pub fn write_mtx(path: &str, csr: &Csr, comment: &str) -> Result<()> {
    let mut out = std::io::BufWriter::new(std::fs::File::create(path)?);
    writeln!(out, "%%MatrixMarket matrix coordinate real general")?;
    for line in comment.lines() {
        writeln!(out, "% {line}")?;
    }
    writeln!(out, "{} {} {}", csr.rows, csr.cols, csr.nonzeros())?;
    for i in 0..csr.rows {
        let (start, end) = (csr.indptr[i] as usize, csr.indptr[i + 1] as usize);
        for k in start..end {
            writeln!(out, "{} {} {:e}", i + 1, csr.indices[k] + 1, csr.data[k])?;
        }
    }
    out.flush()?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// 3 x 4 with an empty row, a negative entry, and a value that needs all 17 digits. (The
    /// `.npz` is read back, through the binary, in `tests/scenes.rs`.)
    fn example() -> Csr {
        let dense = [0.0, 1.5, 0.0, -2.0, 0.0, 0.0, 0.0, 0.0, 0.1 + 0.2, 0.0, 0.0, 7e-300];
        Csr::from_dense(3, 4, &dense)
    }

    #[test]
    fn csr_holds_the_non_zero_entries_row_by_row() {
        let csr = example();
        assert_eq!(csr.indptr, vec![0, 2, 2, 4]);
        assert_eq!(csr.indices, vec![1, 3, 0, 3]);
        assert_eq!(csr.data, vec![1.5, -2.0, 0.1 + 0.2, 7e-300]);
        assert_eq!(csr.nonzeros(), 4);
    }

    #[test]
    fn npy_headers_end_on_64_bytes() {
        for shape in [&[][..], &[7], &[123_456_789]] {
            let bytes = npy("<f8", shape, &[]);
            assert_eq!(bytes.len() % 64, 0, "{shape:?}");
            assert_eq!(bytes.last(), Some(&b'\n'));
        }
    }

    #[test]
    fn matrix_market_lists_each_entry_once_one_based_and_exact() {
        let csr = example();
        let path =
            std::env::temp_dir().join(format!("radiosity-sparse-{}.mtx", std::process::id()));
        let path = path.to_str().unwrap();
        write_mtx(path, &csr, "view factors").unwrap();
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
