//! The files an urban large-eddy simulation's preprocessing reads (the formats of uDALES), one
//! value per facet: facet i is the i-th triangle of the input STL file (the mesh's order at
//! refine 0 for other scenes), numbered from 1 in `vfsparse`. Each name takes `.EXPNR` where an
//! experiment number is given.
//!
//! | file | header | then |
//! |---|---|---|
//! | `facetarea.inp` | `# area of facets` | each facet's area, `%.6f` (m²) |
//! | `svf.inp` | `# sky view factors` | each facet's sky view factor, `%.8f` |
//! | `netsw.inp` (one sun) | `# net shortwave on facets [W/m2] (including reflections and diffusive)` | absorbed shortwave, `%6.4f` (W/m²) |
//! | `Sdir.txt` | none | direct shortwave (W/m²), one column per time, `%.4f` |
//! | `vfsparse.inp` | none | `i j F_ij` (`%d %d %.8f`): row i the emitter, sorted by row then column |
//! | `timedepsw.inp` (a day) | `# time-dependent net shortwave on facets [W/m2]. First line: times (1 x nt), then netsw (nfcts x nt)` | the times (seconds) `%9.2f`, then per facet the absorbed shortwave of each time `%9.4f` |
//!
//! A sample: two facing facets of equal area (`svf.inp`, then `vfsparse.inp`; each row plus its
//! sky view factor is 1):
//!
//! ```text
//! # sky view factors
//! 0.80901699
//! 0.80901699
//! 1 2 0.19098301
//! 2 1 0.19098301
//! ```
//!
//! The view factors written are conditioned (reciprocity exact, each row plus its sky view
//! factor 1) with the pairs below [`VFSPARSE_THRESHOLD`] dropped and counted as sky, and the
//! light is computed on those same factors.

use std::collections::HashMap;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use glam::DVec3;

use crate::error::{Error, Result};
use crate::mesh::Mesh;
use crate::scene::Scene;
use crate::shortwave::{Fluxes, Shortwave};
use crate::viewfactors::ViewFactors;

/// Entries of F below this are dropped from `vfsparse.inp` (both directions of a pair).
pub const VFSPARSE_THRESHOLD: f64 = 5e-7;

/// The header of `netsw.inp`.
pub const NETSW_HEADER: &str =
    "# net shortwave on facets [W/m2] (including reflections and diffusive)";

/// The header of `timedepsw.inp`.
pub const TIMEDEPSW_HEADER: &str = "# time-dependent net shortwave on facets [W/m2]. First line: \
                                    times (1 x nt), then netsw (nfcts x nt)";

/// Each facet's element: facet k of `triangles` (an STL file's, in its coordinates) is the
/// element of `mesh` (refine 0) with its three vertices; `None` for the mesh's own order.
/// Refused, naming the facet, where a triangle has no element of its own (a repeat or a
/// degenerate triangle that loading dropped) or the mesh has elements that are no facet.
pub fn facet_elements(
    scene: &Scene,
    mesh: &Mesh,
    triangles: Option<&[[DVec3; 3]]>,
) -> Result<Vec<usize>> {
    let Some(triangles) = triangles else { return Ok((0..mesh.len()).collect()) };
    let key = |vertices: [DVec3; 3]| {
        let mut key = vertices.map(|v| v.to_array().map(f64::to_bits));
        key.sort_unstable();
        key
    };
    // The move to the local frame is exact: adding the origin back gives the file's bits.
    let mut element_of: HashMap<_, usize> = mesh
        .elements()
        .iter()
        .enumerate()
        .map(|(i, e)| (key(e.vertices.map(|v| v + scene.origin)), i))
        .collect();
    let refuse = |reason: String| Error::InvalidParameter {
        name: "export",
        value: scene.name.clone(),
        reason,
    };
    let mut facets = Vec::with_capacity(triangles.len());
    for (k, &triangle) in triangles.iter().enumerate() {
        let element = element_of.remove(&key(triangle)).ok_or_else(|| {
            refuse(format!(
                "facet {} (triangle {k} of the file) has no element of its own: loading dropped it \
                 as a repeat of another or as degenerate; remove it from the file",
                k + 1
            ))
        })?;
        facets.push(element);
    }
    if facets.len() != mesh.len() {
        return Err(refuse(format!(
            "the mesh has {} elements for {} facets: export at --refine 0",
            mesh.len(),
            facets.len()
        )));
    }
    Ok(facets)
}

/// The times of a day as `timedepsw.inp` numbers them, in seconds: each label read as a number,
/// refused naming the first that is not one (checked before the work, and again where written).
pub fn timedepsw_seconds<'a>(labels: impl Iterator<Item = &'a str>) -> Result<Vec<f64>> {
    labels
        .map(|time| {
            time.parse::<f64>().map_err(|_| Error::InvalidParameter {
                name: "export",
                value: time.to_string(),
                reason: "timedepsw.inp numbers its times in seconds: label each sun position \
                         with its time in seconds"
                    .into(),
            })
        })
        .collect()
}

/// What to write: where, the facets' elements ([`facet_elements`]), the conditioned view
/// factors and the light of each time (a label, in seconds for a day).
pub struct UrbanExport<'a> {
    /// The directory the files go to (made if missing).
    pub dir: &'a Path,
    /// The experiment number appended to each name, if any.
    pub expnr: Option<&'a str>,
    /// Each facet's element.
    pub facets: &'a [usize],
    /// The view factors the light was computed on; `None` for direct light alone, which writes
    /// `facetarea.inp` and `Sdir.txt` only.
    pub view_factors: Option<&'a ViewFactors>,
    /// Each time's label and light; one unlabelled entry for one sun.
    pub times: Vec<(&'a str, &'a Shortwave)>,
}

impl UrbanExport<'_> {
    /// Writes the files; returns their paths.
    pub fn write(&self) -> Result<Vec<PathBuf>> {
        std::fs::create_dir_all(self.dir)?;
        if self.times.is_empty() {
            return Err(Error::InvalidParameter {
                name: "export",
                value: "no times".into(),
                reason: "give a sun or sun positions".into(),
            });
        }
        let per_facet = |value: &dyn Fn(usize) -> String| -> String {
            self.facets.iter().map(|&e| value(e) + "\n").collect()
        };
        let mut files = Vec::new();
        let mut write = |name: &str, text: String| -> Result<()> {
            let name = match self.expnr {
                Some(n) => format!("{name}.{n}"),
                None => name.to_string(),
            };
            let path = self.dir.join(name);
            std::fs::write(&path, text)?;
            files.push(path);
            Ok(())
        };
        let areas = &self.times[0].1.elements;
        write(
            "facetarea.inp",
            "# area of facets\n".to_string() + &per_facet(&|e| format!("{:.6}", areas[e].area)),
        )?;
        write("Sdir.txt", per_facet(&|e| self.each_time(e, |f| format!("{:.4}", f.direct))))?;
        let Some(f) = self.view_factors else { return Ok(files) };
        let sky = f.sky_view_factors();
        write(
            "svf.inp",
            "# sky view factors\n".to_string()
                + &per_facet(&|e| format!("{:.8}", non_negative(sky[e]))),
        )?;
        write("vfsparse.inp", self.vfsparse(f))?;
        if let [(time, light)] = self.times[..] {
            if time.is_empty() {
                let absorbed = per_facet(&|e| format!("{:6.4}", light.elements[e].absorbed));
                write("netsw.inp", format!("{NETSW_HEADER}\n{absorbed}"))?;
                return Ok(files);
            }
        }
        let mut text = format!("{TIMEDEPSW_HEADER}\n");
        let seconds: Vec<String> = timedepsw_seconds(self.times.iter().map(|(time, _)| *time))?
            .iter()
            .map(|t| format!("{t:9.2}"))
            .collect();
        text.push_str(&(seconds.join(" ") + "\n"));
        text.push_str(&per_facet(&|e| self.each_time(e, |f| format!("{:9.4}", f.absorbed))));
        write("timedepsw.inp", text)?;
        Ok(files)
    }

    /// Element `e`'s value at each time, as `value` writes it, separated by spaces.
    fn each_time(&self, e: usize, value: impl Fn(&Fluxes) -> String) -> String {
        let values: Vec<String> =
            self.times.iter().map(|(_, light)| value(&light.elements[e])).collect();
        values.join(" ")
    }

    /// `vfsparse.inp`: `i j F_ij` for every entry kept, by facet numbers from 1, sorted by row
    /// then column.
    fn vfsparse(&self, f: &ViewFactors) -> String {
        let mut facet_of = vec![0; self.facets.len()];
        for (k, &e) in self.facets.iter().enumerate() {
            facet_of[e] = k;
        }
        let mut text = String::new();
        let mut row: Vec<(usize, f64)> = Vec::new();
        for (k, &e) in self.facets.iter().enumerate() {
            let (columns, values) = f.row(e);
            row.clear();
            row.extend(columns.iter().zip(values).map(|(&j, &v)| (facet_of[j as usize], v)));
            row.sort_unstable_by_key(|&(j, _)| j);
            for &(j, v) in &row {
                let _ = writeln!(text, "{} {} {v:.8}", k + 1, j + 1);
            }
        }
        text
    }
}

/// `v`, with the rounding below 0 of a sky view factor that closes its row shown as 0.
fn non_negative(v: f64) -> f64 {
    if v > 0.0 { v } else { 0.0 }
}
