//! The occluders that last hid a face from a point, tried before any search.

use glam::DVec3;

use super::occluders::Occluder;

/// The occluders that last hid a whole face from a point, most recent first: a building that
/// hides one face of another from a node usually hides its neighbours too, and hides them from
/// the next node of the same face as well, so they are tried before any search
/// ([`PairPlanner::face_view_with`](super::PairPlanner::face_view_with)). One per thread, kept
/// across the points it treats in turn.
#[derive(Clone, Debug, Default)]
pub struct RecentHiders {
    pub(super) list: Vec<Hider>,
}

/// An occluder piece that hid a face, and its bounding box.
#[derive(Clone, Debug)]
pub(super) struct Hider {
    pub(super) occluder: usize,
    pub(super) lo: DVec3,
    pub(super) hi: DVec3,
}

/// How many occluders [`RecentHiders`] keeps: in a city of 3 281 faces, 32 catch most of the
/// views that 8 sent to the search (setup 0.76 of it; 64 was slower again).
const RECENT_HIDERS: usize = 32;

impl RecentHiders {
    pub(super) fn remember(&mut self, occluder: usize, piece: &Occluder) {
        self.list.retain(|h| h.occluder != occluder);
        let (lo, hi) = piece.bounding_box();
        self.list.insert(0, Hider { occluder, lo, hi });
        self.list.truncate(RECENT_HIDERS);
    }
}
