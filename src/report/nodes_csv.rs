//! The nodal values of a solution as CSV: one row per collocation node.

use std::path::Path;

use crate::error::Result;
use crate::solution::SolutionField;

/// Writes `node, element, face, x, y, z, rho, E, u` for every node to `path` (positions in the
/// user's coordinates).
pub fn write_node_csv(field: &SolutionField, path: &Path) -> Result<()> {
    let mut out = csv::Writer::from_path(path).map_err(csv_error)?;
    out.write_record(["node", "element", "face", "x", "y", "z", "rho", "E", "u"])
        .map_err(csv_error)?;
    for (i, node) in field.disc.nodes.iter().enumerate() {
        // In the user's coordinates.
        let p = node.position + field.scene.origin;
        out.write_record([
            i.to_string(),
            node.element.to_string(),
            field.scene.faces[node.face].name.clone(),
            format!("{:e}", p.x),
            format!("{:e}", p.y),
            format!("{:e}", p.z),
            format!("{:e}", node.rho),
            format!("{:e}", field.emission[i]),
            format!("{:e}", field.u[i]),
        ])
        .map_err(csv_error)?;
    }
    out.flush()?;
    Ok(())
}

fn csv_error(e: csv::Error) -> crate::error::Error {
    std::io::Error::other(format!("CSV: {e}")).into()
}
