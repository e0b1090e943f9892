//! Solving `(I - K) u = E` where K is known by its products alone: the compressed operator
//! ([`crate::operator`]), or K kept on the GPU ([`crate::gpu::DeviceOperator`]). GMRES, since no
//! matrix is there to factor.

use super::gmres::{Gmres, Need, RESTART};
use super::{
    CLOSED_ROW_TOLERANCE, SolveOutcome, SolverOptions, check_tolerance, reject_unit_row_sums,
};
use crate::error::Result;
use crate::gpu::{DeviceBlocks, DeviceOperator};
use crate::operator::CompressedOperator;

/// An operator known by its products.
pub trait Products: Sync {
    /// Number of unknowns.
    fn dof(&self) -> usize;
    /// `K x` for every `x` in `xs`, the operator read once for all of them.
    fn apply_many(&self, xs: &[&[f64]]) -> Result<Vec<Vec<f64>>>;
}

impl Products for CompressedOperator {
    fn dof(&self) -> usize {
        CompressedOperator::dof(self)
    }

    fn apply_many(&self, xs: &[&[f64]]) -> Result<Vec<Vec<f64>>> {
        Ok(CompressedOperator::apply_many(self, xs))
    }
}

impl Products for DeviceOperator {
    fn dof(&self) -> usize {
        DeviceOperator::dof(self)
    }

    fn apply_many(&self, xs: &[&[f64]]) -> Result<Vec<Vec<f64>>> {
        DeviceOperator::apply_many(self, xs)
    }
}

impl Products for DeviceBlocks {
    fn dof(&self) -> usize {
        DeviceBlocks::dof(self)
    }

    fn apply_many(&self, xs: &[&[f64]]) -> Result<Vec<Vec<f64>>> {
        DeviceBlocks::apply_many(self, xs)
    }
}

/// `I - diag(s) K` (s = 1 but for a colour band's rows).
struct ProductSystem<'a> {
    k: &'a dyn Products,
    row_scale: Option<Vec<f64>>,
}

impl ProductSystem<'_> {
    /// `A x` for every `x` in `xs`, the operator read once for all of them.
    fn apply_many(&self, xs: &[&[f64]]) -> Result<Vec<Vec<f64>>> {
        let mut kxs = self.k.apply_many(xs)?;
        for (x, kx) in xs.iter().zip(&mut kxs) {
            if let Some(scale) = &self.row_scale {
                kx.iter_mut().zip(scale).for_each(|(v, s)| *v *= s);
            }
            kx.iter_mut().zip(x.iter()).for_each(|(v, a)| *v = a - *v);
        }
        Ok(kxs)
    }
}

/// Most bytes of the interleaved vectors of one round of products (each of the product's
/// parallel parts holds that much): the solves advance in groups that fit.
const ROUND_BYTES: usize = 64 << 20;

/// Most bytes of the Krylov bases of the solves that advance together (each holds
/// `RESTART + 1` vectors); more right-hand sides are solved group after group.
const SOLVES_BYTES: usize = 512 << 20;

/// Solves `(I - K) u = rhs` by GMRES to `options.tolerance`, which must not be below what the
/// products keep (those of the compressed operator are exact only to `compression_tolerance`;
/// 0 for an exact product). `rho` is each
/// node's reflectivity, that of the operator's rows or, for a colour band, the band's: the
/// rows are then scaled by it over `operator_rho` (K holds rho/π per row; rho = 0 only where
/// every band's is), as the dense path scales its matrix. Nodes that reflect nothing get u = E
/// exactly. A closed surface with rho = 1 everywhere is refused as singular, as by
/// [`super::solve`].
pub fn solve_by_products(
    k: &dyn Products,
    rhs: &[f64],
    rho: (&[f64], &[f64]),
    options: SolverOptions,
    compression_tolerance: f64,
) -> Result<SolveOutcome> {
    let mut outcomes = solve_by_products_many(k, &[rhs], rho, options, compression_tolerance)?;
    Ok(outcomes.pop().expect("one outcome per right-hand side"))
}

/// As [`solve_by_products`], for each right-hand side of `rhs`: the GMRES solves advance in
/// lockstep, each round's products computed together ([`Products::apply_many`]), so that
/// many emission cases read the operator once per round instead of once per case.
pub fn solve_by_products_many(
    k: &dyn Products,
    rhs: &[&[f64]],
    (rho, operator_rho): (&[f64], &[f64]),
    options: SolverOptions,
    compression_tolerance: f64,
) -> Result<Vec<SolveOutcome>> {
    check_tolerance(options.tolerance)?;
    let row_scale = (rho != operator_rho).then(|| {
        rho.iter().zip(operator_rho).map(|(&b, &g)| if g == 0.0 { 0.0 } else { b / g }).collect()
    });
    let sys = ProductSystem { k, row_scale };
    if !rho.is_empty() && rho.iter().all(|&r| r == 1.0) {
        let ones = vec![1.0; k.dof()];
        let mut sums = k.apply_many(&[&ones])?.pop().expect("one product");
        if let Some(scale) = &sys.row_scale {
            sums.iter_mut().zip(scale).for_each(|(v, s)| *v *= s);
        }
        reject_unit_row_sums(&sums, CLOSED_ROW_TOLERANCE.max(10.0 * compression_tolerance))?;
    }
    // Each solve holds its Krylov basis: as many at once as fit in the budget.
    let together = (SOLVES_BYTES / (8 * (RESTART + 2) * k.dof()).max(1)).max(1);
    let mut outcomes = Vec::with_capacity(rhs.len());
    for group in rhs.chunks(together) {
        outcomes.extend(solve_together(&sys, group, rho, options.tolerance)?);
    }
    Ok(outcomes)
}

/// GMRES for each right-hand side of `rhs` on `sys`, in lockstep: each round's products in one
/// pass over the blocks.
fn solve_together(
    sys: &ProductSystem,
    rhs: &[&[f64]],
    rho: &[f64],
    tolerance: f64,
) -> Result<Vec<SolveOutcome>> {
    let round = (ROUND_BYTES / (8 * sys.k.dof()).max(1)).max(1);
    let mut solvers: Vec<Gmres> = rhs.iter().map(|b| Gmres::new(b, tolerance)).collect();
    loop {
        let asking: Vec<usize> =
            (0..solvers.len()).filter(|&i| solvers[i].need().is_some()).collect();
        if asking.is_empty() {
            break;
        }
        for group in asking.chunks(round) {
            let (mut xs, mut residual) = (Vec::new(), Vec::new());
            for &i in group {
                let (x, is_residual) = match solvers[i].need().expect("asking") {
                    Need::Product(x) => (x, false),
                    Need::Residual(x) => (x, true),
                };
                xs.push(x);
                residual.push(is_residual);
            }
            let products = sys.apply_many(&xs)?;
            for ((&i, ax), is_residual) in group.iter().zip(products).zip(residual) {
                let given = match is_residual {
                    false => ax,
                    // In plain arithmetic: the compression's tolerance is far above its rounding.
                    true => rhs[i].iter().zip(&ax).map(|(b, ax)| b - ax).collect(),
                };
                solvers[i].give(given);
            }
        }
    }
    let mut solutions = Vec::with_capacity(rhs.len());
    for (solver, b) in solvers.into_iter().zip(rhs) {
        let g = solver.finish()?;
        let mut u = g.x;
        let mut fixed = 0;
        for ((ui, &r), &e) in u.iter_mut().zip(rho).zip(b.iter()) {
            if r == 0.0 {
                *ui = e;
                fixed += 1;
            }
        }
        solutions.push((u, g.iterations, fixed));
    }
    let mut outcomes = Vec::with_capacity(rhs.len());
    for group in solutions.chunks(round) {
        let us: Vec<&[f64]> = group.iter().map(|(u, ..)| u.as_slice()).collect();
        for ((u, iterations, fixed), au) in group.iter().zip(sys.apply_many(&us)?) {
            let b = rhs[outcomes.len()];
            let r = b.iter().zip(&au).fold(0.0f64, |m, (b, au)| m.max((b - au).abs()));
            let scale = b.iter().fold(0.0f64, |m, v| m.max(v.abs())).max(f64::MIN_POSITIVE);
            outcomes.push(SolveOutcome {
                residual: r / scale,
                u: u.clone(),
                solver: "gmres",
                iterations: *iterations,
                condition_estimate: None,
                refinement_steps: 0,
                rows_eliminated: *fixed,
            });
        }
    }
    Ok(outcomes)
}
