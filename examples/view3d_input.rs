//! A scene's elements as a View3D 4 input file (`.vs3`, format F 3), so that the peer computes
//! the same view factors as `radiosity viewfactors` side by side: each element of the uniform
//! mesh is one triangular surface, in the mesh's order (F_ij of View3D row i is ours).
//!
//!     cargo run --release --example view3d_input -- SCENE REFINE EPS > scene.vs3
//!     View3D scene.vs3 scene.out
//!
//! SCENE is what `--scene` takes (a built-in name, `city:NXxNY`, or a .toml/.obj/.stl file),
//! REFINE the refinement levels, EPS View3D's convergence criterion (its `eps`).

use std::io::Write;

use radiosity::error::{Error, Result};
use radiosity::mesh::{Mesh, MeshKind};
use radiosity::pipeline::SceneSource;
use radiosity::scene::SurfaceParameters;

fn main() -> Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let [name, refine, eps] = args.as_slice() else {
        return Err(Error::InvalidParameter {
            name: "arguments",
            value: args.join(" "),
            reason: "expected SCENE REFINE EPS".into(),
        });
    };
    let invalid = |name: &'static str, value: &str| Error::InvalidParameter {
        name,
        value: value.into(),
        reason: "not a number".into(),
    };
    let refine: u32 = refine.parse().map_err(|_| invalid("refine", refine))?;
    let eps: f64 = eps.parse().map_err(|_| invalid("eps", eps))?;
    let scene = SceneSource::parse(name)?.build(SurfaceParameters::default())?;
    let mesh = Mesh::new(&scene, &MeshKind::Uniform, refine)?;
    let mut out = std::io::BufWriter::new(std::io::stdout().lock());
    writeln!(out, "T {} refine {refine}: {} elements", scene.name, mesh.len())?;
    // Not an enclosure: View3D would otherwise adjust the factors to close the rows.
    writeln!(out, "C encl=0 list=0 eps={eps:e}")?;
    writeln!(out, "F 3")?;
    for (k, e) in mesh.elements().iter().enumerate() {
        for (m, v) in e.vertices.iter().enumerate() {
            writeln!(out, "V {} {:.17e} {:.17e} {:.17e}", 3 * k + m + 1, v.x, v.y, v.z)?;
        }
    }
    for k in 0..mesh.len() {
        let v = 3 * k + 1;
        writeln!(out, "S {} {} {} {} 0 0 0 0.9 e{}", k + 1, v, v + 1, v + 2, k + 1)?;
    }
    writeln!(out, "End of data")?;
    out.flush()?;
    Ok(())
}
