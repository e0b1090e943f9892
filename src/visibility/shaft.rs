//! Shafts between two boxes or polygons: the occluders that may meet a segment between them.

use glam::DVec3;

use super::occluders::{OccluderUnit, ViewVolume};
use super::planner::PairPlanner;
use crate::geometry::{bounding_box_3d, box_corners};

impl PairPlanner {
    /// What segments between a point of the box `nodes` on face `a` and a point of the box
    /// `elements` on face `b` (a block of the compressed operator, each box in front of the other
    /// face's plane) meet: nothing, when no occluder piece other than `a`'s and `b`'s reaches into
    /// the shaft (Haines and Wallace 1994), the convex hull of the two boxes in front of both
    /// planes; one piece that every such segment crosses, or a convex solid that hides one box
    /// from the other (the block is hidden); or something in between. The shaft is bounded by
    /// supporting planes of the two boxes (their faces, and planes along each axis through
    /// corresponding corners), so the test only errs towards [`Shaft::Partial`].
    ///
    /// With `candidates` (those of [`PairPlanner::shaft_candidates`] for these boxes or boxes
    /// around them), only their pieces are tried (a solid's not at all where its box misses the
    /// shaft); every piece that can meet a segment is among them.
    pub fn shaft(
        &self,
        a: usize,
        b: usize,
        nodes: (DVec3, DVec3),
        elements: (DVec3, DVec3),
        candidates: Option<&[OccluderUnit]>,
    ) -> Shaft {
        let (found, hidden) = match candidates {
            Some(units) => self.shaft_occluders_among(a, b, nodes, elements, units),
            None => self.shaft_occluders(a, b, nodes, elements),
        };
        match (hidden, found.is_empty()) {
            (true, _) => Shaft::Hidden,
            (false, true) => Shaft::Clear,
            (false, false) => Shaft::Partial,
        }
    }

    /// The occluders, as units (convex solids whole, the other pieces alone), of `within` (all
    /// when `None`), that may meet a segment between the boxes `nodes` and `elements`: those
    /// with a piece reaching into the boxes' shaft, without the faces' planes and without the
    /// shrink of [`PairPlanner::shaft`], so a superset of what that finds for any faces. Boxes
    /// inside these have their segments among these boxes' segments, so the list of a block of
    /// the compressed operator serves as `within` for its sub-blocks, which then never search
    /// the whole scene; a building is one entry of it, not its walls and roof.
    pub fn shaft_candidates(
        &self,
        nodes: (DVec3, DVec3),
        elements: (DVec3, DVec3),
        within: Option<&[OccluderUnit]>,
    ) -> Vec<OccluderUnit> {
        let mut volume = ViewVolume::default();
        push_shaft(&mut volume, nodes, elements, 0.0);
        self.occluders.units_within(&volume, within)
    }

    /// The occluder pieces that reach into the shaft of [`PairPlanner::shaft`], and whether they
    /// hide the boxes from each other (one crossing every segment, or a convex solid).
    pub fn shaft_occluders(
        &self,
        a: usize,
        b: usize,
        nodes: (DVec3, DVec3),
        elements: (DVec3, DVec3),
    ) -> (Vec<usize>, bool) {
        let (volume, tol) = self.shaft_volume(a, b, nodes, elements);
        let found: Vec<usize> = self.occluders.inside(a, b, &volume).collect();
        let hidden =
            self.hides_shaft(&found, (a, b), &box_corners(nodes), &box_corners(elements), tol);
        (found, hidden)
    }

    /// [`PairPlanner::shaft_occluders`] among `units` (those of
    /// [`PairPlanner::shaft_candidates`] for boxes around these), without a search of the
    /// scene: a building among them that hides the boxes settles it before any piece is tried.
    /// The same pieces, in the order of `units`.
    pub fn shaft_occluders_among(
        &self,
        a: usize,
        b: usize,
        nodes: (DVec3, DVec3),
        elements: (DVec3, DVec3),
        units: &[OccluderUnit],
    ) -> (Vec<usize>, bool) {
        // A building among the units that hides the boxes settles it before the shaft's planes
        // are set up and any of the pieces is searched (most blocks between a city's streets).
        if self.solid_among_hides(a, b, nodes, elements, units) {
            return (Vec::new(), true);
        }
        let (volume, tol) = self.shaft_volume(a, b, nodes, elements);
        let found = self.occluders.pieces_within(a, b, &volume, units);
        // Every solid has been tried: only single pieces are left to try.
        let (from, to) = (box_corners(nodes), box_corners(elements));
        let hidden = self.crossed_by_one(&found, &from, &to, tol);
        (found, hidden)
    }

    /// Whether a convex solid among `units` (not one with a face of `a` or `b`) hides the box
    /// `nodes` on face `a` from the box `elements` on face `b` ([`crate::visibility`]'s
    /// `Solid::hides`).
    pub fn solid_among_hides(
        &self,
        a: usize,
        b: usize,
        nodes: (DVec3, DVec3),
        elements: (DVec3, DVec3),
        units: &[OccluderUnit],
    ) -> bool {
        let tol = self.pair_tolerance(a, b);
        let (from, to) = (box_corners(nodes), box_corners(elements));
        self.occluders.unit_solid_hides(units, (a, b), &from, &to, tol)
    }

    /// Those of `candidates` (occluder pieces, none of faces `a` and `b`) that may meet a
    /// segment from the convex polygon `from` on face `a` to the convex polygon `to` on face
    /// `b`, and whether one of them crosses every such segment (exactly: the crossings of the
    /// corner segments span those of all) or a convex solid they bound hides one polygon from
    /// the other. A piece is left out when a plane separates it from
    /// the segments: one of [`PairPlanner::shaft`]'s, or its own plane with both polygons on
    /// one side of it; or when a convex solid bounded by some of them hides it from the whole
    /// of `from`, whose views see the same without it
    /// (`OccluderIndex::drop_hidden_behind_solids`).
    pub fn polygon_shaft(
        &self,
        a: usize,
        b: usize,
        from: &[DVec3],
        to: &[DVec3],
        candidates: &[usize],
    ) -> (Vec<usize>, bool) {
        let (volume, tol) = self.shaft_volume(a, b, bounding_box_3d(from), bounding_box_3d(to));
        let mut found = Vec::new();
        for &o in candidates {
            let piece = &self.occluders.pieces[o];
            if !volume.may_hold(piece) || piece.plane_separates(from, to, tol) {
                continue;
            }
            if piece.crosses_every_segment(from, to, tol, tol) {
                return (vec![o], true);
            }
            found.push(o);
        }
        if self.occluders.solid_hides(&found, (a, b), from, to, tol) {
            return (found, true);
        }
        self.occluders.drop_hidden_behind_solids(&mut found, (a, b), from, tol);
        (found, false)
    }

    /// The shaft between two boxes on faces `a` and `b`, and the tolerance of its planes.
    fn shaft_volume(
        &self,
        a: usize,
        b: usize,
        nodes: (DVec3, DVec3),
        elements: (DVec3, DVec3),
    ) -> (ViewVolume, f64) {
        let (fa, fb) = (&self.faces[a], &self.faces[b]);
        let tol = self.pair_tolerance(a, b);
        let mut volume = ViewVolume::between(&fa.face.frame, &fb.face.frame, tol);
        push_shaft(&mut volume, nodes, elements, tol);
        (volume, tol)
    }

    /// Whether one of the pieces `found` crosses every segment between the boxes with corners
    /// `from` and `to` (on faces `a` and `b`), or a convex solid that some of them bound hides
    /// one box from the other.
    fn hides_shaft(
        &self,
        found: &[usize],
        faces: (usize, usize),
        from: &[DVec3],
        to: &[DVec3],
        tol: f64,
    ) -> bool {
        self.crossed_by_one(found, from, to, tol)
            || self.occluders.solid_hides(found, faces, from, to, tol)
    }

    /// Whether one of the pieces `found` crosses every segment between the boxes with corners
    /// `from` and `to`.
    fn crossed_by_one(&self, found: &[usize], from: &[DVec3], to: &[DVec3], tol: f64) -> bool {
        found.iter().any(|&o| self.occluders.pieces[o].crosses_every_segment(from, to, tol, tol))
    }
}

/// What an occluder does to the segments between two boxes ([`PairPlanner::shaft`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Shaft {
    /// No occluder meets any segment.
    Clear,
    /// One occluder crosses every segment, or a convex solid hides the boxes from each other.
    Hidden,
    /// Anything else.
    Partial,
}

/// Adds the shaft between two boxes to `volume`, shrunk by `shrink` (a piece that only touches
/// the shaft from outside, as a plate level with the top of a wall, blocks no segment inside
/// it): the box around both, tested first by comparisons alone, and the planes of
/// [`shaft_normals`] through their farthest corners.
fn push_shaft(volume: &mut ViewVolume, a: (DVec3, DVec3), b: (DVec3, DVec3), shrink: f64) {
    volume.push_box(a.0.min(b.0), a.1.max(b.1), shrink);
    let corners: Vec<DVec3> = box_corners(a).into_iter().chain(box_corners(b)).collect();
    for n in shaft_normals(a, b) {
        let reach = corners.iter().map(|c| n.dot(*c)).fold(f64::NEG_INFINITY, f64::max);
        // Inside: n·x <= reach.
        volume.push(-n, reach, shrink);
    }
}

/// Outward normals of the supporting planes of the convex hull of two boxes besides those of
/// the box around both: for each axis and each pair of corresponding corners the two normals
/// perpendicular to the axis and to the segment joining those corners (the planes of Haines and
/// Wallace's shaft).
fn shaft_normals(a: (DVec3, DVec3), b: (DVec3, DVec3)) -> Vec<DVec3> {
    let mut normals = Vec::with_capacity(24);
    let (ca, cb) = (box_corners(a), box_corners(b));
    for (axis, bit) in [(DVec3::X, 1), (DVec3::Y, 2), (DVec3::Z, 4)] {
        // Corners with the axis's bit clear: one per sign pattern of the other two axes.
        for k in (0..8).filter(|k| k & bit == 0) {
            let n = axis.cross(cb[k] - ca[k]);
            if n.length_squared() > 0.0 {
                let n = n.normalize();
                normals.extend([n, -n]);
            }
        }
    }
    normals
}
