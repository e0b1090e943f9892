//! Emission cases on one operator: each case's E solved in turn on the operator built once (LU
//! factored once), and reported as one run.

use super::bands::mean_outcome;
use super::report::range;
use super::{BuiltOperator, CaseReport, Problem, RunConfig};
use crate::error::Result;
use crate::solution::CaseValues;
use crate::solve::SolveOutcome;

/// Solves each case of `columns` (E at the nodes, named by `names`) on `built`: the cases'
/// mean outcome, each case's values and report.
pub(super) fn solve_cases(
    config: &RunConfig,
    problem: &Problem,
    built: &BuiltOperator,
    names: &[String],
    columns: Vec<Vec<f64>>,
) -> Result<(SolveOutcome, Vec<CaseValues>, Vec<CaseReport>)> {
    let rhs: Vec<&[f64]> = columns.iter().map(Vec::as_slice).collect();
    let outcomes = built.solve_many(config, problem, &rhs)?;
    let reports = names
        .iter()
        .zip(&outcomes)
        .map(|(name, o)| CaseReport {
            case: name.clone(),
            solver: o.solver,
            iterations: o.iterations,
            residual: o.residual,
            solution_range: range(&o.u),
        })
        .collect();
    let values = names
        .iter()
        .zip(&outcomes)
        .zip(columns)
        .map(|((name, o), emission)| CaseValues { name: name.clone(), u: o.u.clone(), emission })
        .collect();
    Ok((mean_outcome(outcomes), values, reports))
}
