//! `study stability` and `study stiff` as tables.

use super::table::{TableFormat, plain_table};

/// `study stability` as a table: one row per case, method and backend.
pub fn stability_table(
    result: &crate::study::stability::StabilityResult,
    format: TableFormat,
) -> String {
    let rows: Vec<Vec<String>> = result
        .rows
        .iter()
        .map(|r| {
            vec![
                r.case.clone(),
                r.method.into(),
                format!("{}-{}", r.backend, r.precision),
                format!("{:.6e}", r.reference),
                format!("{:.1e}", r.relative_error),
                r.closed_forms_error.map_or("-".into(), |e| format!("{e:.1e}")),
                format!("{:.0e}", r.bound),
                if r.passed { "ok".into() } else { "FAILED".into() },
            ]
        })
        .collect();
    let header =
        ["case", "method", "backend", "reference", "rel. error", "closed forms", "bound", ""];
    let mut s = plain_table(
        "Stability of the collocation integrals at extreme geometry",
        &header,
        &rows,
        format,
    );
    s += &format!("\n{} of {} rows within their bounds\n", rows.len() - result.failed, rows.len());
    for note in &result.notes {
        s += &format!("\nNote: {note}\n");
    }
    s
}

/// `study stiff` as a table: one row per scene and rho.
pub fn stiff_table(result: &crate::study::stability::StiffResult, format: TableFormat) -> String {
    let opt = |v: Option<f64>| v.map_or("-".to_string(), |x| format!("{x:.1e}"));
    let rows: Vec<Vec<String>> = result
        .rows
        .iter()
        .map(|r| {
            vec![
                r.case.clone(),
                r.method.into(),
                format!("{}", r.rho),
                r.dof.to_string(),
                opt(r.condition_estimate),
                opt(r.error_lu),
                opt(r.error_refined),
                r.refinement_steps.map_or("-".into(), |k| k.to_string()),
                opt(r.bound),
                opt(r.error_gmres),
                opt(r.gmres_vs_lu),
                r.gmres_iterations.map_or("-".into(), |k| k.to_string()),
                r.status.clone(),
            ]
        })
        .collect();
    let header = [
        "case",
        "method",
        "rho",
        "dof",
        "condition",
        "LU error",
        "refined",
        "steps",
        "bound",
        "GMRES error",
        "vs LU",
        "its",
        "status",
    ];
    let mut s =
        plain_table("Stiff systems: rho -> 1 in open and closed boxes", &header, &rows, format);
    for note in &result.notes {
        s += &format!("\nNote: {note}\n");
    }
    s
}
