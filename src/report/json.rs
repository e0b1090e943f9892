//! JSON for programs: a result written to a file or to standard output.

use std::io::Write;
use std::path::Path;

use serde::Serialize;

use crate::error::Result;

/// Writes `value` as pretty JSON to `target` (`-` for standard output).
pub fn write_json<T: Serialize>(value: &T, target: &str) -> Result<()> {
    let text =
        serde_json::to_string_pretty(value).map_err(|e| std::io::Error::other(e.to_string()))?;
    if target == "-" {
        let mut out = std::io::stdout().lock();
        writeln!(out, "{text}")?;
    } else {
        std::fs::write(Path::new(target), text + "\n")?;
    }
    Ok(())
}
