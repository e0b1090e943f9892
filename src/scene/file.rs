//! Scenes from files: the TOML scene format (faces as polygons, OBJ/STL meshes by reference,
//! reflectivity and emissivity per face, per group, per mesh or by default, and which side
//! radiates), and direct OBJ/STL import. Every face goes through [`Face::new`] and the scene
//! through [`Scene::new`], so file scenes meet the same checks as the built-in ones.
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
//! rho = 0.3                                                  # side that radiates ("front")
//! radiates = "front"    # or "back" (vertex order reversed) or "both" (a double-sided plate)
//! [[meshes]]
//! file = "table.obj"    # relative to this file; .obj or .stl
//! translate = [1, 1, 0]
//! scale = 0.01
//! ```
//!
//! Property precedence for a face: its own entry, its group, the OBJ material (rho = mean of Kd,
//! emission = mean of Ke), its mesh entry, `[defaults]`. A face with no rho anywhere is an error.

use std::collections::{BTreeMap, HashSet};
use std::path::{Path, PathBuf};

use glam::DVec3;
use serde::Deserialize;

use super::{Face, Scene};
use crate::error::{Error, Result};

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

#[derive(Clone, Copy, Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
struct Properties {
    rho: Option<f64>,
    emission: Option<f64>,
    radiates: Option<Side>,
}

impl Properties {
    /// `self` where it says something, else `fallback`.
    fn or(self, fallback: Properties) -> Properties {
        Properties {
            rho: self.rho.or(fallback.rho),
            emission: self.emission.or(fallback.emission),
            radiates: self.radiates.or(fallback.radiates),
        }
    }
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct SceneFile {
    name: Option<String>,
    #[serde(default)]
    defaults: Properties,
    #[serde(default)]
    groups: BTreeMap<String, Properties>,
    #[serde(default)]
    faces: Vec<FaceEntry>,
    #[serde(default)]
    meshes: Vec<MeshEntry>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct FaceEntry {
    name: String,
    vertices: Vec<[f64; 3]>,
    group: Option<String>,
    /// Optional check: the normal of the radiating side (of the first face for `both`).
    normal: Option<[f64; 3]>,
    rho: Option<f64>,
    emission: Option<f64>,
    radiates: Option<Side>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct MeshEntry {
    file: PathBuf,
    /// Prefix of the face names (default: the file's stem).
    name: Option<String>,
    #[serde(default)]
    translate: [f64; 3],
    scale: Option<f64>,
    rho: Option<f64>,
    emission: Option<f64>,
    radiates: Option<Side>,
}

/// A polygon read from a mesh file, with its group and material properties.
struct Polygon {
    group: String,
    vertices: Vec<DVec3>,
    material: Properties,
}

/// Whether `name` looks like a scene file (by extension) rather than a built-in scene.
pub fn is_scene_file(name: &str) -> bool {
    let ext = Path::new(name).extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase);
    matches!(ext.as_deref(), Some("toml" | "obj" | "stl"))
}

/// Loads a scene from a `.toml` scene file or an `.obj` / `.stl` mesh (each polygon a face named
/// `GROUP/k`, rho from the OBJ material or [`IMPORT_RHO`], no emission).
pub fn load(path: &Path) -> Result<Scene> {
    let display = path.display().to_string();
    let ext = path.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase);
    match ext.as_deref() {
        Some("toml") => load_toml(path),
        Some("obj" | "stl") => {
            let name = stem(path);
            let defaults = Properties { rho: Some(IMPORT_RHO), ..Default::default() };
            let mut faces = Vec::new();
            let mut names = HashSet::new();
            for (k, poly) in read_mesh(path)?.into_iter().enumerate() {
                let props = poly.material.or(defaults);
                let face_name = format!("{}/{k}", poly.group);
                push_faces(&mut faces, &mut names, &face_name, poly.vertices, props, None)?;
            }
            Scene::new(name, faces)
        }
        _ => Err(Error::SceneFile {
            path: display,
            reason: "expected a .toml scene file, or an .obj or .stl mesh".into(),
        }),
    }
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

fn load_toml(path: &Path) -> Result<Scene> {
    check_readable(path)?;
    let display = path.display().to_string();
    let text = std::fs::read_to_string(path)
        .map_err(|e| Error::SceneFile { path: display.clone(), reason: e.to_string() })?;
    parse_toml(&text, path)
}

/// A scene from the text of a TOML scene file at `path` (meshes are found relative to it).
pub fn parse_toml(text: &str, path: &Path) -> Result<Scene> {
    let display = path.display().to_string();
    let file: SceneFile = toml::from_str(text)
        .map_err(|e| Error::SceneFile { path: display.clone(), reason: e.to_string() })?;
    for (group, props) in &file.groups {
        check_group(&display, group, props)?;
    }
    let group_props = |group: Option<&str>| -> Properties {
        group.and_then(|g| file.groups.get(g)).copied().unwrap_or_default()
    };
    let mut faces = Vec::new();
    let mut names = HashSet::new();
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
        push_faces(&mut faces, &mut names, &entry.name, vertices, props, normal)?;
    }
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
        for (k, poly) in read_mesh(&mesh_path)?.into_iter().enumerate() {
            let props = group_props(Some(&poly.group)).or(poly.material).or(own).or(file.defaults);
            let vertices = poly.vertices.iter().map(|&v| v * scale + shift).collect();
            let face_name = format!("{prefix}/{}/{k}", poly.group);
            push_faces(&mut faces, &mut names, &face_name, vertices, props, None)?;
        }
    }
    Scene::new(file.name.unwrap_or_else(|| stem(path)), faces)
}

fn check_group(path: &str, group: &str, props: &Properties) -> Result<()> {
    let bad = |what: &str, value: f64| Error::SceneFile {
        path: path.into(),
        reason: format!("group '{group}': {what} = {value} is outside its range"),
    };
    match (props.rho, props.emission) {
        (Some(r), _) if !(0.0..=1.0).contains(&r) => Err(bad("rho", r)),
        (_, Some(e)) if !(e.is_finite() && e >= 0.0) => Err(bad("emission", e)),
        _ => Ok(()),
    }
}

/// Adds the face (or the two faces of a double-sided plate) for one polygon.
fn push_faces(
    faces: &mut Vec<Face>,
    names: &mut HashSet<String>,
    name: &str,
    mut vertices: Vec<DVec3>,
    props: Properties,
    normal: Option<DVec3>,
) -> Result<()> {
    let rho = props.rho.ok_or_else(|| Error::InvalidParameter {
        name: "rho",
        value: "missing".into(),
        reason: format!("face '{name}' has no rho: set it on the face, its group or [defaults]"),
    })?;
    let emission = props.emission.unwrap_or(0.0);
    let side = props.radiates.unwrap_or(Side::Front);
    if side == Side::Back {
        vertices.reverse();
    }
    let mut sides = vec![(name.to_string(), vertices.clone())];
    if side == Side::Both {
        vertices.reverse();
        sides.push((format!("{name}.back"), vertices));
    }
    for (k, (face_name, vertices)) in sides.into_iter().enumerate() {
        if !names.insert(face_name.clone()) {
            return Err(Error::InvalidParameter {
                name: "face name",
                value: face_name,
                reason: "face names must be unique".into(),
            });
        }
        let face = Face::new(face_name, vertices, rho)?.with_emission(emission)?;
        if let (Some(n), 0) = (normal, k) {
            face.check_normal(n)?;
        }
        faces.push(face);
    }
    Ok(())
}

/// The polygons of an OBJ (groups and materials kept) or STL file.
fn read_mesh(path: &Path) -> Result<Vec<Polygon>> {
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
            let mut polygons = Vec::new();
            for model in models {
                let m = &model.mesh;
                let material =
                    m.material_id.and_then(|k| materials.get(k)).map(material_properties);
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
                    polygons.push(Polygon {
                        group: model.name.clone(),
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
                .map(|t| Polygon {
                    group: group.clone(),
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

/// rho and emission from an OBJ material: the means of its diffuse colour Kd and emission Ke.
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

fn material_properties(m: &tobj::Material) -> Properties {
    let mean = |c: [f32; 3]| (c[0] as f64 + c[1] as f64 + c[2] as f64) / 3.0;
    Properties { rho: m.diffuse.map(mean), emission: m.emissive.map(mean), radiates: None }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn write(dir: &Path, name: &str, text: &str) -> PathBuf {
        let p = dir.join(name);
        std::fs::write(&p, text).unwrap();
        p
    }

    fn temp_dir(tag: &str) -> PathBuf {
        let d = std::env::temp_dir().join(format!("radiosity-scene-{tag}-{}", std::process::id()));
        std::fs::create_dir_all(&d).unwrap();
        d
    }

    #[test]
    fn toml_faces_groups_sides_and_meshes() {
        let dir = temp_dir("toml");
        write(
            &dir,
            "box.obj",
            "mtllib box.mtl\no lid\nusemtl glow\nv 0 0 1\nv 1 0 1\nv 1 1 1\nv 0 1 1\nf 1 2 3 4\n\
             o side\nv 0 0 0\nv 1 0 0\nv 1 0 1\nf 5 6 7\n",
        );
        write(&dir, "box.mtl", "newmtl glow\nKd 0.1 0.2 0.3\nKe 2 2 2\n");
        let p = write(
            &dir,
            "s.toml",
            r#"
name = "test"
[defaults]
rho = 0.5
[groups.side]
rho = 0.9
[[faces]]
name = "floor"
vertices = [[0, 0, -1], [2, 0, -1], [2, 2, -1], [0, 2, -1]]
normal = [0, 0, 1]
emission = 3.0
[[faces]]
name = "plate"
vertices = [[0, 0, 3], [1, 0, 3], [1, 1, 3]]
radiates = "both"
[[meshes]]
file = "box.obj"
translate = [0, 0, 0.5]
rho = 0.7
"#,
        );
        let s = load(&p).unwrap();
        assert_eq!(s.name, "test");
        let names: Vec<&str> = s.faces.iter().map(|f| f.name.as_str()).collect();
        assert_eq!(names, ["floor", "plate", "plate.back", "box/lid/0", "box/side/1"]);
        let f = |n: &str| &s.faces[s.face_index(n).unwrap()];
        assert_eq!((f("floor").rho, f("floor").emission), (0.5, 3.0));
        assert!((f("plate").frame.normal + f("plate.back").frame.normal).length() < 1e-15);
        // The material's Kd and Ke, above the mesh entry's rho.
        let lid = f("box/lid/0");
        assert!(
            (lid.rho - 0.2).abs() < 1e-7 && lid.emission == 2.0,
            "{} {}",
            lid.rho,
            lid.emission
        );
        assert!((f("box/lid/0").vertices[0].z - 1.5).abs() < 1e-15);
        // The group's rho above the mesh entry's.
        assert_eq!(f("box/side/1").rho, 0.9);
    }

    #[test]
    fn bad_scene_files_name_the_culprit() {
        let dir = temp_dir("bad");
        let cases = [
            ("name = 3", "invalid type"),
            ("[[faces]]\nname = \"a\"\nvertices = [[0,0,0],[1,0,0],[0,1,0]]", "no rho"),
            (
                "[defaults]\nrho = 0.5\n[[faces]]\nname = \"a\"\nvertices = [[0,0,0],[1,0,0],[0,1,0]]\nnormal = [0,0,-1]",
                "normal",
            ),
            (
                "[defaults]\nrho = 0.5\n[[faces]]\nname = \"a\"\nvertices = [[0,0,0],[1,0,0],[0,1,0]]\ngroup = \"g\"",
                "unknown group 'g'",
            ),
            ("[groups.g]\nrho = 2.0", "rho = 2"),
            (
                "[[faces]]\nname = \"a\"\nvertices = [[0,0,0],[1,0,0],[0,1,0]]\nrh = 1",
                "unknown field",
            ),
            ("[defaults]\nrho = 0.5\n[[meshes]]\nfile = \"missing.obj\"", "missing.obj"),
            (
                "[defaults]\nrho = 0.5\n[[faces]]\nname = \"a\"\nvertices = [[0,0,0],[1,0,nan],[0,1,0]]",
                "non-finite",
            ),
            (
                "[defaults]\nrho = 0.5\nradiates = \"both\"\n[[faces]]\nname = \"a\"\nvertices = [[0,0,0],[1,0,0],[0,1,0]]\n[[faces]]\nname = \"a.back\"\nvertices = [[0,0,1],[1,0,1],[0,1,1]]",
                "unique",
            ),
        ];
        for (k, (text, expect)) in cases.iter().enumerate() {
            let p = write(&dir, &format!("bad{k}.toml"), text);
            let e = load(&p).unwrap_err().to_string();
            assert!(e.contains(expect), "case {k}: {e}");
        }
        let p = write(&dir, "broken.obj", "v 0 0 0\nv 1 0 0\nf 1 2 9\n");
        assert!(load(&p).is_err());
        let p = write(&dir, "scene.ply", "");
        assert!(load(&p).unwrap_err().to_string().contains(".toml"));
    }

    #[test]
    fn stl_triangles_become_faces_with_the_import_rho() {
        let dir = temp_dir("stl");
        let text = "solid t\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\n\
                    vertex 0 1 0\nendloop\nendfacet\nendsolid t\n";
        let p = write(&dir, "tri.stl", text);
        let s = load(&p).unwrap();
        assert_eq!(s.faces.len(), 1);
        assert_eq!((s.faces[0].name.as_str(), s.faces[0].rho), ("tri/0", IMPORT_RHO));
    }
}
