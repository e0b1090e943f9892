//! Dense arrays as NumPy .npy files: the matrix K (or F), and vectors such as the sky view
//! factors.

use crate::error::Result;

/// Writes K as a NumPy .npy file (float64, C order, dof × dof).
pub fn write_npy(path: &str, n: usize, values: &[f64]) -> Result<()> {
    let n = n as u64;
    write_shaped(path, &[n, n], values)
}

/// Writes a vector as a NumPy .npy file (float64, one dimension).
pub fn write_npy_vector(path: &str, values: &[f64]) -> Result<()> {
    write_shaped(path, &[values.len() as u64], values)
}

fn write_shaped(path: &str, shape: &[u64], values: &[f64]) -> Result<()> {
    use npyz::WriterBuilder;
    let file = std::io::BufWriter::new(std::fs::File::create(path)?);
    let mut writer =
        npyz::WriteOptions::<f64>::new().default_dtype().shape(shape).writer(file).begin_nd()?;
    writer.extend(values.iter().copied())?;
    writer.finish()?;
    Ok(())
}
