//! The entries of K for the blocks of a compressed operator: exact ones by the dense path's
//! pair plan and kernels, smooth ones for the cross approximations.

use std::cell::OnceCell;
use std::f64::consts::PI;
use std::sync::atomic::{AtomicU64, Ordering};

use super::aca;
use super::blocks::FacePairs;
use super::built::Built;
use super::cluster::ClusterTree;
use super::compressed::Block;
use super::sight::ClusterSight;
use super::stored::{self, BlockData, Precision};
use crate::assembly::PairIntegrator;
use crate::discretization::{Discretization, Node, Placed};
use crate::kernels::lanes;
use crate::mesh::Mesh;
use crate::visibility::{
    ClusterCandidates, ElementBoxes, FaceSight, FaceView, KeptViews, PairPlanner, PairStats,
    RecentHiders, Views, Visibility, by_face,
};

/// Bytes an element placed takes while a cross approximation of its block runs
/// ([`Entries::low_rank`]).
pub(super) const PLACED_BYTES: u64 = std::mem::size_of::<Placed>() as u64;

/// Admissible blocks whose break-even rank is below this are stored exactly.
pub(super) const MIN_USEFUL_RANK: usize = 4;

/// The views of faces found so far from each node of one node cluster, kept while its blocks
/// are computed one after another; what the views cost is added to `tally` as they are
/// dropped.
#[derive(Default)]
pub(super) struct NodeViews<'a> {
    pub(super) cluster: Option<usize>,
    pub(super) rows: Vec<KeptViews>,
    /// The occluders that last hid a face from one of the cluster's nodes.
    pub(super) hiders: RecentHiders,
    /// The occluders that may come between the cluster's nodes and each face they view.
    pub(super) candidates: ClusterCandidates,
    tally: Option<&'a FaceTally>,
    /// Where found, the faces each node cluster may see (the others hidden without a view).
    sight: Option<&'a ClusterSight>,
}

impl NodeViews<'_> {
    /// Ready for node cluster `t` of `nodes` of `disc` (cleared when it is another cluster).
    pub(super) fn prepare(&mut self, t: usize, nodes: &[usize], disc: &Discretization) {
        if self.cluster != Some(t) {
            self.cluster = Some(t);
            self.count();
            self.rows.clear();
            self.candidates.reset(nodes.iter().map(|&i| {
                let node = disc.node(i);
                (node.position, node.face())
            }));
            match self.sight {
                Some(sight) => self.rows.extend(
                    nodes.iter().map(|&i| KeptViews::limited_to(sight.faces_of_node(i).to_vec())),
                ),
                None => self.rows.resize_with(nodes.len(), KeptViews::default),
            }
        }
    }

    fn count(&self) {
        if let Some(tally) = self.tally {
            let viewed = self.rows.iter().map(KeptViews::faces_viewed).sum();
            tally.viewed.fetch_add(viewed, Ordering::Relaxed);
            let unseen = self.rows.iter().map(KeptViews::faces_viewed_unseen).sum();
            tally.viewed_unseen.fetch_add(unseen, Ordering::Relaxed);
            let culled = self.rows.iter().map(KeptViews::faces_culled).sum();
            tally.culled.fetch_add(culled, Ordering::Relaxed);
        }
    }
}

impl Drop for NodeViews<'_> {
    fn drop(&mut self) {
        self.count();
    }
}

/// The views of faces that the row walks of a build computed, over all nodes
/// ([`crate::operator::OperatorStats::faces_viewed`]).
#[derive(Debug, Default)]
pub(super) struct FaceTally {
    viewed: AtomicU64,
    viewed_unseen: AtomicU64,
    culled: AtomicU64,
}

impl FaceTally {
    /// Views computed.
    pub(super) fn viewed(&self) -> u64 {
        self.viewed.load(Ordering::Relaxed)
    }

    /// Of the views computed, those that found nothing of the face seen.
    pub(super) fn viewed_unseen(&self) -> u64 {
        self.viewed_unseen.load(Ordering::Relaxed)
    }

    /// Faces taken as hidden without a view, outside what their nodes' cluster may see.
    pub(super) fn culled(&self) -> u64 {
        self.culled.load(Ordering::Relaxed)
    }
}

/// Computes entries of K for blocks.
pub(super) struct Entries<'a> {
    pub(super) mesh: &'a Mesh,
    pub(super) disc: &'a Discretization,
    pub(super) planner: &'a PairPlanner,
    pub(super) integrator: &'a PairIntegrator,
    pub(super) nodes: &'a ClusterTree,
    pub(super) elements: &'a ClusterTree,
    pub(super) per: usize,
    /// The precision the blocks store their values in (from the tolerance).
    pub(super) precision: Precision,
    /// What the row walks' views of faces cost.
    pub(super) faces: FaceTally,
    /// Where found, the faces each node cluster may see.
    pub(super) sight: Option<&'a ClusterSight>,
}

/// The elements of one face in a block's element cluster.
pub(super) struct BlockFace {
    pub(super) face: usize,
    /// Their columns in the block (positions in the cluster).
    pub(super) columns: Vec<usize>,
    /// Their indices.
    pub(super) elements: Vec<usize>,
    /// Their boxes, halved down to a few elements, for the nodes that see the face in part.
    pub(super) tree: ElementBoxes,
}

/// A face of a block that a node sees in part, left to an engine that clips its elements.
pub(super) struct PartSeen {
    /// The node's row in the block, and its index.
    pub(super) row: usize,
    pub(super) node: usize,
    /// The face's position in the block's [`BlockFace`]s.
    pub(super) face: usize,
    pub(super) view: FaceView,
}

impl Entries<'_> {
    /// Views for the row walks of one node cluster at a time, counted in this build's tally.
    pub(super) fn node_views(&self) -> NodeViews<'_> {
        let mut views = NodeViews::default();
        views.tally = Some(&self.faces);
        views.sight = self.sight;
        views
    }

    /// Walks the pairs of block (t, s) by the dense path's pair plan (the row walk of
    /// [`PairPlanner::walk_row`]), calling `each(r, k, i, j, visibility)` for every pair that is
    /// not skipped: row r of the block (node i), element k of the block (element j). `views`
    /// keeps the nodes' views of faces between blocks of the same node cluster.
    pub(super) fn visible_pairs(
        &self,
        t: usize,
        s: usize,
        views: &mut NodeViews,
        each: impl FnMut(usize, usize, usize, usize, Visibility),
    ) -> PairStats {
        self.walk_block(t, &self.block_faces(s), views, each, None)
    }

    /// The elements of element cluster `s` face by face, as the row walk takes them.
    pub(super) fn block_faces(&self, s: usize) -> Vec<BlockFace> {
        let sc = &self.elements.clusters[s];
        let element_ids = &self.elements.order[sc.start..sc.end];
        by_face(element_ids.iter().enumerate().map(|(k, &j)| (self.disc.face_of(j), k)))
            .into_iter()
            .map(|(face, columns)| {
                let elements: Vec<usize> = columns.iter().map(|&k| element_ids[k]).collect();
                let polygons = elements.iter().map(|&j| self.disc.in_face(j)).collect();
                BlockFace { face, columns, elements, tree: ElementBoxes::new(polygons) }
            })
            .collect()
    }

    /// [`Self::visible_pairs`] over the block's `faces` ([`Self::block_faces`] of its element
    /// cluster). With `parts`, a face seen in part is not clipped here: (r, i, position of the
    /// face in `faces`, the view) is listed for an engine that clips its elements itself
    /// ([`crate::assembly::CutEvaluation`]), and its pairs are neither given to `each` nor
    /// counted.
    pub(super) fn walk_block(
        &self,
        t: usize,
        faces: &[BlockFace],
        views: &mut NodeViews,
        mut each: impl FnMut(usize, usize, usize, usize, Visibility),
        mut parts: Option<&mut Vec<PartSeen>>,
    ) -> PairStats {
        let tc = &self.nodes.clusters[t];
        let mut stats = PairStats::default();
        views.prepare(t, &self.nodes.order[tc.start..tc.end], self.disc);
        for (r, &i) in self.nodes.order[tc.start..tc.end].iter().enumerate() {
            let viewer = self.disc.node(i).viewer();
            let walked = faces.iter().map(|f| (f.face, f.columns.iter().zip(&f.elements)));
            let kept = Views::Kept(&mut views.rows[r], &mut views.hiders, &mut views.candidates);
            stats +=
                self.planner.walk_row(&viewer, walked, kept, |face, list, sight| match sight {
                    FaceSight::Hidden(_) => {}
                    FaceSight::Whole => {
                        list.for_each(|(&k, &j)| each(r, k, i, j, Visibility::Full))
                    }
                    FaceSight::Part(mut part) => {
                        let g = faces.iter().position(|f| f.face == face).expect("a block's face");
                        if let Some(parts) = parts.as_deref_mut() {
                            parts.push(PartSeen {
                                row: r,
                                node: i,
                                face: g,
                                view: part.view().clone(),
                            });
                            return;
                        }
                        let f = &faces[g];
                        part.elements(&f.tree, |at, vis| {
                            if !matches!(vis, Visibility::Skip(_)) {
                                each(r, f.columns[at], i, f.elements[at], vis)
                            }
                        });
                    }
                });
        }
        stats
    }

    /// Every entry of the block, by the dense path's pair plan and kernels, stored by what it
    /// holds ([`Block::compact`]).
    pub(super) fn exact_block(
        &self,
        t: usize,
        s: usize,
        views: &mut NodeViews,
    ) -> (Block, PairStats) {
        let (data, stats) = self.exact_entries(t, s, views, None);
        let mut block = self.block(t, s, BlockData::exact(data));
        block.compact(self.precision);
        (block, stats)
    }

    /// The entries of block (t, s), row-major. With `whole` (mask words of the block's columns
    /// per row, as [`stored::SparseRows`] has them), an element the node sees whole is not
    /// integrated but marked there, in the rows of nodes that reflect (a shadowed block's
    /// factors give those entries).
    pub(super) fn exact_entries(
        &self,
        t: usize,
        s: usize,
        views: &mut NodeViews,
        mut whole: Option<&mut [u64]>,
    ) -> (Vec<f64>, PairStats) {
        let per = self.per;
        let (m, width) = self.block_size(t, s);
        let words = stored::mask_words(width);
        // Zeros written, not mapped (`vec!` of zeros would leave a large block's pages to the
        // zero page, which the lanes' additions read before they write).
        let mut data = Vec::with_capacity(m * width);
        data.resize(m * width, 0.0);
        // The centroid method's closed forms wait in lanes, each with where its value goes and
        // the node's rho / pi; a partly visible element's pieces add into its entry.
        let mut batch = lanes::Batch::<(usize, f64)>::default();
        // The block's elements placed once for all its rows, its nodes once for all its columns.
        let sc = &self.elements.clusters[s];
        let placed: Vec<Placed> =
            self.elements.order[sc.start..sc.end].iter().map(|&j| self.disc.placed(j)).collect();
        let tc = &self.nodes.clusters[t];
        let nodes: Vec<Node> =
            self.nodes.order[tc.start..tc.end].iter().map(|&i| self.disc.node(i)).collect();
        let stats = self.visible_pairs(t, s, views, |r, k, _, j, vis| {
            let node = &nodes[r];
            if let Some(mask) = whole.as_deref_mut() {
                if matches!(vis, Visibility::Full) {
                    if node.rho != 0.0 {
                        for c in k * per..(k + 1) * per {
                            mask[r * words + c / 64] |= 1 << (c % 64);
                        }
                    }
                    return;
                }
            }
            let el = &placed[k];
            let at = r * width + k * per;
            let scale = node.rho / PI;
            let sink = |(at, scale): (usize, f64), v: f64| data[at] += scale * v;
            let Some(values) = self.integrator.integrate_or_batch(
                el,
                self.disc.basis(j),
                node.position,
                node.normal,
                &vis,
                ((at, scale), &mut batch),
                sink,
            ) else {
                return;
            };
            for (c, v) in values.iter().take(per).enumerate() {
                data[at + c] = scale * v;
            }
        });
        batch.flush(|(at, scale), v| data[at] += scale * v);
        (data, stats)
    }

    /// Rows and columns (elements × basis functions) of block (t, s).
    pub(super) fn block_size(&self, t: usize, s: usize) -> (usize, usize) {
        (self.nodes.clusters[t].len(), self.elements.clusters[s].len() * self.per)
    }

    /// Block (t, s) holding `data`.
    pub(super) fn block(&self, t: usize, s: usize, data: BlockData) -> Block {
        let (tc, sc) = (&self.nodes.clusters[t], &self.elements.clusters[s]);
        Block::new(tc.start..tc.end, sc.start..sc.end, data)
    }

    /// Whether node i (original index) gives element j anything, where the block's plan says
    /// the element is wholly visible from the node unless their faces give nothing.
    pub(super) fn smooth_sees(&self, i: usize, j: usize, faces: &FacePairs) -> bool {
        self.node_sees(&self.disc.node(i), j, faces)
    }

    /// [`Self::smooth_sees`] for `node`.
    fn node_sees(&self, node: &Node, j: usize, faces: &FacePairs) -> bool {
        node.rho != 0.0
            && !faces.nothing_between(node.face(), node.position, &self.mesh.elements()[j])
    }

    /// The values of the pairs (node i, element j, j placed) of a smooth block, in order: all of each
    /// element's basis functions, or only `basis`. The centroid method's closed forms are
    /// evaluated in lanes. `continued`: the kernel over every element whole, without testing
    /// each pair for planes that make it give nothing ([`FacePairs::nothing_between`]).
    pub(super) fn smooth_values<'p>(
        &self,
        pairs: impl Iterator<Item = (usize, usize, &'p Placed)>,
        basis: Option<usize>,
        faces: &FacePairs,
        continued: bool,
    ) -> Vec<f64> {
        let take = if basis.is_some() { 1 } else { self.per };
        let mut out = Vec::new();
        let mut batch = lanes::Batch::<(usize, f64)>::default();
        for (i, j, el) in pairs {
            let at = out.len();
            out.resize(at + take, 0.0);
            let node = &self.disc.node(i);
            let gives = if continued { node.rho != 0.0 } else { self.node_sees(node, j, faces) };
            if !gives {
                continue;
            }
            let scale = node.rho / PI;
            let sink = |(at, scale): (usize, f64), v: f64| out[at] += scale * v;
            let Some(values) = self.integrator.integrate_or_batch(
                el,
                self.disc.basis(j),
                node.position,
                node.normal,
                &Visibility::Full,
                ((at, scale), &mut batch),
                sink,
            ) else {
                continue;
            };
            match basis {
                Some(b) => out[at] = scale * values[b],
                None => (0..take).for_each(|c| out[at + c] = scale * values[c]),
            }
        }
        batch.flush(|(at, scale), v| out[at] += scale * v);
        out
    }

    /// Rank beyond which block (t, s)'s factors take more memory than the block itself, or
    /// `None` when that is below [`MIN_USEFUL_RANK`] (computed exactly without trying).
    pub(super) fn useful_rank(&self, t: usize, s: usize) -> Option<usize> {
        let (m, c) = self.block_size(t, s);
        let max_rank = (m * c) / (m + c);
        (max_rank >= MIN_USEFUL_RANK).then_some(max_rank)
    }

    /// The admissible block (t, s) as a low-rank product, or exact where its rank would not save
    /// memory (counted in `met` as incompressible).
    pub(super) fn compressed_or_exact(
        &self,
        t: usize,
        s: usize,
        faces: &FacePairs,
        tolerance: f64,
        met: &mut Built,
    ) -> Block {
        match self.low_rank(t, s, faces, tolerance, false) {
            Some(lr) => self.block(t, s, BlockData::low_rank(lr, self.precision)),
            None => {
                let (block, stats) = self.exact_block(t, s, &mut self.node_views());
                met.add(stats, true);
                block
            }
        }
    }

    /// The factors of block (t, s) with every element seen whole (the kernel without
    /// occlusion), to `tolerance`, or `None` when their rank would not save memory.
    pub(super) fn low_rank(
        &self,
        t: usize,
        s: usize,
        faces: &FacePairs,
        tolerance: f64,
        continued: bool,
    ) -> Option<aca::LowRank> {
        let (tc, sc) = (&self.nodes.clusters[t], &self.elements.clusters[s]);
        let per = self.per;
        let (m, c) = (tc.len(), sc.len() * per);
        let node_ids = &self.nodes.order[tc.start..tc.end];
        let element_ids = &self.elements.order[sc.start..sc.end];
        // Where no pair can give nothing, every entry is the kernel over the whole element, as
        // in a continued block.
        let continued = continued || faces.every_pair_gives(tc, sc);
        // The block's elements placed once for all the rows the approximation takes
        // ([`PLACED_BYTES`] each while it runs), a column's element once for its rows.
        let placed = OnceCell::new();
        let row = |r: usize| {
            let i = node_ids[r];
            let placed: &Vec<Placed> =
                placed.get_or_init(|| element_ids.iter().map(|&j| self.disc.placed(j)).collect());
            let pairs = element_ids.iter().zip(placed).map(|(&j, el)| (i, j, el));
            self.smooth_values(pairs, None, faces, continued)
        };
        let col = |q: usize| {
            let (j, basis) = (element_ids[q / per], q % per);
            let el = self.disc.placed(j);
            let pairs = node_ids.iter().map(|&i| (i, j, &el));
            self.smooth_values(pairs, Some(basis), faces, continued)
        };
        aca::aca(m, c, row, col, tolerance, self.useful_rank(t, s)?)
    }
}
