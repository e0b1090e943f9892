//! The pair planner itself: [`PairPlanner`], built once per scene from its faces (outlines,
//! hulls, sizes and boxes) and its occluders (their index and, for small scenes, the table of
//! those between each pair of faces), and the questions two faces' planes answer alone: are
//! they one plane, which occluders can lie between them, is a point on or behind a face. The
//! views themselves are computed in [`super::face_view`], [`super::part_view`] and
//! [`super::visible_part`], each an `impl PairPlanner` of its own.

use glam::{DVec2, DVec3};

use super::occluders::{Acceleration, Occluder, OccluderIndex, ViewVolume};
use super::view::SkipReason;
use crate::geometry::convex_hull;
use crate::scene::{COPLANAR_DISTANCE, Scene};

/// A point's height above a plane is known to within this many ulps of its distance from the
/// plane's origin.
pub(super) const HEIGHT_ROUNDING: f64 = 8.0 * f64::EPSILON;

/// Decides visibility for a scene; built once per scene.
#[derive(Clone, Debug)]
pub struct PairPlanner {
    pub(super) faces: Vec<PlannerFace>,
    pub(super) occluders: OccluderIndex,
    /// For scenes of at most [`PAIR_TABLE_FACES`] faces, per ordered pair of faces (a * F + b):
    /// whether they are coplanar, and the occluders that may lie between them, so that a view
    /// only filters a short list.
    pub(super) pairs: Option<Vec<(bool, Vec<usize>)>>,
}

/// Largest scene whose pairs of faces are tabulated (512² entries).
const PAIR_TABLE_FACES: usize = 512;

#[derive(Clone, Debug)]
pub(super) struct PlannerFace {
    pub(super) face: crate::scene::Face,
    pub(super) polygon: Vec<DVec2>,
    pub(super) hull: Vec<DVec2>,
    pub(super) size: f64,
    pub(super) lo: DVec3,
    pub(super) hi: DVec3,
}

impl PairPlanner {
    /// Prepares the occluders of `scene` and their index.
    pub fn new(scene: &Scene) -> Self {
        Self::with_acceleration(scene, Acceleration::default())
    }

    /// As [`PairPlanner::new`], choosing how candidate occluders are found (the views are the
    /// same either way; only the time differs).
    pub fn with_acceleration(scene: &Scene, acceleration: Acceleration) -> Self {
        let faces = scene
            .faces
            .iter()
            .map(|f| {
                let polygon = f.local_polygon();
                let (lo, hi) = f.bounding_box();
                PlannerFace {
                    face: f.clone(),
                    hull: convex_hull(&polygon).into_vec(),
                    polygon,
                    size: f.size(),
                    lo,
                    hi,
                }
            })
            .collect();
        let mut planner =
            Self { faces, occluders: OccluderIndex::new(scene, acceleration), pairs: None };
        let n = planner.faces.len();
        if n <= PAIR_TABLE_FACES && acceleration == Acceleration::Tree {
            let table = (0..n * n)
                .map(|k| {
                    let (a, b) = (k / n, k % n);
                    let coplanar = planner.same_plane(a, b);
                    (coplanar, if coplanar { Vec::new() } else { planner.occluders_between(a, b) })
                })
                .collect();
            planner.pairs = Some(table);
        }
        planner
    }

    /// Faces of the scene.
    pub fn face_count(&self) -> usize {
        self.faces.len()
    }

    /// Whether any pair of faces can have an occluder between them (one query per pair of faces).
    pub fn has_occlusion(&self) -> bool {
        let n = self.faces.len();
        (0..n).any(|a| (0..n).any(|b| a != b && !self.candidates(a, b).is_empty()))
    }

    /// Occluders that may lie between faces `a` and `b` (none for one face or one plane).
    pub fn candidates(&self, a: usize, b: usize) -> Vec<usize> {
        if self.same_plane(a, b) { Vec::new() } else { self.occluders_between(a, b) }
    }

    /// Whether faces `a` and `b` are one face or lie in one plane ([`crate::scene::Face::is_coplanar_with`],
    /// with the sizes measured once for the planner).
    pub fn same_plane(&self, a: usize, b: usize) -> bool {
        let (fa, fb) = (&self.faces[a], &self.faces[b]);
        a == b || fa.face.is_coplanar_at_size(&fb.face, || fa.size.max(fb.size))
    }

    /// The height of `p` over the plane of `face`, with a bound of its distance from the plane's
    /// origin (the sum of the coordinates' sizes: no square root) for the height's rounding.
    pub(super) fn height(&self, p: DVec3, face: usize) -> Height {
        let frame = &self.faces[face].face.frame;
        Height { z: frame.height(p), distance_bound: (p - frame.origin).abs().element_sum() }
    }

    /// [`PairPlanner::same_plane`] for a point of face `own_face` at height `h` over the plane
    /// of `face`: the height of a point of a face is an average of its vertices' heights, all
    /// within the coplanarity tolerance of a face in its plane, so a larger height (beyond
    /// twice that tolerance and the height's rounding) decides it without measuring the faces.
    pub(super) fn same_plane_seen_from(&self, h: Height, own_face: usize, face: usize) -> bool {
        let (own, f) = (&self.faces[own_face], &self.faces[face]);
        let rounding = HEIGHT_ROUNDING * h.distance_bound;
        let reach = 2.0 * COPLANAR_DISTANCE * own.size.max(f.size) + rounding;
        h.z.abs() <= reach && self.same_plane(own_face, face)
    }

    /// The tolerance of the planes and segments between faces `a` and `b` (shafts, view
    /// volumes, occluders crossing segments): 1e-12 of the larger face's size.
    pub(super) fn pair_tolerance(&self, a: usize, b: usize) -> f64 {
        1e-12 * self.faces[a].size.max(self.faces[b].size)
    }

    /// Occluders in the box of faces `a` and `b` and in front of both, in index order.
    fn occluders_between(&self, a: usize, b: usize) -> Vec<usize> {
        let (fa, fb) = (&self.faces[a], &self.faces[b]);
        let tol = self.pair_tolerance(a, b);
        let mut volume = ViewVolume::between(&fa.face.frame, &fb.face.frame, tol);
        volume.push_box(fa.lo.min(fb.lo), fa.hi.max(fb.hi), tol);
        let mut found: Vec<usize> = self.occluders.inside(a, b, &volume).collect();
        found.sort_unstable();
        found
    }

    /// The convex occluder pieces of the scene.
    pub fn occluders(&self) -> &[Occluder] {
        &self.occluders.pieces
    }

    /// Why the point `p` on face `own_face` sees nothing of face `face`, where the planes alone
    /// tell: the two faces share a plane, or `p` is on or behind `face`'s plane. Most faces
    /// met by a node of a compressed operator's exact blocks are such (41 of 61 million views
    /// on city:20x20:lit at refine 1); [`PairPlanner::face_view`] gives the same skip.
    pub fn plane_skip_of(&self, p: DVec3, own_face: usize, face: usize) -> Option<SkipReason> {
        self.plane_skip(self.height(p, face), own_face, face)
    }

    /// [`PairPlanner::plane_skip_of`] for a point at height `h` over `face`'s plane.
    pub(super) fn plane_skip(&self, h: Height, own_face: usize, face: usize) -> Option<SkipReason> {
        let coplanar = match &self.pairs {
            Some(table) => table[own_face * self.faces.len() + face].0,
            None => self.same_plane_seen_from(h, own_face, face),
        };
        if coplanar {
            Some(SkipReason::SamePlane)
        } else {
            (h.z <= 0.0).then_some(SkipReason::FacingAway)
        }
    }
}

/// A point's height over a face's plane ([`PairPlanner::height`]).
#[derive(Clone, Copy)]
pub(super) struct Height {
    pub(super) z: f64,
    /// At least the point's distance from the plane's origin.
    pub(super) distance_bound: f64,
}
