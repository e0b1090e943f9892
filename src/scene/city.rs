//! A generated urban scene for scaling tests: a grid of buildings (roof and four walls each, of
//! varying heights) on a ground made of the street rectangles between them, about 8 faces per
//! building. Every face is a rectangle; the ground is not under the buildings, so no face lies
//! inside a solid.

use glam::DVec3;

use super::{Face, Scene};
use crate::error::{Error, Result};

/// Footprint side of a building and width of a street.
const BLOCK: f64 = 10.0;
const STREET: f64 = 6.0;

/// Height of the sky panel of a lit city: above the tallest building (40).
const SKY_HEIGHT: f64 = 60.0;

/// The city of `nx` x `ny` buildings; rho 0.3 for the ground, 0.6 for the buildings.
pub fn city(nx: usize, ny: usize) -> Result<Scene> {
    Scene::new(format!("city-{nx}x{ny}"), city_faces(nx, ny)?)
}

/// The city of `nx` x `ny` buildings under a sky: one rectangle over the whole city at height
/// [`SKY_HEIGHT`], facing down, emitting E = 1 and reflecting nothing, so that `solve` has light
/// to spread (`city:NXxNY:lit`).
pub fn lit_city(nx: usize, ny: usize) -> Result<Scene> {
    let mut faces = city_faces(nx, ny)?;
    let (lo, hi) = faces.iter().fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(lo, hi), f| {
        let (a, b) = f.bounding_box();
        (lo.min(a), hi.max(b))
    });
    let z = SKY_HEIGHT;
    let corners = [(lo.x, lo.y), (lo.x, hi.y), (hi.x, hi.y), (hi.x, lo.y)];
    let sky = corners.iter().map(|&(x, y)| DVec3::new(x, y, z)).collect();
    faces.push(Face::new("sky", sky, 0.0)?.with_emission(1.0)?);
    Scene::new(format!("city-{nx}x{ny}-lit"), faces)
}

/// The faces of the city of `nx` x `ny` buildings.
fn city_faces(nx: usize, ny: usize) -> Result<Vec<Face>> {
    if nx == 0 || ny == 0 || nx * ny > 100_000 {
        return Err(Error::InvalidParameter {
            name: "city",
            value: format!("{nx}x{ny}"),
            reason: "between 1 and 100000 buildings".into(),
        });
    }
    // Grid lines: street, block, street, block, ..., street.
    let lines = |n: usize| -> Vec<f64> {
        let mut v = vec![0.0];
        for _ in 0..n {
            v.push(v[v.len() - 1] + STREET);
            v.push(v[v.len() - 1] + BLOCK);
        }
        v.push(v[v.len() - 1] + STREET);
        v
    };
    let (xs, ys) = (lines(nx), lines(ny));
    let rect = |name: String, o: DVec3, u: DVec3, v: DVec3, rho: f64| {
        Face::new(name, vec![o, o + u, o + u + v, o + v], rho)
    };
    let mut faces = Vec::new();
    for j in 0..ys.len() - 1 {
        for i in 0..xs.len() - 1 {
            let (x0, x1, y0, y1) = (xs[i], xs[i + 1], ys[j], ys[j + 1]);
            let (dx, dy) = (DVec3::new(x1 - x0, 0.0, 0.0), DVec3::new(0.0, y1 - y0, 0.0));
            if i % 2 == 1 && j % 2 == 1 {
                // A building; heights from a fixed hash of its position, 8 to 40.
                let k = (i / 2) * 7919 + (j / 2) * 104_729;
                let h = 8.0 + (k % 33) as f64;
                let z = DVec3::new(0.0, 0.0, h);
                let o = DVec3::new(x0, y0, 0.0);
                let name = |part: &str| format!("b{}-{}/{part}", i / 2, j / 2);
                faces.push(rect(name("roof"), o + z, dx, dy, 0.6)?);
                faces.push(rect(name("south"), o, dx, z, 0.6)?);
                faces.push(rect(name("north"), o + dy + dx, -dx, z, 0.6)?);
                faces.push(rect(name("west"), o + dy, -dy, z, 0.6)?);
                faces.push(rect(name("east"), o + dx, dy, z, 0.6)?);
            } else {
                faces.push(rect(format!("ground-{i}-{j}"), DVec3::new(x0, y0, 0.0), dx, dy, 0.3)?);
            }
        }
    }
    Ok(faces)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_city_has_eight_faces_per_building_and_outward_walls() {
        let s = city(3, 2).unwrap();
        assert_eq!(s.faces.len(), 5 * 6 + 7 * 5 - 6);
        let south = &s.faces[s.face_index("b0-0/south").unwrap()];
        assert!((south.frame.normal - DVec3::new(0.0, -1.0, 0.0)).length() < 1e-15);
        let roof = &s.faces[s.face_index("b0-0/roof").unwrap()];
        assert!((roof.frame.normal - DVec3::Z).length() < 1e-15);
        let east = &s.faces[s.face_index("b1-1/east").unwrap()];
        assert!((east.frame.normal - DVec3::X).length() < 1e-15);
        assert!(city(0, 3).is_err());
    }

    #[test]
    fn a_lit_city_has_a_sky_over_every_building_facing_down() {
        let s = lit_city(3, 2).unwrap();
        assert_eq!(s.faces.len(), city(3, 2).unwrap().faces.len() + 1);
        let sky = &s.faces[s.face_index("sky").unwrap()];
        assert!((sky.frame.normal + DVec3::Z).length() < 1e-15);
        assert_eq!((sky.rho, sky.emission), (0.0, 1.0));
        let (lo, hi) = sky.bounding_box();
        for f in s.faces.iter().filter(|f| f.name != "sky") {
            let (a, b) = f.bounding_box();
            assert!(a.x >= lo.x && a.y >= lo.y && b.x <= hi.x && b.y <= hi.y && b.z < lo.z);
        }
    }
}
