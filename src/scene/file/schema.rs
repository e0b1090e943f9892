//! The TOML scene format: the file's tables as serde reads them, and the checks on a group.

use std::collections::BTreeMap;
use std::path::PathBuf;

use serde::Deserialize;

use super::Side;
use crate::error::{Error, Result};

/// A value for every colour channel (grey), or one per channel r, g, b (`[r, g, b]` in a scene
/// file, `Kd`/`Ke` of an OBJ material), for `--bands`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) enum Channels {
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
    pub(super) fn grey(self) -> f64 {
        match self {
            Self::Grey(x) => x,
            Self::Rgb(c) => (c[0] + c[1] + c[2]) / 3.0,
        }
    }

    pub(super) fn rgb(self) -> Option<[f64; 3]> {
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
pub(super) struct Properties {
    pub(super) rho: Option<Channels>,
    pub(super) emission: Option<Channels>,
    pub(super) radiates: Option<Side>,
}

impl Properties {
    /// `self` where it says something, else `fallback`.
    pub(super) fn or(self, fallback: Properties) -> Properties {
        Properties {
            rho: self.rho.or(fallback.rho),
            emission: self.emission.or(fallback.emission),
            radiates: self.radiates.or(fallback.radiates),
        }
    }
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct SceneFile {
    pub(super) name: Option<String>,
    #[serde(default)]
    pub(super) defaults: Properties,
    #[serde(default)]
    pub(super) groups: BTreeMap<String, Properties>,
    #[serde(default)]
    pub(super) faces: Vec<FaceEntry>,
    #[serde(default)]
    pub(super) meshes: Vec<MeshEntry>,
    /// The sun of `radiosity sun`.
    pub(super) sun: Option<crate::scene::Daylight>,
    /// Its sky.
    pub(super) sky: Option<SkyEntry>,
}

/// `[sky]`: an isotropic sky.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct SkyEntry {
    pub(super) diffuse_horizontal: f64,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct FaceEntry {
    pub(super) name: String,
    pub(super) vertices: Vec<[f64; 3]>,
    pub(super) group: Option<String>,
    /// Optional check: the normal of the radiating side (of the first face for `both`).
    pub(super) normal: Option<[f64; 3]>,
    pub(super) rho: Option<Channels>,
    pub(super) emission: Option<Channels>,
    pub(super) radiates: Option<Side>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct MeshEntry {
    pub(super) file: PathBuf,
    /// Prefix of the face names (default: the file's stem).
    pub(super) name: Option<String>,
    #[serde(default)]
    pub(super) translate: [f64; 3],
    pub(super) scale: Option<f64>,
    pub(super) rho: Option<Channels>,
    pub(super) emission: Option<Channels>,
    pub(super) radiates: Option<Side>,
}

pub(super) fn check_group(path: &str, group: &str, props: &Properties) -> Result<()> {
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
