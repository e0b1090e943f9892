//! The compressed operator's build held to what may be used: the estimate refused before the
//! plan, the plan's walk given a budget, and the blocks stored (with the growth of the resident
//! memory) counted while they are built.

use std::sync::atomic::{AtomicU64, Ordering};

use super::blocks::PlanBudget;
use super::estimate::MemoryEstimate;
use crate::assembly::{allowance_source, gib, memory_allowance, resident_bytes, size_text};
use crate::error::{Error, Result};

/// What the build of a compressed operator holds against what may be used
/// ([`memory_allowance`] when the build starts: what `--memory-limit` leaves above what the
/// process holds, or a share of the available memory): before the plan, the estimate of its
/// peak ([`MemoryGuard::refusal`]); while the plan is walked, its lists ([`PlanBudget`]); while
/// the blocks are built, the blocks stored and the growth of the process's resident memory, so
/// that the build's transient buffers count too. A build that outgrows it stops with
/// [`Error::OperatorTooLarge`] instead of ending in the out-of-memory killer.
pub(super) struct MemoryGuard {
    dof: usize,
    allowance: Option<f64>,
    /// Where the allowance comes from, in words.
    source: String,
    /// What the process held when the build began.
    resident: u64,
    /// The estimate made before the plan.
    pub(super) estimate: Option<MemoryEstimate>,
    stored: AtomicU64,
    /// Resident memory when the build started.
    resident_at_start: Option<u64>,
    /// The most the resident memory has grown above that, at the looks so far.
    grown: AtomicU64,
    /// Stored bytes at the last look.
    looked_at: AtomicU64,
}

/// The guard looks at the resident memory each time the stored blocks grow by this much.
const LOOK_EVERY: u64 = 16 << 20;

impl MemoryGuard {
    /// The process's resident memory when the build began, where the system tells.
    pub(super) fn resident_at_start(&self) -> Option<u64> {
        self.resident_at_start
    }

    pub(super) fn new(dof: usize) -> Self {
        Self { source: allowance_source(), ..Self::with_allowance(dof, memory_allowance()) }
    }

    /// A guard of `allowance` bytes (tests give their own).
    pub(super) fn with_allowance(dof: usize, allowance: Option<f64>) -> Self {
        let resident_at_start = resident_bytes();
        Self {
            dof,
            allowance,
            source: "the guard's allowance; see --memory-limit".into(),
            resident: resident_at_start.unwrap_or(0),
            estimate: None,
            stored: AtomicU64::new(0),
            resident_at_start,
            grown: AtomicU64::new(0),
            looked_at: AtomicU64::new(0),
        }
    }

    /// The error refusing the build before it begins, where even the low end of `estimate`
    /// (two standard errors below it) exceeds the allowance; `refine`, the mesh's level where
    /// known, for the advice.
    pub(super) fn refusal(&self, estimate: &MemoryEstimate, refine: Option<u32>) -> Option<Error> {
        let available = self.allowance?;
        if estimate.low_bytes() as f64 <= available {
            return None;
        }
        let peak = estimate.peak_bytes() as f64;
        Some(Error::OperatorTooLarge {
            dof: self.dof,
            needed_gib: gib(peak),
            available_gib: gib(available),
            what: format!(
                "the compressed operator of {} unknowns would need about {} at the peak of its \
                 build (at least {}: the estimate less two standard errors; stored operator \
                 about {}{}), but {} may be used ({})",
                self.dof,
                size_text(peak),
                size_text(estimate.low_bytes() as f64),
                size_text(estimate.operator_bytes() as f64),
                estimate.mostly_blocks().map_or(String::new(), |why| format!("; {why}")),
                size_text(available),
                self.source
            ),
            advice: estimate.advice(available, self.resident, refine),
        })
    }

    /// The error of a rank whose estimate fits where another rank's does not.
    pub(super) fn refused_elsewhere(&self, estimate: &MemoryEstimate) -> Error {
        let available = self.allowance.unwrap_or(0.0);
        let peak = estimate.peak_bytes() as f64;
        Error::OperatorTooLarge {
            dof: self.dof,
            needed_gib: gib(peak),
            available_gib: gib(available),
            what: format!(
                "the compressed operator of {} unknowns was refused: another rank may use less \
                 than its estimate of about {} at the peak (this one may use {})",
                self.dof,
                size_text(peak),
                size_text(available)
            ),
            advice: "give every rank the same --memory-limit, or use machines with more memory"
                .into(),
        }
    }

    /// The plan's budget: what the allowance leaves beside the cluster trees (`trees` bytes);
    /// `None` without an allowance.
    pub(super) fn plan_budget(&self, trees: u64) -> Option<PlanBudget> {
        self.allowance.map(|a| PlanBudget::new((a - trees as f64).max(0.0) as u64))
    }

    /// The error of a plan whose walk passed `budget` (beside the trees' `trees` bytes).
    pub(super) fn plan_too_large(&self, budget: &PlanBudget, trees: u64) -> Error {
        let available = self.allowance.unwrap_or(0.0);
        let taken = (budget.used() + trees) as f64;
        Error::OperatorTooLarge {
            dof: self.dof,
            needed_gib: gib(taken),
            available_gib: gib(available),
            what: format!(
                "the compressed operator of {} unknowns was stopped while its block plan was \
                 walked: the plan's lists (counted twice: they grow by doubling) and the cluster \
                 trees had reached {}, more than the {} that may be used ({}){}",
                self.dof,
                size_text(taken),
                size_text(available),
                self.source,
                self.estimate_was(taken)
            ),
            advice: format!(
                "{BUILD_ADVICE}; the plan grows with the square of the unknowns where faces hold \
                 few elements (a city at refine 0)"
            ),
        }
    }

    /// What the estimate made before said, for a build stopped at `taken` bytes.
    fn estimate_was(&self, taken: f64) -> String {
        match &self.estimate {
            Some(e) if (e.peak_bytes() as f64) < taken => {
                format!(
                    "; the estimate made before, about {}, was low",
                    size_text(e.peak_bytes() as f64)
                )
            }
            Some(e) => format!("; estimated before at about {}", size_text(e.peak_bytes() as f64)),
            None => String::new(),
        }
    }

    /// Counts `bytes` stored.
    pub(super) fn add(&self, bytes: u64) {
        let stored = self.stored.fetch_add(bytes, Ordering::Relaxed) + bytes;
        let last = self.looked_at.load(Ordering::Relaxed);
        if stored >= last + LOOK_EVERY
            && self
                .looked_at
                .compare_exchange(last, stored, Ordering::Relaxed, Ordering::Relaxed)
                .is_ok()
        {
            self.look();
        }
    }

    /// Takes the growth of the resident memory since the build began into account.
    fn look(&self) {
        if let (Some(start), Some(now)) = (self.resident_at_start, resident_bytes()) {
            self.grown.fetch_max(now.saturating_sub(start), Ordering::Relaxed);
        }
    }

    /// Memory the build has taken: the blocks stored, or the growth of the resident memory
    /// where that was more.
    fn used(&self) -> u64 {
        self.stored.load(Ordering::Relaxed).max(self.grown.load(Ordering::Relaxed))
    }

    /// Bytes kept aside from the allowance for what the guard does not see at once: the growth
    /// between two of its looks at the memory, and the cross approximations in flight (as
    /// estimated).
    fn aside(&self) -> f64 {
        (LOOK_EVERY + self.estimate.map_or(0, |e| e.crossing)) as f64
    }

    /// Bytes the blocks and the build's buffers may take while the blocks are built: the
    /// allowance less what is kept aside.
    fn cap(&self) -> Option<f64> {
        self.allowance.map(|a| a - self.aside())
    }

    /// Whether what is used exceeds the cap.
    pub(super) fn is_over(&self) -> bool {
        self.over_by(0)
    }

    /// Whether what is used, with `more`, exceeds the cap: the blocks other threads are
    /// building and the growth since the last look are not seen yet.
    fn over_by(&self, more: u64) -> bool {
        self.cap().is_some_and(|cap| (self.used() + more) as f64 > cap)
    }

    /// The error when what is used, with `more` bytes, exceeds the cap.
    pub(super) fn check(&self, more: u64) -> Result<()> {
        self.look();
        if !self.over_by(more) {
            return Ok(());
        }
        let available = self.allowance.unwrap_or(0.0);
        let cap = self.cap().unwrap_or(0.0);
        let taken = (self.used() + more) as f64;
        let stopped = if cap > 0.0 {
            format!(
                "it had taken {} with what it was about to allocate, more than the {} it may \
                 take: the {} that may be used ({}) less {} kept aside for what the guard does \
                 not see at once (the growth between two of its looks at the memory, the cross \
                 approximations in flight)",
                size_text(taken),
                size_text(cap),
                size_text(available),
                self.source,
                size_text(self.aside())
            )
        } else {
            format!(
                "the {} that may be used ({}) leaves nothing once {} are kept aside for what the \
                 guard does not see at once",
                size_text(available),
                self.source,
                size_text(self.aside())
            )
        };
        Err(Error::OperatorTooLarge {
            dof: self.dof,
            needed_gib: gib(taken),
            available_gib: gib(available),
            what: format!(
                "the build of the compressed operator of {} unknowns was stopped: {stopped}{}",
                self.dof,
                self.estimate_was(taken)
            ),
            advice: BUILD_ADVICE.into(),
        })
    }
}

/// What a build stopped for memory may try.
const BUILD_ADVICE: &str = "raise --memory-limit or --compression-tolerance, use a coarser mesh \
     (each refinement level multiplies the memory by about 5) or a machine with more memory";
