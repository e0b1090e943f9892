//! Counts of (node, element) pairs by class, for reports (`radiosity inspect`).

use std::ops::AddAssign;

use serde::Serialize;

use super::{SkipReason, Visibility};

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
    /// Fully visible.
    pub full: u64,
    /// Partly visible (clipped or partly shadowed): evaluated over exact visible pieces.
    pub partial: u64,
}

impl PairStats {
    /// Pairs that contribute nothing.
    pub fn skipped(&self) -> u64 {
        self.same_plane + self.facing_away + self.hidden
    }

    /// Records `count` pairs of one class.
    pub fn record(&mut self, v: &Visibility, count: u64) {
        self.total += count;
        match v {
            Visibility::Skip(SkipReason::SamePlane) => self.same_plane += count,
            Visibility::Skip(SkipReason::FacingAway) => self.facing_away += count,
            Visibility::Skip(SkipReason::Hidden) => self.hidden += count,
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
        self.full += o.full;
        self.partial += o.partial;
    }
}
