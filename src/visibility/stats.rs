//! Counts of (node, element) pairs by class, for reports (`radiosity inspect`).

use std::ops::AddAssign;

use serde::Serialize;

use super::view::{SkipReason, Visibility};

/// How many (node, element) pairs fell in each class.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
pub struct PairStats {
    /// All pairs: dof × n.
    pub total: u64,
    /// Node and element in one plane.
    pub same_plane: u64,
    /// Facing away from each other.
    pub facing_away: u64,
    /// Fully hidden by occluders.
    pub hidden: u64,
    /// The node reflects nothing (rho = 0): not evaluated.
    pub not_reflecting: u64,
    /// Fully visible.
    pub full: u64,
    /// Partly visible (clipped or partly shadowed): evaluated over exact visible pieces.
    pub partial: u64,
}

impl PairStats {
    /// The pairs of one node that reflects nothing (rho = 0): a zero row, nothing evaluated.
    pub fn not_reflecting_row(elements: usize) -> Self {
        let mut s = Self::default();
        s.record(&Visibility::Skip(SkipReason::NotReflecting), elements as u64);
        s
    }

    /// The counts in a fixed order (total, same plane, facing away, hidden, not reflecting,
    /// full, partial), as files and messages between processes carry them.
    pub fn counts(&self) -> [u64; 7] {
        [
            self.total,
            self.same_plane,
            self.facing_away,
            self.hidden,
            self.not_reflecting,
            self.full,
            self.partial,
        ]
    }

    /// The statistics of [`PairStats::counts`].
    pub fn from_counts(
        [total, same_plane, facing_away, hidden, not_reflecting, full, partial]: [u64; 7],
    ) -> Self {
        Self { total, same_plane, facing_away, hidden, not_reflecting, full, partial }
    }

    /// Pairs that contribute nothing.
    pub fn skipped(&self) -> u64 {
        self.same_plane + self.facing_away + self.hidden + self.not_reflecting
    }

    /// Records `count` pairs of one class.
    pub fn record(&mut self, v: &Visibility, count: u64) {
        self.total += count;
        match v {
            Visibility::Skip(SkipReason::SamePlane) => self.same_plane += count,
            Visibility::Skip(SkipReason::FacingAway) => self.facing_away += count,
            Visibility::Skip(SkipReason::Hidden) => self.hidden += count,
            Visibility::Skip(SkipReason::NotReflecting) => self.not_reflecting += count,
            Visibility::Full => self.full += count,
            Visibility::Partial(_) => self.partial += count,
        }
    }
}

impl AddAssign for PairStats {
    fn add_assign(&mut self, o: Self) {
        self.total += o.total;
        self.same_plane += o.same_plane;
        self.facing_away += o.facing_away;
        self.hidden += o.hidden;
        self.not_reflecting += o.not_reflecting;
        self.full += o.full;
        self.partial += o.partial;
    }
}
