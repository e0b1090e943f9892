//! Colour bands and how the picture is drawn: `ColourArgs`, its tone map and up direction.

use clap::Args;

use radiosity::error::{Error, Result};
use radiosity::pipeline::{RunOptions, SceneSource};
use radiosity::report::Tone;

use super::named::named;
use super::values::parse_point;

/// Colour bands, and how the picture is drawn.
#[derive(Args)]
pub(crate) struct ColourArgs {
    /// Solve per colour band on one assembled operator, each with its channel of rho and E (OBJ:
    /// Kd, Ke; grey faces the same in every band): rgb, a list such as r,g, or grey (one solve
    /// with the channels' means)
    #[arg(long, value_name = "BANDS", default_value_t = RunOptions::default().bands)]
    pub(crate) bands: String,
    /// The direction that is up in the picture [default: 0,1,0 for OBJ files, 0,0,1 otherwise]
    #[arg(long, value_name = "X,Y,Z")]
    pub(crate) up: Option<String>,
    /// How u becomes colour
    #[arg(long, value_parser = named::<Tone>(), default_value_t = Tone::Gamma)]
    pub(crate) tone: Tone,
}

impl ColourArgs {
    /// The channels of --bands (empty: grey).
    pub(crate) fn channels(&self) -> Result<Vec<usize>> {
        radiosity::scene::parse_bands(&self.bands)
    }

    /// The up direction of --up, or the default for `scene`.
    pub(crate) fn up(&self, scene: &SceneSource) -> Result<glam::DVec3> {
        let Some(text) = &self.up else {
            return Ok(if scene.is_obj() { glam::DVec3::Y } else { glam::DVec3::Z });
        };
        let up = parse_point("up", text)?;
        if up.length() == 0.0 || !up.length().is_finite() {
            return Err(Error::InvalidParameter {
                name: "up",
                value: text.clone(),
                reason: "the up direction must be a non-zero vector".into(),
            });
        }
        Ok(up)
    }
}
