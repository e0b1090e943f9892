//! What each cluster of nodes may see: the union over its nodes of the faces each may see
//! ([`FaceHierarchy::seen_from`]), so that the block plan settles a block none of whose faces
//! its nodes may see as empty at once, at any level of the tree, and the exact blocks' row walks
//! take the faces outside it as hidden without viewing them. On a city most pairs are hidden by
//! several houses together, which no one occluder's shaft test proves: without this the plan
//! settles them leaf block by leaf block, n² of them.
//!
//! Nothing changes in the operator: a face left out is hidden from every node of the cluster
//! (each node's set is conservative), so the blocks dropped hold only zeros, and the faces
//! skipped in a walk would have been found hidden.

use std::sync::Arc;
use std::time::Instant;

use rayon::prelude::*;

use super::cluster::ClusterTree;
use crate::discretization::Discretization;
use crate::progress::Progress;
use crate::visibility::{FaceSet, OcclusionCube, PairPlanner, SightCount};

/// Clusters of fewer nodes share their parent's set (the smallest size doubles until the sets
/// fit in [`SIGHT_BYTES`]).
const SMALLEST_CLUSTER: usize = 16;

/// Most bytes the clusters' sets may take.
const SIGHT_BYTES: usize = 64 << 20;

/// The faces each node cluster may see.
#[derive(Debug)]
pub(super) struct ClusterSight {
    /// Per cluster of the node tree, the set it takes (its own, or its nearest ancestor's that
    /// has one).
    set_of: Vec<usize>,
    sets: Vec<Arc<FaceSet>>,
    /// Per node (by number), the faces it may see, sorted: those of node i are
    /// `node_faces[node_start[i]..node_start[i + 1]]`.
    node_start: Vec<usize>,
    node_faces: Vec<u32>,
    /// Faces of the scene.
    faces: usize,
    /// The nodes' walks, summed.
    count: SightCount,
    /// Wall-clock seconds the sets took.
    seconds: f64,
}

impl ClusterSight {
    /// The sets of the clusters of `nodes` (a tree over the nodes of `disc`) on the scene that
    /// `planner` plans, reporting the nodes walked to `progress` (a stage of its own).
    pub(super) fn new(
        planner: &PairPlanner,
        disc: &Discretization,
        nodes: &ClusterTree,
        progress: &dyn Progress,
    ) -> Self {
        let start = Instant::now();
        progress.start("faces in sight", nodes.order.len());
        let faces = planner.face_count();
        let hierarchy = planner.face_hierarchy();
        let clusters = &nodes.clusters;
        let mut parent = vec![usize::MAX; clusters.len()];
        for (c, cluster) in clusters.iter().enumerate() {
            if let Some((a, b)) = cluster.children {
                parent[a] = c;
                parent[b] = c;
            }
        }
        let mut smallest = SMALLEST_CLUSTER;
        let bytes = |smallest: usize| {
            let kept = clusters.iter().filter(|c| c.len() >= smallest).count().max(1);
            kept * 8 * faces.div_ceil(64)
        };
        while bytes(smallest) > SIGHT_BYTES && smallest < nodes.order.len() {
            smallest *= 2;
        }
        // The clusters with a set of their own: the root, and both halves of such a cluster
        // where each has at least `smallest` nodes (parents come before their children).
        let mut has_set = vec![false; clusters.len()];
        has_set[0] = true;
        for c in 0..clusters.len() {
            if let (true, Some((a, b))) = (has_set[c], clusters[c].children)
                && clusters[a].len().min(clusters[b].len()) >= smallest
            {
                has_set[a] = true;
                has_set[b] = true;
            }
        }
        let own: Vec<usize> = (0..clusters.len()).filter(|&c| has_set[c]).collect();
        let mut index = vec![usize::MAX; clusters.len()];
        for (k, &c) in own.iter().enumerate() {
            index[c] = k;
        }
        // Its bottom clusters (whose halves have no sets of their own) hold every node once:
        // their sets come from the nodes, the others' from their halves.
        let bottom = |c: usize| clusters[c].children.is_none_or(|(a, _)| !has_set[a]);
        let from_nodes: Vec<(usize, FaceSet, Vec<Vec<u32>>, SightCount)> = own
            .par_iter()
            .filter(|&&c| bottom(c))
            .map_init(OcclusionCube::default, |cube, &c| {
                let cluster = &clusters[c];
                let mut set = FaceSet::new(faces);
                let mut lists = Vec::with_capacity(cluster.len());
                let mut count = SightCount::default();
                for &i in &nodes.order[cluster.start..cluster.end] {
                    let viewer = disc.node(i).viewer();
                    let mut list = Vec::new();
                    let walked = hierarchy.seen_from(planner, &viewer, cube, |f| {
                        set.insert(f);
                        list.push(f as u32);
                    });
                    list.sort_unstable();
                    lists.push(list);
                    count += walked;
                }
                progress.advance(cluster.len());
                (c, set, lists, count)
            })
            .collect();
        let mut sets: Vec<Option<FaceSet>> = vec![None; own.len()];
        let mut count = SightCount::default();
        let mut per_node: Vec<Vec<u32>> = vec![Vec::new(); nodes.order.len()];
        for (c, set, lists, walked) in from_nodes {
            sets[index[c]] = Some(set);
            let cluster = &clusters[c];
            for (&i, list) in nodes.order[cluster.start..cluster.end].iter().zip(lists) {
                per_node[i] = list;
            }
            count += walked;
        }
        let mut node_start = Vec::with_capacity(per_node.len() + 1);
        node_start.push(0);
        for list in &per_node {
            node_start.push(node_start.last().copied().unwrap_or(0) + list.len());
        }
        let node_faces: Vec<u32> = per_node.into_iter().flatten().collect();
        // Children after their parents in the tree's list: from the last cluster up.
        for &c in own.iter().rev() {
            if sets[index[c]].is_some() {
                continue;
            }
            let mut set = FaceSet::new(faces);
            if let Some((a, b)) = clusters[c].children {
                for child in [a, b] {
                    let own_set = sets[index[child]].as_ref().expect("a child's set comes first");
                    set.union_with(own_set);
                }
            }
            sets[index[c]] = Some(set);
        }
        let mut set_of = vec![0; clusters.len()];
        for c in 0..clusters.len() {
            set_of[c] = if has_set[c] { index[c] } else { set_of[parent[c]] };
        }
        let sets = sets.into_iter().map(|s| Arc::new(s.expect("every set is made"))).collect();
        progress.finish();
        let seconds = start.elapsed().as_secs_f64();
        Self { set_of, sets, node_start, node_faces, faces, count, seconds }
    }

    /// The faces that the nodes of cluster `t` may see.
    pub(super) fn faces_of(&self, t: usize) -> &Arc<FaceSet> {
        &self.sets[self.set_of[t]]
    }

    /// The faces that node `i` may see, sorted.
    pub(super) fn faces_of_node(&self, i: usize) -> &[u32] {
        &self.node_faces[self.node_start[i]..self.node_start[i + 1]]
    }

    /// Whether the nodes of cluster `t` may see any of `faces`.
    pub(super) fn sees_any(&self, t: usize, faces: &[usize]) -> bool {
        let set = self.faces_of(t);
        faces.iter().any(|&f| set.contains(f))
    }

    /// What was found, for the run's notes.
    pub(super) fn note(&self) -> String {
        let nodes = (self.node_start.len() - 1).max(1) as f64;
        format!(
            "faces in sight: {:.1} a node of {} (its walk reached {:.1} and proved {:.1} boxes \
             hidden), in {:.2} s",
            self.node_faces.len() as f64 / nodes,
            self.faces,
            self.count.faces_reached as f64 / nodes,
            self.count.boxes_hidden as f64 / nodes,
            self.seconds,
        )
    }

    /// Bytes the sets take.
    pub(super) fn bytes(&self) -> usize {
        let sets: usize = self.sets.iter().map(|s| s.bytes()).sum();
        sets + 8 * (self.set_of.len() + self.node_start.len()) + 4 * self.node_faces.len()
    }
}
