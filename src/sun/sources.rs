//! The sources: the sun at one moment ([`Sun`]: where it stands, how strongly it shines) and an
//! isotropic sky beside it ([`Sources`]).

use glam::DVec3;
use serde::Serialize;

use crate::error::{Error, Result};
use crate::scene::Daylight;

/// The compass direction of +x when the scene does not say: east (+y is then north).
pub const DEFAULT_X_AZIMUTH: f64 = 90.0;

/// The sun at one moment: where it stands and how strongly it shines.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Sun {
    /// Angle from the zenith, degrees: 0 overhead, 90 on the horizon (beyond: below it, no
    /// direct light).
    pub zenith: f64,
    /// Compass azimuth, degrees clockwise from north.
    pub azimuth: f64,
    /// Compass direction of the scene's +x, degrees clockwise from north (90: east).
    pub x_azimuth: f64,
    /// Direct normal irradiance, W/m² (or any unit: the results are in the same).
    pub direct_normal: f64,
}

impl Sun {
    /// The sun at `zenith` and `azimuth` (degrees) with `direct_normal` irradiance, +x at
    /// compass direction `x_azimuth`; refused, naming the value, where an angle is not finite,
    /// the zenith outside [0, 180] or the irradiance negative or not finite.
    pub fn new(zenith: f64, azimuth: f64, x_azimuth: f64, direct_normal: f64) -> Result<Self> {
        let invalid = |name: &'static str, value: f64, reason: &str| Error::InvalidParameter {
            name,
            value: value.to_string(),
            reason: reason.into(),
        };
        if !(0.0..=180.0).contains(&zenith) {
            return Err(invalid("sun zenith", zenith, "degrees from the zenith, in [0, 180]"));
        }
        if !azimuth.is_finite() {
            return Err(invalid("sun azimuth", azimuth, "degrees clockwise from north"));
        }
        if !x_azimuth.is_finite() {
            return Err(invalid("x azimuth", x_azimuth, "the compass direction of +x, degrees"));
        }
        if !(direct_normal.is_finite() && direct_normal >= 0.0) {
            return Err(invalid("direct normal irradiance", direct_normal, "at least 0"));
        }
        Ok(Self { zenith, azimuth, x_azimuth, direct_normal })
    }

    /// The unit vector towards the sun: with a = azimuth − x_azimuth,
    /// (sin Z cos a, −sin Z sin a, cos Z) (z up, +y a quarter turn anticlockwise from +x).
    pub fn direction(&self) -> DVec3 {
        let (z, a) = (self.zenith.to_radians(), (self.azimuth - self.x_azimuth).to_radians());
        DVec3::new(z.sin() * a.cos(), -z.sin() * a.sin(), z.cos())
    }

    /// Whether the sun is above the horizon (it lights nothing otherwise).
    pub fn is_up(&self) -> bool {
        self.zenith < 90.0
    }
}

/// The sources: the sun (direct light, with exact shadows) and an isotropic sky.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Sources {
    /// The sun.
    pub sun: Sun,
    /// Diffuse horizontal irradiance of the sky (isotropic), in the sun's unit.
    pub diffuse_horizontal: f64,
}

impl Sources {
    /// The sources of a scene file's `[sun]` and `[sky]` tables, checked as [`Sun::new`] and
    /// [`Sources::new`] check them.
    pub fn of_daylight(daylight: &Daylight) -> Result<Self> {
        let x_azimuth = daylight.x_azimuth.unwrap_or(DEFAULT_X_AZIMUTH);
        let sun = Sun::new(daylight.zenith, daylight.azimuth, x_azimuth, daylight.direct_normal)?;
        Self::new(sun, daylight.diffuse_horizontal)
    }

    /// The sun and a sky of `diffuse_horizontal` irradiance; refused where that is negative or
    /// not finite.
    pub fn new(sun: Sun, diffuse_horizontal: f64) -> Result<Self> {
        if !(diffuse_horizontal.is_finite() && diffuse_horizontal >= 0.0) {
            return Err(Error::InvalidParameter {
                name: "diffuse horizontal irradiance",
                value: diffuse_horizontal.to_string(),
                reason: "at least 0".into(),
            });
        }
        Ok(Self { sun, diffuse_horizontal })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_direction_follows_the_compass() {
        let east = Sun::new(90.0, 90.0, 90.0, 1.0).unwrap().direction();
        assert!((east - DVec3::X).length() < 1e-15, "{east}");
        let north = Sun::new(90.0, 0.0, 90.0, 1.0).unwrap().direction();
        assert!((north - DVec3::Y).length() < 1e-15, "{north}");
        let south_west = Sun::new(45.0, 225.0, 90.0, 1.0).unwrap().direction();
        let h = 0.5f64;
        assert!((south_west - DVec3::new(-h, -h, 0.5f64.sqrt())).length() < 1e-15);
        // +x pointing north: a sun in the north lies along +x.
        let along_x = Sun::new(30.0, 0.0, 0.0, 1.0).unwrap().direction();
        assert!((along_x - DVec3::new(0.5, 0.0, 0.75f64.sqrt())).length() < 1e-15);
        assert!(Sun::new(0.0, 17.0, 90.0, 1.0).unwrap().direction().abs_diff_eq(DVec3::Z, 1e-15));
    }

    #[test]
    fn bad_values_are_refused_by_name() {
        for (z, a, x, i, name) in [
            (f64::NAN, 0.0, 90.0, 1.0, "sun zenith"),
            (190.0, 0.0, 90.0, 1.0, "sun zenith"),
            (10.0, f64::INFINITY, 90.0, 1.0, "sun azimuth"),
            (10.0, 0.0, f64::NAN, 1.0, "x azimuth"),
            (10.0, 0.0, 90.0, -1.0, "direct normal irradiance"),
        ] {
            let e = Sun::new(z, a, x, i).unwrap_err().to_string();
            assert!(e.contains(name), "{e}");
        }
    }
}
