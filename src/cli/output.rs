//! Printing a result: JSON, a table, or both.

use serde::Serialize;

use radiosity::error::Result;
use radiosity::report;

/// A study's result: JSON to `json` when given, and the table unless the JSON goes to stdout.
pub(crate) fn emit<T: Serialize>(
    result: &T,
    json: Option<&str>,
    table: impl FnOnce() -> String,
) -> Result<()> {
    if let Some(target) = json {
        report::write_json(result, target)?;
    }
    if json != Some("-") {
        print!("{}", table());
    }
    Ok(())
}

/// What the loader repaired in the scene file, one line each on standard error.
pub(crate) fn print_notes(scene: &radiosity::scene::Scene) {
    for note in &scene.notes {
        eprintln!("note: {note}");
    }
}
