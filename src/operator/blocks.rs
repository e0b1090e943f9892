//! The block tree: which pairs (node cluster, element cluster) hold nothing, which are smooth and
//! far enough apart to be compressed, and which are leaves computed exactly.

use std::cell::OnceCell;
use std::sync::atomic::{AtomicU64, Ordering};

use glam::DVec3;
use rayon::prelude::*;

use super::cluster::{Cluster, ClusterTree};
use super::options::{CompressionOptions, ShadowedBlocks};
use super::sight::ClusterSight;
use crate::distributed::Collective;
use crate::geometry::box_corners;
use crate::mesh::Element;
use crate::progress::Progress;
use crate::scene::Scene;
use crate::visibility::{OccluderUnit, PairPlanner, Shaft};

/// What a block of nodes on face a and elements on face b needs.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum PairClass {
    /// G V = 0 for every pair: one plane, one box wholly behind the other face's plane, or one
    /// occluder crossing every segment between the boxes.
    Nothing,
    /// Every element in front of every node's plane and facing it, no occluder in the shaft.
    Smooth,
    /// As smooth, but occluders may come between (one pair of faces): the unoccluded kernel is
    /// smooth, visibility cuts it.
    Shadowed,
    /// Anything else: partly behind, or an occluder may come between.
    Mixed,
}

/// Blocks whose clusters span more face pairs than this are subdivided without being classified
/// (classification costs a shaft test per face pair).
const MAX_FACE_PAIRS: usize = 16;

/// The scene's faces as the block classification sees them.
pub(super) struct FacePairs<'a> {
    scene: &'a Scene,
    planner: &'a PairPlanner,
    /// Whether elements across the nodes' tangent planes make a block shadowed (a shadowed
    /// block can take them) rather than mixed.
    planes_shadow: bool,
    /// Where found, the faces each node cluster may see: a block of none of them is empty.
    pub(super) sight: Option<&'a ClusterSight>,
}

impl<'a> FacePairs<'a> {
    pub(super) fn new(
        scene: &'a Scene,
        planner: &'a PairPlanner,
        options: &CompressionOptions,
        sight: Option<&'a ClusterSight>,
    ) -> Self {
        let planes_shadow = options.shadowed_blocks == ShadowedBlocks::On;
        Self { scene, planner, planes_shadow, sight }
    }

    fn class(
        &self,
        a: usize,
        b: usize,
        nodes: &Cluster,
        elements: &Cluster,
        between: &Between,
    ) -> PairClass {
        if self.planner.same_plane(a, b) {
            return PairClass::Nothing;
        }
        let (fa, fb) = (&self.scene.faces[a].frame, &self.scene.faces[b].frame);
        let (elo, ehi) = height_range(fa, elements.bounds());
        let (nlo, nhi) = height_range(fb, nodes.bounds());
        if ehi <= 0.0 || nhi <= 0.0 {
            return PairClass::Nothing;
        }
        // Touching the other plane is fine (an element along the common edge of two faces):
        // G is analytic up to cos = 0; only a part behind it would need clipping. The margin is
        // the dense plan's (no clip within 1e-12 of the size).
        let margin = -1e-12 * (nodes.diameter() + elements.diameter() + nodes.distance(elements));
        if nlo < margin || (elo < margin && !self.planes_shadow) {
            return PairClass::Mixed;
        }
        let candidates = Some(between.candidates(self.planner, nodes, elements));
        match self.planner.shaft(a, b, nodes.bounds(), elements.bounds(), candidates) {
            Shaft::Hidden => PairClass::Nothing,
            // Elements across the nodes' tangent planes: the kernel continues across them
            // analytically (the nodes are in front of the elements' plane), and the planes cut
            // it as occluders do.
            _ if elo < margin => PairClass::Shadowed,
            Shaft::Clear => PairClass::Smooth,
            Shaft::Partial => PairClass::Shadowed,
        }
    }

    /// Whether node (on `face`, at `p`) and element `el` give G = 0 throughout: one plane, the
    /// element on or behind the node's tangent plane, or the node on or behind the element's.
    /// In a smooth block this is the whole difference between an entry and the kernel over the
    /// whole element.
    pub(super) fn nothing_between(&self, face: usize, p: DVec3, el: &Element) -> bool {
        let fa = &self.scene.faces[face].frame;
        let element_frame = self.scene.faces[el.face].frame.with_origin(el.centroid());
        self.planner.same_plane(face, el.face)
            || el.vertices.iter().all(|&v| fa.normal.dot(v - p) <= 0.0)
            || element_frame.height(p) <= 0.0
    }

    /// Whether [`FacePairs::nothing_between`] is false for every node of `nodes` and element of
    /// `elements`, as their boxes tell: no face pair in one plane, and each box clear of the
    /// other's planes by a thousandth of the block's size, which covers an element's own plane
    /// leaning from its face's within the planarity tolerance. Far blocks mostly are, and their
    /// cross approximations then skip the test of each entry.
    pub(super) fn every_pair_gives(&self, nodes: &Cluster, elements: &Cluster) -> bool {
        let margin = 1e-3 * (nodes.diameter() + elements.diameter() + nodes.distance(elements));
        let clear = |face: usize, cluster: &Cluster| {
            height_range(&self.scene.faces[face].frame, cluster.bounds()).0 > margin
        };
        nodes.faces.iter().all(|&a| {
            elements
                .faces
                .iter()
                .all(|&b| !self.planner.same_plane(a, b) && clear(a, elements) && clear(b, nodes))
        })
    }
}

/// The occluder pieces that may come between a block's two clusters, found when a shaft test
/// first needs them: from the parent block's list where it has one (the block's segments are
/// among the parent's), else from the whole scene. The block's list is its sub-blocks' parent
/// list, so the walk narrows the occluders as it descends instead of searching the scene's
/// index from its root for every block.
struct Between<'a> {
    parent: Option<&'a [OccluderUnit]>,
    found: OnceCell<Vec<OccluderUnit>>,
}

impl<'a> Between<'a> {
    fn new(parent: Option<&'a [OccluderUnit]>) -> Self {
        Self { parent, found: OnceCell::new() }
    }

    fn candidates(
        &self,
        planner: &PairPlanner,
        nodes: &Cluster,
        elements: &Cluster,
    ) -> &[OccluderUnit] {
        self.found.get_or_init(|| {
            planner.shaft_candidates(nodes.bounds(), elements.bounds(), self.parent)
        })
    }

    /// The list for the sub-blocks: this block's if found, else its parent's.
    fn for_children(&self) -> Option<&[OccluderUnit]> {
        self.found.get().map(Vec::as_slice).or(self.parent)
    }
}

/// Smallest and largest height of a box's corners above a plane.
fn height_range(frame: &crate::geometry::PlaneFrame, bounds: (DVec3, DVec3)) -> (f64, f64) {
    box_corners(bounds).iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &c| {
        let h = frame.height(c);
        (lo.min(h), hi.max(h))
    })
}

/// A block computed exactly: node cluster t, element cluster s.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub(super) struct NearBlock {
    pub t: usize,
    pub s: usize,
    /// Every element in front of every node and seen whole (class smooth): every entry is
    /// non-zero and stored. Otherwise the block stores what is seen, from nothing to all.
    pub seen_whole: bool,
}

/// An admissible block that occluders cut (class shadowed): its unoccluded kernel is
/// compressed once, and its sub-blocks take their entries from those factors where they are
/// seen whole and from the exact integrals where visibility varies.
#[derive(Clone, Debug, PartialEq, Eq)]
pub(super) struct ShadowedBlock {
    pub t: usize,
    pub s: usize,
    /// Sub-blocks seen whole: the factors' product.
    pub seen: Vec<(usize, usize)>,
    /// Leaves where visibility varies: the product on the elements a node sees whole, the
    /// exact integral on those it sees in part.
    pub leaves: Vec<(usize, usize)>,
}

/// The blocks of K: pairs (node cluster, element cluster) by index into their trees.
#[derive(Clone, Debug, Default)]
pub(super) struct BlockPlan {
    /// Leaves computed exactly.
    pub near: Vec<NearBlock>,
    /// Smooth admissible blocks, to be compressed.
    pub far: Vec<(usize, usize)>,
    /// Admissible blocks that occluders cut, with their sub-blocks.
    pub shadowed: Vec<ShadowedBlock>,
    /// Blocks holding nothing, left out.
    pub empty: Empty,
}

/// The blocks a plan found to hold nothing (sub-blocks of shadowed blocks among them), and the
/// (node, element) pairs in them: pairs settled without a test of their own, which shows how
/// much of the pair matrix the plan culls whole.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub(super) struct Empty {
    pub blocks: usize,
    pub pairs: u64,
}

impl Empty {
    fn add(&mut self, nodes: &Cluster, elements: &Cluster) {
        self.blocks += 1;
        self.pairs += (nodes.len() * elements.len()) as u64;
    }
}

impl std::ops::AddAssign for Empty {
    fn add_assign(&mut self, other: Self) {
        self.blocks += other.blocks;
        self.pairs += other.pairs;
    }
}

/// How far a walk of the plan has got, reported to a [`Progress`] in thousandths of the
/// (node, element) pairs it settles: the pairs of every block it settles, whatever its kind,
/// so the count ends at the whole. A block's cost is that of its classification, not of its
/// pairs, so this paces the walk only roughly (large blocks settle early).
pub(super) struct PlanProgress<'a> {
    progress: &'a dyn Progress,
    total: u64,
    settled: AtomicU64,
}

/// Steps of a plan's progress stage.
pub(super) const PLAN_STEPS: usize = 1000;

impl<'a> PlanProgress<'a> {
    /// Progress over `total` pairs, whose stage the caller has started with [`PLAN_STEPS`].
    pub(super) fn new(progress: &'a dyn Progress, total: u64) -> Self {
        Self { progress, total: total.max(1), settled: AtomicU64::new(0) }
    }

    fn settle(&self, pairs: u64) {
        let before = self.settled.fetch_add(pairs, Ordering::Relaxed);
        let step = |p: u64| {
            (u128::from(p.min(self.total)) * PLAN_STEPS as u128 / u128::from(self.total)) as usize
        };
        let (from, to) = (step(before), step(before + pairs));
        if to > from {
            self.progress.advance(to - from);
        }
    }
}

impl BlockPlan {
    /// The plan of the blocks of `nodes` × `elements`; with `budget`, unfinished where the
    /// plan passes it ([`PlanBudget::is_over`] then tells). The walk reports to `progress`
    /// ([`PLAN_STEPS`] steps).
    pub(super) fn new(
        nodes: &ClusterTree,
        elements: &ClusterTree,
        faces: &FacePairs,
        options: &CompressionOptions,
        budget: Option<&PlanBudget>,
        progress: &dyn Progress,
    ) -> Self {
        let mut plan = Self::default();
        if !nodes.clusters.is_empty() && !elements.clusters.is_empty() {
            let total = (nodes.order.len() * elements.order.len()) as u64;
            let pace = PlanProgress::new(progress, total);
            let walk = Walk { nodes, elements, faces, options, budget, pace: Some(&pace) };
            walk.visit(&mut plan, 0, 0, None);
        }
        plan
    }

    /// The block that [`BlockPlan::new`] would put the pair at `at` in (positions in the node
    /// tree's order and the element tree's), found by descending from the root through the
    /// blocks that hold it: the plan's decisions for one pair, without the plan.
    pub(super) fn locate(
        nodes: &ClusterTree,
        elements: &ClusterTree,
        faces: &FacePairs,
        options: &CompressionOptions,
        at: (usize, usize),
    ) -> Located {
        let walk = Walk { nodes, elements, faces, options, budget: None, pace: None };
        walk.locate(0, 0, None, at)
    }

    /// The plan [`BlockPlan::new`] makes, walked in parts by the ranks of `ranks` (every rank
    /// calls this) and gathered: the top of the block tree is walked by all, the subtrees below
    /// it dealt out in turn. The same blocks as the single walk's, in another order. Each rank
    /// reports its own subtrees' walk to `progress` ([`PLAN_STEPS`] steps).
    pub(super) fn new_shared(
        nodes: &ClusterTree,
        elements: &ClusterTree,
        faces: &FacePairs,
        options: &CompressionOptions,
        ranks: &dyn Collective,
        budget: Option<&PlanBudget>,
        progress: &dyn Progress,
    ) -> Self {
        let mut plan = Self::default();
        let mut mine = Self::default();
        if !nodes.clusters.is_empty() && !elements.clusters.is_empty() {
            let top = Walk { nodes, elements, faces, options, budget, pace: None };
            let frontier = top.frontier(&mut plan, FRONTIER_PER_RANK * ranks.size());
            let dealt = || frontier.iter().skip(ranks.rank()).step_by(ranks.size());
            let total = dealt()
                .map(|(t, s, _)| (nodes.clusters[*t].len() * elements.clusters[*s].len()) as u64)
                .sum();
            let pace = PlanProgress::new(progress, total);
            let walk = Walk { pace: Some(&pace), ..top };
            let parts: Vec<BlockPlan> = frontier
                .par_iter()
                .skip(ranks.rank())
                .step_by(ranks.size())
                .map(|(t, s, within)| {
                    let mut part = BlockPlan::default();
                    walk.visit(&mut part, *t, *s, within.as_deref());
                    part
                })
                .collect();
            parts.into_iter().for_each(|part| mine.append(part));
        }
        // Each rank's blocks as (t << 32 | s), the near ones with whether they are seen whole
        // in the top bit (cluster indices stay below 2^31), then the empty count.
        let code = |&(t, s): &(usize, usize)| ((t as u64) << 32) | s as u64;
        let decode = |c: &u64| ((c >> 32) as usize, (c & 0xffff_ffff) as usize);
        const WHOLE: u64 = 1 << 63;
        let near: Vec<u64> = mine
            .near
            .iter()
            .map(|b| code(&(b.t, b.s)) | if b.seen_whole { WHOLE } else { 0 })
            .collect();
        let far: Vec<u64> = mine.far.iter().map(code).collect();
        for part in ranks.gather(&near) {
            plan.near.extend(part.iter().map(|c| {
                let (t, s) = decode(&(c & !WHOLE));
                NearBlock { t, s, seen_whole: c & WHOLE != 0 }
            }));
        }
        for part in ranks.gather(&far) {
            plan.far.extend(part.iter().map(decode));
        }
        // Each shadowed block as its code, the numbers of its seen sub-blocks and leaves, then
        // their codes.
        let mut shadowed = Vec::new();
        for b in &mine.shadowed {
            shadowed.extend([code(&(b.t, b.s)), b.seen.len() as u64, b.leaves.len() as u64]);
            shadowed.extend(b.seen.iter().chain(&b.leaves).map(code));
        }
        for part in ranks.gather(&shadowed) {
            let mut rest = part.as_slice();
            while let [at, seen, leaves, after @ ..] = rest {
                let (seen, leaves) = (*seen as usize, *leaves as usize);
                let (t, s) = decode(at);
                plan.shadowed.push(ShadowedBlock {
                    t,
                    s,
                    seen: after[..seen].iter().map(decode).collect(),
                    leaves: after[seen..seen + leaves].iter().map(decode).collect(),
                });
                rest = &after[seen + leaves..];
            }
        }
        for part in ranks.gather(&[mine.empty.blocks as u64, mine.empty.pairs]) {
            plan.empty += Empty { blocks: part[0] as usize, pairs: part[1] };
        }
        plan
    }

    /// Adds `other`'s blocks after this plan's.
    fn append(&mut self, other: BlockPlan) {
        self.near.extend(other.near);
        self.far.extend(other.far);
        self.shadowed.extend(other.shadowed);
        self.empty += other.empty;
    }

    /// Entries that the near blocks store for certain: those of the blocks seen whole, in the
    /// rows of nodes that `reflect` (a row of rho = 0 is zero). The others store from nothing
    /// to all of theirs, as visibility decides.
    pub(super) fn certain_near_entries(
        &self,
        nodes: &ClusterTree,
        elements: &ClusterTree,
        per: usize,
        reflects: impl Fn(usize) -> bool,
    ) -> u64 {
        self.near
            .iter()
            .filter(|b| b.seen_whole)
            .map(|b| {
                let tc = &nodes.clusters[b.t];
                let rows = nodes.order[tc.start..tc.end].iter().filter(|&&i| reflects(i)).count();
                (rows * elements.clusters[b.s].len() * per) as u64
            })
            .sum()
    }
}

/// The recursion over pairs of clusters.
struct Walk<'a> {
    nodes: &'a ClusterTree,
    elements: &'a ClusterTree,
    faces: &'a FacePairs<'a>,
    options: &'a CompressionOptions,
    /// What the plan may take; the walk stops where it passes it.
    budget: Option<&'a PlanBudget>,
    /// Where the walk reports the pairs it settles.
    pace: Option<&'a PlanProgress<'a>>,
}

/// How the walk settles a block ([`Walk::settle`]).
enum Settled<'b> {
    /// It holds nothing.
    Empty,
    /// Smooth and admissible: compressed.
    Far,
    /// Admissible, occluders or tangent planes cut it: a shadowed block.
    Shadowed(Between<'b>),
    /// A leaf computed exactly.
    Near { seen_whole: bool },
    /// Split into these sub-blocks, which inherit its occluders.
    Split(Vec<(usize, usize)>, Between<'b>),
}

/// The block of the plan that holds a pair ([`BlockPlan::locate`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub(super) enum Located {
    /// A block holding nothing.
    Empty,
    /// An exact block.
    Near { t: usize, s: usize, seen_whole: bool },
    /// A smooth admissible block.
    Far { t: usize, s: usize },
    /// Shadowed block (t, s), and which of its sub-blocks.
    Shadowed { t: usize, s: usize, part: ShadowedPart },
}

/// Where a pair lies in a shadowed block.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub(super) enum ShadowedPart {
    /// A sub-block that holds nothing.
    Empty,
    /// A sub-block seen whole: the factors' product.
    Seen(usize, usize),
    /// A leaf where visibility varies.
    Leaf(usize, usize),
}

/// Bytes a near block takes in the plan's list.
pub(super) const PLAN_NEAR_BYTES: u64 = std::mem::size_of::<NearBlock>() as u64;
/// Bytes a far block, or a sub-block of a shadowed block, takes in the plan's lists.
pub(super) const PLAN_FAR_BYTES: u64 = std::mem::size_of::<(usize, usize)>() as u64;

/// Bytes of a shadowed block in the plan, its sub-blocks' lists included.
fn shadowed_plan_bytes(block: &ShadowedBlock) -> u64 {
    std::mem::size_of::<ShadowedBlock>() as u64
        + PLAN_FAR_BYTES * (block.seen.capacity() + block.leaves.capacity()) as u64
}

/// What the block plan may take while it is walked: every block settled counts its bytes in the
/// plan's lists twice (the lists grow by doubling, and the parts walked in parallel are copied
/// into the whole), and the walk stops where the count passes the limit.
#[derive(Debug)]
pub(super) struct PlanBudget {
    limit: u64,
    used: AtomicU64,
}

impl PlanBudget {
    /// A budget of `limit` bytes.
    pub(super) fn new(limit: u64) -> Self {
        Self { limit, used: AtomicU64::new(0) }
    }

    fn add(&self, bytes: u64) {
        self.used.fetch_add(2 * bytes, Ordering::Relaxed);
    }

    /// Bytes counted so far.
    pub(super) fn used(&self) -> u64 {
        self.used.load(Ordering::Relaxed)
    }

    /// Whether the count has passed the limit (the walk then stops, its plan unfinished).
    pub(super) fn is_over(&self) -> bool {
        self.used() > self.limit
    }
}

impl Walk<'_> {
    /// How block (t, s), whose occluders are among `within` (any when `None`), is settled: the
    /// one decision that the walk ([`Walk::step`]) and the sampling descent ([`Walk::locate`])
    /// both follow.
    fn settle<'b>(&self, t: usize, s: usize, within: Option<&'b [OccluderUnit]>) -> Settled<'b> {
        let (tc, sc) = (&self.nodes.clusters[t], &self.elements.clusters[s]);
        if self.faces.sight.is_some_and(|sight| !sight.sees_any(t, &sc.faces)) {
            return Settled::Empty;
        }
        let between = Between::new(within);
        let class = classify(self.faces, tc, sc, &between);
        if class == PairClass::Nothing {
            return Settled::Empty;
        }
        let admissible = tc.diameter().min(sc.diameter()) <= self.options.eta * tc.distance(sc);
        if class == PairClass::Smooth && admissible {
            return Settled::Far;
        }
        if class == PairClass::Shadowed
            && admissible
            && self.options.shadowed_blocks == ShadowedBlocks::On
        {
            return Settled::Shadowed(between);
        }
        // Smooth neighbours gain nothing from small leaves; where visibility varies they do,
        // down to the mixed leaf size, also where a cluster spans several faces (a city's
        // faces hold two elements each: split to single faces, a city makes tens of millions
        // of empty blocks, each classified on its own).
        let leaf = if class == PairClass::Smooth {
            self.options.leaf_size
        } else {
            self.options.mixed_leaf_size
        };
        match self.children(t, s, leaf) {
            None => Settled::Near { seen_whole: class == PairClass::Smooth },
            Some(children) => Settled::Split(children, between),
        }
    }

    /// Settles block (t, s), whose occluders are among `within` (any when `None`), into `plan`,
    /// or returns its sub-blocks and what they inherit of its occluders.
    fn step<'b>(
        &self,
        plan: &mut BlockPlan,
        t: usize,
        s: usize,
        within: Option<&'b [OccluderUnit]>,
    ) -> Option<(Vec<(usize, usize)>, Between<'b>)> {
        let settled = self.settle(t, s, within);
        if let (Some(pace), false) = (self.pace, matches!(settled, Settled::Split(..))) {
            pace.settle((self.nodes.clusters[t].len() * self.elements.clusters[s].len()) as u64);
        }
        let bytes = match settled {
            Settled::Empty => {
                plan.empty.add(&self.nodes.clusters[t], &self.elements.clusters[s]);
                0
            }
            Settled::Far => {
                plan.far.push((t, s));
                PLAN_FAR_BYTES
            }
            Settled::Shadowed(between) => {
                let mut block = ShadowedBlock { t, s, seen: Vec::new(), leaves: Vec::new() };
                match self.children(t, s, SHADOWED_LEAF * self.options.mixed_leaf_size) {
                    None => block.leaves.push((t, s)),
                    Some(children) => {
                        let within = between.for_children();
                        for (a, b) in children {
                            self.visit_shadowed(&mut block, &mut plan.empty, a, b, within);
                        }
                    }
                }
                let bytes = shadowed_plan_bytes(&block);
                plan.shadowed.push(block);
                bytes
            }
            Settled::Near { seen_whole } => {
                plan.near.push(NearBlock { t, s, seen_whole });
                PLAN_NEAR_BYTES
            }
            Settled::Split(children, between) => return Some((children, between)),
        };
        if let Some(budget) = self.budget {
            budget.add(bytes);
        }
        None
    }

    /// Where the pair at `at` (a position in the node tree's order, one in the element tree's)
    /// lies in the plan: the block that holds it, found by the walk's own decisions from block
    /// (t, s) down, without walking the blocks beside it.
    pub(super) fn locate(
        &self,
        t: usize,
        s: usize,
        within: Option<&[OccluderUnit]>,
        at: (usize, usize),
    ) -> Located {
        match self.settle(t, s, within) {
            Settled::Empty => Located::Empty,
            Settled::Far => Located::Far { t, s },
            Settled::Near { seen_whole } => Located::Near { t, s, seen_whole },
            Settled::Shadowed(between) => {
                let part = match self.children(t, s, SHADOWED_LEAF * self.options.mixed_leaf_size) {
                    None => ShadowedPart::Leaf(t, s),
                    Some(children) => {
                        let (a, b) = self.holding(&children, at);
                        self.locate_shadowed(a, b, between.for_children(), at)
                    }
                };
                Located::Shadowed { t, s, part }
            }
            Settled::Split(children, between) => {
                let (a, b) = self.holding(&children, at);
                self.locate(a, b, between.for_children(), at)
            }
        }
    }

    /// [`Walk::locate`] inside a shadowed block, as [`Walk::visit_shadowed`] plans it.
    fn locate_shadowed(
        &self,
        t: usize,
        s: usize,
        within: Option<&[OccluderUnit]>,
        at: (usize, usize),
    ) -> ShadowedPart {
        let (tc, sc) = (&self.nodes.clusters[t], &self.elements.clusters[s]);
        let between = Between::new(within);
        match classify(self.faces, tc, sc, &between) {
            PairClass::Nothing => ShadowedPart::Empty,
            PairClass::Smooth => ShadowedPart::Seen(t, s),
            PairClass::Shadowed | PairClass::Mixed => {
                match self.children(t, s, SHADOWED_LEAF * self.options.mixed_leaf_size) {
                    None => ShadowedPart::Leaf(t, s),
                    Some(children) => {
                        let (a, b) = self.holding(&children, at);
                        self.locate_shadowed(a, b, between.for_children(), at)
                    }
                }
            }
        }
    }

    /// The sub-block of `children` that holds the pair at `at`.
    fn holding(&self, children: &[(usize, usize)], (k, l): (usize, usize)) -> (usize, usize) {
        let inside = |c: &Cluster, p: usize| (c.start..c.end).contains(&p);
        *children
            .iter()
            .find(|&&(a, b)| {
                inside(&self.nodes.clusters[a], k) && inside(&self.elements.clusters[b], l)
            })
            .expect("the sub-blocks cover their block")
    }

    /// The sub-blocks of block (t, s), splitting each cluster larger than `leaf`, or `None`
    /// where neither is.
    fn children(&self, t: usize, s: usize, leaf: usize) -> Option<Vec<(usize, usize)>> {
        let (tc, sc) = (&self.nodes.clusters[t], &self.elements.clusters[s]);
        let split = |c: &Cluster| c.children.filter(|_| c.len() > leaf);
        match (split(tc), split(sc)) {
            (None, None) => None,
            (None, Some((s1, s2))) => Some(vec![(t, s1), (t, s2)]),
            (Some((t1, t2)), None) => Some(vec![(t1, s), (t2, s)]),
            (Some((t1, t2)), Some((s1, s2))) => Some(vec![(t1, s1), (t1, s2), (t2, s1), (t2, s2)]),
        }
    }

    /// Plans sub-block (t, s) of a shadowed block, its occluders among `within`: nothing,
    /// seen whole, or split down to leaves of [`SHADOWED_LEAF`] times the mixed leaf size
    /// where occluders or tangent planes cut it.
    fn visit_shadowed(
        &self,
        block: &mut ShadowedBlock,
        empty: &mut Empty,
        t: usize,
        s: usize,
        within: Option<&[OccluderUnit]>,
    ) {
        let (tc, sc) = (&self.nodes.clusters[t], &self.elements.clusters[s]);
        let between = Between::new(within);
        match classify(self.faces, tc, sc, &between) {
            PairClass::Nothing => empty.add(tc, sc),
            PairClass::Smooth => block.seen.push((t, s)),
            PairClass::Shadowed | PairClass::Mixed => {
                match self.children(t, s, SHADOWED_LEAF * self.options.mixed_leaf_size) {
                    None => block.leaves.push((t, s)),
                    Some(children) => {
                        let within = between.for_children();
                        for (a, b) in children {
                            self.visit_shadowed(block, empty, a, b, within);
                        }
                    }
                }
            }
        }
    }

    /// Plans block (t, s) and everything below it, its occluders among `within`.
    fn visit(&self, plan: &mut BlockPlan, t: usize, s: usize, within: Option<&[OccluderUnit]>) {
        if self.budget.is_some_and(PlanBudget::is_over) {
            return;
        }
        let Some((children, between)) = self.step(plan, t, s, within) else {
            return;
        };
        // Large blocks' subtrees in parallel (each classification is a shaft test); the plans
        // are joined in order, so the plan is the same as a sequential walk's.
        let within = between.for_children();
        let (tc, sc) = (&self.nodes.clusters[t], &self.elements.clusters[s]);
        if tc.len() * sc.len() >= PARALLEL_PAIRS {
            let parts: Vec<BlockPlan> = children
                .par_iter()
                .map(|&(a, b)| {
                    let mut part = BlockPlan::default();
                    self.visit(&mut part, a, b, within);
                    part
                })
                .collect();
            for part in parts {
                plan.append(part);
            }
        } else {
            for (a, b) in children {
                self.visit(plan, a, b, within);
            }
        }
    }

    /// The blocks below the top of the block tree, breadth first, until there are at least
    /// `count` (or nothing is left to split), with the occluders each inherits; the blocks
    /// settled on the way go into `plan`.
    fn frontier(&self, plan: &mut BlockPlan, count: usize) -> Vec<Pending> {
        let mut frontier = vec![(0, 0, None)];
        while frontier.len() < count && !frontier.is_empty() {
            let mut next = Vec::new();
            for (t, s, within) in &frontier {
                if let Some((children, between)) = self.step(plan, *t, *s, within.as_deref()) {
                    let list = between.for_children().map(<[OccluderUnit]>::to_vec);
                    next.extend(children.into_iter().map(|(a, b)| (a, b, list.clone())));
                }
            }
            frontier = next;
        }
        frontier
    }
}

/// A block still to be walked, with the occluders it inherits.
type Pending = (usize, usize, Option<Vec<OccluderUnit>>);

/// Blocks of the frontier per rank when the walk is shared: enough for the ranks' parts to
/// cost about the same.
const FRONTIER_PER_RANK: usize = 64;

/// The leaves of a shadowed block are this many times the mixed leaf size: a row of a leaf
/// costs the factors' rank for each run of columns it sees whole, so wide leaves spread that
/// over more entries, which makes the products faster at no cost in storage or setup
/// (docs/performance.md, "What was tried and did not pay").
const SHADOWED_LEAF: usize = 4;

/// Blocks of at least this many pairs have their subtrees walked in parallel.
const PARALLEL_PAIRS: usize = 1 << 16;

/// The class of a block: nothing if every face pair gives nothing, smooth if every one is smooth
/// or nothing, mixed otherwise (and whenever it spans too many face pairs to test).
fn classify(
    faces: &FacePairs,
    nodes: &Cluster,
    elements: &Cluster,
    between: &Between,
) -> PairClass {
    if nodes.faces.len() * elements.faces.len() > MAX_FACE_PAIRS {
        return PairClass::Mixed;
    }
    // Smooth only on one pair of faces (see ClusterTree::new); below a cluster on several faces
    // every cluster is on one.
    let one_pair = nodes.faces.len() == 1 && elements.faces.len() == 1;
    let mut class = PairClass::Nothing;
    for &a in &nodes.faces {
        for &b in &elements.faces {
            match faces.class(a, b, nodes, elements, between) {
                PairClass::Mixed => return PairClass::Mixed,
                PairClass::Smooth | PairClass::Shadowed if !one_pair => return PairClass::Mixed,
                seen => class = seen,
            }
        }
    }
    class
}
