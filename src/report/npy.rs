//! The dense matrix K as a NumPy .npy file.

use crate::error::Result;

/// Writes K as a NumPy .npy file (float64, C order, dof × dof).
pub fn write_npy(path: &str, n: usize, values: &[f64]) -> Result<()> {
    use npyz::WriterBuilder;
    let file = std::io::BufWriter::new(std::fs::File::create(path)?);
    let n = n as u64;
    let mut writer =
        npyz::WriteOptions::<f64>::new().default_dtype().shape(&[n, n]).writer(file).begin_nd()?;
    writer.extend(values.iter().copied())?;
    writer.finish()?;
    Ok(())
}
