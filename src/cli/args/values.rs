//! Flag values written as comma-separated numbers: points and surface parameters.

use radiosity::error::{Error, Result};
use radiosity::scene::SurfaceParameters;

/// Three comma-separated numbers.
pub(crate) fn parse_point(name: &'static str, text: &str) -> Result<glam::DVec3> {
    // Every component must parse: "1,x,2,3" is refused, not read as (1, 2, 3).
    let values: Option<Vec<f64>> = text.split(',').map(|s| s.trim().parse().ok()).collect();
    match values.as_deref().unwrap_or_default() {
        &[x, y, z] if x.is_finite() && y.is_finite() && z.is_finite() => {
            Ok(glam::DVec3::new(x, y, z))
        }
        _ => Err(Error::InvalidParameter {
            name,
            value: text.into(),
            reason: "expected three finite numbers X,Y,Z".into(),
        }),
    }
}

/// A picture's size, `WxH` in pixels.
pub(crate) fn parse_size(name: &'static str, text: &str) -> Result<(u32, u32)> {
    text.split_once('x').and_then(|(w, h)| Some((w.parse().ok()?, h.parse().ok()?))).ok_or_else(
        || Error::InvalidParameter {
            name,
            value: text.into(),
            reason: "expected WIDTHxHEIGHT in pixels".into(),
        },
    )
}

pub(crate) fn parse_params(text: &str) -> Result<SurfaceParameters> {
    let bad = || Error::InvalidParameter {
        name: "params",
        value: text.into(),
        reason: "expected three numbers A,B,C".into(),
    };
    let values: Vec<f64> = text
        .split(',')
        .map(|s| s.trim().parse::<f64>())
        .collect::<std::result::Result<_, _>>()
        .map_err(|_| bad())?;
    let [a, b, c] = values[..] else { return Err(bad()) };
    let p = SurfaceParameters { a, b, c };
    p.validate()?;
    Ok(p)
}
