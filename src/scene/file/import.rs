//! OBJ and STL files read into polygons, with their groups, OBJ materials and source lines.

use std::path::Path;

use glam::DVec3;

use super::schema::{Channels, Properties};
use super::{check_readable, stem};
use crate::error::{Error, Result};

/// A polygon read from a mesh file, with its group and material properties.
pub(super) struct Polygon {
    pub(super) group: String,
    /// `file:line (g GROUP; usemtl MATERIAL)` for OBJ faces, `GROUP/k` for STL triangles.
    pub(super) label: String,
    pub(super) vertices: Vec<DVec3>,
    pub(super) material: Properties,
}

/// The polygons of an OBJ (groups and materials kept) or STL file.
pub(super) fn read_mesh(path: &Path) -> Result<Vec<Polygon>> {
    check_readable(path)?;
    let display = path.display().to_string();
    let fail = |reason: String| Error::SceneFile { path: display.clone(), reason };
    let ext = path.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase);
    match ext.as_deref() {
        Some("obj") => {
            let options = tobj::LoadOptions {
                triangulate: false,
                single_index: false,
                ignore_points: true,
                ignore_lines: true,
            };
            let (models, materials) = tobj::load_obj(path, &options).map_err(|e| {
                let place = std::fs::read_to_string(path).ok().and_then(|t| obj_bad_index(&t));
                fail(place.unwrap_or_else(|| e.to_string()))
            })?;
            // A missing or broken .mtl leaves the faces to the scene's properties.
            let materials = materials.unwrap_or_default();
            let file_name =
                path.file_name().map_or(display.clone(), |f| f.to_string_lossy().into());
            let text = std::fs::read_to_string(path).map_err(|e| fail(e.to_string()))?;
            // tobj keeps the faces in file order: the k-th polygon is the k-th `f` line.
            let mut lines = text.lines().enumerate().filter_map(|(k, l)| {
                let rest = l.trim_start().strip_prefix('f')?;
                rest.starts_with(char::is_whitespace).then_some(k + 1)
            });
            let mut polygons = Vec::new();
            for model in models {
                let m = &model.mesh;
                let mtl = m.material_id.and_then(|k| materials.get(k));
                let material = mtl.map(material_properties);
                let about = match mtl {
                    Some(mtl) => format!(" (g {}; usemtl {})", model.name, mtl.name),
                    None => format!(" (g {})", model.name),
                };
                let arities: Vec<usize> = if m.face_arities.is_empty() {
                    vec![3; m.indices.len() / 3]
                } else {
                    m.face_arities.iter().map(|&a| a as usize).collect()
                };
                let mut start = 0;
                for arity in arities {
                    let vertices = m.indices[start..start + arity]
                        .iter()
                        .map(|&i| {
                            let i = 3 * i as usize;
                            DVec3::new(
                                m.positions[i] as f64,
                                m.positions[i + 1] as f64,
                                m.positions[i + 2] as f64,
                            )
                        })
                        .collect();
                    start += arity;
                    let line = lines.next().map_or_else(|| "?".into(), |l| l.to_string());
                    polygons.push(Polygon {
                        group: model.name.clone(),
                        label: format!("{file_name}:{line}{about}"),
                        vertices,
                        material: material.unwrap_or_default(),
                    });
                }
            }
            Ok(polygons)
        }
        Some("stl") => {
            let mut file = std::fs::File::open(path).map_err(|e| fail(e.to_string()))?;
            let mesh = stl_io::read_stl(&mut file).map_err(|e| fail(e.to_string()))?;
            let group = stem(path);
            Ok(mesh
                .faces
                .iter()
                .enumerate()
                .map(|(k, t)| Polygon {
                    group: group.clone(),
                    label: format!("{group}/{k}"),
                    vertices: t
                        .vertices
                        .iter()
                        .map(|&i| {
                            let v = mesh.vertices[i];
                            DVec3::new(v[0] as f64, v[1] as f64, v[2] as f64)
                        })
                        .collect(),
                    material: Properties::default(),
                })
                .collect())
        }
        _ => Err(fail("meshes must be .obj or .stl files".into())),
    }
}

/// Where an OBJ file's face refers to a vertex it does not have (tobj says only that one does):
/// "line L: face vertex V, but the file has N vertices".
fn obj_bad_index(text: &str) -> Option<String> {
    let vertices = text.lines().filter(|l| l.trim_start().starts_with("v ")).count() as i64;
    text.lines().enumerate().find_map(|(k, line)| {
        let rest = line.trim_start().strip_prefix("f ")?;
        rest.split_whitespace().find_map(|corner| {
            let v: i64 = corner.split('/').next()?.parse().ok()?;
            let in_range = (1..=vertices).contains(&v) || (-vertices..=-1).contains(&v);
            (!in_range).then(|| {
                format!(
                    "line {}: face vertex {v}, but the file has {vertices} vertices (OBJ indices \
                     count from 1, negative ones from the end)",
                    k + 1
                )
            })
        })
    })
}

/// rho and emission from an OBJ material: the means of its diffuse colour Kd and emission Ke, with
/// the channels kept.
fn material_properties(m: &tobj::Material) -> Properties {
    let channels = |c: [f32; 3]| Channels::Rgb(c.map(f64::from));
    Properties { rho: m.diffuse.map(channels), emission: m.emissive.map(channels), radiates: None }
}
