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
//! since an OBJ file's `g` may follow the faces it means to name.

use std::collections::{BTreeMap, HashMap, HashSet};
use std::path::{Path, PathBuf};

use glam::DVec3;
use serde::Deserialize;

use super::{Colour, Face, Scene};
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

/// What to do with a polygon that is not planar.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum NonPlanar {
    /// Split it into planar triangles (a quadrilateral along its shorter diagonal).
    Split,
    /// Refuse the scene, naming the face.
    Refuse,
}

/// What to do with a face that repeats an earlier one exactly (same vertices in the same cyclic
/// order, same properties).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Duplicates {
    /// Keep the first, drop the others.
    Drop,
    /// Keep all: the scene is refused as overlapping.
    Refuse,
}

/// How a scene file's imperfections are treated; `None`: split and drop for OBJ/STL polygons,
/// refuse for TOML faces (whose coordinates the user typed).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct ImportOptions {
    /// Non-planar polygons.
    pub nonplanar: Option<NonPlanar>,
    /// Exact duplicates.
    pub duplicates: Option<Duplicates>,
}

/// A value for every colour channel (grey), or one per channel r, g, b (`[r, g, b]` in a scene
/// file, `Kd`/`Ke` of an OBJ material), for `--bands`.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Channels {
    Grey(f64),
    Rgb([f64; 3]),
}

impl<'de> Deserialize<'de> for Channels {
    // By hand: serde's untagged enums say only "data did not match any variant".
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> std::result::Result<Self, D::Error> {
        struct Visitor;
        impl<'de> serde::de::Visitor<'de> for Visitor {
            type Value = Channels;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("a number, or three numbers [r, g, b]")
            }
            fn visit_f64<E>(self, v: f64) -> std::result::Result<Channels, E> {
                Ok(Channels::Grey(v))
            }
            fn visit_i64<E>(self, v: i64) -> std::result::Result<Channels, E> {
                Ok(Channels::Grey(v as f64))
            }
            fn visit_u64<E>(self, v: u64) -> std::result::Result<Channels, E> {
                Ok(Channels::Grey(v as f64))
            }
            fn visit_seq<A: serde::de::SeqAccess<'de>>(
                self,
                mut seq: A,
            ) -> std::result::Result<Channels, A::Error> {
                let mut c = [0.0; 3];
                for (k, slot) in c.iter_mut().enumerate() {
                    *slot = seq
                        .next_element()?
                        .ok_or_else(|| serde::de::Error::invalid_length(k, &self))?;
                }
                if seq.next_element::<f64>()?.is_some() {
                    return Err(serde::de::Error::invalid_length(4, &self));
                }
                Ok(Channels::Rgb(c))
            }
        }
        d.deserialize_any(Visitor)
    }
}

impl Channels {
    /// The grey value: the channels' mean.
    fn grey(self) -> f64 {
        match self {
            Self::Grey(x) => x,
            Self::Rgb(c) => (c[0] + c[1] + c[2]) / 3.0,
        }
    }

    fn rgb(self) -> Option<[f64; 3]> {
        match self {
            Self::Grey(_) => None,
            Self::Rgb(c) => Some(c),
        }
    }

    /// Every value given: the grey one, or each channel.
    fn values(self) -> Vec<f64> {
        match self {
            Self::Grey(x) => vec![x],
            Self::Rgb(c) => c.to_vec(),
        }
    }
}

#[derive(Clone, Copy, Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
struct Properties {
    rho: Option<Channels>,
    emission: Option<Channels>,
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
    rho: Option<Channels>,
    emission: Option<Channels>,
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
    rho: Option<Channels>,
    emission: Option<Channels>,
    radiates: Option<Side>,
}

/// A polygon read from a mesh file, with its group and material properties.
struct Polygon {
    group: String,
    /// `file:line (g GROUP; usemtl MATERIAL)` for OBJ faces, `GROUP/k` for STL triangles.
    label: String,
    vertices: Vec<DVec3>,
    material: Properties,
}

/// Whether `name` looks like a scene file (by extension) rather than a built-in scene.
pub fn is_scene_file(name: &str) -> bool {
    let ext = Path::new(name).extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase);
    matches!(ext.as_deref(), Some("toml" | "obj" | "stl"))
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
    builder.finish(file.name.unwrap_or_else(|| stem(path)))
}

fn check_group(path: &str, group: &str, props: &Properties) -> Result<()> {
    let bad = |what: &str, value: f64| Error::SceneFile {
        path: path.into(),
        reason: format!("group '{group}': {what} = {value} is outside its range"),
    };
    let values = |c: Option<Channels>| c.map(Channels::values).unwrap_or_default();
    if let Some(r) = values(props.rho).into_iter().find(|r| !(0.0..=1.0).contains(r)) {
        return Err(bad("rho", r));
    }
    match values(props.emission).into_iter().find(|e| !(e.is_finite() && *e >= 0.0)) {
        Some(e) => Err(bad("emission", e)),
        None => Ok(()),
    }
}

impl ImportOptions {
    /// The rules for polygons read from OBJ/STL files: split and drop unless told otherwise.
    fn for_meshes(self) -> Rules {
        Rules {
            split: self.nonplanar.unwrap_or(NonPlanar::Split) == NonPlanar::Split,
            drop: self.duplicates.unwrap_or(Duplicates::Drop) == Duplicates::Drop,
        }
    }

    /// The rules for faces typed into a TOML file: refuse unless told otherwise.
    fn for_typed_faces(self) -> Rules {
        Rules {
            split: self.nonplanar == Some(NonPlanar::Split),
            drop: self.duplicates == Some(Duplicates::Drop),
        }
    }
}

/// Whether non-planar polygons are split and exact duplicates dropped.
#[derive(Clone, Copy)]
struct Rules {
    split: bool,
    drop: bool,
}

/// Collects a file's faces: unique names, non-planar polygons split, exact duplicates dropped,
/// and what was done, for [`Scene::notes`].
struct Builder {
    rules: Rules,
    faces: Vec<Face>,
    names: HashSet<String>,
    /// Each face's vertices and properties (bit patterns, from its smallest vertex on): the
    /// first face with them.
    seen: HashMap<Vec<u64>, String>,
    /// (polygon, its largest distance from its plane, its size), per split polygon.
    split: Vec<(String, f64, f64)>,
    /// (dropped face, the face it repeats).
    dropped: Vec<(String, String)>,
}

impl Builder {
    fn new(rules: Rules) -> Self {
        Self {
            rules,
            faces: Vec::new(),
            names: HashSet::new(),
            seen: HashMap::new(),
            split: Vec::new(),
            dropped: Vec::new(),
        }
    }

    /// The same faces and records, under other rules.
    fn continued(self, rules: Rules) -> Self {
        Self { rules, ..self }
    }

    /// Adds the face (or the two faces of a double-sided plate) for one polygon.
    fn push(
        &mut self,
        name: &str,
        mut vertices: Vec<DVec3>,
        props: Properties,
        normal: Option<DVec3>,
    ) -> Result<()> {
        let rho = props.rho.ok_or_else(|| Error::InvalidParameter {
            name: "rho",
            value: "missing".into(),
            reason: format!(
                "face '{name}' has no rho: set it on the face, its group or [defaults]"
            ),
        })?;
        let emission = props.emission.map_or(0.0, Channels::grey);
        let colour = Colour {
            rho: props.rho.and_then(Channels::rgb),
            emission: props.emission.and_then(Channels::rgb),
        };
        let rho = rho.grey();
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
            if !self.names.insert(face_name.clone()) {
                return Err(Error::InvalidParameter {
                    name: "face name",
                    value: face_name,
                    reason: "face names must be unique".into(),
                });
            }
            if self.rules.drop {
                let key = duplicate_key(&vertices, rho, emission, colour);
                if let Some(first) = self.seen.get(&key) {
                    self.dropped.push((face_name, first.clone()));
                    continue;
                }
                self.seen.insert(key, face_name.clone());
            }
            let pieces = match Face::new(face_name.clone(), vertices.clone(), rho) {
                Err(Error::NonPlanarFace { .. }) if self.rules.split => {
                    let (deviation, size) = deviation_from_plane(&vertices);
                    self.split.push((face_name.clone(), deviation, size));
                    split_into_triangles(&face_name, &vertices, rho)?
                }
                face => vec![face?],
            };
            for face in pieces {
                let face = face.with_emission(emission)?.with_colour(colour)?;
                if let (Some(n), 0) = (normal, k) {
                    face.check_normal(n)?;
                }
                self.faces.push(face);
            }
        }
        Ok(())
    }

    /// The scene, with a note on each kind of repair made.
    fn finish(self, name: String) -> Result<Scene> {
        let mut notes = Vec::new();
        if let Some((worst, deviation, size)) =
            self.split.iter().max_by(|a, b| (a.1 / a.2).total_cmp(&(b.1 / b.2)))
        {
            notes.push(format!(
                "split {} non-planar polygon(s) into planar triangles (quadrilaterals along the \
                 shorter diagonal); the worst, '{worst}', lies up to {deviation:.2e} from its \
                 plane ({:.1e} of its size); --nonplanar refuse to refuse them instead",
                self.split.len(),
                deviation / size
            ));
        }
        if let Some((dropped, first)) = self.dropped.first() {
            notes.push(format!(
                "dropped {} face(s) that repeat an earlier face exactly (e.g. '{dropped}' repeats \
                 '{first}'); --duplicates refuse to refuse them instead",
                self.dropped.len()
            ));
        }
        let mut scene = Scene::new(name, self.faces)?;
        scene.notes = notes;
        Ok(scene)
    }
}

/// The bits of a face's vertices (from its smallest vertex on, so that the same cycle begun
/// elsewhere matches) and of its properties.
fn duplicate_key(vertices: &[DVec3], rho: f64, emission: f64, colour: Colour) -> Vec<u64> {
    let bits = |v: &DVec3| [v.x.to_bits(), v.y.to_bits(), v.z.to_bits()];
    let start = (0..vertices.len())
        .min_by(|&a, &b| bits(&vertices[a]).cmp(&bits(&vertices[b])))
        .unwrap_or(0);
    let mut key: Vec<u64> =
        vertices[start..].iter().chain(&vertices[..start]).flat_map(bits).collect();
    key.extend([rho.to_bits(), emission.to_bits()]);
    for channels in [colour.rho, colour.emission] {
        key.extend(channels.iter().flatten().map(|c| c.to_bits()));
        key.push(channels.is_some() as u64);
    }
    key
}

/// The largest distance of a polygon's vertices from the plane through their centre with the
/// normal of Newell's method, and the polygon's size (largest vertex distance).
fn deviation_from_plane(vertices: &[DVec3]) -> (f64, f64) {
    let centre = vertices.iter().sum::<DVec3>() / vertices.len() as f64;
    let normal = newell_normal(vertices, centre);
    let deviation = vertices.iter().map(|v| (*v - centre).dot(normal).abs()).fold(0.0, f64::max);
    let size = vertices
        .iter()
        .flat_map(|a| vertices.iter().map(move |b| (*a - *b).length()))
        .fold(0.0, f64::max);
    (deviation, size)
}

fn newell_normal(vertices: &[DVec3], centre: DVec3) -> DVec3 {
    let n = vertices.len();
    (0..n)
        .map(|k| (vertices[k] - centre).cross(vertices[(k + 1) % n] - centre))
        .sum::<DVec3>()
        .normalize_or_zero()
}

/// A non-planar polygon as planar triangles `NAME/t0`, `NAME/t1`, ...: a quadrilateral along its
/// shorter diagonal (the fold that changes the surface least), a larger polygon by ear clipping
/// of its projection onto the plane of Newell's normal.
fn split_into_triangles(name: &str, v: &[DVec3], rho: f64) -> Result<Vec<Face>> {
    let triangles: Vec<[usize; 3]> = if v.len() == 4 {
        if (v[2] - v[0]).length() <= (v[3] - v[1]).length() {
            vec![[0, 1, 2], [0, 2, 3]]
        } else {
            vec![[1, 2, 3], [1, 3, 0]]
        }
    } else {
        let centre = v.iter().sum::<DVec3>() / v.len() as f64;
        let normal = newell_normal(v, centre);
        let a = normal.any_orthonormal_vector();
        // (a, b, normal) is right-handed, so counter-clockwise about the normal stays so.
        let b = normal.cross(a);
        let flat: Vec<glam::DVec2> = v
            .iter()
            .map(|p| glam::DVec2::new((*p - centre).dot(a), (*p - centre).dot(b)))
            .collect();
        crate::geometry::triangulate(&flat).ok_or_else(|| Error::DegenerateFace {
            face: name.to_string(),
            area: 0.0,
            size: deviation_from_plane(v).1,
        })?
    };
    triangles
        .iter()
        .enumerate()
        .map(|(k, t)| Face::new(format!("{name}/t{k}"), t.iter().map(|&i| v[i]).collect(), rho))
        .collect()
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
rho = [0.25, 0.5, 0.75]
emission = [1, 0, 0.5]
[[meshes]]
file = "box.obj"
translate = [0, 0, 0.5]
rho = 0.7
"#,
        );
        let s = load(&p).unwrap();
        assert_eq!(s.name, "test");
        let names: Vec<&str> = s.faces.iter().map(|f| f.name.as_str()).collect();
        // OBJ faces by file and line, with their group and material.
        let (lid, side) =
            ("box/box.obj:8 (g lid; usemtl glow)", "box/box.obj:13 (g side; usemtl glow)");
        assert_eq!(names, ["floor", "plate", "plate.back", lid, side]);
        let f = |n: &str| &s.faces[s.face_index(n).unwrap()];
        assert_eq!((f("floor").rho, f("floor").emission), (0.5, 3.0));
        assert!((f("plate").frame.normal + f("plate.back").frame.normal).length() < 1e-15);
        // Per channel in the file: the means for the grey problem, the channels kept.
        let plate = f("plate.back");
        assert_eq!((plate.rho, plate.emission), (0.5, 0.5));
        assert_eq!(plate.colour.rho, Some([0.25, 0.5, 0.75]));
        assert_eq!((plate.channel(0), plate.channel(2)), ((0.25, 1.0), (0.75, 0.5)));
        assert_eq!(f("floor").colour, Colour::default());
        // The material's Kd and Ke, above the mesh entry's rho.
        let lid = f(lid);
        assert!(
            (lid.rho - 0.2).abs() < 1e-7 && lid.emission == 2.0,
            "{} {}",
            lid.rho,
            lid.emission
        );
        assert!((lid.vertices[0].z - 1.5).abs() < 1e-15);
        assert_eq!(lid.colour.rho.map(|c| c.map(|x| x as f32)), Some([0.1, 0.2, 0.3]));
        // The group's rho above the mesh entry's, and above the material's channels.
        assert_eq!((f(side).rho, f(side).colour.rho), (0.9, None));
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
            ("[groups.g]\nrho = [0.5, 2.0, 0.5]", "rho = 2"),
            (
                "[defaults]\nrho = [0.5, 0.5, 1.5]\n[[faces]]\nname = \"a\"\nvertices = [[0,0,0],[1,0,0],[0,1,0]]",
                "'a (channel b)'",
            ),
            ("[defaults]\nrho = \"x\"", "expected a number, or three numbers [r, g, b]"),
            ("[defaults]\nrho = [0.5, 0.5]", "invalid length 2"),
            ("[defaults]\nemission = [1, 1, 1, 1]", "invalid length 4"),
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

    /// The view factor from a point at `p` with normal `n` to a planar polygon facing it, by
    /// Lambert's contour formula (independent of the code under test).
    fn point_view_factor(p: DVec3, n: DVec3, polygon: &[DVec3]) -> f64 {
        let k = polygon.len();
        let sum: f64 = (0..k)
            .map(|i| {
                let (a, b) = (polygon[i] - p, polygon[(i + 1) % k] - p);
                let c = a.cross(b);
                c.length().atan2(a.dot(b)) * n.dot(c) / c.length()
            })
            .sum();
        (sum / (2.0 * std::f64::consts::PI)).abs()
    }

    #[test]
    fn a_slightly_non_planar_quad_is_split_along_its_shorter_diagonal() {
        let dir = temp_dir("warped");
        // A quadrilateral at z = 1 facing down, vertex 3 lifted by delta (f32-exact values, as
        // tobj reads f32); diagonal 0-2 (2.02) is shorter than 1-3 (2.24).
        let delta = 2f64.powi(-10);
        let corners = [[0.0, 0.0, 1.0], [0.0, 1.0, 1.0], [1.75, 1.0, 1.0], [2.0, 0.0, 1.0 + delta]];
        let mut text = String::new();
        for c in corners {
            text += &format!("v {} {} {}\n", c[0], c[1], c[2]);
        }
        text += "g warped\nf 1 2 3 4\n";
        let p = write(&dir, "warped.obj", &text);
        let s = load(&p).unwrap();
        let names: Vec<&str> = s.faces.iter().map(|f| f.name.as_str()).collect();
        assert_eq!(names, ["warped.obj:6 (g warped)/t0", "warped.obj:6 (g warped)/t1"]);
        let v: Vec<DVec3> = corners.iter().map(|&c| DVec3::from_array(c)).collect();
        assert_eq!(s.faces[0].vertices, [v[0], v[1], v[2]]);
        assert_eq!(s.faces[1].vertices, [v[0], v[2], v[3]]);
        assert_eq!(s.notes.len(), 1, "{:?}", s.notes);
        assert!(s.notes[0].contains("split 1 non-planar"), "{:?}", s.notes);
        // Seen from points below, the two triangles' view factors sum to the flat quad's within
        // the quad's non-planarity relative to the point's distance (delta / height).
        let mut flat = v.clone();
        flat[3].z = 1.0;
        for p in [DVec3::new(1.0, 0.5, 0.0), DVec3::new(-0.5, 2.0, 0.3), DVec3::new(1.9, 0.1, 0.9)]
        {
            let halves: f64 =
                s.faces.iter().map(|f| point_view_factor(p, DVec3::Z, &f.vertices)).sum();
            let quad = point_view_factor(p, DVec3::Z, &flat);
            assert!((halves - quad).abs() <= delta / (1.0 - p.z), "{p}: {halves} vs {quad}");
            assert!((halves - quad).abs() > 1e-9, "{p}: the warp must show");
        }
        // Refused on request, naming the line.
        let refuse = ImportOptions { nonplanar: Some(NonPlanar::Refuse), ..Default::default() };
        let e = load_with(&p, refuse).unwrap_err().to_string();
        assert!(e.contains("warped.obj:6") && e.contains("not planar"), "{e}");
        // A typed TOML face is refused unless splitting is asked for.
        let toml = "[defaults]\nrho = 0.5\n[[faces]]\nname = \"w\"\n\
            vertices = [[0, 0, 1], [0, 1, 1], [1.75, 1, 1], [2, 0, 1.001]]\n";
        let t = write(&dir, "warped.toml", toml);
        assert!(load(&t).unwrap_err().to_string().contains("'w': not planar"));
        let split = ImportOptions { nonplanar: Some(NonPlanar::Split), ..Default::default() };
        assert_eq!(load_with(&t, split).unwrap().faces.len(), 2);
    }

    #[test]
    fn exact_duplicates_are_dropped_and_counted_partial_overlaps_refused() {
        let dir = temp_dir("dups");
        let square =
            "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0.5 0 0\nv 1.5 0 0\nv 1.5 1 0\nv 0.5 1 0\n";
        // Face 2 repeats face 1 from another vertex on; face 3 is its other side (a plate).
        let p = write(&dir, "dup.obj", &format!("{square}f 1 2 3 4\nf 3 4 1 2\nf 4 3 2 1\n"));
        let s = load(&p).unwrap();
        assert_eq!(s.faces.len(), 2);
        assert_eq!(s.notes.len(), 1);
        assert!(
            s.notes[0].contains("dropped 1 face") && s.notes[0].contains("'dup.obj:10"),
            "{:?}",
            s.notes
        );
        // Kept on request: then refused as overlapping, both named by line.
        let keep = ImportOptions { duplicates: Some(Duplicates::Refuse), ..Default::default() };
        let e = load_with(&p, keep).unwrap_err().to_string();
        assert!(e.contains("'dup.obj:9") && e.contains("'dup.obj:10") && e.contains("overlap"));
        // Half a square over another is no duplicate: refused.
        let p = write(&dir, "half.obj", &format!("{square}f 1 2 3 4\nf 5 6 7 8\n"));
        let e = load(&p).unwrap_err().to_string();
        assert!(e.contains("overlap") && e.contains("5e-1"), "{e}");
        // The same vertices with another material are no duplicate either.
        write(&dir, "two.mtl", "newmtl a\nKd 0.5 0.5 0.5\nnewmtl b\nKd 0.2 0.2 0.2\n");
        let text = format!("mtllib two.mtl\n{square}usemtl a\nf 1 2 3 4\nusemtl b\nf 1 2 3 4\n");
        let p = write(&dir, "two.obj", &text);
        assert!(load(&p).unwrap_err().to_string().contains("overlap"));
    }
}
