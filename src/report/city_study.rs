//! `study cities`' report: one row per city, with the growth exponents from the row before.

use super::table::{TableFormat, plain_table};
use crate::assembly::size_text;
use crate::study::cities::CityStudy;

/// `study cities` as a table.
pub fn city_table(study: &CityStudy, format: TableFormat) -> String {
    let exponent = |e: Option<f64>| e.map_or("-".into(), |e| format!("{e:.2}"));
    let rows: Vec<Vec<String>> = study
        .rows
        .iter()
        .map(|r| {
            vec![
                r.scene.clone(),
                r.faces.to_string(),
                r.n.to_string(),
                format!("{:.2}", r.setup_seconds),
                exponent(r.setup_exponent),
                format!("{:.2} ({})", r.solve_seconds, r.iterations),
                size_text(r.operator_bytes as f64),
                r.memory_estimate_bytes.map_or("-".into(), |b| size_text(b as f64)),
                format!("{:.0}", r.faces_viewed_per_node),
                exponent(r.faces_viewed_exponent),
                format!("{:.1}", r.unseen_faces_viewed_per_node),
                exponent(r.unseen_faces_viewed_exponent),
                format!("{:.0} / {:.0}", r.hidden_pairs_per_node, r.seen_pairs_per_node),
                format!("{:.3}", r.culled_share),
            ]
        })
        .collect();
    let header = [
        "scene",
        "faces",
        "n",
        "setup s",
        "setup ~ n^",
        "GMRES s (iterations)",
        "operator",
        "peak estimate",
        "faces viewed per node",
        "~ n^",
        "of them unseen",
        "~ n^",
        "pairs per node hidden / seen",
        "culled whole",
    ];
    let title = "Lit cities at refine 0, compressed operator on the CPU: growth with n";
    plain_table(title, &header, &rows, format)
}
