//! Occluders: the scene's faces as convex pieces (non-convex faces cut into convex parts, the two sides of a
//! double-sided plate merged), an index over their bounding boxes, and which of them can come
//! between a point and a face.

use glam::DVec3;
use rstar::primitives::{GeomWithData, Rectangle};
use rstar::{AABB, RTree, SelectionFunction};
use serde::Serialize;
use smallvec::SmallVec;

use super::solids::{Solid, convex_solids};
use crate::geometry::PlaneFrame;
use crate::scene::Scene;

/// A convex planar piece of one or more faces that blocks light.
#[derive(Clone, Debug, PartialEq)]
pub struct Occluder {
    /// Faces this piece belongs to (both sides of a plate share one piece).
    pub faces: Vec<usize>,
    /// Vertices (convex polygon).
    pub polygon: Vec<DVec3>,
    lo: DVec3,
    hi: DVec3,
    /// The diagonal of its bounding box.
    pub(super) diameter: f64,
    /// Unit normal of its plane (the orientation of `polygon`).
    normal: DVec3,
    /// Per edge (from vertex k to k + 1), the unit normal in the plane pointing into the polygon.
    edge_normals: Vec<DVec3>,
}

/// How candidate occluders of a view are found. All three leave the same visible parts, to
/// rounding (the core plan's shadows are piece by piece, the others' one per convex solid).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Acceleration {
    /// An R*-tree (the `rstar` crate) over the occluders' bounding boxes, searched with the view
    /// pyramid (apex at the node, over the face's visible window, in front of both faces).
    #[default]
    Tree,
    /// Every occluder tested against the view pyramid.
    Scan,
    /// Every occluder tested against the box of the node and the face and the two faces' planes
    /// (the core solver's rule, before the index).
    BoxScan,
}

type Boxed = GeomWithData<Rectangle<[f64; 3]>, usize>;

/// What a view or a shaft searches for ([`OccluderIndex::units_reaching`]): a convex solid whole
/// (by its number), or a piece that bounds no solid (by its number).
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum OccluderUnit {
    /// A convex solid.
    Solid(usize),
    /// An occluder piece.
    Piece(usize),
}

type BoxedUnit = GeomWithData<Rectangle<[f64; 3]>, OccluderUnit>;

/// The occluders and the structure that finds those overlapping a box.
#[derive(Clone, Debug)]
pub(super) struct OccluderIndex {
    pub(super) pieces: Vec<Occluder>,
    /// The convex solids that pieces bound, and per piece its solid (none for
    /// [`Acceleration::BoxScan`], the core plan, which shadows piece by piece).
    pub(super) solids: Vec<Solid>,
    solid_of: Vec<Option<usize>>,
    /// Per piece, whether it bounds the scene ([`boundary_pieces`]) and no solid.
    bounds_scene: Vec<bool>,
    pub(super) acceleration: Acceleration,
    tree: Option<RTree<Boxed>>,
    /// The pieces of each solid, in index order, and the box around them.
    pub(super) solid_pieces: Vec<Vec<usize>>,
    solid_boxes: Vec<(DVec3, DVec3)>,
    /// An R*-tree over the units (each solid by the box of its pieces, each other piece by its
    /// own), which the views search: a building is one leaf, not its walls and roof, and is
    /// met once.
    units: Option<RTree<BoxedUnit>>,
}

impl OccluderIndex {
    pub(super) fn new(scene: &Scene, acceleration: Acceleration) -> Self {
        let pieces = convex_pieces(scene);
        let (solids, solid_of) = if acceleration == Acceleration::BoxScan {
            (Vec::new(), vec![None; pieces.len()])
        } else {
            convex_solids(&pieces)
        };
        // The trees leave out the pieces that bound the scene and no solid (a city's ground, a
        // room's walls): never a candidate of a view or a shaft. Scans keep them, the
        // references that the trees are checked against.
        let on_boundary = boundary_pieces(&pieces);
        let bounds_scene: Vec<bool> =
            on_boundary.iter().zip(&solid_of).map(|(&on, solid)| on && solid.is_none()).collect();
        let searched = |k: usize| !bounds_scene[k];
        let tree = (acceleration == Acceleration::Tree).then(|| {
            RTree::bulk_load(
                pieces
                    .iter()
                    .enumerate()
                    .filter(|&(k, _)| searched(k))
                    .map(|(k, o)| {
                        GeomWithData::new(Rectangle::from_corners(o.lo.into(), o.hi.into()), k)
                    })
                    .collect(),
            )
        });
        let mut solid_pieces = vec![Vec::new(); solids.len()];
        for (k, solid) in solid_of.iter().enumerate() {
            if let Some(s) = solid {
                solid_pieces[*s].push(k);
            }
        }
        let solid_boxes: Vec<(DVec3, DVec3)> = solid_pieces
            .iter()
            .map(|list| {
                list.iter().fold(
                    (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY)),
                    |(lo, hi), &k| (lo.min(pieces[k].lo), hi.max(pieces[k].hi)),
                )
            })
            .collect();
        let units = (acceleration == Acceleration::Tree).then(|| {
            let boxed = |(lo, hi): (DVec3, DVec3), unit| {
                GeomWithData::new(Rectangle::from_corners(lo.into(), hi.into()), unit)
            };
            let solids =
                solid_boxes.iter().enumerate().map(|(s, &b)| boxed(b, OccluderUnit::Solid(s)));
            let free = (0..pieces.len())
                .filter(|&k| solid_of[k].is_none() && searched(k))
                .map(|k| boxed((pieces[k].lo, pieces[k].hi), OccluderUnit::Piece(k)));
            RTree::bulk_load(solids.chain(free).collect())
        });
        Self {
            pieces,
            solids,
            solid_of,
            bounds_scene,
            acceleration,
            tree,
            solid_pieces,
            solid_boxes,
            units,
        }
    }

    /// Whether piece `o` bounds the scene and no solid ([`boundary_pieces`]): left out of the
    /// trees, and hiding nothing from a point of the scene.
    pub(super) fn bounds_scene(&self, o: usize) -> bool {
        self.bounds_scene[o]
    }

    /// The units that may reach into `volume` (a solid where one of its pieces may), among
    /// `within` in its order, else in the unit tree's order; without that tree, each piece
    /// that may reach as a unit of its own.
    pub(super) fn units_within(
        &self,
        volume: &ViewVolume,
        within: Option<&[OccluderUnit]>,
    ) -> Vec<OccluderUnit> {
        let reaches = |unit: &OccluderUnit| match *unit {
            OccluderUnit::Piece(k) => volume.may_hold(&self.pieces[k]),
            OccluderUnit::Solid(s) => {
                self.solid_pieces[s].iter().any(|&k| volume.may_hold(&self.pieces[k]))
            }
        };
        match (within, self.units_reaching(volume)) {
            (Some(list), _) => list.iter().copied().filter(reaches).collect(),
            (None, Some(units)) => units.map(|(u, _, _)| u).filter(reaches).collect(),
            (None, None) => (0..self.pieces.len())
                .filter(|&k| volume.may_hold(&self.pieces[k]))
                .map(OccluderUnit::Piece)
                .collect(),
        }
    }

    /// The pieces of `units` that may block a segment between faces `a` and `b` in `volume`
    /// ([`OccluderIndex::may_block`]): the same as [`OccluderIndex::inside`] among
    /// the pieces of the units, with a solid's pieces left out at once where its box misses.
    pub(super) fn pieces_within(
        &self,
        a: usize,
        b: usize,
        volume: &ViewVolume,
        units: &[OccluderUnit],
    ) -> Vec<usize> {
        let keep = |k: usize| self.may_block(k, a, b, volume);
        let mut found = Vec::new();
        for &unit in units {
            match unit {
                OccluderUnit::Piece(k) => found.extend(Some(k).filter(|&k| keep(k))),
                OccluderUnit::Solid(s) => {
                    let (lo, hi) = self.solid_boxes[s];
                    if volume.may_hold_box(lo, hi) {
                        found.extend(self.solid_pieces[s].iter().copied().filter(|&k| keep(k)));
                    }
                }
            }
        }
        found
    }

    /// Whether the units have a tree ([`OccluderIndex::units_reaching`]).
    pub(super) fn has_unit_tree(&self) -> bool {
        self.units.is_some()
    }

    /// The units whose boxes may reach into `volume`, in the tree's order, each with its box;
    /// `None` without the tree.
    pub(super) fn units_reaching<'a>(
        &'a self,
        volume: &'a ViewVolume,
    ) -> Option<impl Iterator<Item = (OccluderUnit, DVec3, DVec3)> + 'a> {
        let tree = self.units.as_ref()?;
        Some(tree.locate_with_selection_function(volume).map(|g| {
            let r = g.geom();
            (g.data, DVec3::from(r.lower()), DVec3::from(r.upper()))
        }))
    }

    /// The convex solid that piece `o` bounds, if any.
    pub(super) fn solid_of_piece(&self, o: usize) -> Option<usize> {
        self.solid_of[o]
    }

    /// The solid that piece `o` bounds, unless it has a face of `a` or `b` (seen from or seen on
    /// one of its own faces, a solid is no occluder of its own).
    pub(super) fn solid_for_view(&self, o: usize, a: usize, b: usize) -> Option<usize> {
        self.solid_of[o].filter(|&s| self.solid_occludes(s, a, b))
    }

    /// Whether solid `s` may occlude between faces `a` and `b`: it has neither as a face.
    fn solid_occludes(&self, s: usize, a: usize, b: usize) -> bool {
        let faces = &self.solids[s].faces;
        faces.binary_search(&a).is_err() && faces.binary_search(&b).is_err()
    }

    /// Whether a convex solid bounded by some of `pieces` (not one with a face of `a` or `b`)
    /// hides every point of the convex hull of `from` from every point of that of `to`
    /// ([`Solid::hides`]).
    pub(super) fn solid_hides(
        &self,
        pieces: &[usize],
        (a, b): (usize, usize),
        from: &[DVec3],
        to: &[DVec3],
        tol: f64,
    ) -> bool {
        let mut tried: SmallVec<[usize; 8]> = SmallVec::new();
        pieces.iter().filter_map(|&o| self.solid_for_view(o, a, b)).any(|s| {
            if tried.contains(&s) {
                return false;
            }
            tried.push(s);
            self.solids[s].hides(from, to, tol)
        })
    }

    /// Leaves out of `pieces` (those in a shaft from the convex polygon `from` on face `a` to
    /// face `b`) each that a convex solid bounded by some of them (not one with a face of `a`
    /// or `b`) hides from every point of `from` ([`Solid::hides`]): a building's far walls
    /// behind its near ones, the buildings behind a nearer one. Views among the rest see the
    /// same: along a segment from `from` that meets pieces, the first piece it meets is never
    /// left out, since the segment to a left-out piece enters the solid that hides it before,
    /// through one of the solid's pieces, which that segment puts in the shaft (nothing enters
    /// through the open cap, which no segment of the scene crosses).
    pub(super) fn drop_hidden_behind_solids(
        &self,
        pieces: &mut Vec<usize>,
        (a, b): (usize, usize),
        from: &[DVec3],
        tol: f64,
    ) {
        let mut solids: SmallVec<[usize; 8]> =
            pieces.iter().filter_map(|&o| self.solid_for_view(o, a, b)).collect();
        solids.sort_unstable();
        solids.dedup();
        if solids.is_empty() {
            return;
        }
        pieces.retain(|&o| {
            let polygon = &self.pieces[o].polygon;
            !solids.iter().any(|&s| self.solids[s].hides(from, polygon, tol))
        });
    }

    /// Whether a convex solid among `units` (not one with a face of `a` or `b`) hides every
    /// point of the convex hull of `from` from every point of that of `to` ([`Solid::hides`]).
    /// Every solid that [`OccluderIndex::solid_hides`] would try on the pieces of `units` found
    /// in a shaft between them is among these.
    pub(super) fn unit_solid_hides(
        &self,
        units: &[OccluderUnit],
        (a, b): (usize, usize),
        from: &[DVec3],
        to: &[DVec3],
        tol: f64,
    ) -> bool {
        units.iter().any(|&unit| match unit {
            OccluderUnit::Piece(_) => false,
            OccluderUnit::Solid(s) => {
                self.solid_occludes(s, a, b) && self.solids[s].hides(from, to, tol)
            }
        })
    }

    /// Occluders that may block a segment between faces `a` and `b` that lies in `volume`
    /// ([`OccluderIndex::may_block`]), found lazily in the tree's order or in index order.
    pub(super) fn inside<'a>(
        &'a self,
        a: usize,
        b: usize,
        volume: &'a ViewVolume,
    ) -> Box<dyn Iterator<Item = usize> + 'a> {
        let keep = move |&k: &usize| self.may_block(k, a, b, volume);
        match &self.tree {
            Some(tree) => {
                Box::new(tree.locate_with_selection_function(volume).map(|g| g.data).filter(keep))
            }
            None => Box::new((0..self.pieces.len()).filter(keep)),
        }
    }

    /// Whether piece `k` may block a segment between faces `a` and `b` that lies in `volume`:
    /// it is part of neither face, and not wholly outside one of the volume's planes.
    pub(super) fn may_block(&self, k: usize, a: usize, b: usize, volume: &ViewVolume) -> bool {
        let o = &self.pieces[k];
        !o.faces.contains(&a) && !o.faces.contains(&b) && volume.may_hold(o)
    }
}

/// A convex region bounded by planes: the segments from a node to a face (the pyramid over the
/// face's window with apex at the node, in front of both faces), or between two faces (their
/// bounding box, in front of both). Each plane is `n·x + d`, and a polygon or box is outside when
/// that is at most `margin` at all its points.
#[derive(Clone, Debug, Default)]
pub(super) struct ViewVolume {
    /// The box of [`ViewVolume::push_box`], tested first and by comparisons alone (its planes
    /// are the axes'): most boxes of the index fail there.
    bounds: Option<(DVec3, DVec3, f64)>,
    planes: Vec<(DVec3, f64, f64)>,
}

impl ViewVolume {
    /// The region in front of both planes (heights above `tol`).
    pub(super) fn between(fa: &PlaneFrame, fb: &PlaneFrame, tol: f64) -> Self {
        let mut volume = Self::default();
        volume.push_front_of(fa, tol);
        volume.push_front_of(fb, tol);
        volume
    }

    /// Adds the region in front of a plane (heights above `tol`).
    pub(super) fn push_front_of(&mut self, frame: &PlaneFrame, tol: f64) {
        self.push(frame.normal, -frame.normal.dot(frame.origin), tol);
    }

    /// Adds the half-space `n·x + d > margin`.
    pub(super) fn push(&mut self, normal: DVec3, offset: f64, margin: f64) {
        self.planes.push((normal, offset, margin));
    }

    /// Adds the six faces of the box `[lo, hi]`, shrunk by `shrink` (a piece touching the box
    /// from outside blocks no segment inside it); one box per volume.
    pub(super) fn push_box(&mut self, lo: DVec3, hi: DVec3, shrink: f64) {
        debug_assert!(self.bounds.is_none(), "one box per view volume");
        self.bounds = Some((lo, hi, shrink));
    }

    /// Whether the occluder may reach inside (its box first, kept since it was built).
    pub(super) fn may_hold(&self, occluder: &Occluder) -> bool {
        self.box_reaches(occluder.lo, occluder.hi)
            && self
                .planes
                .iter()
                .all(|&(n, d, margin)| occluder.polygon.iter().any(|&v| n.dot(v) + d > margin))
    }

    /// Whether `[lo, hi]` reaches into the box of [`ViewVolume::push_box`] by more than its
    /// shrink on every side: the test of that box's six planes, `x - lo_x > shrink` and
    /// `hi_x - x > shrink` at the farthest point, to the same bits.
    fn box_reaches(&self, lo: DVec3, hi: DVec3) -> bool {
        self.bounds.is_none_or(|(blo, bhi, shrink)| {
            (hi - blo).cmpgt(DVec3::splat(shrink)).all()
                && (bhi - lo).cmpgt(DVec3::splat(shrink)).all()
        })
    }

    /// Whether the box `[lo, hi]` may reach inside (its corner farthest along each normal).
    pub(super) fn may_hold_box(&self, lo: DVec3, hi: DVec3) -> bool {
        self.box_reaches(lo, hi)
            && self.planes.iter().all(|&(n, d, margin)| {
                let far = DVec3::select(n.cmpge(DVec3::ZERO), hi, lo);
                n.dot(far) + d > margin
            })
    }
}

/// The search of both trees (pieces and units): a node or leaf is entered where its box may
/// reach inside the volume.
impl<T: Copy> SelectionFunction<GeomWithData<Rectangle<[f64; 3]>, T>> for &ViewVolume {
    fn should_unpack_parent(&self, envelope: &AABB<[f64; 3]>) -> bool {
        self.may_hold_box(DVec3::from(envelope.lower()), DVec3::from(envelope.upper()))
    }

    fn should_unpack_leaf(&self, leaf: &GeomWithData<Rectangle<[f64; 3]>, T>) -> bool {
        let r = leaf.geom();
        self.may_hold_box(DVec3::from(r.lower()), DVec3::from(r.upper()))
    }
}

/// Convex pieces of every face, without duplicates.
fn convex_pieces(scene: &Scene) -> Vec<Occluder> {
    let mut pieces: Vec<Occluder> = Vec::new();
    // Pieces by their rounded lowest corner, to find the other side of a plate without a scan.
    let mut by_corner: std::collections::HashMap<[i64; 3], Vec<usize>> = Default::default();
    for (k, face) in scene.faces.iter().enumerate() {
        let polygons: Vec<Vec<DVec3>> = if face.is_convex() {
            vec![face.vertices.clone()]
        } else {
            crate::geometry::convex_partition(&face.local_polygon())
                .expect(crate::scene::TRIANGULABLE)
                .into_iter()
                .map(|piece| piece.iter().map(|&i| face.vertices[i]).collect())
                .collect()
        };
        for polygon in polygons {
            let tol = 1e-12 * face.size();
            let (lo, _) = crate::geometry::bounding_box_3d(&polygon);
            let key = |c: DVec3| (c / (64.0 * tol).max(f64::MIN_POSITIVE)).round().as_i64vec3();
            let near: Vec<[i64; 3]> = neighbour_keys(key(lo));
            let same = near
                .iter()
                .flat_map(|c| by_corner.get(c).into_iter().flatten())
                .find(|&&o| same_vertex_set(&pieces[o].polygon, &polygon, tol));
            if let Some(&o) = same {
                pieces[o].faces.push(k);
                continue;
            }
            by_corner.entry(key(lo).into()).or_default().push(pieces.len());
            pieces.push(Occluder::new(k, polygon));
        }
    }
    pieces
}

/// Per piece, whether the whole scene lies on one side of its plane (the box around the pieces,
/// tested at its corners, on it or beyond it): the ground under a city, the sky over it, the
/// walls of a room. Such a piece crosses no segment between two points of the scene, which
/// meets its plane at most at an end or lies in it: it casts no shadow of any area, hides
/// nothing and blocks no shaft.
pub(super) fn boundary_pieces(pieces: &[Occluder]) -> Vec<bool> {
    let (lo, hi) = pieces
        .iter()
        .fold((DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY)), |(lo, hi), o| {
            (lo.min(o.lo), hi.max(o.hi))
        });
    let corners = crate::geometry::box_corners((lo, hi));
    pieces
        .iter()
        .map(|o| {
            let origin = o.polygon[0];
            let heights = corners.iter().map(|&c| o.normal.dot(c - origin));
            let (least, most) =
                heights.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), h| (a.min(h), b.max(h)));
            o.normal != DVec3::ZERO && (least >= 0.0 || most <= 0.0)
        })
        .collect()
}

/// The 27 grid keys around `c` (a corner within the tolerance may round to a neighbouring cell).
fn neighbour_keys(c: glam::I64Vec3) -> Vec<[i64; 3]> {
    let mut keys = Vec::with_capacity(27);
    for dx in -1..=1 {
        for dy in -1..=1 {
            for dz in -1..=1 {
                keys.push([c.x + dx, c.y + dy, c.z + dz]);
            }
        }
    }
    keys
}

impl Occluder {
    fn new(face: usize, polygon: Vec<DVec3>) -> Self {
        let (lo, hi) = crate::geometry::bounding_box_3d(&polygon);
        let m = polygon.len();
        let normal = (1..m - 1)
            .map(|k| (polygon[k] - polygon[0]).cross(polygon[k + 1] - polygon[0]))
            .sum::<DVec3>()
            .normalize_or_zero();
        let edge_normals = (0..m)
            .map(|k| normal.cross(polygon[(k + 1) % m] - polygon[k]).normalize_or_zero())
            .collect();
        Self {
            faces: vec![face],
            polygon,
            lo,
            hi,
            diameter: (hi - lo).length(),
            normal,
            edge_normals,
        }
    }

    /// Whether this piece may cast a shadow of positive area seen from `p` on the convex window
    /// with corners `corners` (in space): false when a plane separates the pyramid with apex `p`
    /// over the window from this piece's cone from `p` (its own plane, or the plane through `p`
    /// and one of its edges); cheaper than clipping the piece to the pyramid, which most
    /// candidates found by boxes miss. A piece whose plane holds `p` casts nothing: every
    /// segment from `p` lies in that plane or leaves it at `p` (a node on the line where a
    /// partition meets a wall sees past the partition's edge on both sides).
    pub(super) fn may_shadow(&self, p: DVec3, corners: &[DVec3]) -> bool {
        if self.plane_holds(p) {
            return false;
        }
        let origin = self.polygon[0];
        let hp = self.normal.dot(p - origin);
        if corners.iter().all(|&c| hp * self.normal.dot(c - origin) >= 0.0) {
            return false;
        }
        // Interior points x of the piece have (v_k - p) x (v_k+1 - p) . (x - p) of the sign of -hp.
        let m = self.polygon.len();
        !(0..m).any(|k| {
            let n = (self.polygon[k] - p).cross(self.polygon[(k + 1) % m] - p);
            corners.iter().all(|&c| hp * n.dot(c - p) >= 0.0)
        })
    }

    /// Whether this piece's plane passes through `p`, up to the rounding of its size.
    pub(super) fn plane_holds(&self, p: DVec3) -> bool {
        self.normal != DVec3::ZERO
            && self.normal.dot(p - self.polygon[0]).abs() <= 1e-12 * self.diameter
    }

    /// Whether every point of `from` and `to` is on one side of this piece's plane or within
    /// `tol` of it: a segment between them then meets the plane at most at an end, or lies in
    /// it, and the piece blocks none of them.
    pub(super) fn plane_separates(&self, from: &[DVec3], to: &[DVec3], tol: f64) -> bool {
        if self.normal == DVec3::ZERO {
            return false;
        }
        let origin = self.polygon[0];
        let heights = from.iter().chain(to).map(|&p| self.normal.dot(p - origin));
        let (mut above, mut below) = (false, false);
        for h in heights {
            above |= h > tol;
            below |= h < -tol;
        }
        !(above && below)
    }

    /// Whether this piece crosses every segment from a point of the convex hull of `from` to one
    /// of `to`: the two sets lie strictly (beyond `tol`) on opposite sides of its plane, and every
    /// segment between their corners crosses the plane inside the polygon (the crossings of all
    /// segments are the convex hull of those, central projection keeping convexity). A crossing
    /// counts as inside when it is at least `edge_margin` inside each edge: positive for a strict
    /// test, negative (the margin of a shadow covering a window) where a crossing on the outline
    /// still hides, as from a node on the ground looking along the foot of a wall.
    pub(super) fn crosses_every_segment(
        &self,
        from: &[DVec3],
        to: &[DVec3],
        tol: f64,
        edge_margin: f64,
    ) -> bool {
        if self.normal == DVec3::ZERO {
            return false;
        }
        let origin = self.polygon[0];
        let height = |p: DVec3| self.normal.dot(p - origin);
        let above = |points: &[DVec3]| points.iter().all(|&p| height(p) > tol);
        let below = |points: &[DVec3]| points.iter().all(|&p| height(p) < -tol);
        if !((above(from) && below(to)) || (below(from) && above(to))) {
            return false;
        }
        from.iter().all(|&p| {
            let hp = height(p);
            to.iter().all(|&q| {
                let x = p + (q - p) * (hp / (hp - height(q)));
                self.polygon
                    .iter()
                    .zip(&self.edge_normals)
                    .all(|(&v, e)| e.dot(x - v) > edge_margin)
            })
        })
    }

    /// Centre of its bounding box.
    pub fn centre(&self) -> DVec3 {
        0.5 * (self.lo + self.hi)
    }

    /// Unit normal of its plane.
    pub fn normal(&self) -> DVec3 {
        self.normal
    }

    /// Its bounding box (smallest and largest corner).
    pub fn bounding_box(&self) -> (DVec3, DVec3) {
        (self.lo, self.hi)
    }
}

fn same_vertex_set(a: &[DVec3], b: &[DVec3], tol: f64) -> bool {
    a.len() == b.len() && a.iter().all(|p| b.iter().any(|q| (*p - *q).length() <= tol))
}
