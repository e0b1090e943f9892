//! What a compressed operator's build will hold at its peak, estimated before its blocks are
//! built (from a sample of its block plan: `CompressedOperator::build`), and what to say when
//! that cannot fit: how much is needed, how much may be used, and what would fit instead.

use serde::Serialize;

use super::stored::F32_FROM_TOLERANCE;
use crate::assembly::{MEMORY_SHARE, size_text};

/// The parts of a compressed operator's build, in bytes: the cluster trees counted, the rest
/// estimated from sampled pairs (`CompressedOperator::build` says how).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct MemoryEstimate {
    /// Unknowns.
    pub dof: usize,
    /// The node and element cluster trees (counted).
    pub trees: u64,
    /// The block plan's lists of blocks.
    pub plan: u64,
    /// The build's working lists of the blocks to build (grouped by node cluster, and the
    /// shadowed blocks' leaves) and the slots the blocks are built into, one `Block` each.
    pub lists: u64,
    /// The slots of the blocks that hold something, which the operator keeps as its index.
    pub index: u64,
    /// Exact entries: values and the row masks of sparse blocks and shadowed leaves.
    pub exact: u64,
    /// Low-rank factors.
    pub factors: u64,
    /// The node and element orders the operator keeps.
    pub orders: u64,
    /// The views of faces that the row walks keep for the nodes of the clusters being built,
    /// every thread's.
    pub views: u64,
    /// The cross approximations in flight, one of the widest blocks on each thread.
    pub crossing: u64,
    /// GMRES's Krylov vectors for one right-hand side and the products' buffers.
    pub solver: u64,
    /// Where a device evaluates the entries in batches: the host's buffers of one round of
    /// exact blocks (their pairs' tasks, twice while they are gathered, where each value goes,
    /// the values read back and the blocks' entries before they are compacted), at most.
    pub rounds: u64,
    /// One standard error of the sampled parts' sum (sampling alone; the ranks of the blocks
    /// not cross-approximated in the sample are the sampled ones' mean).
    pub error: u64,
    /// Pairs sampled.
    pub samples: usize,
    /// Blocks of the plan (exact, low-rank, shadowed blocks' parts), estimated.
    pub blocks: u64,
    /// Ranks the blocks are spread over (1: one process).
    pub ranks: usize,
    /// Whether the values are stored in f32.
    pub single: bool,
}

/// Factor by which the stored operator and the plan shrink at least with each refinement level
/// fewer: the unknowns shrink by 4, and the operator grows at least linearly with them
/// (docs/performance.md: like n^1.24 to n^1.6).
const PER_LEVEL: f64 = 4.0;

impl MemoryEstimate {
    /// The stored operator's bytes, as `operator_bytes` reports them: exact entries, factors,
    /// the blocks' index and the orders.
    pub fn operator_bytes(&self) -> u64 {
        self.exact + self.factors + self.index + self.orders
    }

    /// This rank's share of what is divided among the ranks.
    fn share(&self, bytes: u64) -> u64 {
        bytes / self.ranks.max(1) as u64
    }

    /// The most the build holds at once, in bytes above what the process held when it began:
    /// while the plan is walked (the trees and the plan's lists, twice: they grow by doubling,
    /// and the parts walked in parallel are copied into the whole), while the blocks are built
    /// (trees, plan, lists with every block's slot, views, cross approximations in flight and
    /// the values), or afterwards (the operator and the solver's vectors).
    pub fn peak_bytes(&self) -> u64 {
        let values = self.share(self.exact + self.factors) + self.orders;
        let walk = self.trees + 2 * self.plan;
        let build =
            self.trees + self.plan + self.lists + self.views + self.crossing + self.rounds + values;
        let after = values + self.share(self.index) + self.solver;
        walk.max(build).max(after)
    }

    /// The peak less two standard errors: a run is refused only where even this does not fit.
    pub fn low_bytes(&self) -> u64 {
        self.peak_bytes().saturating_sub(2 * self.error)
    }

    /// The estimate in a line (a note on stderr).
    pub fn note(&self) -> String {
        let t = |b: u64| size_text(b as f64);
        format!(
            "memory estimate: about {} at the peak of the compressed operator's build (stored \
             operator {}: exact entries {}, low-rank factors {}, block index {}; block plan {}, \
             build lists and slots {}, cluster trees {}, row walks' views {}, cross \
             approximations in flight {}, solver vectors {}{}; {} blocks), within {} (one \
             standard error) from {} sampled pairs{}",
            t(self.peak_bytes()),
            t(self.operator_bytes()),
            t(self.exact),
            t(self.factors),
            t(self.index),
            t(self.plan),
            t(self.lists),
            t(self.trees),
            t(self.views),
            t(self.crossing),
            t(self.solver),
            match self.rounds {
                0 => String::new(),
                r => format!(", a round of batches for the device {}", t(r)),
            },
            self.blocks,
            t(self.error),
            self.samples,
            if self.ranks > 1 { format!("; per rank of {}", self.ranks) } else { String::new() },
        )
    }

    /// Where most of the peak goes when the block plan and the build's lists and slots take
    /// more than half of it (a city at refine 0: faces of two elements make many small blocks,
    /// most of which end empty), in words.
    pub fn mostly_blocks(&self) -> Option<String> {
        let blocks = self.plan + self.lists;
        (2 * blocks > self.peak_bytes()).then(|| {
            format!(
                "{} of it for the block plan, the build's lists and the blocks' slots: about {} \
                 blocks, many small ones on faces of few elements",
                size_text(blocks as f64),
                self.blocks
            )
        })
    }

    /// The estimate with everything that grows with the mesh divided by `factor` (a coarser
    /// mesh: at most this much).
    fn coarser(&self, factor: f64) -> Self {
        let d = |b: u64| (b as f64 / factor).ceil() as u64;
        Self {
            trees: d(self.trees),
            plan: d(self.plan),
            lists: d(self.lists),
            index: d(self.index),
            exact: d(self.exact),
            factors: d(self.factors),
            orders: d(self.orders),
            views: d(self.views),
            crossing: d(self.crossing),
            solver: d(self.solver),
            rounds: d(self.rounds),
            error: d(self.error),
            ..*self
        }
    }

    /// What would fit in `available` bytes (this process holding `resident` already), as a
    /// sentence; `refine` (the mesh's level, where known) bounds the coarser meshes proposed.
    pub fn advice(&self, available: f64, resident: u64, refine: Option<u32>) -> String {
        let fits = |e: &Self| (e.peak_bytes() as f64) <= available;
        let mut ways = Vec::new();
        // Values in f32 take half the bytes of f64 ones.
        if !self.single {
            let f32 = Self { exact: self.exact / 2, factors: self.factors / 2, ..*self };
            if fits(&f32) {
                ways.push(format!(
                    "--compression-tolerance {:.0e} (values in f32: about {})",
                    F32_FROM_TOLERANCE.max(1e-6),
                    size_text(f32.peak_bytes() as f64)
                ));
            }
        }
        if let Some(refine) = refine {
            let level = (1..=refine).find_map(|fewer| {
                let e = self.coarser(PER_LEVEL.powi(fewer as i32));
                fits(&e).then(|| (refine - fewer, e.peak_bytes()))
            });
            if let Some((level, bytes)) = level {
                ways.push(format!(
                    "--refine {level} (about {} or less: each level fewer divides the unknowns by 4)",
                    size_text(bytes as f64)
                ));
            }
        } else {
            let e = self.coarser(PER_LEVEL);
            if fits(&e) {
                ways.push(format!(
                    "one refinement level fewer (about {} or less)",
                    size_text(e.peak_bytes() as f64)
                ));
            }
        }
        // Over MPI each rank holds the trees, the whole plan and its lists, its threads' views
        // and cross approximations, and its share of the blocks.
        let whole = self.trees + 2 * self.plan + self.lists + self.views + self.crossing;
        let whole = whole + self.solver + self.orders;
        let divided = self.exact + self.factors + self.index;
        if (whole as f64) < available && divided > 0 {
            let ranks = (divided as f64 / (available - whole as f64)).ceil() as usize;
            if ranks > self.ranks.max(1) && ranks <= 4096 {
                ways.push(format!(
                    "{ranks} ranks over MPI, each on a machine like this one (each holds the \
                     block plan, about {}, and its share of the blocks; docs/distributed.md)",
                    size_text(self.plan as f64)
                ));
            }
        }
        let whole_run = (resident + self.peak_bytes()) as f64;
        ways.push(format!(
            "a machine with about {} available (the process holds {} before the build; \
             without --memory-limit a run may use {:.0} % of what is available)",
            size_text(whole_run / MEMORY_SHARE),
            size_text(resident as f64),
            100.0 * MEMORY_SHARE
        ));
        format!("it would fit with {}", ways.join(", or "))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn estimate() -> MemoryEstimate {
        MemoryEstimate {
            dof: 1000,
            trees: 1 << 20,
            plan: 10 << 20,
            lists: 30 << 20,
            index: 20 << 20,
            exact: 400 << 20,
            factors: 100 << 20,
            orders: 16_000,
            views: 1 << 20,
            crossing: 2 << 20,
            solver: 300_000,
            rounds: 0,
            error: 5 << 20,
            samples: 4096,
            blocks: 100_000,
            ranks: 1,
            single: false,
        }
    }

    #[test]
    fn the_peak_is_the_largest_phase_and_the_low_bound_two_errors_below() {
        let e = estimate();
        let build =
            e.trees + e.plan + e.lists + e.views + e.crossing + e.exact + e.factors + e.orders;
        assert_eq!(e.peak_bytes(), build);
        assert_eq!(e.low_bytes(), build - 2 * e.error);
        assert_eq!(e.operator_bytes(), e.exact + e.factors + e.index + e.orders);
        // Over two ranks each holds half the blocks.
        let two = MemoryEstimate { ranks: 2, ..e };
        assert!(two.peak_bytes() < e.peak_bytes());
    }

    #[test]
    fn the_advice_proposes_only_what_fits() {
        let e = estimate();
        let peak = e.peak_bytes() as f64;
        // f32 values fit in 60 %, one level fewer in 30 %, two in 7 %.
        let advice = e.advice(0.6 * peak, 1 << 20, Some(3));
        assert!(advice.contains("--compression-tolerance 1e-6") && advice.contains("--refine 2"));
        let advice = e.advice(0.07 * peak, 1 << 20, Some(3));
        assert!(!advice.contains("--compression-tolerance") && advice.contains("--refine 1"));
        // At refine 0 no coarser mesh is proposed; a bigger machine always is.
        let advice = e.advice(0.07 * peak, 1 << 20, Some(0));
        assert!(!advice.contains("--refine") && advice.contains("a machine with about"));
        // MPI ranks where the plan fits.
        assert!(e.advice(0.3 * peak, 0, Some(0)).contains("ranks over MPI"));
    }
}
