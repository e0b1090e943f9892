//! The nodal values of a solution as CSV: one row per collocation node.

use std::path::Path;

use crate::error::Result;
use crate::scene::CHANNELS;
use crate::solution::SolutionField;

/// Writes `node, element, face, x, y, z, rho, E, u` for every node to `path` (positions in the
/// user's coordinates), and `rho_B, E_B, u_B` per colour band B when bands were solved (`u` is
/// then their mean), or `E_C, u_C` per emission case C when cases were solved (`u` is then
/// their mean).
pub fn write_node_csv(field: &SolutionField, path: &Path) -> Result<()> {
    let mut out = csv::Writer::from_path(path).map_err(csv_error)?;
    let mut header: Vec<String> =
        ["node", "element", "face", "x", "y", "z", "rho", "E", "u"].map(String::from).to_vec();
    for band in field.bands {
        let name = CHANNELS[band.channel];
        header.extend([format!("rho_{name}"), format!("E_{name}"), format!("u_{name}")]);
    }
    for case in field.cases {
        header.extend([format!("E_{}", case.name), format!("u_{}", case.name)]);
    }
    out.write_record(&header).map_err(csv_error)?;
    for (i, node) in field.disc.nodes().enumerate() {
        // In the user's coordinates.
        let p = node.position + field.scene.origin;
        let face = &field.scene.faces[node.face()];
        let bands = field.bands.iter().flat_map(|b| {
            [face.channel(b.channel).0, b.emission[i], b.u[i]].map(|v| format!("{v:e}"))
        });
        let cases =
            field.cases.iter().flat_map(|c| [c.emission[i], c.u[i]].map(|v| format!("{v:e}")));
        out.write_record(
            [
                i.to_string(),
                node.element().to_string(),
                field.scene.faces[node.face()].name.clone(),
                format!("{:e}", p.x),
                format!("{:e}", p.y),
                format!("{:e}", p.z),
                format!("{:e}", node.rho),
                format!("{:e}", field.emission[i]),
                format!("{:e}", field.u[i]),
            ]
            .into_iter()
            .chain(bands)
            .chain(cases),
        )
        .map_err(csv_error)?;
    }
    out.flush()?;
    Ok(())
}

fn csv_error(e: csv::Error) -> crate::error::Error {
    std::io::Error::other(format!("CSV: {e}")).into()
}
