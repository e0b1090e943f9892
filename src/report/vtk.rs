//! The solution as a VTK XML unstructured grid (`.vtu`) for ParaView: one triangle per element
//! (three points of its own, since collocation meshes need not conform), u_n at the points, and
//! u_n, E, rho and the face index per cell; per colour band B, `u_B` at the points and `u_B`,
//! `E_B`, `rho_B` per cell.

use std::fmt::Write as _;
use std::path::Path;

use crate::error::Result;
use crate::mesh::Mesh;
use crate::scene::{CHANNELS, Scene};
use crate::solution::SolutionField;

/// Writes to `path` the VTU document of `mesh`'s elements, one triangle each with three points
/// of its own (in the user's coordinates), with `data`: the `PointData` and `CellData` sections.
fn write_grid(scene: &Scene, mesh: &Mesh, data: &str, path: &Path) -> Result<()> {
    let n = mesh.len();
    let mut points = String::new();
    for e in mesh.elements() {
        for v in e.vertices {
            let v = v + scene.origin;
            let _ = writeln!(points, "{:e} {:e} {:e}", v.x, v.y, v.z);
        }
    }
    let connectivity: String = (0..3 * n).map(|k| format!("{k} ")).collect();
    let offsets: String = (1..=n).map(|k| format!("{} ", 3 * k)).collect();
    let types = "5 ".repeat(n);
    let text = format!(
        r#"<?xml version="1.0"?>
<VTKFile type="UnstructuredGrid" version="1.0" byte_order="LittleEndian">
  <UnstructuredGrid>
    <Piece NumberOfPoints="{points_count}" NumberOfCells="{n}">
      <Points>
        <DataArray type="Float64" NumberOfComponents="3" format="ascii">
{points}        </DataArray>
      </Points>
      <Cells>
        <DataArray type="Int64" Name="connectivity" format="ascii">{connectivity}</DataArray>
        <DataArray type="Int64" Name="offsets" format="ascii">{offsets}</DataArray>
        <DataArray type="UInt8" Name="types" format="ascii">{types}</DataArray>
      </Cells>
{data}    </Piece>
  </UnstructuredGrid>
</VTKFile>
"#,
        points_count = 3 * n,
    );
    std::fs::write(path, text)?;
    Ok(())
}

/// Writes the elements of `mesh` to `path` as ASCII VTU with a value per element of each of
/// `fields` (name, values in the mesh's order) and each element's face.
pub fn write_cell_vtu(
    scene: &Scene,
    mesh: &Mesh,
    fields: &[(&str, Vec<f64>)],
    path: &Path,
) -> Result<()> {
    let face: String = mesh.elements().iter().map(|e| format!("{} ", e.face)).collect();
    let mut cell_data = String::new();
    for (name, values) in fields {
        let values: String = values.iter().map(|v| format!("{v:e} ")).collect();
        let _ = writeln!(
            cell_data,
            r#"        <DataArray type="Float64" Name="{}" format="ascii">{values}</DataArray>"#,
            xml_escaped(name)
        );
    }
    let data = format!(
        r#"      <CellData>
{cell_data}        <DataArray type="Int64" Name="face" format="ascii">{face}</DataArray>
      </CellData>
"#
    );
    write_grid(scene, mesh, &data, path)
}

/// Writes `field` to `path` as ASCII VTU.
pub fn write_vtu(field: &SolutionField, path: &Path) -> Result<()> {
    let elements = field.mesh.elements();
    let n = elements.len();
    let mut point_u = String::new();
    for j in 0..n {
        for u in field.vertex_values(j) {
            let _ = writeln!(point_u, "{u:e}");
        }
    }
    let cells = |f: &dyn Fn(usize) -> String| -> String { (0..n).map(|j| f(j) + " ").collect() };
    let cell_u = cells(&|j| format!("{:e}", field.element_value(j)));
    let cell_e = cells(&|j| format!("{:e}", field.element_emission(j)));
    let cell_rho = cells(&|j| format!("{:e}", field.scene.faces[elements[j].face].rho));
    let cell_face = cells(&|j| elements[j].face.to_string());
    let (mut point_bands, mut cell_bands) = (String::new(), String::new());
    // Colour bands (with their rho) and emission cases: each its u at the vertices, u and E
    // per cell.
    let series = field
        .bands
        .iter()
        .map(|b| (CHANNELS[b.channel].to_string(), &b.u, &b.emission, Some(b.channel)))
        .chain(field.cases.iter().map(|c| (xml_escaped(&c.name), &c.u, &c.emission, None)));
    for (name, u, emission, channel) in series {
        let values: String =
            (0..n).flat_map(|j| field.vertex_values_of(u, j)).map(|u| format!("{u:e}\n")).collect();
        let _ = writeln!(
            point_bands,
            r#"        <DataArray type="Float64" Name="u_{name}" format="ascii">
{values}        </DataArray>"#
        );
        let u = cells(&|j| format!("{:e}", field.element_mean(u, j)));
        let e = cells(&|j| format!("{:e}", field.element_mean(emission, j)));
        let rho = channel.map(|channel| {
            cells(&|j| format!("{:e}", field.scene.faces[elements[j].face].channel(channel).0))
        });
        for (what, text) in [("u", Some(u)), ("E", Some(e)), ("rho", rho)] {
            let Some(text) = text else { continue };
            let _ = writeln!(
                cell_bands,
                r#"        <DataArray type="Float64" Name="{what}_{name}" format="ascii">{text}</DataArray>"#
            );
        }
    }
    let data = format!(
        r#"      <PointData Scalars="u">
        <DataArray type="Float64" Name="u" format="ascii">
{point_u}        </DataArray>
{point_bands}      </PointData>
      <CellData Scalars="u">
        <DataArray type="Float64" Name="u" format="ascii">{cell_u}</DataArray>
        <DataArray type="Float64" Name="E" format="ascii">{cell_e}</DataArray>
        <DataArray type="Float64" Name="rho" format="ascii">{cell_rho}</DataArray>
        <DataArray type="Int64" Name="face" format="ascii">{cell_face}</DataArray>
{cell_bands}      </CellData>
"#
    );
    write_grid(field.scene, field.mesh, &data, path)
}

/// `text` with the characters XML gives meaning to replaced by their entities.
fn xml_escaped(text: &str) -> String {
    text.replace('&', "&amp;").replace('<', "&lt;").replace('>', "&gt;").replace('"', "&quot;")
}
