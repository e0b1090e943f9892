//! Faces from polygons: unique names, non-planar polygons split into planar triangles, exact
//! duplicates dropped, and a note on each kind of repair.

use std::collections::{HashMap, HashSet};

use glam::DVec3;

use super::schema::{Channels, Properties};
use super::{Coplanar, Duplicates, ImportOptions, NonPlanar, Side};
use crate::error::{Error, Result};
use crate::scene::{Colour, Face, Scene, merge_coplanar};

impl ImportOptions {
    /// The rules for polygons read from OBJ/STL files: split and drop unless told otherwise.
    pub(super) fn for_meshes(self) -> Rules {
        Rules {
            split: self.nonplanar.unwrap_or(NonPlanar::Split) == NonPlanar::Split,
            drop: self.duplicates.unwrap_or(Duplicates::Drop) == Duplicates::Drop,
            merge: self.coplanar.unwrap_or(Coplanar::Merge) == Coplanar::Merge,
        }
    }

    /// The rules for faces typed into a TOML file: refuse unless told otherwise.
    pub(super) fn for_typed_faces(self) -> Rules {
        Rules {
            split: self.nonplanar == Some(NonPlanar::Split),
            drop: self.duplicates == Some(Duplicates::Drop),
            merge: false,
        }
    }
}

/// Whether non-planar polygons are split, exact duplicates dropped and coplanar triangles
/// merged.
#[derive(Clone, Copy)]
pub(super) struct Rules {
    split: bool,
    drop: bool,
    merge: bool,
}

/// Collects a file's faces: unique names, non-planar polygons split, exact duplicates dropped,
/// and what was done, for [`Scene::notes`].
pub(super) struct Builder {
    rules: Rules,
    faces: Vec<Face>,
    /// Per face, whether it may be merged with coplanar neighbours (a mesh's one-sided faces).
    mergeable: Vec<bool>,
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
    pub(super) fn new(rules: Rules) -> Self {
        Self {
            rules,
            faces: Vec::new(),
            mergeable: Vec::new(),
            names: HashSet::new(),
            seen: HashMap::new(),
            split: Vec::new(),
            dropped: Vec::new(),
        }
    }

    /// The same faces and records, under other rules.
    pub(super) fn continued(self, rules: Rules) -> Self {
        Self { rules, ..self }
    }

    /// Adds the face (or the two faces of a double-sided plate) for one polygon.
    pub(super) fn push(
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
                // The two sides of a plate would merge each their own way, into polygons
                // that no longer cover each other.
                self.mergeable.push(self.rules.merge && side != Side::Both);
            }
        }
        Ok(())
    }

    /// The scene, with a note on each kind of repair made.
    pub(super) fn finish(self, name: String) -> Result<Scene> {
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
        let (faces, merged) = merge_coplanar(self.faces, &self.mergeable);
        if merged.to < merged.from {
            notes.push(format!(
                "faces_merged: {} -> {}: coplanar triangles that share edges and properties \
                 joined into planar faces for visibility, the triangles kept as elements; \
                 --coplanar keep to keep them apart",
                merged.from, merged.to
            ));
        }
        let mut scene = Scene::new(name, faces)?;
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
