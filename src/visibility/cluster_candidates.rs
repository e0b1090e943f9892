//! The occluders that may come between a cluster of viewers (the nodes of one node cluster of
//! the compressed operator, whose row walks run in turn) and each face they view, searched in
//! the occluders' tree once for the cluster and filtered for each viewer, instead of a search
//! of the tree per view.
//!
//! A view's candidates are the units of the tree whose boxes may reach into its volume
//! ([`super::PairPlanner::face_view_with`]), in the tree's order. The cluster's search takes a
//! volume around every view's of the cluster: the box around the viewers and the face (grown
//! past the views' tolerances and rounding), in front of the face's plane (and of the viewers'
//! plane where they share a face), with no larger margins than a view's. Each of a box's tests
//! passes for every box around it, so a unit that a view's search reaches passes the cluster's
//! search too, and its ancestors pass the view's: filtering the cluster's list (in the tree's
//! order) by the view's test of a unit's box gives the view's own search, unit for unit and in
//! its order.

use glam::DVec3;
use rustc_hash::FxHashMap;

use super::occluders::{OccluderUnit, ViewVolume};
use super::planner::PairPlanner;

/// A unit of the occluders' tree and its box.
pub(super) type BoxedUnit = (OccluderUnit, DVec3, DVec3);

/// Per face, the occluder units that may come between a cluster of viewers and it.
#[derive(Debug, Default)]
pub struct ClusterCandidates {
    /// The box around the viewers' positions.
    lo: DVec3,
    hi: DVec3,
    /// The face all the viewers lie on, where they share one.
    face: Option<usize>,
    /// Whether any viewer was given.
    viewers: bool,
    lists: FxHashMap<usize, Vec<BoxedUnit>>,
}

impl ClusterCandidates {
    /// The lists for viewers at the positions of `viewers`, each with its face; emptied of an
    /// earlier cluster's.
    pub fn reset(&mut self, viewers: impl IntoIterator<Item = (DVec3, usize)>) {
        self.lists.clear();
        self.viewers = false;
        self.face = None;
        let (mut lo, mut hi) = (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY));
        let mut shared = true;
        for (p, face) in viewers {
            lo = lo.min(p);
            hi = hi.max(p);
            shared &= !self.viewers || self.face == Some(face);
            self.face = Some(face);
            self.viewers = true;
        }
        (self.lo, self.hi) = (lo, hi);
        if !shared {
            self.face = None;
        }
    }

    /// Whether the viewer at `p` on face `own_face` is one of the cluster's: in its box, and on
    /// its face where the lists were searched in front of one.
    pub(super) fn holds(&self, p: DVec3, own_face: usize) -> bool {
        self.viewers
            && p.cmpge(self.lo).all()
            && p.cmple(self.hi).all()
            && self.face.is_none_or(|f| f == own_face)
    }

    /// The units that may come between any of the viewers and face `face`, in the tree's order
    /// (searched the first time the face is asked for); `None` without the tree.
    pub(super) fn units(&mut self, planner: &PairPlanner, face: usize) -> Option<&[BoxedUnit]> {
        if !planner.occluders.has_unit_tree() {
            return None;
        }
        let (lo, hi, own) = (self.lo, self.hi, self.face);
        let list = self.lists.entry(face).or_insert_with(|| {
            let f = &planner.faces[face];
            let (lo, hi) = (lo.min(f.lo), hi.max(f.hi));
            // Past every view's tolerance (1e-12 of the larger face) and the rounding of the
            // windows' corners in space, by far.
            let size = (hi - lo).max_element() + lo.abs().max(hi.abs()).max_element();
            let margin = DVec3::splat(1e-9 * size);
            let mut volume = ViewVolume::default();
            volume.push_box(lo - margin, hi + margin, 0.0);
            // A view's margin in front of the face is 1e-12 of the larger of the two faces.
            volume.push_front_of(&f.face.frame, 1e-12 * f.size);
            if let Some(own) = own {
                let frame = &planner.faces[own].face.frame;
                volume.push_front_of(frame, planner.pair_tolerance(own, face));
            }
            let found = planner.occluders.units_reaching(&volume);
            found.map(Iterator::collect).unwrap_or_default()
        });
        Some(list)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::{Mesh, MeshKind};
    use crate::scene::{generated, lit_city};
    use crate::visibility::{FaceView, RecentHiders};

    /// Every view from the viewers of `groups` (each a list of elements of `mesh`, their
    /// centroids the viewers) of every face, with the group's candidates and with a search of
    /// the tree per view: the same to the bit. Returns the views with shadows.
    fn views_agree(scene: &crate::scene::Scene, mesh: &Mesh, groups: &[Vec<usize>]) -> usize {
        let planner = PairPlanner::new(scene);
        let mut shared = ClusterCandidates::default();
        let mut shadowed = 0;
        for group in groups {
            let viewer = |j: usize| {
                let e = &mesh.elements()[j];
                (e.centroid(), scene.faces[e.face].frame.normal, e.face)
            };
            shared.reset(group.iter().map(|&j| (viewer(j).0, viewer(j).2)));
            let (mut hiders, mut alone) = (RecentHiders::default(), RecentHiders::default());
            for &j in group {
                let (p, n, own) = viewer(j);
                for face in 0..scene.faces.len() {
                    let among =
                        planner.face_view_among(p, n, own, face, &mut hiders, Some(&mut shared));
                    let searched = planner.face_view_with(p, n, own, face, &mut alone);
                    assert_eq!(among, searched, "{}: face {face} from {p}", scene.name);
                    shadowed += usize::from(
                        matches!(&among, FaceView::Visible { shadows, .. } if !shadows.is_empty()),
                    );
                }
            }
        }
        shadowed
    }

    #[test]
    fn views_through_a_cluster_s_candidates_are_those_of_a_search_per_view() {
        // Over 512 faces, so that views search the tree: a lit city, its viewers grouped by
        // face, by pairs of faces, and one group of every element of the scene.
        let scene = lit_city(10, 10).unwrap();
        let mesh = Mesh::new(&scene, &MeshKind::Uniform, 1).unwrap();
        let by_face: Vec<Vec<usize>> =
            (0..scene.faces.len()).step_by(37).map(|f| mesh.face_range(f).collect()).collect();
        let by_pairs: Vec<Vec<usize>> = (0..scene.faces.len() - 1)
            .step_by(53)
            .map(|f| mesh.face_range(f).chain(mesh.face_range(f + 1)).collect())
            .collect();
        let all = vec![(0..mesh.elements().len()).step_by(97).collect::<Vec<usize>>()];
        let shadowed = views_agree(&scene, &mesh, &by_face)
            + views_agree(&scene, &mesh, &by_pairs)
            + views_agree(&scene, &mesh, &all);
        assert!(shadowed > 1000, "{shadowed} views with shadows");
        // A generated city far from the origin (its few faces tabulated: the same views).
        let city = generated::city(2);
        let mesh = Mesh::new(&city, &MeshKind::Uniform, 1).unwrap();
        views_agree(&city, &mesh, &[(0..mesh.elements().len()).collect()]);
    }

    #[test]
    fn a_viewer_outside_the_cluster_is_not_held() {
        let mut shared = ClusterCandidates::default();
        assert!(!shared.holds(DVec3::ZERO, 0));
        shared.reset([(DVec3::ZERO, 3), (DVec3::ONE, 3)]);
        assert!(shared.holds(DVec3::splat(0.5), 3));
        assert!(!shared.holds(DVec3::splat(0.5), 4));
        assert!(!shared.holds(DVec3::new(0.5, 0.5, 1.5), 3));
        shared.reset([(DVec3::ZERO, 3), (DVec3::ONE, 4)]);
        assert!(shared.holds(DVec3::splat(0.5), 5));
    }
}
