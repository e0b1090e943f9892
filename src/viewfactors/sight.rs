//! What a point of T_i sees of T_j among the occluders of its piece: the whole element, nothing,
//! or signed convex pieces (inclusion and exclusion of the shadows, which avoids cutting the
//! window into the pieces that subtracting them leaves).

use glam::{DVec2, DVec3};
use smallvec::SmallVec;

use super::context::Context;
use super::opening::Opening;
use crate::geometry::{self, SmallPolygon};
use crate::visibility::{Caster, FaceView, Shadows, Visibility};

/// How the point-to-element integral of a pair is found at each outer point of a piece.
#[derive(Clone, Copy)]
pub(super) enum Sight<'a> {
    /// The whole element is seen from every point of the piece.
    Whole,
    /// Per point: the node's view of the face, clipped and shadowed exactly by these occluder
    /// pieces (those that can come between the piece and the element).
    PerPoint(Among<'a>),
}

/// What can come between the points of a piece and the element: occluder pieces, and where a
/// plate of them leaves one opening, that opening and the others.
#[derive(Clone, Copy)]
pub(super) struct Among<'a> {
    pub(super) occluders: &'a [Caster],
    pub(super) opening: Option<(&'a Opening, &'a [Caster])>,
}

#[cfg(test)]
impl<'a> Among<'a> {
    /// These occluder pieces, without an opening.
    pub(super) fn occluders(occluders: &'a [Caster]) -> Self {
        Self { occluders, opening: None }
    }
}

impl Context<'_> {
    /// What the point `p` of element `i` sees of element `j`, shadowed exactly by the occluder
    /// pieces `among` (those that can come between them): where they hold a plate with an
    /// opening, what it sees on its side of the plate and through the opening, shadowed by the
    /// others.
    pub(super) fn point_view(&self, i: usize, j: usize, p: DVec3, among: Among<'_>) -> PointView {
        let element = self.disc.in_face(j);
        let frame = &self.scene.faces[self.disc.face_of(j)].frame;
        let Some((windows, others)) =
            among.opening.and_then(|(o, others)| Some((o.windows(p, frame, &element)?, others)))
        else {
            return self
                .window_view(i, j, p, &element, among.occluders)
                .unwrap_or(PointView::Whole);
        };
        let (mut added, mut taken) = (Vec::new(), Vec::new());
        for window in windows.iter().flatten() {
            match self.window_view(i, j, p, window, others) {
                Some(PointView::Signed { added: a, taken: t }) => {
                    added.extend(a);
                    taken.extend(t);
                }
                Some(_) => {}
                None => added.push(window.to_vec()),
            }
        }
        if added.is_empty() { PointView::Nothing } else { PointView::Signed { added, taken } }
    }

    /// What the point `p` of element `i` sees of the convex part `window` of element `j`
    /// (face coordinates), shadowed by the occluder pieces `among`: `None` where it sees all of
    /// it.
    fn window_view(
        &self,
        i: usize,
        j: usize,
        p: DVec3,
        window: &[DVec2],
        among: &[Caster],
    ) -> Option<PointView> {
        let ei = &self.mesh.elements()[i];
        let normal = self.scene.faces[ei.face].frame.normal;
        let face = self.disc.face_of(j);
        Some(match self.planner.part_view_among(p, normal, ei.face, face, window, among) {
            FaceView::Skip(_) => PointView::Nothing,
            FaceView::Visible { clip, shadows } if shadows.len() <= INCLUSION_EXCLUSION => {
                // The shadows lie in the window, T_j in front of the tangent plane: the
                // integral over the window less that over their union, by inclusion and
                // exclusion of their (convex) intersections, without cutting the window into
                // the pieces that the subtraction makes.
                let window = match clip {
                    Some(hp) => match geometry::clip_convex(window, &hp) {
                        Some(w) => w,
                        None => return Some(PointView::Nothing),
                    },
                    None => window.to_vec(),
                };
                let (added, taken) = inclusion_exclusion(window, shadows);
                PointView::Signed { added, taken }
            }
            view => match self.planner.visible(&view, window) {
                Visibility::Skip(_) => PointView::Nothing,
                Visibility::Full => return None,
                Visibility::Partial(pieces) => {
                    PointView::Signed { added: pieces, taken: Vec::new() }
                }
            },
        })
    }
}

/// What a point of T_i sees of T_j ([`Context::point_view`]).
pub(super) enum PointView {
    /// Nothing: T_j is hidden, behind the point or facing away.
    Nothing,
    /// The whole of T_j.
    Whole,
    /// The convex pieces `added` (face coordinates) less the convex pieces `taken`.
    Signed { added: Vec<Vec<DVec2>>, taken: Vec<Vec<DVec2>> },
}

impl PointView {
    /// The view's shape as a number: its kind, and for signed pieces how many there are of
    /// each sign and how many corners each has, leaving out pieces without area and corners
    /// without a side (where two shadows share an edge, a building's walls at its corner, their
    /// common part is such a sliver or not by rounding). The points of a piece of T_i between
    /// its visibility events see one shape; a patch whose points see several straddles an
    /// event that was not cut along (where three mutually skew edges line up), and the
    /// difference of its rules can miss by far more than it says.
    pub(super) fn shape(&self) -> u64 {
        match self {
            PointView::Nothing => 1,
            PointView::Whole => 2,
            PointView::Signed { added, taken } => {
                let scale = added.first().map_or(0.0, |w| {
                    let (lo, hi) = geometry::bounding_box(w);
                    (hi - lo).length()
                });
                let areas = |pieces: &[Vec<DVec2>]| -> SmallVec<[f64; 8]> {
                    pieces.iter().map(|p| geometry::signed_area(p).abs()).collect()
                };
                let (added_areas, taken_areas) = (areas(added), areas(taken));
                // Shadows that cover the whole window: nothing is seen, as where one occluder
                // was found to cross every segment.
                let seen = added_areas.iter().sum::<f64>() - taken_areas.iter().sum::<f64>();
                if seen <= SLIVER * scale * scale {
                    return 1;
                }
                let corners = |pieces: &[Vec<DVec2>], areas: &[f64], seed: u64| {
                    pieces.iter().zip(areas).fold(seed, |h, (p, &area)| {
                        if area <= SLIVER * scale * scale {
                            return h;
                        }
                        let sides = (0..p.len())
                            .filter(|&k| p[k].distance(p[(k + 1) % p.len()]) > SLIVER * scale)
                            .count();
                        h.wrapping_mul(31).wrapping_add(sides as u64)
                    })
                };
                let added = corners(added, &added_areas, 3);
                corners(taken, &taken_areas, added.wrapping_mul(1_000_003))
            }
        }
    }
}

/// Relative size (of a side, or of an area against the window's square) below which a
/// view's piece or corner does not count in its shape.
const SLIVER: f64 = 1e-9;

/// The shapes of the views from a set of points ([`PointView::shape`]): none yet, one, or
/// more than one.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(super) enum Shapes {
    #[default]
    None,
    One(u64),
    Many,
}

impl Shapes {
    /// These shapes and that of `view`.
    pub(super) fn with(self, view: &PointView) -> Self {
        self.and(Shapes::One(view.shape()))
    }

    /// These shapes and `other`'s.
    pub(super) fn and(self, other: Shapes) -> Self {
        match (self, other) {
            (Shapes::None, s) | (s, Shapes::None) => s,
            (Shapes::One(a), Shapes::One(b)) if a == b => self,
            _ => Shapes::Many,
        }
    }
}

/// The window less the union of the convex `shadows` as signed convex pieces: the window and
/// the intersections of an even number of shadows added, those of an odd number taken. The
/// intersections grow one shadow at a time, in index order: one that is empty, or whose box is
/// apart from the next shadow's, ends that branch (no set holding both meets).
fn inclusion_exclusion(window: Vec<DVec2>, shadows: Shadows) -> (Vec<Vec<DVec2>>, Vec<Vec<DVec2>>) {
    let boxes = shadows.boxes();
    let apart = |(lo, hi): (DVec2, DVec2), (slo, shi): (DVec2, DVec2)| {
        hi.x < slo.x || shi.x < lo.x || hi.y < slo.y || shi.y < lo.y
    };
    // [added, taken]: a set of an odd number of shadows is taken, the shadows themselves first.
    let mut signed = [vec![window], Vec::new()];
    // (last shadow, number of shadows, their intersection) still to extend.
    let mut sets: SmallVec<[(usize, usize, SmallPolygon<DVec2>); 4]> = SmallVec::new();
    let extend = |last: usize, members: usize, common: &[DVec2], own, sets: &mut SmallVec<_>| {
        for b in last + 1..shadows.len() {
            if !apart(own, boxes[b]) {
                if let Some(next) = geometry::clip_to_convex(common, &shadows[b]) {
                    sets.push((b, members + 1, next));
                }
            }
        }
    };
    for a in 0..shadows.len() {
        extend(a, 1, &shadows[a], boxes[a], &mut sets);
        while let Some((last, members, common)) = sets.pop() {
            extend(last, members, &common, geometry::bounding_box(&common), &mut sets);
            signed[members % 2].push(common.into_vec());
        }
    }
    let [added, mut taken] = signed;
    taken.splice(0..0, shadows.into_polygons());
    (added, taken)
}

/// Up to this many shadows on T_j, a point's view is integrated by inclusion and exclusion of the
/// shadows' intersections (at most 2^k - 1 convex polygons, fewer where shadows are apart)
/// instead of over the pieces left by subtracting them: above a few shadows the 2^k - 1
/// intersections outgrow the pieces, below that subtracting clips more, and on the occluded box
/// 4 balances the two.
pub(super) const INCLUSION_EXCLUSION: usize = 4;
