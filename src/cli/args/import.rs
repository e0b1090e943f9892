//! How imperfect scene files are read: `ImportArgs` and the library's `ImportOptions` it gives.

use clap::Args;

use radiosity::scene::{Coplanar, Duplicates, ImportOptions, NonPlanar};

use super::named::named;

/// How imperfect scene files are read.
#[derive(Args)]
pub(crate) struct ImportArgs {
    /// Non-planar polygons [default: split for OBJ/STL polygons, refuse for TOML faces]
    #[arg(long, value_parser = named::<NonPlanar>())]
    pub(crate) nonplanar: Option<NonPlanar>,
    /// Faces that repeat an earlier face exactly [default: drop for OBJ/STL polygons, refuse
    /// for TOML faces]; partial overlaps are always refused
    #[arg(long, value_parser = named::<Duplicates>())]
    pub(crate) duplicates: Option<Duplicates>,
    /// Coplanar triangles of OBJ/STL meshes that share edges and properties [default: merge]
    #[arg(long, value_parser = named::<Coplanar>())]
    pub(crate) coplanar: Option<Coplanar>,
}

impl ImportArgs {
    pub(crate) fn options(&self) -> ImportOptions {
        ImportOptions {
            nonplanar: self.nonplanar,
            duplicates: self.duplicates,
            coplanar: self.coplanar,
        }
    }
}
