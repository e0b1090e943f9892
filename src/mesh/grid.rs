//! Cutting quadrilateral faces along lines parallel to their sides: the discontinuity mesh of the
//! paper's surfaces (sec. 3.1, Fig. 3.3), whose cuts follow the shadow lines of S1.

use glam::DVec3;

use crate::error::{Error, Result};
use crate::scene::{Diagonal, Face, Scene, SurfaceParameters};

/// Cuts of a parallelogram face `v0, v1, v2, v3` at parameters of its sides: a point is
/// `v0 + u (v1 - v0) + v (v3 - v0)`, cut at the given u and v in (0, 1).
#[derive(Clone, Debug, PartialEq)]
pub struct GridCuts {
    /// Face index.
    pub face: usize,
    /// Cut positions along v0 -> v1.
    pub u: Vec<f64>,
    /// Cut positions along v0 -> v3.
    pub v: Vec<f64>,
    /// The diagonal that splits every cell of the grid.
    pub diagonal: Diagonal,
}

/// Which diagonal splits the cells of S5 in the paper's discontinuity mesh.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum S5Diagonals {
    /// The other diagonal than the uniform mesh's: the paper's choice. Only this split reproduces
    /// Table 3.3's discontinuity rows to every printed digit (with the uniform mesh's diagonal E_n
    /// is about a third smaller from n = 120 on; docs/results.md).
    #[default]
    Paper,
    /// The same diagonal as the uniform mesh (S5's own).
    AsUniform,
}

/// The paper's discontinuity mesh cuts for the 4-piece and 5-piece surfaces: S1 along the shadow
/// lines x, y = 2B - C and 2B, and S5 at x = 2B - C and 2B so that it conforms with S1.
pub fn paper_discontinuity_cuts(
    scene: &Scene,
    p: &SurfaceParameters,
    s5_diagonals: S5Diagonals,
) -> Result<Vec<GridCuts>> {
    p.validate()?;
    let lines = [(2.0 * p.b - p.c) / p.a, 2.0 * p.b / p.a];
    let s1 = scene.face_index("S1").ok_or_else(|| Error::UnknownName {
        kind: "face",
        name: "S1".into(),
        expected: "the paper's surfaces (four-piece, five-piece)".into(),
    })?;
    let mut cuts = vec![GridCuts {
        face: s1,
        u: lines.to_vec(),
        v: lines.to_vec(),
        diagonal: scene.faces[s1].diagonal,
    }];
    if let Some(s5) = scene.face_index("S5") {
        let own = scene.faces[s5].diagonal;
        // S5 runs from x = A (v = 0) to x = 0 (v = 1).
        cuts.push(GridCuts {
            face: s5,
            u: vec![],
            v: lines.iter().rev().map(|l| 1.0 - l).collect(),
            diagonal: match s5_diagonals {
                S5Diagonals::Paper => own.other(),
                S5Diagonals::AsUniform => own,
            },
        });
    }
    Ok(cuts)
}

/// Triangles of a parallelogram face cut into a grid; each cell is split by the cuts' diagonal.
pub(crate) fn cut_quadrilateral(face: &Face, cuts: &GridCuts) -> Result<Vec<[DVec3; 3]>> {
    let v = &face.vertices;
    let is_parallelogram =
        v.len() == 4 && ((v[1] - v[0]) - (v[2] - v[3])).length() <= 1e-12 * face.size();
    let bad = |value: &str, reason: &str| Error::InvalidParameter {
        name: "discontinuity cuts",
        value: format!("face '{}' {value}", face.name),
        reason: reason.into(),
    };
    if !is_parallelogram {
        return Err(bad("", "grid cuts need a parallelogram face"));
    }
    let breaks = |c: &[f64]| -> Result<Vec<f64>> {
        let mut b = vec![0.0];
        for &t in c {
            if !(t > *b.last().expect("non-empty") && t < 1.0) {
                return Err(bad(&format!("cut {t}"), "cuts must increase strictly inside (0, 1)"));
            }
            b.push(t);
        }
        b.push(1.0);
        Ok(b)
    };
    let (us, vs) = (breaks(&cuts.u)?, breaks(&cuts.v)?);
    let point = |u: f64, w: f64| v[0] + (v[1] - v[0]) * u + (v[3] - v[0]) * w;
    let mut tris = Vec::new();
    for j in 0..vs.len() - 1 {
        for i in 0..us.len() - 1 {
            let c00 = point(us[i], vs[j]);
            let c10 = point(us[i + 1], vs[j]);
            let c11 = point(us[i + 1], vs[j + 1]);
            let c01 = point(us[i], vs[j + 1]);
            match cuts.diagonal {
                Diagonal::FromFirst => tris.extend([[c00, c10, c11], [c00, c11, c01]]),
                Diagonal::FromSecond => tris.extend([[c00, c10, c01], [c10, c11, c01]]),
            }
        }
    }
    Ok(tris)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::{Mesh, MeshKind};
    use crate::scene::{five_piece, four_piece};

    #[test]
    fn discontinuity_meshes_have_the_paper_sizes() {
        let p = SurfaceParameters::default();
        for (refine, n4, n5) in [(0, 24, 30), (1, 96, 120), (2, 384, 480), (3, 1536, 1920)] {
            for (scene, n) in [(four_piece(p).unwrap(), n4), (five_piece(p).unwrap(), n5)] {
                let cuts = paper_discontinuity_cuts(&scene, &p, S5Diagonals::Paper).unwrap();
                let mesh = Mesh::new(&scene, &MeshKind::Discontinuity(cuts), refine).unwrap();
                assert_eq!(mesh.len(), n, "{} refine {refine}", scene.name);
            }
        }
    }

    #[test]
    fn no_element_of_s1_crosses_a_shadow_line() {
        let p = SurfaceParameters::default();
        let scene = five_piece(p).unwrap();
        let cuts = paper_discontinuity_cuts(&scene, &p, S5Diagonals::Paper).unwrap();
        let mesh = Mesh::new(&scene, &MeshKind::Discontinuity(cuts), 2).unwrap();
        for e in mesh.elements().iter().filter(|e| e.face == 0 || e.face == 4) {
            for line in [3.0, 4.0] {
                let xs = e.vertices.map(|v| v.x - line);
                assert!(!(xs.iter().any(|&d| d < -1e-12) && xs.iter().any(|&d| d > 1e-12)));
                if e.face == 0 {
                    let ys = e.vertices.map(|v| v.y - line);
                    assert!(!(ys.iter().any(|&d| d < -1e-12) && ys.iter().any(|&d| d > 1e-12)));
                }
            }
        }
    }
}
