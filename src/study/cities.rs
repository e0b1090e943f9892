//! `study cities`: how a city's solve grows with its size. Generated lit cities
//! (`city:NxN:lit`: buildings under a sky panel that emits, [`crate::scene::lit_city`]) of
//! growing N, each solved at refine 0 with the compressed operator on the CPU, and per node the
//! work of the pair plan: the faces its exact blocks' row walks viewed, the pairs they found
//! hidden and seen, and the share of all pairs the block plan culled whole. Between one size
//! and the next, the exponents of the setup's and of the faces viewed per node's growth with n:
//! what a plan that follows what is seen must bring down.

use std::sync::Arc;

use serde::Serialize;

use crate::error::Result;
use crate::mesh::{Mesh, MeshKind};
use crate::operator::OperatorChoice;
use crate::pipeline::{self, RunOptions, SceneSource};
use crate::progress::Progress;

/// The sizes N run by default (`city:NxN:lit`), as far as `max_n` allows.
pub const SIZES: [usize; 6] = [4, 8, 12, 16, 24, 32];

/// What the study runs.
#[derive(Clone, Debug)]
pub struct CitySeries {
    /// Blocks along each side.
    pub sizes: Vec<usize>,
    /// The largest number of unknowns to run; larger cities are left out.
    pub max_n: Option<usize>,
}

/// One city's run.
#[derive(Clone, Debug, Serialize)]
pub struct CityRow {
    /// The scene's name.
    pub scene: String,
    /// Faces.
    pub faces: usize,
    /// Unknowns.
    pub n: usize,
    /// Setup (mesh, plan, operator) time.
    pub setup_seconds: f64,
    /// GMRES time.
    pub solve_seconds: f64,
    /// GMRES iterations.
    pub iterations: usize,
    /// Bytes of the stored operator.
    pub operator_bytes: u64,
    /// The build's peak as estimated before it began.
    pub memory_estimate_bytes: Option<u64>,
    /// Views of faces the exact blocks' row walks computed, over n.
    pub faces_viewed_per_node: f64,
    /// Of them, the views that found nothing of the face seen, over n.
    pub unseen_faces_viewed_per_node: f64,
    /// Pairs the row walks found hidden, over n.
    pub hidden_pairs_per_node: f64,
    /// Pairs the row walks found seen whole or in part, over n.
    pub seen_pairs_per_node: f64,
    /// Share of all (node, element) pairs in blocks the plan found empty: culled whole.
    pub culled_share: f64,
    /// Growth of the setup time with n from the previous size: log(t / t') / log(n / n').
    pub setup_exponent: Option<f64>,
    /// The same for the faces viewed per node.
    pub faces_viewed_exponent: Option<f64>,
    /// The same for the views that found nothing of the face seen.
    pub unseen_faces_viewed_exponent: Option<f64>,
}

/// The study's result.
#[derive(Clone, Debug, Serialize)]
pub struct CityStudy {
    /// Study id.
    pub study: &'static str,
    /// One row per city, smallest first.
    pub rows: Vec<CityRow>,
}

/// Runs the study; `progress` counts the cities (each run's own stages are not shown).
pub fn run_cities(series: &CitySeries, progress: &dyn Progress) -> Result<CityStudy> {
    let mut sizes = series.sizes.clone();
    sizes.sort_unstable();
    sizes.dedup();
    let options =
        RunOptions { refine: 0, operator: OperatorChoice::Compressed, ..RunOptions::default() };
    progress.start("cities", sizes.len());
    let mut rows: Vec<CityRow> = Vec::new();
    for size in sizes {
        let scene = crate::scene::lit_city(size, size)?;
        // Refine 0: an unknown per triangle of the faces.
        let n = Mesh::new(&scene, &MeshKind::Uniform, 0)?.len();
        if series.max_n.is_some_and(|max| n > max) {
            break;
        }
        let (faces, name) = (scene.faces.len(), scene.name.clone());
        let report = pipeline::run(&options.config(SceneSource::Given(Arc::new(scene)))?)?;
        let blocks = report.blocks.unwrap_or_default();
        let pairs = report.pairs;
        let per_node = |count: u64| count as f64 / n.max(1) as f64;
        let faces_viewed_per_node = per_node(blocks.faces_viewed);
        let unseen_faces_viewed_per_node = per_node(blocks.faces_viewed_unseen);
        let exponent = |now: f64, before: f64, n_before: usize| {
            let ratio = (n as f64 / n_before as f64).ln();
            (now > 0.0 && before > 0.0 && ratio > 0.0).then(|| (now / before).ln() / ratio)
        };
        let previous = rows.last();
        rows.push(CityRow {
            scene: name,
            faces,
            n,
            setup_seconds: report.setup_seconds,
            solve_seconds: report.solve_seconds,
            iterations: report.iterations,
            operator_bytes: report.operator_bytes,
            memory_estimate_bytes: report.memory_estimate_bytes,
            faces_viewed_per_node,
            unseen_faces_viewed_per_node,
            hidden_pairs_per_node: per_node(pairs.hidden),
            seen_pairs_per_node: per_node(pairs.full + pairs.partial),
            culled_share: blocks.empty_block_pairs as f64 / (n as f64 * n as f64).max(1.0),
            setup_exponent: previous
                .and_then(|p| exponent(report.setup_seconds, p.setup_seconds, p.n)),
            faces_viewed_exponent: previous
                .and_then(|p| exponent(faces_viewed_per_node, p.faces_viewed_per_node, p.n)),
            unseen_faces_viewed_exponent: previous.and_then(|p| {
                exponent(unseen_faces_viewed_per_node, p.unseen_faces_viewed_per_node, p.n)
            }),
        });
        progress.advance(1);
    }
    progress.finish();
    Ok(CityStudy { study: "cities", rows })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::progress::Silent;

    #[test]
    fn a_small_series_grows_in_order_and_within_its_cap() {
        let series = CitySeries { sizes: vec![3, 2, 3], max_n: None };
        let study = run_cities(&series, &Silent).unwrap();
        // Sorted, each size once.
        let ns: Vec<usize> = study.rows.iter().map(|r| r.n).collect();
        assert_eq!(ns.len(), 2);
        assert!(ns[0] < ns[1], "{ns:?}");
        let (small, large) = (&study.rows[0], &study.rows[1]);
        assert!(small.setup_exponent.is_none() && large.setup_exponent.is_some());
        for row in &study.rows {
            assert!(row.faces_viewed_per_node > 0.0 && row.seen_pairs_per_node > 0.0, "{row:?}");
            assert!(row.unseen_faces_viewed_per_node < row.faces_viewed_per_node, "{row:?}");
            // Faces of two triangles: the plan's blocks span many faces and cull little whole.
            assert!((0.0..1.0).contains(&row.culled_share), "{row:?}");
            let walked = row.hidden_pairs_per_node + row.seen_pairs_per_node;
            assert!(walked <= row.n as f64, "{row:?}");
            assert!(row.operator_bytes > 0 && row.memory_estimate_bytes.is_some(), "{row:?}");
        }
        // The cap leaves out the larger city.
        let capped = CitySeries { sizes: vec![2, 3], max_n: Some(small.n) };
        assert_eq!(run_cities(&capped, &Silent).unwrap().rows.len(), 1);
    }
}
