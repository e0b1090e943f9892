//! Shortwave radiation in a scene under the sun and an isotropic sky: what each element
//! receives directly from the sun through its exactly sunlit part ([`crate::sun`]), from the sky
//! through its sky view factor, and from the other elements' reflections, and what it absorbs
//! and reflects.
//!
//! The reflections solve the radiosity equation on the view factors: with E_i = ρ_i (direct_i +
//! sky_i), B = E + diag(ρ) F B by GMRES; the irradiance reflected onto element i is
//! Σ_j F_ij B_j. Everything a scene does not fill of an element's hemisphere is sky: a scene
//! without a ground sees the sky below the horizon too.

use rayon::prelude::*;
use serde::Serialize;

use crate::error::{Error, Result};
use crate::mesh::Mesh;
use crate::scene::Scene;
use crate::solve::{self, KrylovSystem};
use crate::sun::{Sources, Sunlit, sunlit};
use crate::viewfactors::ViewFactors;

/// What one element (or, averaged over its elements by area, one face) receives, absorbs and
/// reflects: irradiances in the sources' unit (W/m² where they are in W/m²).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct Fluxes {
    /// Area.
    pub area: f64,
    /// The share of the area in the sun.
    pub sunlit_fraction: f64,
    /// Cosine of the sun's angle of incidence (0 facing away).
    pub cos_incidence: f64,
    /// 1 − Σ_j F_ij: the share of the hemisphere that is sky.
    pub sky_view_factor: f64,
    /// Direct irradiance from the sun.
    pub direct: f64,
    /// Diffuse irradiance from the sky.
    pub sky: f64,
    /// Irradiance reflected onto it by the other elements.
    pub reflected: f64,
    /// Absorbed: (1 − ρ) times all it receives.
    pub absorbed: f64,
    /// Reflected away (the radiosity B): ρ times all it receives.
    pub outgoing: f64,
}

impl Fluxes {
    /// The names of [`Fluxes::values`], as the CSV files head their columns.
    pub const COLUMNS: [&'static str; 9] = [
        "area",
        "sunlit_fraction",
        "cos_incidence",
        "sky_view_factor",
        "direct",
        "sky",
        "reflected",
        "absorbed",
        "outgoing",
    ];

    /// Every field, in the order of [`Fluxes::COLUMNS`].
    pub fn values(&self) -> [f64; 9] {
        [
            self.area,
            self.sunlit_fraction,
            self.cos_incidence,
            self.sky_view_factor,
            self.direct,
            self.sky,
            self.reflected,
            self.absorbed,
            self.outgoing,
        ]
    }

    /// All it receives: direct, sky and reflected.
    pub fn incident(&self) -> f64 {
        self.direct + self.sky + self.reflected
    }
}

/// Where the power went, summed over the elements (irradiance times area): what the sources
/// gave equals what was absorbed plus what escaped to the sky, where F is reciprocal and each
/// sky view factor closes its row.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Balance {
    /// Σ A_i (direct_i + sky_i).
    pub received: f64,
    /// Σ A_i absorbed_i.
    pub absorbed: f64,
    /// Σ A_i B_i SVF_i: reflected light that leaves through the sky.
    pub escaped: f64,
    /// |received − absorbed − escaped| / received (0 where nothing was received).
    pub relative_gap: f64,
}

/// The shortwave solution.
#[derive(Clone, Debug)]
pub struct Shortwave {
    /// Per element, in the mesh's order.
    pub elements: Vec<Fluxes>,
    /// GMRES's products for the reflections.
    pub iterations: usize,
    /// Where the power went.
    pub balance: Balance,
}

/// The shortwave fluxes of every element of `mesh` under `sources`, reflections solved on the
/// view factors `f` of the same mesh to GMRES's relative residual `tolerance`. Without view
/// factors, direct light alone: no sky light, reflections not followed (all reflected light
/// counts as escaped), sky view factors NaN (not computed).
pub fn shortwave(
    scene: &Scene,
    mesh: &Mesh,
    f: Option<&ViewFactors>,
    sources: &Sources,
    tolerance: f64,
) -> Result<Shortwave> {
    if let Some(f) = f.filter(|f| f.len() != mesh.len()) {
        return Err(Error::InvalidParameter {
            name: "view factors",
            value: format!("{} elements", f.len()),
            reason: format!("the mesh has {} elements", mesh.len()),
        });
    }
    let Sources { sun, diffuse_horizontal } = *sources;
    let lit = if sun.is_up() {
        sunlit(scene, mesh, sun.direction())?
    } else {
        mesh.elements().iter().map(|e| Sunlit { area: e.area(), ..Default::default() }).collect()
    };
    let rho: Vec<f64> = mesh.elements().iter().map(|e| scene.faces[e.face].rho).collect();
    let sky_view_factors = f.map_or_else(|| vec![f64::NAN; mesh.len()], |f| f.sky_view_factors());
    let sky = |i: usize| if f.is_some() { diffuse_horizontal * sky_view_factors[i] } else { 0.0 };
    let received: Vec<f64> =
        (0..mesh.len()).map(|i| lit[i].irradiance(sun.direct_normal) + sky(i)).collect();
    let emission: Vec<f64> = received.iter().zip(&rho).map(|(r, p)| r * p).collect();
    let (b, iterations) = match f {
        Some(f) => {
            let solution = solve::gmres(&Reflections { f, rho: &rho }, &emission, tolerance)?;
            (solution.x, solution.iterations)
        }
        None => (Vec::new(), 0),
    };
    let elements: Vec<Fluxes> = (0..mesh.len())
        .into_par_iter()
        .map(|i| {
            let reflected = f.map_or(0.0, |f| row_dot(f, i, &b));
            let incident = received[i] + reflected;
            Fluxes {
                area: lit[i].area,
                sunlit_fraction: lit[i].fraction(),
                cos_incidence: lit[i].cos_incidence,
                sky_view_factor: sky_view_factors[i],
                direct: lit[i].irradiance(sun.direct_normal),
                sky: sky(i),
                reflected,
                absorbed: (1.0 - rho[i]) * incident,
                outgoing: rho[i] * incident,
            }
        })
        .collect();
    let balance = balance(&elements, f.is_some());
    Ok(Shortwave { elements, iterations, balance })
}

impl Shortwave {
    /// The fluxes averaged by area over each face of `mesh` (areas summed).
    pub fn by_face(&self, mesh: &Mesh) -> Vec<Fluxes> {
        (0..mesh.face_count())
            .map(|face| {
                let elements = &self.elements[mesh.face_range(face)];
                let area: f64 = elements.iter().map(|e| e.area).sum();
                let mean = |value: fn(&Fluxes) -> f64| {
                    let total: f64 = elements.iter().map(|e| e.area * value(e)).sum();
                    if area > 0.0 { total / area } else { 0.0 }
                };
                Fluxes {
                    area,
                    sunlit_fraction: mean(|e| e.sunlit_fraction),
                    cos_incidence: mean(|e| e.cos_incidence),
                    sky_view_factor: mean(|e| e.sky_view_factor),
                    direct: mean(|e| e.direct),
                    sky: mean(|e| e.sky),
                    reflected: mean(|e| e.reflected),
                    absorbed: mean(|e| e.absorbed),
                    outgoing: mean(|e| e.outgoing),
                }
            })
            .collect()
    }
}

/// Where the power of `elements` went; where reflections were not `followed`, all reflected
/// light escaped.
fn balance(elements: &[Fluxes], followed: bool) -> Balance {
    let sum =
        |value: &dyn Fn(&Fluxes) -> f64| elements.iter().map(|e| e.area * value(e)).sum::<f64>();
    let received = sum(&|e| e.direct + e.sky);
    let absorbed = sum(&|e| e.absorbed);
    let escaped = sum(&|e| e.outgoing * if followed { e.sky_view_factor } else { 1.0 });
    let gap = (received - absorbed - escaped).abs();
    Balance {
        received,
        absorbed,
        escaped,
        relative_gap: if received > 0.0 { gap / received } else { 0.0 },
    }
}

/// Σ_j F_ij x_j.
fn row_dot(f: &ViewFactors, i: usize, x: &[f64]) -> f64 {
    let (columns, values) = f.row(i);
    columns.iter().zip(values).map(|(&j, &v)| v * x[j as usize]).sum()
}

/// `I − diag(ρ) F`, the reflections' operator, by its products.
struct Reflections<'a> {
    f: &'a ViewFactors,
    rho: &'a [f64],
}

impl KrylovSystem for Reflections<'_> {
    fn dim(&self) -> usize {
        self.rho.len()
    }

    fn apply(&self, x: &[f64]) -> Vec<f64> {
        (0..self.dim())
            .into_par_iter()
            .map(|i| x[i] - self.rho[i] * row_dot(self.f, i, x))
            .collect()
    }

    fn residual(&self, x: &[f64], b: &[f64]) -> Vec<f64> {
        self.apply(x).iter().zip(b).map(|(ax, b)| b - ax).collect()
    }
}
