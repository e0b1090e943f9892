//! How imperfect scene files are read: `ImportArgs` and the library's `ImportOptions` it gives.

use clap::{Args, ValueEnum};

use radiosity::scene::{Coplanar, Duplicates, ImportOptions, NonPlanar};

#[derive(Clone, Copy, ValueEnum)]
pub(crate) enum NonPlanarArg {
    /// Into planar triangles: a quadrilateral along its shorter diagonal, others by ear clipping
    Split,
    Refuse,
}

#[derive(Clone, Copy, ValueEnum)]
pub(crate) enum DuplicatesArg {
    /// Keep the first of faces with the same vertices (same order) and properties
    Drop,
    Refuse,
}

#[derive(Clone, Copy, ValueEnum)]
pub(crate) enum CoplanarArg {
    /// Join them into planar faces for visibility, the triangles kept as elements
    Merge,
    /// Every triangle a face of its own
    Keep,
}

/// How imperfect scene files are read.
#[derive(Args)]
pub(crate) struct ImportArgs {
    /// Non-planar polygons [default: split for OBJ/STL polygons, refuse for TOML faces]
    #[arg(long, value_enum)]
    pub(crate) nonplanar: Option<NonPlanarArg>,
    /// Faces that repeat an earlier face exactly [default: drop for OBJ/STL polygons, refuse
    /// for TOML faces]; partial overlaps are always refused
    #[arg(long, value_enum)]
    pub(crate) duplicates: Option<DuplicatesArg>,
    /// Coplanar triangles of OBJ/STL meshes that share edges and properties [default: merge]
    #[arg(long, value_enum)]
    pub(crate) coplanar: Option<CoplanarArg>,
}

impl ImportArgs {
    pub(crate) fn options(&self) -> ImportOptions {
        ImportOptions {
            nonplanar: self.nonplanar.map(|n| match n {
                NonPlanarArg::Split => NonPlanar::Split,
                NonPlanarArg::Refuse => NonPlanar::Refuse,
            }),
            duplicates: self.duplicates.map(|d| match d {
                DuplicatesArg::Drop => Duplicates::Drop,
                DuplicatesArg::Refuse => Duplicates::Refuse,
            }),
            coplanar: self.coplanar.map(|c| match c {
                CoplanarArg::Merge => Coplanar::Merge,
                CoplanarArg::Keep => Coplanar::Keep,
            }),
        }
    }
}
