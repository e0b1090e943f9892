//! One viewer's row of the pair plan: the one walk over the faces a point sees, in which every
//! (node, element) pair is classified and counted. The CPU assembly, the thin-column
//! recomputation, the GPU plan, the compressed operator's exact blocks and the emission integrals
//! all walk their rows here, so that a pair is classified the same way on every backend.
//!
//! For one viewer: a point that reflects nothing (rho = 0) has a zero row and sees nothing; else
//! each face is viewed once ([`PairPlanner::face_view_with`]); a skipped face hides all its
//! elements, an unobstructed one shows them all whole without per-element work, and otherwise
//! each element is clipped to its exactly visible part ([`PairPlanner::visible`]), except where
//! a half of the face's elements ([`ElementBoxes`]) has a box that the view shows whole or hides
//! whole: its elements are taken so at once (a louvre's slat shadows a few of a face's elements,
//! not all).

use std::ops::Range;

use glam::{DVec2, DVec3};
use rustc_hash::FxHashMap;

use super::cluster_candidates::ClusterCandidates;
use super::hiders::RecentHiders;
use super::planner::PairPlanner;
use super::stats::PairStats;
use super::view::{FaceView, SkipReason, Visibility};

/// A point of S that looks at the scene: a collocation node, or any point of a face.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Viewer {
    /// Position.
    pub position: DVec3,
    /// Unit normal of its face.
    pub normal: DVec3,
    /// The face it lies on.
    pub face: usize,
    /// Reflectivity there: a point with rho = 0 has a zero row of K and views nothing.
    pub rho: f64,
}

/// Where a walk finds its views of faces.
pub enum Views<'a> {
    /// Each face is viewed anew, trying the thread's recent hiders first.
    Fresh(&'a mut RecentHiders),
    /// Views are kept across walks of the same viewer (blocks of the compressed operator that
    /// share faces): each face is viewed once. The recent hiders are shared by the viewers
    /// walked in turn (the nodes of one cluster, whose hiders are mostly the same), and so are
    /// the candidate occluders found for each face (where the viewer is among those
    /// [`ClusterCandidates`] was made for).
    Kept(&'a mut KeptViews, &'a mut RecentHiders, &'a mut ClusterCandidates),
}

/// One viewer's views of the faces met so far. A node of a city meets
/// thousands of faces over its cluster's blocks: looked up by face, not searched in a list
/// (a search would dominate a large city's compressed setup), by a fast hash of the face's
/// number (SipHash's resistance to chosen keys buys nothing for face numbers).
#[derive(Debug, Default)]
pub struct KeptViews {
    views: FxHashMap<usize, FaceView>,
    /// Faces viewed, beside those that the planes tell.
    viewed: u64,
    /// Where known, the faces the viewer may see, sorted ([`super::FaceHierarchy::seen_from`]):
    /// any other is hidden without a view.
    seen: Option<Vec<u32>>,
    /// Faces found hidden so, without a view.
    culled: u64,
    /// Of `viewed`, the faces whose view found nothing seen: the work that a tighter set of
    /// the faces in sight would save.
    viewed_unseen: u64,
}

impl KeptViews {
    /// Views of a viewer that may see only the faces of `seen` (a superset of those it sees
    /// anything of): the others are hidden without a view.
    pub fn limited_to(seen: Vec<u32>) -> Self {
        Self { seen: Some(seen), ..Self::default() }
    }

    fn view(
        &mut self,
        planner: &PairPlanner,
        viewer: &Viewer,
        face: usize,
        (hiders, shared): (&mut RecentHiders, &mut ClusterCandidates),
    ) -> &FaceView {
        // Faces in the viewer's plane or behind it are told by the planes: not kept (most of
        // a node's faces in a city, whose insertions would cost more than the test).
        const SAME_PLANE: FaceView = FaceView::Skip(SkipReason::SamePlane);
        const FACING_AWAY: FaceView = FaceView::Skip(SkipReason::FacingAway);
        match planner.plane_skip_of(viewer.position, viewer.face, face) {
            Some(SkipReason::SamePlane) => return &SAME_PLANE,
            Some(_) => return &FACING_AWAY,
            None => {}
        }
        const HIDDEN: FaceView = FaceView::Skip(SkipReason::Hidden);
        if self.seen.as_ref().is_some_and(|seen| seen.binary_search(&(face as u32)).is_err()) {
            self.culled += 1;
            return &HIDDEN;
        }
        let (viewed, unseen) = (&mut self.viewed, &mut self.viewed_unseen);
        self.views.entry(face).or_insert_with(|| {
            let (p, n) = (viewer.position, viewer.normal);
            let view = planner.face_view_among(p, n, viewer.face, face, hiders, Some(shared));
            *viewed += 1;
            *unseen += u64::from(matches!(view, FaceView::Skip(_)));
            view
        })
    }

    /// Faces this viewer has viewed (each once), besides those that the planes told.
    pub fn faces_viewed(&self) -> u64 {
        self.viewed
    }

    /// Of [`KeptViews::faces_viewed`], those whose view found nothing of the face seen.
    pub fn faces_viewed_unseen(&self) -> u64 {
        self.viewed_unseen
    }

    /// Faces found hidden without a view (outside the faces it may see), each time asked.
    pub fn faces_culled(&self) -> u64 {
        self.culled
    }
}

/// What a viewer sees of the listed elements of one face. The pairs of a hidden or whole face
/// are already counted; those of a face seen in part are counted as [`PartSight::element`]
/// classifies them.
pub enum FaceSight<'a> {
    /// None of them.
    Hidden(SkipReason),
    /// Every one whole.
    Whole,
    /// Some in part, some whole, some not at all.
    Part(PartSight<'a>),
}

/// A face seen in part: clipped by the viewer's tangent plane or shadowed.
pub struct PartSight<'a> {
    planner: &'a PairPlanner,
    view: &'a FaceView,
    stats: &'a mut PairStats,
}

impl PartSight<'_> {
    /// The view of the face: the tangent plane's clip and the shadows, for a consumer that
    /// classifies the elements itself (the device's clipping kernel), counting them as it does.
    pub fn view(&self) -> &FaceView {
        self.view
    }

    /// What the viewer sees of the element `polygon` (convex, counter-clockwise, face
    /// coordinates), counted.
    pub fn element(&mut self, polygon: &[DVec2]) -> Visibility {
        let visibility = self.planner.visible(self.view, polygon);
        self.stats.record(&visibility, 1);
        visibility
    }

    /// What the viewer sees of each of the elements that `tree` holds, counted, given to
    /// `visit` with the element's position in its list. A half of the tree whose box the viewer
    /// sees whole, or not at all, is taken so at once ([`PairPlanner::visible_in_box`]); the
    /// elements of the others one by one.
    pub fn elements(&mut self, tree: &ElementBoxes, mut visit: impl FnMut(usize, Visibility)) {
        let mut at = 0;
        while let Some(node) = tree.nodes.get(at) {
            let range = node.range.clone();
            if let Some(visibility) = self.planner.visible_in_box(self.view, node.bounds) {
                self.stats.record(&visibility, range.len() as u64);
                range.for_each(|k| visit(k, visibility.clone()));
                at = node.past;
            } else if range.len() <= ElementBoxes::LEAF {
                for k in range {
                    visit(k, self.element(&tree.polygons[k]));
                }
                at = node.past;
            } else {
                at += 1;
            }
        }
    }
}

/// The boxes of a list of elements of one face (face coordinates), halved down to a few
/// elements: a viewer that sees a half's box whole or not at all sees each of its elements so.
/// The halves are runs of the list, so a list in the order of a cluster tree (which bisects
/// space) has halves that lie apart.
#[derive(Debug)]
pub struct ElementBoxes {
    /// The elements (convex, counter-clockwise, face coordinates).
    polygons: Vec<[DVec2; 3]>,
    /// Depth first: each node, then its halves.
    nodes: Vec<BoxNode>,
}

#[derive(Debug)]
struct BoxNode {
    /// Positions in the list.
    range: Range<usize>,
    bounds: (DVec2, DVec2),
    /// Index of the node after its subtree.
    past: usize,
}

impl ElementBoxes {
    /// Most elements of a half classified one by one rather than halved again.
    pub const LEAF: usize = 4;

    /// The tree's nodes depth first, each node before its halves: the positions it holds, its
    /// box, and the index of the node after its subtree (its second half's, if it has halves:
    /// they split its positions at the middle, down to [`ElementBoxes::LEAF`] or fewer).
    pub fn nodes(&self) -> impl Iterator<Item = (Range<usize>, (DVec2, DVec2), usize)> + '_ {
        self.nodes.iter().map(|n| (n.range.clone(), n.bounds, n.past))
    }

    /// The element at position `k` of the list (convex, counter-clockwise, face coordinates).
    pub fn polygon(&self, k: usize) -> &[DVec2] {
        &self.polygons[k]
    }

    /// The tree over the elements `polygons` (convex, counter-clockwise, face coordinates).
    pub fn new(polygons: Vec<[DVec2; 3]>) -> Self {
        let mut tree = Self { polygons, nodes: Vec::new() };
        tree.add(0..tree.polygons.len());
        tree
    }

    fn add(&mut self, range: Range<usize>) {
        if range.is_empty() {
            return;
        }
        let bounds = self.polygons[range.clone()].iter().flatten().fold(
            (DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY)),
            |(lo, hi), &v| (lo.min(v), hi.max(v)),
        );
        let at = self.nodes.len();
        self.nodes.push(BoxNode { range: range.clone(), bounds, past: 0 });
        if range.len() > Self::LEAF {
            let middle = range.start + range.len() / 2;
            self.add(range.start..middle);
            self.add(middle..range.end);
        }
        self.nodes[at].past = self.nodes.len();
    }
}

/// `items` (each with its face) grouped face by face, faces in the order they first appear, as
/// [`PairPlanner::walk_row`] takes them.
pub fn by_face(items: impl IntoIterator<Item = (usize, usize)>) -> Vec<(usize, Vec<usize>)> {
    let mut groups: Vec<(usize, Vec<usize>)> = Vec::new();
    for (face, item) in items {
        match groups.iter_mut().rev().find(|(f, _)| *f == face) {
            Some((_, list)) => list.push(item),
            None => groups.push((face, vec![item])),
        }
    }
    groups
}

impl PairPlanner {
    /// Walks `viewer`'s row over `faces`, each given with the elements of it to classify, calling
    /// `visit(face, elements, sight)` for every face (none when the viewer reflects nothing), and
    /// returns the counts of the pairs by class.
    pub fn walk_row<E: ExactSizeIterator>(
        &self,
        viewer: &Viewer,
        faces: impl IntoIterator<Item = (usize, E)>,
        mut views: Views<'_>,
        mut visit: impl FnMut(usize, E, FaceSight<'_>),
    ) -> PairStats {
        let mut stats = PairStats::default();
        if viewer.rho == 0.0 {
            let count = faces.into_iter().map(|(_, elements)| elements.len()).sum();
            return PairStats::not_reflecting_row(count);
        }
        for (face, elements) in faces {
            let count = elements.len() as u64;
            let fresh;
            let view = match &mut views {
                Views::Fresh(hiders) => {
                    let (p, n) = (viewer.position, viewer.normal);
                    fresh = self.face_view_with(p, n, viewer.face, face, hiders);
                    &fresh
                }
                Views::Kept(kept, hiders, shared) => {
                    kept.view(self, viewer, face, (hiders, shared))
                }
            };
            let sight = match view {
                FaceView::Skip(reason) => {
                    stats.record(&Visibility::Skip(*reason), count);
                    FaceSight::Hidden(*reason)
                }
                view if view.is_unobstructed() => {
                    stats.record(&Visibility::Full, count);
                    FaceSight::Whole
                }
                view => FaceSight::Part(PartSight { planner: self, view, stats: &mut stats }),
            };
            visit(face, elements, sight);
        }
        stats
    }
}
