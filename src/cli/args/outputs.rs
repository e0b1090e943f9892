//! The files a solve writes: `OutputArgs`.

use clap::Args;

/// Files written from a solution.
#[derive(Args)]
pub(crate) struct OutputArgs {
    /// Write the mesh with u, E, rho per element and u at the vertices as VTK (.vtu, for ParaView)
    #[arg(long, value_name = "FILE.vtu")]
    pub(crate) vtu: Option<String>,
    /// Write the nodal values (position, face, rho, E, u) as CSV
    #[arg(long, value_name = "FILE.csv")]
    pub(crate) csv: Option<String>,
    /// Render a false-colour picture of u (back faces culled: a closed room seen from outside
    /// shows its inside)
    #[arg(long, value_name = "FILE.png")]
    pub(crate) png: Option<String>,
    /// Picture size in pixels
    #[arg(long, value_name = "WxH", default_value = "1200x800")]
    pub(crate) png_size: String,
    /// Eye position of the picture (default: outside the scene, from the south-west, above)
    #[arg(long, value_name = "X,Y,Z")]
    pub(crate) eye: Option<String>,
    /// Point the picture looks at (default: the centre of the scene)
    #[arg(long, value_name = "X,Y,Z")]
    pub(crate) target: Option<String>,
}
