//! A day of sun positions from a CSV file, one [`Moment`] a row:
//!
//! ```text
//! time,zenith,azimuth,direct_normal,diffuse_horizontal
//! 08:00,71.2,102.5,420,85
//! 12:00,28.4,181.0,860,110
//! ```
//!
//! `time` is a label (any text without a comma); the angles are in degrees (zenith from the
//! zenith, azimuth clockwise from north), the irradiances in W/m² (or any unit, the results are
//! in the same). The columns may come in any order; lines starting with `#` are comments.

use std::path::Path;

use serde::Serialize;

use super::sources::{Sources, Sun};
use crate::error::{Error, Result};

/// The columns a sun-positions file must have.
pub const COLUMNS: [&str; 5] = ["time", "zenith", "azimuth", "direct_normal", "diffuse_horizontal"];

/// One moment of a day: its label and the sources then.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Moment {
    /// The time, as the file labels it.
    pub time: String,
    /// The sun and the sky then.
    pub sources: Sources,
}

/// The moments of the CSV file at `path` ([module docs](self)), the scene's +x at compass
/// direction `x_azimuth`; refused with the file's name and the line where a column is missing,
/// a value is not a number or out of range, or no row is given.
pub fn read_moments(path: &Path, x_azimuth: f64) -> Result<Vec<Moment>> {
    let name = path.display().to_string();
    let bad = |reason: String| Error::DataFile { path: name.clone(), reason };
    let mut reader = csv::ReaderBuilder::new()
        .trim(csv::Trim::All)
        .comment(Some(b'#'))
        .from_path(path)
        .map_err(|e| bad(e.to_string()))?;
    let headers = reader.headers().map_err(|e| bad(e.to_string()))?.clone();
    let mut at = [0; COLUMNS.len()];
    for (slot, column) in at.iter_mut().zip(COLUMNS) {
        *slot = headers.iter().position(|h| h == column).ok_or_else(|| {
            bad(format!("no column '{column}' in the header (expected {})", COLUMNS.join(",")))
        })?;
    }
    let mut moments = Vec::new();
    for (k, record) in reader.records().enumerate() {
        let record = record.map_err(|e| bad(e.to_string()))?;
        let line = record.position().map_or(k + 2, |p| p.line() as usize);
        let number = |c: usize| -> Result<f64> {
            let field = &record[at[c]];
            field
                .parse()
                .map_err(|_| bad(format!("line {line}: {} '{field}' is not a number", COLUMNS[c])))
        };
        let sources = Sun::new(number(1)?, number(2)?, x_azimuth, number(3)?)
            .and_then(|sun| Sources::new(sun, number(4)?))
            .map_err(|e| bad(format!("line {line}: {e}")))?;
        moments.push(Moment { time: record[at[0]].to_string(), sources });
    }
    if moments.is_empty() {
        return Err(bad("no sun positions: give one row per time".into()));
    }
    Ok(moments)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `text` written to a file of its own (tests run in parallel).
    fn written(tag: &str, text: &str) -> std::path::PathBuf {
        let path = std::env::temp_dir()
            .join(format!("radiosity-sun-positions-{}-{tag}.csv", std::process::id()));
        std::fs::write(&path, text).unwrap();
        path
    }

    #[test]
    fn rows_become_moments_whatever_the_columns_order() {
        let path = written(
            "order",
            "# a clear day\nazimuth,time,zenith,diffuse_horizontal,direct_normal\n\
             102.5, 08:00, 71.2, 85, 420\n181,12:00,28.4,110,860\n",
        );
        let moments = read_moments(&path, 90.0).unwrap();
        assert_eq!(moments.len(), 2);
        assert_eq!(moments[0].time, "08:00");
        let s = moments[1].sources;
        assert_eq!((s.sun.zenith, s.sun.azimuth, s.sun.direct_normal), (28.4, 181.0, 860.0));
        assert_eq!((s.sun.x_azimuth, s.diffuse_horizontal), (90.0, 110.0));
    }

    #[test]
    fn bad_files_name_the_line_and_the_value() {
        for (tag, text, named) in [
            (
                "header",
                "time,zenith,azimuth,direct_normal\n1,2,3,4\n",
                "no column 'diffuse_horizontal'",
            ),
            (
                "number",
                "time,zenith,azimuth,direct_normal,diffuse_horizontal\nnoon,x,3,4,5\n",
                "line 2: zenith 'x'",
            ),
            (
                "range",
                "time,zenith,azimuth,direct_normal,diffuse_horizontal\na,1,2,3,4\nb,1,2,-3,4\n",
                "line 3: ",
            ),
            ("empty", "time,zenith,azimuth,direct_normal,diffuse_horizontal\n", "no sun positions"),
            ("short", "time,zenith,azimuth,direct_normal,diffuse_horizontal\na,1,2\n", "record"),
        ] {
            let e = read_moments(&written(tag, text), 90.0).unwrap_err().to_string();
            assert!(e.contains(named) && e.contains("radiosity-sun-positions"), "{tag}: {e}");
        }
        let e = read_moments(Path::new("/nonexistent/day.csv"), 90.0).unwrap_err().to_string();
        assert!(e.contains("/nonexistent/day.csv"), "{e}");
    }
}
