//! Scenes from files: the TOML scene format (faces as polygons, OBJ/STL meshes by reference,
//! reflectivity and emissivity per face, per group, per mesh or by default, and which side
//! radiates), and direct OBJ/STL import. Every face goes through [`Face::new`](super::Face::new)
//! and the scene through [`Scene::new`], so file scenes meet the same checks as the built-in ones.
//!
//! ```toml
//! name = "room"
//! [defaults]            # for every face that does not say otherwise
//! rho = 0.5
//! [groups.lamp]         # faces with group = "lamp", and OBJ groups (o/g) named "lamp"
//! rho = 0.0
//! emission = 1.0
//! [[faces]]
//! name = "floor"
//! vertices = [[0, 0, 0], [4, 0, 0], [4, 3, 0], [0, 3, 0]]   # counter-clockwise about the
//! rho = 0.3             # side that radiates ("front"); rho and emission may be [r, g, b]
//! radiates = "front"    # or "back" (vertex order reversed) or "both" (a double-sided plate)
//! [[meshes]]
//! file = "table.obj"    # relative to this file; .obj or .stl
//! translate = [1, 1, 0]
//! scale = 0.01
//! ```
//!
//! Property precedence for a face: its own entry, its group, the OBJ material (rho = mean of Kd,
//! emission = mean of Ke; the channels are kept for `--bands`), its mesh entry, `[defaults]`. A
//! face with no rho anywhere is an error.
//!
//! Imperfect meshes ([`ImportOptions`]): a slightly non-planar polygon is split into planar
//! triangles (a quadrilateral along its shorter diagonal, other polygons by ear clipping in the
//! plane that fits them best), and a face that repeats an earlier one exactly is dropped; both by
//! default for OBJ/STL polygons and on request for TOML faces, and both counted in
//! [`Scene::notes`]. OBJ faces are named by file and line (`box.obj:12 (g lid; usemtl glow)`),
//! since an OBJ file's `g` may follow the faces it means to name. Coplanar triangles of a mesh
//! that share edges and properties are joined into polygons for visibility, keeping the
//! triangles as elements ([`crate::scene::merge_coplanar`]; `--coplanar keep` keeps them apart).

mod builder;
mod import;
mod schema;

use std::path::Path;

use glam::DVec3;
use serde::Deserialize;

use super::Scene;
use crate::error::{Error, Result};

use builder::Builder;
use import::read_mesh;
use schema::{Channels, Properties, SceneFile, check_group};

/// Reflectivity given to the faces of a directly imported OBJ/STL file without a material.
pub const IMPORT_RHO: f64 = 0.5;

/// Which side of a polygon radiates.
#[derive(Clone, Copy, Debug, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "lowercase")]
pub enum Side {
    /// The side about which the vertices run counter-clockwise (the outside of an OBJ/STL solid).
    Front,
    /// The other side (vertex order reversed): the inside of a room modelled as a closed solid.
    Back,
    /// Both: two faces, `NAME` and `NAME.back` (a double-sided plate).
    Both,
}

crate::vocabulary::named_options! {
    /// What to do with a polygon that is not planar.
    #[derive(Clone, Copy, Debug, PartialEq, Eq)]
    pub enum NonPlanar as "nonplanar" {
        /// Into planar triangles: a quadrilateral along its shorter diagonal, others by ear
        /// clipping
        Split = "split",
        /// Refuse the scene, naming the face
        Refuse = "refuse",
    }
}

crate::vocabulary::named_options! {
    /// What to do with a face that repeats an earlier one exactly (same vertices in the same
    /// cyclic order, same properties).
    #[derive(Clone, Copy, Debug, PartialEq, Eq)]
    pub enum Duplicates as "duplicates" {
        /// Keep the first, drop the others
        Drop = "drop",
        /// Keep all: the scene is refused as overlapping
        Refuse = "refuse",
    }
}

crate::vocabulary::named_options! {
    /// What to do with coplanar triangles of a mesh file that share edges and properties
    /// ([`crate::scene::merge_coplanar`]).
    #[derive(Clone, Copy, Debug, PartialEq, Eq)]
    pub enum Coplanar as "coplanar" {
        /// Join them into planar faces for visibility, the triangles kept as elements
        Merge = "merge",
        /// Every triangle a face of its own
        Keep = "keep",
    }
}

/// How a scene file's imperfections are treated; `None`: split, drop and merge for OBJ/STL
/// polygons, refuse for TOML faces (whose coordinates the user typed), which are never merged.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct ImportOptions {
    /// Non-planar polygons.
    pub nonplanar: Option<NonPlanar>,
    /// Exact duplicates.
    pub duplicates: Option<Duplicates>,
    /// Coplanar triangles of OBJ/STL meshes.
    pub coplanar: Option<Coplanar>,
}

/// Whether `name` looks like a scene file (by extension) rather than a built-in scene.
pub fn is_scene_file(name: &str) -> bool {
    let ext = Path::new(name).extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase);
    matches!(ext.as_deref(), Some("toml" | "obj" | "stl"))
}

/// The triangles of an STL file in the file's order and coordinates (f32 widened to f64): the
/// facets that urban models number.
pub fn stl_triangles(path: &Path) -> Result<Vec<[DVec3; 3]>> {
    let is_stl = path.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase);
    if is_stl.as_deref() != Some("stl") {
        return Err(Error::SceneFile {
            path: path.display().to_string(),
            reason: "expected an .stl file (its triangles are the facets)".into(),
        });
    }
    Ok(read_mesh(path)?
        .into_iter()
        .map(|p| [p.vertices[0], p.vertices[1], p.vertices[2]])
        .collect())
}

/// Loads a scene from a `.toml` scene file or an `.obj` / `.stl` mesh (OBJ faces named by file
/// and line, STL triangles `STEM/k`; rho from the OBJ material or [`IMPORT_RHO`], no emission),
/// with the default [`ImportOptions`].
pub fn load(path: &Path) -> Result<Scene> {
    load_with(path, ImportOptions::default())
}

/// [`load`] with the given treatment of non-planar and duplicate faces.
pub fn load_with(path: &Path, options: ImportOptions) -> Result<Scene> {
    let display = path.display().to_string();
    let ext = path.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase);
    match ext.as_deref() {
        Some("toml") => load_toml(path, options),
        Some("obj" | "stl") => {
            let defaults =
                Properties { rho: Some(Channels::Grey(IMPORT_RHO)), ..Default::default() };
            let mut builder = Builder::new(options.for_meshes());
            for poly in read_mesh(path)? {
                let props = poly.material.or(defaults);
                builder.push(&poly.label, poly.vertices, props, None)?;
            }
            builder.finish(stem(path))
        }
        _ => Err(Error::SceneFile {
            path: display,
            reason: "expected a .toml scene file, or an .obj or .stl mesh".into(),
        }),
    }
}

/// A scene from a triangle mesh given as arrays (as a mesh file is read: non-planar faces cannot
/// occur, exact repeats are dropped, coplanar triangles merged unless `options` say otherwise):
/// `triangles[k]` indexes `vertices`, with reflectivity `rho[k]` and emissivity `emission[k]`.
/// Triangle k is named `NAME/k`.
pub fn from_triangles(
    name: &str,
    vertices: &[DVec3],
    triangles: &[[usize; 3]],
    rho: &[f64],
    emission: &[f64],
    options: ImportOptions,
) -> Result<Scene> {
    let per_triangle = |what: &'static str, len: usize| Error::InvalidParameter {
        name: what,
        value: format!("{len} values"),
        reason: format!("give one per triangle ({} triangles)", triangles.len()),
    };
    if rho.len() != triangles.len() {
        return Err(per_triangle("rho", rho.len()));
    }
    if emission.len() != triangles.len() {
        return Err(per_triangle("emission", emission.len()));
    }
    let mut builder = Builder::new(options.for_meshes());
    for (k, (triangle, (&rho, &emission))) in
        triangles.iter().zip(rho.iter().zip(emission)).enumerate()
    {
        let corners = triangle.iter().map(|&i| {
            vertices.get(i).copied().ok_or_else(|| Error::InvalidParameter {
                name: "triangles",
                value: format!("triangle {k}: vertex {i}"),
                reason: format!("there are {} vertices", vertices.len()),
            })
        });
        let properties = Properties {
            rho: Some(Channels::Grey(rho)),
            emission: Some(Channels::Grey(emission)),
            radiates: None,
        };
        builder.push(&format!("{name}/{k}"), corners.collect::<Result<_>>()?, properties, None)?;
    }
    builder.finish(name.to_string())
}

/// A clear error for a path that is not there, instead of the reader's own ("open file failed").
fn check_readable(path: &Path) -> Result<()> {
    if path.is_file() {
        return Ok(());
    }
    let reason = if path.exists() { "not a file" } else { "no such file" };
    Err(Error::SceneFile {
        path: path.display().to_string(),
        reason: format!(
            "{reason} (paths are relative to the current directory; mesh files in a \
                         scene file, to the scene file's)"
        ),
    })
}

fn stem(path: &Path) -> String {
    path.file_stem().and_then(|s| s.to_str()).unwrap_or("scene").to_string()
}

fn load_toml(path: &Path, options: ImportOptions) -> Result<Scene> {
    check_readable(path)?;
    let display = path.display().to_string();
    let text = std::fs::read_to_string(path)
        .map_err(|e| Error::SceneFile { path: display.clone(), reason: e.to_string() })?;
    parse_toml_with(&text, path, options)
}

/// A scene from the text of a TOML scene file at `path` (meshes are found relative to it).
pub fn parse_toml(text: &str, path: &Path) -> Result<Scene> {
    parse_toml_with(text, path, ImportOptions::default())
}

fn parse_toml_with(text: &str, path: &Path, options: ImportOptions) -> Result<Scene> {
    let display = path.display().to_string();
    let file: SceneFile = toml::from_str(text)
        .map_err(|e| Error::SceneFile { path: display.clone(), reason: e.to_string() })?;
    for (group, props) in &file.groups {
        check_group(&display, group, props)?;
    }
    let group_props = |group: Option<&str>| -> Properties {
        group.and_then(|g| file.groups.get(g)).copied().unwrap_or_default()
    };
    let mut typed = Builder::new(options.for_typed_faces());
    for entry in &file.faces {
        if let Some(g) = &entry.group {
            if !file.groups.contains_key(g) {
                return Err(Error::SceneFile {
                    path: display,
                    reason: format!("face '{}': unknown group '{g}' (no [groups.{g}])", entry.name),
                });
            }
        }
        let own = Properties { rho: entry.rho, emission: entry.emission, radiates: entry.radiates };
        let props = own.or(group_props(entry.group.as_deref())).or(file.defaults);
        let vertices = entry.vertices.iter().map(|&v| DVec3::from_array(v)).collect();
        let normal = entry.normal.map(DVec3::from_array);
        typed.push(&entry.name, vertices, props, normal)?;
    }
    // Mesh polygons follow their own rules, and their faces' names must not clash with the typed
    // ones: one builder continues the other.
    let mut builder = typed.continued(options.for_meshes());
    let base = path.parent().unwrap_or(Path::new("."));
    for entry in &file.meshes {
        let mesh_path = base.join(&entry.file);
        let scale = entry.scale.unwrap_or(1.0);
        if !(scale.is_finite() && scale > 0.0) {
            return Err(Error::SceneFile {
                path: display,
                reason: format!(
                    "mesh '{}': scale = {scale} must be positive",
                    entry.file.display()
                ),
            });
        }
        let shift = DVec3::from_array(entry.translate);
        let prefix = entry.name.clone().unwrap_or_else(|| stem(&mesh_path));
        let own = Properties { rho: entry.rho, emission: entry.emission, radiates: entry.radiates };
        for poly in read_mesh(&mesh_path)? {
            let props = group_props(Some(&poly.group)).or(poly.material).or(own).or(file.defaults);
            let vertices = poly.vertices.iter().map(|&v| v * scale + shift).collect();
            builder.push(&format!("{prefix}/{}", poly.label), vertices, props, None)?;
        }
    }
    let mut scene = builder.finish(file.name.unwrap_or_else(|| stem(path)))?;
    scene.daylight = match (file.sun, file.sky) {
        (Some(sun), sky) => Some(crate::scene::Daylight {
            diffuse_horizontal: sky.map_or(0.0, |s| s.diffuse_horizontal),
            ..sun
        }),
        (None, Some(_)) => {
            return Err(Error::SceneFile {
                path: display,
                reason:
                    "a [sky] table needs a [sun] table (give direct_normal = 0 for a sky alone)"
                        .into(),
            });
        }
        (None, None) => None,
    };
    Ok(scene)
}

#[cfg(test)]
mod tests;
