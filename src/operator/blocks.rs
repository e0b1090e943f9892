//! The block tree: which pairs (node cluster, element cluster) hold nothing, which are smooth and
//! far enough apart to be compressed, and which are leaves computed exactly.

use glam::DVec3;

use super::cluster::{Cluster, ClusterTree};
use crate::discretization::ElementFrame;
use crate::scene::Scene;
use crate::visibility::PairPlanner;

/// What a block of nodes on face a and elements on face b needs.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum PairClass {
    /// G = 0 for every pair: one plane, or one box wholly behind the other face's plane.
    Nothing,
    /// Every element in front of every node's plane and facing it, no occluder in the shaft.
    Smooth,
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
}

impl<'a> FacePairs<'a> {
    pub(super) fn new(scene: &'a Scene, planner: &'a PairPlanner) -> Self {
        Self { scene, planner }
    }

    fn class(&self, a: usize, b: usize, nodes: &Cluster, elements: &Cluster) -> PairClass {
        if self.scene.coplanar(a, b) {
            return PairClass::Nothing;
        }
        let (fa, fb) = (&self.scene.faces[a].frame, &self.scene.faces[b].frame);
        let (elo, ehi) = height_range(fa, elements.bounds());
        let (nlo, nhi) = height_range(fb, nodes.bounds());
        if ehi <= 0.0 || nhi <= 0.0 {
            return PairClass::Nothing;
        }
        if elo > 0.0
            && nlo > 0.0
            && self.planner.shaft_is_clear(a, b, nodes.bounds(), elements.bounds())
        {
            PairClass::Smooth
        } else {
            PairClass::Mixed
        }
    }

    /// Whether node (on `face`, at `p`) and element `el` give G = 0 throughout: one plane, the
    /// element on or behind the node's tangent plane, or the node on or behind the element's.
    /// In a smooth block this is the whole difference between an entry and the kernel over the
    /// whole element.
    pub(super) fn nothing_between(
        &self,
        face: usize,
        p: DVec3,
        el: &ElementFrame,
        vertices: &[DVec3; 3],
    ) -> bool {
        let fa = &self.scene.faces[face].frame;
        self.scene.coplanar(face, el.face)
            || vertices.iter().all(|&v| fa.normal.dot(v - p) <= 0.0)
            || el.frame.height(p) <= 0.0
    }
}

/// Smallest and largest height of a box's corners above a plane.
fn height_range(frame: &crate::geometry::PlaneFrame, (lo, hi): (DVec3, DVec3)) -> (f64, f64) {
    let mut range = (f64::INFINITY, f64::NEG_INFINITY);
    for k in 0..8 {
        let c = DVec3::new(
            if k & 1 == 0 { lo.x } else { hi.x },
            if k & 2 == 0 { lo.y } else { hi.y },
            if k & 4 == 0 { lo.z } else { hi.z },
        );
        let h = frame.height(c);
        range = (range.0.min(h), range.1.max(h));
    }
    range
}

/// The blocks of K: pairs (node cluster, element cluster) by index into their trees.
#[derive(Clone, Debug, Default)]
pub(super) struct BlockPlan {
    /// Leaves computed exactly.
    pub near: Vec<(usize, usize)>,
    /// Smooth admissible blocks, to be compressed.
    pub far: Vec<(usize, usize)>,
    /// Blocks holding nothing, left out.
    pub empty: usize,
}

impl BlockPlan {
    pub(super) fn new(
        nodes: &ClusterTree,
        elements: &ClusterTree,
        faces: &FacePairs,
        eta: f64,
    ) -> Self {
        let mut plan = Self::default();
        if !nodes.clusters.is_empty() && !elements.clusters.is_empty() {
            plan.visit(nodes, elements, faces, eta, 0, 0);
        }
        plan
    }

    fn visit(
        &mut self,
        nodes: &ClusterTree,
        elements: &ClusterTree,
        faces: &FacePairs,
        eta: f64,
        t: usize,
        s: usize,
    ) {
        let (tc, sc) = (&nodes.clusters[t], &elements.clusters[s]);
        let class = classify(faces, tc, sc);
        if class == PairClass::Nothing {
            self.empty += 1;
            return;
        }
        let admissible = tc.diameter().min(sc.diameter()) <= eta * tc.distance(sc);
        if class == PairClass::Smooth && admissible {
            self.far.push((t, s));
            return;
        }
        match (tc.children, sc.children) {
            (None, None) => self.near.push((t, s)),
            (None, Some((s1, s2))) => {
                self.visit(nodes, elements, faces, eta, t, s1);
                self.visit(nodes, elements, faces, eta, t, s2);
            }
            (Some((t1, t2)), None) => {
                self.visit(nodes, elements, faces, eta, t1, s);
                self.visit(nodes, elements, faces, eta, t2, s);
            }
            (Some((t1, t2)), Some((s1, s2))) => {
                for (a, b) in [(t1, s1), (t1, s2), (t2, s1), (t2, s2)] {
                    self.visit(nodes, elements, faces, eta, a, b);
                }
            }
        }
    }

    /// Entries of the near blocks (an upper bound on what they store).
    pub(super) fn near_entries(
        &self,
        nodes: &ClusterTree,
        elements: &ClusterTree,
        per: usize,
    ) -> u64 {
        self.near
            .iter()
            .map(|&(t, s)| (nodes.clusters[t].len() * elements.clusters[s].len() * per) as u64)
            .sum()
    }
}

/// The class of a block: nothing if every face pair gives nothing, smooth if every one is smooth
/// or nothing, mixed otherwise (and whenever it spans too many face pairs to test).
fn classify(faces: &FacePairs, nodes: &Cluster, elements: &Cluster) -> PairClass {
    if nodes.faces.len() * elements.faces.len() > MAX_FACE_PAIRS {
        return PairClass::Mixed;
    }
    let mut class = PairClass::Nothing;
    for &a in &nodes.faces {
        for &b in &elements.faces {
            match faces.class(a, b, nodes, elements) {
                PairClass::Mixed => return PairClass::Mixed,
                PairClass::Smooth => class = PairClass::Smooth,
                PairClass::Nothing => {}
            }
        }
    }
    class
}
