//! Emission cases: many right-hand sides E for one operator (a day of sun positions, a transient
//! of changing emission), given per face or per node, one column per case.

use std::path::Path;

use crate::discretization::Discretization;
use crate::error::{Error, Result};
use crate::scene::Scene;

/// Emission cases: `values[c]` is case c's E per face (in the scene's face order) or per node.
#[derive(Clone, Debug, PartialEq)]
pub struct EmissionCases {
    /// Case names: the CSV header, or `1`, `2`, ... without one.
    pub names: Vec<String>,
    /// Each case's values, one per row of the file.
    pub values: Vec<Vec<f64>>,
}

impl EmissionCases {
    /// Cases from columns of values (one per face or per node), named `1`, `2`, ...; every value
    /// must be finite and non-negative.
    pub fn from_columns(values: Vec<Vec<f64>>) -> Result<Self> {
        Self::named(numbered(values.len()), values, "emission cases")
    }

    /// Checks the cases: at least one, all of one length, values finite and non-negative.
    fn named(names: Vec<String>, values: Vec<Vec<f64>>, path: &str) -> Result<Self> {
        let bad = |reason: String| Error::DataFile { path: path.into(), reason };
        let rows = values.first().map_or(0, Vec::len);
        if values.is_empty() || rows == 0 {
            return Err(bad("no emission values: give one column per case, one row per face \
                            or per node"
                .into()));
        }
        for (name, column) in names.iter().zip(&values) {
            if column.len() != rows {
                return Err(bad(format!(
                    "case '{name}' has {} values where the first has {rows}",
                    column.len()
                )));
            }
            if let Some((row, v)) =
                column.iter().enumerate().find(|(_, v)| !(v.is_finite() && **v >= 0.0))
            {
                return Err(bad(format!(
                    "case '{name}', row {}: emissivity {v} must be finite and non-negative",
                    row + 1
                )));
            }
        }
        Ok(Self { names, values })
    }

    /// Reads a CSV file: one column per case, one row per face or per node, an optional header
    /// of case names (a first row that is not all numbers).
    pub fn read_csv(path: &Path) -> Result<Self> {
        let name = path.display().to_string();
        let bad = |reason: String| Error::DataFile { path: name.clone(), reason };
        let mut reader = csv::ReaderBuilder::new()
            .has_headers(false)
            .trim(csv::Trim::All)
            .comment(Some(b'#'))
            .from_path(path)
            .map_err(|e| bad(e.to_string()))?;
        let mut names: Option<Vec<String>> = None;
        let mut columns: Vec<Vec<f64>> = Vec::new();
        for (k, record) in reader.records().enumerate() {
            let record = record.map_err(|e| bad(e.to_string()))?;
            let line = record.position().map_or(k + 1, |p| p.line() as usize);
            let numbers: Option<Vec<f64>> = record.iter().map(|f| f.parse().ok()).collect();
            match numbers {
                None if k == 0 => names = Some(record.iter().map(str::to_owned).collect()),
                None => {
                    let field = record.iter().find(|f| f.parse::<f64>().is_err()).unwrap_or("");
                    return Err(bad(format!("line {line}: '{field}' is not a number")));
                }
                Some(row) => {
                    if columns.is_empty() {
                        columns = vec![Vec::new(); row.len()];
                    }
                    for (column, v) in columns.iter_mut().zip(row) {
                        column.push(v);
                    }
                }
            }
        }
        // The reader refuses rows of unequal length, so a header names every column.
        let names = names.unwrap_or_else(|| numbered(columns.len()));
        Self::named(names, columns, &name)
    }

    /// Each case's E at the nodes of `disc`: a face's value at each of its nodes when there is
    /// one row per face, else one row per node.
    pub fn at_nodes(&self, scene: &Scene, disc: &Discretization) -> Result<Vec<Vec<f64>>> {
        let rows = self.values[0].len();
        if rows == scene.faces.len() {
            Ok(self
                .values
                .iter()
                .map(|column| disc.nodes().map(|n| column[n.face()]).collect())
                .collect())
        } else if rows == disc.dof() {
            Ok(self.values.clone())
        } else {
            Err(Error::InvalidParameter {
                name: "emission-file",
                value: format!("{rows} rows"),
                reason: format!(
                    "give one row per face ({} faces in '{}') or one per node ({} nodes)",
                    scene.faces.len(),
                    scene.name,
                    disc.dof()
                ),
            })
        }
    }
}

/// The names of `count` cases without a header: `1`, `2`, ...
fn numbered(count: usize) -> Vec<String> {
    (1..=count).map(|c| c.to_string()).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `text` written to a file of its own (tests run in parallel).
    fn written(text: &str) -> std::path::PathBuf {
        use std::sync::atomic::{AtomicUsize, Ordering};
        static NEXT: AtomicUsize = AtomicUsize::new(0);
        let k = NEXT.fetch_add(1, Ordering::Relaxed);
        let path =
            std::env::temp_dir().join(format!("radiosity-cases-{}-{k}.csv", std::process::id()));
        std::fs::write(&path, text).unwrap();
        path
    }

    #[test]
    fn columns_are_cases_and_a_header_names_them() {
        let path = written("noon, dusk\n1, 0\n0.5, 2\n");
        let cases = EmissionCases::read_csv(&path).unwrap();
        assert_eq!(cases.names, ["noon", "dusk"]);
        assert_eq!(cases.values, [vec![1.0, 0.5], vec![0.0, 2.0]]);
        let path = written("# per face\n1\n2\n");
        let cases = EmissionCases::read_csv(&path).unwrap();
        assert_eq!((cases.names, cases.values), (vec!["1".to_string()], vec![vec![1.0, 2.0]]));
    }

    #[test]
    fn bad_files_are_refused_naming_the_culprit() {
        for (text, says) in [
            ("1,2\n3\n", "found record with 1 field"),
            ("a,b\n1,x\n", "'x' is not a number"),
            ("a,b,c\n1,2\n", "found record with 2 fields, but the previous record has 3"),
            ("1\n-1\n", "row 2: emissivity -1"),
            ("1\nNaN\n", "emissivity NaN"),
            ("a\n", "no emission values"),
            ("", "no emission values"),
        ] {
            let path = written(text);
            let e = EmissionCases::read_csv(&path).unwrap_err().to_string();
            assert!(e.contains(says), "{text:?}: {e}");
        }
        let missing = EmissionCases::read_csv(Path::new("/nonexistent/e.csv")).unwrap_err();
        assert!(missing.to_string().contains("/nonexistent/e.csv"));
    }
}
