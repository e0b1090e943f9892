//! A planar polygonal face: validated geometry, its frame, reflectivity and emissivity.

use glam::{DVec2, DVec3};

use crate::error::{Error, Result};
use crate::geometry::PlaneFrame;

/// Which diagonal splits a quadrilateral face into its two initial triangles (paper sec. 3.1).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Diagonal {
    /// From vertex 0 to vertex 2.
    #[default]
    FromFirst,
    /// From vertex 1 to vertex 3.
    FromSecond,
}

impl Diagonal {
    /// The other diagonal of the quadrilateral.
    pub fn other(self) -> Self {
        match self {
            Self::FromFirst => Self::FromSecond,
            Self::FromSecond => Self::FromFirst,
        }
    }
}

/// A planar polygon whose vertices run counter-clockwise about its normal; the normal points to the
/// side that radiates and receives (the paper's inner normal).
#[derive(Clone, Debug)]
pub struct Face {
    /// Name, unique in its scene.
    pub name: String,
    /// Vertices, counter-clockwise about the normal.
    pub vertices: Vec<DVec3>,
    /// Frame of the face's plane: origin at vertex 0, first axis along the first edge.
    pub frame: PlaneFrame,
    /// Reflectivity rho in [0, 1].
    pub rho: f64,
    /// Emissivity E (constant over the face), for emission-driven scenes.
    pub emission: f64,
    /// The diagonal used when the face is a quadrilateral split into two triangles.
    pub diagonal: Diagonal,
    /// Red, green and blue channels of rho and E where the scene gives them (an OBJ material's
    /// Kd and Ke); `rho` and `emission` are then their means.
    pub colour: Colour,
    /// The triangles the face was merged from, where it joins coplanar triangles of an imported
    /// mesh ([`crate::scene::merge_coplanar`]): they stay its initial elements. Empty: the mesh
    /// triangulates the polygon.
    pub triangles: Vec<[DVec3; 3]>,
}

/// The colour channels (r, g, b) behind a face's rho and E; `None`: grey (every channel equals
/// the scalar).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Colour {
    /// rho per channel.
    pub rho: Option<[f64; 3]>,
    /// E per channel.
    pub emission: Option<[f64; 3]>,
}

/// The names of the colour channels, in order.
pub const CHANNELS: [&str; 3] = ["r", "g", "b"];

crate::vocabulary::named_options! {
    /// The sets of colour bands named as a whole (`--bands`); any other value lists channels.
    #[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
    pub enum BandSet as "bands" {
        /// One grey band: each face's rho and E (the channels' means where it has colour)
        Grey = "grey" default,
        /// Every channel of CHANNELS, in order
        Rgb = "rgb",
    }
}

/// The channels of `--bands`: a [`BandSet`]'s name, or channel names of [`CHANNELS`],
/// comma-separated, each once. Empty: grey.
pub fn parse_bands(text: &str) -> Result<Vec<usize>> {
    match text.parse::<BandSet>() {
        Ok(BandSet::Grey) => return Ok(Vec::new()),
        Ok(BandSet::Rgb) => return Ok((0..CHANNELS.len()).collect()),
        Err(_) => {}
    }
    let mut channels = Vec::new();
    for name in text.split(',').map(str::trim) {
        let channel =
            CHANNELS.iter().position(|&c| c == name).ok_or_else(|| Error::UnknownName {
                kind: "band",
                name: name.into(),
                expected: format!(
                    "{}, or a comma-separated list of {}",
                    <BandSet as crate::vocabulary::Named>::names().collect::<Vec<_>>().join(", "),
                    CHANNELS.join(", ")
                ),
            })?;
        if channels.contains(&channel) {
            return Err(Error::InvalidParameter {
                name: "bands",
                value: text.into(),
                reason: format!("band '{name}' is named twice"),
            });
        }
        channels.push(channel);
    }
    Ok(channels)
}

/// Largest coordinate magnitude accepted. The pair plan and the face checks work with fourth
/// powers of lengths (squared lengths of vector areas, cross products of cross products), which
/// must stay inside f64's normal range: lengths within [1e-50, 1e50] keep them there.
pub const MAX_COORDINATE: f64 = 1e50;

/// Smallest area of a face, of the triangle at each of its corners and of each triangle of its
/// triangulation, relative to the squared size: an aspect ratio up to about 1e10. Thinner
/// triangles have normals set by the rounding of their coordinates (fuzzing found a 1e12 sliver
/// whose normal was off by 1e-2), and no visibility decision about them can be trusted.
pub const MIN_RELATIVE_AREA: f64 = 1e-10;

/// Smallest face size (diameter) accepted; see [`MAX_COORDINATE`].
pub const MIN_FACE_SIZE: f64 = 1e-50;

/// Faces whose planes are this close (relative to their size) and ...
pub const COPLANAR_DISTANCE: f64 = 1e-9;
/// ... this parallel (radians) count as one plane.
const COPLANAR_ANGLE: f64 = 1e-6;

/// Relative tolerance (of the face's size) for planarity.
pub(crate) const PLANARITY: f64 = 1e-9;

impl Face {
    /// A face from its vertices (counter-clockwise about the radiating side) and reflectivity.
    /// Rejects non-finite coordinates, fewer than three vertices, zero area, non-planar or
    /// self-intersecting polygons and rho outside [0, 1].
    pub fn new(name: impl Into<String>, vertices: Vec<DVec3>, rho: f64) -> Result<Self> {
        let name = name.into();
        if vertices.len() < 3 {
            return Err(Error::TooFewVertices { face: name, count: vertices.len() });
        }
        if let Some((k, v)) = vertices.iter().enumerate().find(|(_, v)| !v.is_finite()) {
            return Err(Error::NonFiniteVertex { face: name, vertex: k, x: v.x, y: v.y, z: v.z });
        }
        if let Some((k, v)) =
            vertices.iter().enumerate().find(|(_, v)| v.abs().max_element() > MAX_COORDINATE)
        {
            return Err(Error::CoordinateOutOfRange {
                face: name,
                vertex: k,
                magnitude: v.abs().max_element(),
                limit: MAX_COORDINATE,
            });
        }
        if !(0.0..=1.0).contains(&rho) {
            return Err(Error::ReflectivityOutOfRange { face: name, rho });
        }
        let size = diameter(&vertices);
        if size < MIN_FACE_SIZE {
            return Err(Error::DegenerateFace { face: name, area: 0.0, size });
        }
        // Newell's method: twice the vector area, robust for non-convex polygons.
        let centre = vertices.iter().sum::<DVec3>() / vertices.len() as f64;
        let n = vertices.len();
        let twice_area: DVec3 =
            (0..n).map(|k| (vertices[k] - centre).cross(vertices[(k + 1) % n] - centre)).sum();
        let area = 0.5 * twice_area.length();
        if area.is_nan() || area <= MIN_RELATIVE_AREA * size * size {
            return Err(Error::DegenerateFace { face: name, area, size });
        }
        // A vertex on the line through its neighbours makes a degenerate triangle in the face's
        // triangulation (and a zero-area element with an infinite basis gradient).
        for k in 0..n {
            let (a, b, c) = (vertices[(k + n - 1) % n], vertices[k], vertices[(k + 1) % n]);
            let corner = 0.5 * (b - a).cross(c - b).length();
            if corner.is_nan() || corner <= MIN_RELATIVE_AREA * size * size {
                return Err(Error::CollinearVertex { face: name, vertex: k });
            }
        }
        let normal = twice_area / (2.0 * area);
        // Coordinates far from the origin carry a rounding error of ε |v| that no planarity test
        // can see through; a triangle is planar whatever its coordinates.
        let magnitude = vertices.iter().map(|v| v.abs().max_element()).fold(0.0, f64::max);
        let tolerance = PLANARITY * size + 64.0 * f64::EPSILON * magnitude;
        for (k, &v) in vertices.iter().enumerate().filter(|_| n > 3) {
            let distance = (v - centre).dot(normal).abs();
            if distance > tolerance {
                return Err(Error::NonPlanarFace { face: name, vertex: k, distance, tolerance });
            }
        }
        let frame = plane_frame(&vertices, normal, size).ok_or(Error::DegenerateFace {
            face: name.clone(),
            area,
            size,
        })?;
        let face = Self {
            name,
            vertices,
            frame,
            rho,
            emission: 0.0,
            diagonal: Diagonal::default(),
            colour: Colour::default(),
            triangles: Vec::new(),
        };
        face.check_simple()?;
        Ok(face)
    }

    /// The same face moved by `-offset`, its frame computed anew from the moved vertices. With an
    /// offset chosen as in [`crate::scene::Scene::new`] the subtraction is exact, so the face is
    /// the same one, described in coordinates whose rounding is relative to the scene's size.
    pub(crate) fn moved_by(&self, offset: DVec3) -> Self {
        let vertices: Vec<DVec3> = self.vertices.iter().map(|v| *v - offset).collect();
        let centre = vertices.iter().sum::<DVec3>() / vertices.len() as f64;
        let n = vertices.len();
        let twice_area: DVec3 =
            (0..n).map(|k| (vertices[k] - centre).cross(vertices[(k + 1) % n] - centre)).sum();
        let frame = plane_frame(&vertices, twice_area.normalize(), self.size())
            .expect("a validated face keeps its first edge when moved");
        let triangles = self.triangles.iter().map(|t| t.map(|v| v - offset)).collect();
        Self { vertices, frame, triangles, ..self.clone() }
    }

    /// Sets the emissivity (finite, non-negative).
    pub fn with_emission(mut self, emission: f64) -> Result<Self> {
        if !(emission.is_finite() && emission >= 0.0) {
            return Err(Error::InvalidEmission { face: self.name, value: emission });
        }
        self.emission = emission;
        Ok(self)
    }

    /// The face with the triangles it was merged from as its initial elements.
    pub(crate) fn with_triangles(mut self, triangles: Vec<[DVec3; 3]>) -> Self {
        self.triangles = triangles;
        self
    }

    /// Sets the colour channels (rho in [0, 1], E finite and non-negative).
    pub fn with_colour(mut self, colour: Colour) -> Result<Self> {
        for (k, &rho) in colour.rho.iter().flatten().enumerate() {
            if !(0.0..=1.0).contains(&rho) {
                let face = format!("{} (channel {})", self.name, CHANNELS[k]);
                return Err(Error::ReflectivityOutOfRange { face, rho });
            }
        }
        for (k, &value) in colour.emission.iter().flatten().enumerate() {
            if !(value.is_finite() && value >= 0.0) {
                let face = format!("{} (channel {})", self.name, CHANNELS[k]);
                return Err(Error::InvalidEmission { face, value });
            }
        }
        self.colour = colour;
        Ok(self)
    }

    /// rho and E in colour channel `channel` (0, 1, 2: r, g, b); a grey face's in every channel.
    pub fn channel(&self, channel: usize) -> (f64, f64) {
        (
            self.colour.rho.map_or(self.rho, |c| c[channel]),
            self.colour.emission.map_or(self.emission, |c| c[channel]),
        )
    }

    /// Sets the diagonal of a quadrilateral.
    pub fn with_diagonal(mut self, diagonal: Diagonal) -> Self {
        self.diagonal = diagonal;
        self
    }

    /// Checks a normal given alongside the vertices: it must be non-zero and agree with the
    /// normal implied by the vertex order.
    pub fn check_normal(&self, given: DVec3) -> Result<()> {
        let unit = given.normalize_or_zero();
        if !given.is_finite() || unit == DVec3::ZERO || unit.dot(self.frame.normal) < 1.0 - 1e-6 {
            let e = self.frame.normal;
            return Err(Error::InconsistentNormal {
                face: self.name.clone(),
                x: given.x,
                y: given.y,
                z: given.z,
                expected: [e.x, e.y, e.z],
            });
        }
        Ok(())
    }

    /// Whether this face and `other` lie in one plane (either orientation), up to the planarity
    /// tolerance of a face (1e-9 of the larger size) and a 1e-6 angle between their normals.
    /// See [`crate::scene::Scene::coplanar`].
    pub fn is_coplanar_with(&self, other: &Face) -> bool {
        self.is_coplanar_at_size(other, || self.size().max(other.size()))
    }

    /// As [`Face::is_coplanar_with`], the larger size of the two faces given (measured only for
    /// faces with parallel normals): for callers that keep the sizes.
    pub fn is_coplanar_at_size(&self, other: &Face, size: impl FnOnce() -> f64) -> bool {
        // Squared, without a square root: pair plans and cross approximations ask this of
        // many (node, element) pairs.
        let sine_squared = self.frame.normal.cross(other.frame.normal).length_squared();
        if sine_squared >= COPLANAR_ANGLE * COPLANAR_ANGLE {
            return false; // most pairs: decided before the sizes are measured
        }
        let tol = COPLANAR_DISTANCE * size();
        other.vertices.iter().all(|&v| self.frame.height(v).abs() <= tol)
            && self.vertices.iter().all(|&v| other.frame.height(v).abs() <= tol)
    }

    /// Vertices in the face frame's 2-D coordinates (counter-clockwise).
    pub fn local_polygon(&self) -> Vec<DVec2> {
        self.vertices.iter().map(|&v| self.frame.to_plane(v)).collect()
    }

    /// Area.
    pub fn area(&self) -> f64 {
        crate::geometry::signed_area(&self.local_polygon())
    }

    /// Smallest and largest corner of the axis-aligned box around the face.
    pub fn bounding_box(&self) -> (DVec3, DVec3) {
        crate::geometry::bounding_box_3d(&self.vertices)
    }

    /// Largest distance between two vertices.
    pub fn size(&self) -> f64 {
        diameter(&self.vertices)
    }

    /// Whether the polygon is convex.
    pub fn is_convex(&self) -> bool {
        let p = self.local_polygon();
        let n = p.len();
        (0..n).all(|k| {
            let (a, b, c) = (p[k], p[(k + 1) % n], p[(k + 2) % n]);
            (b - a).perp_dot(c - b) >= -1e-12 * self.size() * self.size()
        })
    }

    fn check_simple(&self) -> Result<()> {
        let p = self.local_polygon();
        let n = p.len();
        for i in 0..n {
            for j in i + 1..n {
                let adjacent = j == i + 1 || (i == 0 && j == n - 1);
                if adjacent {
                    continue;
                }
                if segments_cross(p[i], p[(i + 1) % n], p[j], p[(j + 1) % n]) {
                    return Err(Error::SelfIntersectingFace {
                        face: self.name.clone(),
                        first: i,
                        second: j,
                    });
                }
            }
        }
        // Visibility splits non-convex faces into triangles: a face must have a triangulation,
        // so that no later step can lose its pieces.
        if !self.is_convex() && crate::geometry::triangulate(&p).is_none() {
            return Err(Error::DegenerateFace {
                face: self.name.clone(),
                area: self.area(),
                size: self.size(),
            });
        }
        Ok(())
    }
}

/// The frame of a face's plane: origin at vertex 0, first axis along the first edge that is not
/// negligibly short.
fn plane_frame(vertices: &[DVec3], normal: DVec3, size: f64) -> Option<PlaneFrame> {
    let first_edge = (1..vertices.len())
        .map(|k| vertices[k] - vertices[0])
        .find(|d| d.length() > 1e-12 * size)?;
    Some(PlaneFrame::new(vertices[0], normal, first_edge))
}

fn diameter(points: &[DVec3]) -> f64 {
    let mut d: f64 = 0.0;
    for (k, a) in points.iter().enumerate() {
        for b in &points[k + 1..] {
            d = d.max((*a - *b).length());
        }
    }
    d
}

/// Whether closed segments ab and cd share a point.
fn segments_cross(a: DVec2, b: DVec2, c: DVec2, d: DVec2) -> bool {
    let orient = |p: DVec2, q: DVec2, r: DVec2| (q - p).perp_dot(r - p);
    let (d1, d2) = (orient(c, d, a), orient(c, d, b));
    let (d3, d4) = (orient(a, b, c), orient(a, b, d));
    if ((d1 > 0.0 && d2 < 0.0) || (d1 < 0.0 && d2 > 0.0))
        && ((d3 > 0.0 && d4 < 0.0) || (d3 < 0.0 && d4 > 0.0))
    {
        return true;
    }
    let on = |p: DVec2, q: DVec2, r: DVec2| {
        orient(p, q, r) == 0.0 && r.cmpge(p.min(q)).all() && r.cmple(p.max(q)).all()
    };
    on(c, d, a) || on(c, d, b) || on(a, b, c) || on(a, b, d)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn square() -> Vec<DVec3> {
        vec![DVec3::ZERO, DVec3::X, DVec3::new(1.0, 1.0, 0.0), DVec3::Y]
    }

    #[test]
    fn a_unit_square_has_normal_z_and_area_one() {
        let f = Face::new("sq", square(), 0.5).unwrap();
        assert!((f.frame.normal - DVec3::Z).length() < 1e-15);
        assert!((f.area() - 1.0).abs() < 1e-15);
        assert!(f.is_convex());
    }

    #[test]
    fn bad_faces_are_rejected_with_the_culprit_named() {
        let mut v = square();
        v[2].y = f64::NAN;
        let e = Face::new("bad", v, 0.5).unwrap_err().to_string();
        assert!(e.contains("'bad'") && e.contains("vertex 2"), "{e}");

        let mut v = square();
        v[2].z = 0.1;
        let e = Face::new("warped", v, 0.5).unwrap_err().to_string();
        assert!(e.contains("not planar"), "{e}");

        let v = vec![DVec3::ZERO, DVec3::X, DVec3::new(2.0, 0.0, 0.0)];
        assert!(matches!(Face::new("line", v, 0.5), Err(Error::DegenerateFace { .. })));

        let e = Face::new("rho", square(), 1.5).unwrap_err().to_string();
        assert!(e.contains("rho = 1.5"), "{e}");

        let bowtie = vec![
            DVec3::ZERO,
            DVec3::new(3.0, 1.0, 0.0),
            DVec3::new(3.0, 0.0, 0.0),
            DVec3::new(0.0, 2.0, 0.0),
        ];
        assert!(matches!(
            Face::new("bowtie", bowtie, 0.5),
            Err(Error::SelfIntersectingFace { .. })
        ));

        // Found by the fuzzer: a quadrilateral with three collinear vertices, whose diagonal
        // split made a triangle without area (and NaN basis functions).
        let kinked = vec![DVec3::ZERO, DVec3::X, DVec3::new(2.0, 0.0, 0.0), DVec3::Y];
        let e = Face::new("kinked", kinked, 0.5).unwrap_err().to_string();
        assert!(e.contains("'kinked'") && e.contains("vertex 1"), "{e}");

        let f = Face::new("sq", square(), 0.5).unwrap();
        assert!(f.check_normal(-DVec3::Z).is_err());
        assert!(f.check_normal(DVec3::ZERO).is_err());
        assert!(f.check_normal(DVec3::Z * 3.0).is_ok());
        assert!(f.clone().with_emission(-1.0).is_err());
    }

    #[test]
    fn non_convex_polygons_are_accepted_and_flagged() {
        let l_shape = vec![
            DVec3::ZERO,
            DVec3::new(2.0, 0.0, 0.0),
            DVec3::new(2.0, 1.0, 0.0),
            DVec3::new(1.0, 1.0, 0.0),
            DVec3::new(1.0, 2.0, 0.0),
            DVec3::new(0.0, 2.0, 0.0),
        ];
        let f = Face::new("L", l_shape, 0.5).unwrap();
        assert!(!f.is_convex());
        assert!((f.area() - 3.0).abs() < 1e-14);
    }
}
