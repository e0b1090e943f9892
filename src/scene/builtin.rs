//! Built-in scenes: the paper's 4-piece and 5-piece surfaces (sec. 3.1) and closed enclosures
//! used for identity checks (Lemma 2.1: inside a closed surface every row of K/rho sums to 1).

use std::fmt;
use std::str::FromStr;

use glam::DVec3;

use super::{Face, Scene};
use crate::error::{Error, Result};

/// Parameters (A, B, C) of the paper's surfaces; the paper uses (5, 2, 1).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SurfaceParameters {
    /// Side of S1 (and length of S5).
    pub a: f64,
    /// Side of the occluding square S2/S3.
    pub b: f64,
    /// Side of S4.
    pub c: f64,
}

impl Default for SurfaceParameters {
    /// The paper's (A, B, C) = (5, 2, 1).
    fn default() -> Self {
        Self { a: 5.0, b: 2.0, c: 1.0 }
    }
}

impl SurfaceParameters {
    /// Checks (3.1): C < B, 2B < A, all positive and finite.
    pub fn validate(&self) -> Result<()> {
        let Self { a, b, c } = *self;
        let finite = a.is_finite() && b.is_finite() && c.is_finite();
        if !(finite && c > 0.0 && c < b && 2.0 * b < a) {
            return Err(Error::InvalidSurfaceParameters { a, b, c });
        }
        Ok(())
    }
}

/// The built-in scenes, by their command-line names.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BuiltinScene {
    /// `four-piece`: S1..S4 of sec. 3.1.
    FourPiece,
    /// `five-piece`: the 4-piece surface and S5.
    FivePiece,
    /// `cube`: the closed unit cube, inner normals.
    Cube,
    /// `baffled-box`: the closed unit box with a floating double-sided plate inside.
    BaffledBox,
}

impl BuiltinScene {
    /// All built-in scenes.
    pub const ALL: [Self; 4] = [Self::FourPiece, Self::FivePiece, Self::Cube, Self::BaffledBox];

    /// Command-line name.
    pub fn name(&self) -> &'static str {
        match self {
            Self::FourPiece => "four-piece",
            Self::FivePiece => "five-piece",
            Self::Cube => "cube",
            Self::BaffledBox => "baffled-box",
        }
    }

    /// Builds the scene; `params` is used by the paper's surfaces only.
    pub fn build(&self, params: SurfaceParameters) -> Result<Scene> {
        match self {
            Self::FourPiece => four_piece(params),
            Self::FivePiece => five_piece(params),
            Self::Cube => cube(),
            Self::BaffledBox => baffled_box(),
        }
    }

    /// Whether this is one of the paper's surfaces (where the true solutions of sec. 3.2 live).
    pub fn is_paper_surface(&self) -> bool {
        matches!(self, Self::FourPiece | Self::FivePiece)
    }
}

impl fmt::Display for BuiltinScene {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for BuiltinScene {
    type Err = Error;
    fn from_str(s: &str) -> Result<Self> {
        Self::ALL.into_iter().find(|b| b.name() == s).ok_or_else(|| Error::UnknownName {
            kind: "scene",
            name: s.to_string(),
            expected: format!(
                "{}, city:NXxNY (a generated city), or a scene file FILE.toml, FILE.obj or \
                 FILE.stl",
                Self::ALL.map(|b| b.name()).join(", ")
            ),
        })
    }
}

/// The parallelogram `origin, origin + u, origin + u + v, origin + v`; its normal is along u × v.
fn parallelogram(name: &str, origin: DVec3, u: DVec3, v: DVec3, rho: f64) -> Result<Face> {
    Face::new(name, vec![origin, origin + u, origin + u + v, origin + v], rho)
}

fn paper_faces(p: SurfaceParameters) -> Result<Vec<Face>> {
    p.validate()?;
    let SurfaceParameters { a, b, c } = p;
    // rho = 1 on every face (paper sec. 3.2). Vertex 0 of each square is its (0, 0) corner, so the
    // default diagonal runs from (0, 0) to the opposite corner, as in sec. 3.1.
    Ok(vec![
        parallelogram("S1", DVec3::ZERO, DVec3::new(a, 0.0, 0.0), DVec3::new(0.0, a, 0.0), 1.0)?,
        parallelogram("S2", DVec3::Z, DVec3::new(0.0, b, 0.0), DVec3::new(b, 0.0, 0.0), 1.0)?,
        parallelogram("S3", DVec3::Z, DVec3::new(b, 0.0, 0.0), DVec3::new(0.0, b, 0.0), 1.0)?,
        parallelogram(
            "S4",
            DVec3::new(0.0, 0.0, 2.0),
            DVec3::new(0.0, c, 0.0),
            DVec3::new(c, 0.0, 0.0),
            1.0,
        )?,
    ])
}

/// The 4-piece surface: S1 = [0,A]² at z = 0 (normal +z), S2/S3 the bottom/top of [0,B]² at z = 1,
/// S4 = [0,C]² at z = 2 (normal -z).
pub fn four_piece(p: SurfaceParameters) -> Result<Scene> {
    Scene::new("four-piece", paper_faces(p)?)
}

/// The 5-piece surface: the 4-piece surface and S5 = {y = A, 0 <= x <= A, 0 <= z <= 1} (normal -y).
/// Vertex 0 of S5 is (A, A, 0), so its default diagonal runs from (A, A, 0) to (0, A, 1): the choice
/// that reproduces the paper's 5-piece columns.
pub fn five_piece(p: SurfaceParameters) -> Result<Scene> {
    let mut faces = paper_faces(p)?;
    let a = p.a;
    faces.push(parallelogram(
        "S5",
        DVec3::new(a, a, 0.0),
        DVec3::new(0.0, 0.0, 1.0),
        DVec3::new(-a, 0.0, 0.0),
        1.0,
    )?);
    Scene::new("five-piece", faces)
}

/// The six inward-facing faces of the box [lo, hi].
fn box_faces(lo: DVec3, hi: DVec3, rho: f64) -> Result<Vec<Face>> {
    let d = hi - lo;
    let (x, y, z) =
        (DVec3::new(d.x, 0.0, 0.0), DVec3::new(0.0, d.y, 0.0), DVec3::new(0.0, 0.0, d.z));
    Ok(vec![
        parallelogram("bottom", lo, x, y, rho)?,
        parallelogram("top", lo + z, y, x, rho)?,
        parallelogram("front", lo, z, x, rho)?,
        parallelogram("back", lo + y, x, z, rho)?,
        parallelogram("left", lo, y, z, rho)?,
        parallelogram("right", lo + x, z, y, rho)?,
    ])
}

/// The closed unit cube with inner normals, rho = 0.5, the top face emitting E = 1.
pub fn cube() -> Result<Scene> {
    let mut faces = box_faces(DVec3::ZERO, DVec3::ONE, 0.5)?;
    faces[1] = faces[1].clone().with_emission(1.0)?;
    Scene::new("cube", faces)
}

/// The closed unit box with a floating double-sided square plate (x = 0.5, 0.2 <= y, z <= 0.8),
/// which hides part of the box from itself; rho = 0.5, the top face emitting E = 1.
pub fn baffled_box() -> Result<Scene> {
    let mut faces = box_faces(DVec3::ZERO, DVec3::ONE, 0.5)?;
    faces[1] = faces[1].clone().with_emission(1.0)?;
    let corner = DVec3::new(0.5, 0.2, 0.2);
    let (y, z) = (DVec3::new(0.0, 0.6, 0.0), DVec3::new(0.0, 0.0, 0.6));
    faces.push(parallelogram("baffle-left", corner, z, y, 0.5)?);
    faces.push(parallelogram("baffle-right", corner, y, z, 0.5)?);
    Scene::new("baffled-box", faces)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn paper_faces_have_the_inner_normals_of_sec_3_1() {
        let s = five_piece(SurfaceParameters::default()).unwrap();
        let normals: Vec<DVec3> = s.faces.iter().map(|f| f.frame.normal).collect();
        let want = [DVec3::Z, -DVec3::Z, DVec3::Z, -DVec3::Z, -DVec3::Y];
        for (k, (n, w)) in normals.iter().zip(want).enumerate() {
            assert!((*n - w).length() < 1e-15, "S{}: {n}", k + 1);
        }
        assert!((s.area() - (25.0 + 4.0 + 4.0 + 1.0 + 5.0)).abs() < 1e-12);
        assert!(s.coplanar(1, 2), "S2 and S3 lie in one plane");
        assert!(!s.coplanar(0, 4));
    }

    #[test]
    fn parameters_violating_3_1_are_rejected() {
        for (a, b, c) in [(5.0, 2.0, 2.0), (4.0, 2.0, 1.0), (5.0, 2.0, -1.0), (f64::NAN, 2.0, 1.0)]
        {
            let e = four_piece(SurfaceParameters { a, b, c }).unwrap_err();
            assert!(matches!(e, Error::InvalidSurfaceParameters { .. }), "{e}");
        }
    }

    #[test]
    fn enclosures_face_inwards() {
        for scene in [cube().unwrap(), baffled_box().unwrap()] {
            let centre = DVec3::splat(0.5) + DVec3::new(0.0, 0.01, 0.0);
            for f in scene.faces.iter().take(6) {
                assert!(f.frame.height(centre) > 0.0, "{} faces outwards", f.name);
            }
        }
        assert_eq!("baffled-box".parse::<BuiltinScene>().unwrap(), BuiltinScene::BaffledBox);
        let e = "sphere".parse::<BuiltinScene>().unwrap_err().to_string();
        assert!(e.contains("'sphere'") && e.contains("four-piece"), "{e}");
    }
}
