//! Solving `(I - K) u = E` where K is known by its products alone: the compressed operator
//! ([`crate::operator`]), or K kept on the GPU ([`crate::gpu::DeviceOperator`]). GMRES, since no
//! matrix is there to factor.

use std::ops::Range;

use super::gmres::{Gmres, Need, RESTART, Rows};
use super::{
    CLOSED_ROW_TOLERANCE, SolveOutcome, SolverOptions, check_tolerance, reject_unit_row_sums,
};
use crate::distributed::Collective;
use crate::error::Result;
use crate::gpu::{DeviceBlocks, DeviceOperator};
use crate::operator::CompressedOperator;

/// An operator known by its products.
pub trait Products: Sync {
    /// Number of unknowns.
    fn dof(&self) -> usize;
    /// `K x` for every `x` in `xs`, the operator read once for all of them; over several
    /// ranks every rank calls it with the same `xs` and gets the whole products.
    fn apply_many(&self, xs: &[&[f64]]) -> Result<Vec<Vec<f64>>>;
    /// The ranks the operator is spread over, if it is: the solve then divides its vectors
    /// among them.
    fn ranks(&self) -> Option<&dyn Collective> {
        None
    }
}

impl Products for CompressedOperator {
    fn dof(&self) -> usize {
        CompressedOperator::dof(self)
    }

    fn apply_many(&self, xs: &[&[f64]]) -> Result<Vec<Vec<f64>>> {
        Ok(CompressedOperator::apply_many(self, xs))
    }

    fn ranks(&self) -> Option<&dyn Collective> {
        self.share.as_ref().map(|share| &*share.ranks as &dyn Collective)
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

/// `I - diag(s) K` (s = 1 but for a colour band's rows), on this process's rows of the
/// vectors: over several ranks each holds the rows [`own_rows`] gives it, and a product
/// gathers the whole `x` from them, every rank's partial `K x` is summed, and each keeps its
/// rows of the result.
struct ProductSystem<'a> {
    k: &'a dyn Products,
    /// This process's rows of `s`.
    row_scale: Option<Vec<f64>>,
    rows: Range<usize>,
}

impl ProductSystem<'_> {
    /// This process's rows of `A x` for every `x` in `xs` (this process's rows of each), the
    /// operator read once for all of them.
    fn apply_many(&self, xs: &[&[f64]]) -> Result<Vec<Vec<f64>>> {
        let whole = whole_vectors(xs, self.k.dof(), self.k.ranks());
        let whole: Vec<&[f64]> = whole.iter().map(Vec::as_slice).collect();
        let whole = if whole.is_empty() { xs } else { &whole[..] };
        let mut kxs = self.k.apply_many(whole)?;
        for (x, kx) in xs.iter().zip(&mut kxs) {
            if kx.len() != x.len() {
                *kx = kx[self.rows.clone()].to_vec();
            }
            if let Some(scale) = &self.row_scale {
                kx.iter_mut().zip(scale).for_each(|(v, s)| *v *= s);
            }
            kx.iter_mut().zip(x.iter()).for_each(|(v, a)| *v = a - *v);
        }
        Ok(kxs)
    }
}

/// The rows of an `n`-vector that this process holds in a solve over `ranks`: a contiguous
/// range, the ranks' ranges in rank order, their lengths differing by one at most.
fn own_rows(n: usize, ranks: Option<&dyn Collective>) -> Range<usize> {
    match ranks {
        None => 0..n,
        Some(ranks) => rows_of(n, ranks.rank(), ranks.size()),
    }
}

fn rows_of(n: usize, rank: usize, size: usize) -> Range<usize> {
    n * rank / size..n * (rank + 1) / size
}

/// The whole `n`-vectors of which `parts` are this process's rows ([`own_rows`]), gathered
/// from every rank in one exchange; nothing (the parts are whole) in one process.
fn whole_vectors(parts: &[&[f64]], n: usize, ranks: Option<&dyn Collective>) -> Vec<Vec<f64>> {
    let Some(ranks) = ranks else {
        return Vec::new();
    };
    // Every rank sends as many values: its rows of each vector, padded to the longest share.
    let width = n.div_ceil(ranks.size());
    let mut mine = vec![0.0; width * parts.len()];
    for (slot, part) in mine.chunks_mut(width).zip(parts) {
        slot[..part.len()].copy_from_slice(part);
    }
    let all = ranks.gather_f64(&mine);
    (0..parts.len())
        .map(|v| {
            let mut x = Vec::with_capacity(n);
            for (rank, theirs) in all.iter().enumerate() {
                let len = rows_of(n, rank, ranks.size()).len();
                x.extend_from_slice(&theirs[v * width..v * width + len]);
            }
            x
        })
        .collect()
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
    let row_scale: Option<Vec<f64>> = (rho != operator_rho).then(|| {
        rho.iter().zip(operator_rho).map(|(&b, &g)| if g == 0.0 { 0.0 } else { b / g }).collect()
    });
    if !rho.is_empty() && rho.iter().all(|&r| r == 1.0) {
        let ones = vec![1.0; k.dof()];
        let mut sums = k.apply_many(&[&ones])?.pop().expect("one product");
        if let Some(scale) = &row_scale {
            sums.iter_mut().zip(scale).for_each(|(v, s)| *v *= s);
        }
        reject_unit_row_sums(&sums, CLOSED_ROW_TOLERANCE.max(10.0 * compression_tolerance))?;
    }
    let rows = own_rows(k.dof(), k.ranks());
    let row_scale = row_scale.map(|s| s[rows.clone()].to_vec());
    let sys = ProductSystem { k, row_scale, rows };
    // Each solve holds its Krylov basis: as many at once as fit in the budget. Counted for the
    // longest share, so that every rank advances the same groups.
    let longest = k.ranks().map_or(k.dof(), |ranks| k.dof().div_ceil(ranks.size()));
    let together = (SOLVES_BYTES / (8 * (RESTART + 2) * longest).max(1)).max(1);
    let mut outcomes = Vec::with_capacity(rhs.len());
    for group in rhs.chunks(together) {
        outcomes.extend(solve_together(&sys, group, rho, options.tolerance)?);
    }
    Ok(outcomes)
}

/// GMRES for each right-hand side of `rhs` on `sys`, in lockstep: each round's products in one
/// pass over the blocks. The solves hold their vectors' rows of `sys`; the solutions are whole.
fn solve_together(
    sys: &ProductSystem,
    whole_rhs: &[&[f64]],
    whole_rho: &[f64],
    tolerance: f64,
) -> Result<Vec<SolveOutcome>> {
    let round = (ROUND_BYTES / (8 * sys.k.dof()).max(1)).max(1);
    let ranks = sys.k.ranks();
    let rows = ranks.map_or(Rows::whole(), Rows::over);
    let rhs: Vec<&[f64]> = whole_rhs.iter().map(|b| &b[sys.rows.clone()]).collect();
    let rho = &whole_rho[sys.rows.clone()];
    let mut solvers: Vec<Gmres> =
        rhs.iter().map(|b| Gmres::over_rows(b, tolerance, rows)).collect();
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
    for (solver, b) in solvers.into_iter().zip(&rhs) {
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
        let products = sys.apply_many(&us)?;
        // The residuals' largest entries and the rows eliminated, over the ranks' rows; the
        // solutions whole.
        let first = outcomes.len();
        let largest: Vec<f64> = (rhs[first..].iter().zip(&products))
            .map(|(b, au)| b.iter().zip(au).fold(0.0f64, |m, (b, au)| m.max((b - au).abs())))
            .collect();
        let fixed: Vec<f64> = group.iter().map(|(_, _, fixed)| *fixed as f64).collect();
        let (largest, fixed) = (rows.largest(&largest), rows.summed(&fixed));
        let whole = whole_vectors(&us, sys.k.dof(), ranks);
        for (at, (u, iterations, _)) in group.iter().enumerate() {
            let b = whole_rhs[first + at];
            let scale = b.iter().fold(0.0f64, |m, v| m.max(v.abs())).max(f64::MIN_POSITIVE);
            outcomes.push(SolveOutcome {
                residual: largest[at] / scale,
                // In one process the rows are the whole.
                u: whole.get(at).unwrap_or(u).clone(),
                solver: "gmres",
                iterations: *iterations,
                condition_estimate: None,
                refinement_steps: 0,
                rows_eliminated: fixed[at] as usize,
            });
        }
    }
    Ok(outcomes)
}
