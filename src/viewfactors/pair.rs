//! The adaptive outer integral of one pair, F_ij: T_i cut into pieces where the integrand is not
//! smooth, each covered by cells whose Gauss or tanh-sinh estimates decide where to refine.

use std::collections::BinaryHeap;
use std::f64::consts::PI;

use glam::{DVec2, DVec3};
use smallvec::SmallVec;

use super::Between;
use super::events::{centroid, clip_polygon_3d, contact_cuts, event_planes, split};
use super::opening::Opening;
use super::outer::{Check, Outer};
use super::patch::{GaussRules, Patch};
use super::poles::poles;
use super::sight::{Among, PointView, Shapes, Sight};
use super::{Context, MAX_SPLITS, Tally, ViewFactorOptions};
use crate::assembly::{FullPair, LaneObserver, push_fan};
use crate::geometry::{bounding_box_3d, convex_polygons_distance};
use crate::kernels::lanes;
use crate::quadrature::TanhSinh;
use crate::visibility::{Caster, Visibility};

/// The outer rules: tanh-sinh for elements that touch, Gauss of a chosen order otherwise.
pub(super) struct OuterRules {
    tanh_sinh: TanhSinh,
    gauss: GaussRules,
}

/// Highest order of the Gauss rules on a patch (GAUSS_MAX² points).
const GAUSS_MAX: usize = 16;

/// The share of a pair's error budget that patches taken by their bounds may take at first
/// ([`Context::bounded_cell`]), the patches that can hold the least first.
const BOUNDED_SHARE: f64 = 0.5;

/// The outer rule's target error where T_j is seen whole, relative to the integrand's size near
/// the element: a tenth of the tolerance, and no less than 1e-13. The Gauss order is chosen from
/// the separation so that the Bernstein-ellipse bound meets it ([`OuterRules::bound_order`]);
/// the integrand is analytic away from T_j and the bound is trusted (one rule, no estimate). A
/// tenth leaves the bound's constant (the rule's, and the integrand's growth off the real
/// patch) a factor of ten within the tolerance. Aimed at a ten-thousandth with the ellipse of a
/// point beyond a side's end instead, two facing walls of city:4x4 6 m apart (elements 35 m
/// across) came out 2.1e-6 off at --tolerance 1e-6, with an estimate of 1e-6.
fn certified_target(tolerance: f64) -> f64 {
    (0.1 * tolerance).max(1e-13)
}

impl OuterRules {
    /// The rules for `options`: the tanh-sinh rule truncated where its weights fall below a
    /// hundredth of the tolerance (the integrand, a point-to-element factor, is at most 1).
    /// Truncated at 1e-20 instead, city:4x4 and the louvre room at --tolerance 1e-6 took
    /// 4.54 M and 7.17 M evaluations in touching triangles instead of 2.41 M and 3.79 M, with
    /// every entry the same to 1e-10.
    pub(super) fn new(options: &ViewFactorOptions) -> Self {
        let tail = 1e-2 * options.tolerance;
        Self {
            tanh_sinh: TanhSinh::new(options.max_level, tail),
            gauss: GaussRules::new(GAUSS_MAX),
        }
    }

    /// The Gauss order for a patch of size `size` at distance `distance` from the nearest
    /// point where the integrand is not analytic (the other element, an occluder), as a first
    /// guess that the cell's estimate checks: the integrand is analytic in an ellipse with foci
    /// at a side's ends, and where the point lies beyond a side's end, its semi-axis sum is
    /// rho = a + sqrt(a² - 1), a = 1 + 2 distance / size; the q-point rule's error falls like
    /// rho^-2q. `None` when even the highest order but one does not reach the target (the cell
    /// then takes that order and the highest, and its estimate decides whether to split).
    fn guessed_order(&self, size: f64, distance: f64, target: f64) -> Option<usize> {
        let a = 1.0 + 2.0 * distance / size;
        self.order_for(a + (a * a - 1.0).sqrt(), target)
    }

    /// The Gauss order whose a priori bound meets the target wherever the point at `distance`
    /// lies: the smallest ellipse is that through a point at that distance from a side's
    /// middle, a = sqrt(1 + (2 distance / size)²). Where the distance is small against the
    /// patch (two facing walls across a street) it is far smaller than beyond a side's end,
    /// whose order missed the target by 2e4 there. `None` where no order up to the highest but
    /// one meets it.
    fn bound_order(&self, size: f64, distance: f64, target: f64) -> Option<usize> {
        let across = 2.0 * distance / size;
        let a = (1.0 + across * across).sqrt();
        self.order_for(a + (a * a - 1.0).sqrt(), target)
    }

    /// The Gauss order whose error, falling like rho^-2q, meets the target, where the integrand
    /// is analytic inside the Bernstein ellipse of parameter `rho`, from 2; `None` where even
    /// the highest order but one does not. From 1 (one point, checked against 2), city:4x4 at
    /// --tolerance 1e-3 took 0.52 M evaluations instead of 0.62 M, but on the 12 x 12
    /// tessellated city at 1e-6 a pair reached the split limit at 1.3e-6.
    fn order_for(&self, rho: f64, target: f64) -> Option<usize> {
        let q = ((1.0 / target).ln() / (2.0 * rho.ln())).ceil();
        (q < GAUSS_MAX as f64).then(|| (q as usize).max(2))
    }
}

impl Context<'_> {
    /// F_ij.
    pub(super) fn pair(
        &self,
        i: usize,
        j: usize,
        between: &mut Option<Between>,
        rules: &OuterRules,
        tally: &mut Tally,
    ) -> f64 {
        let (ei, ej) = (&self.mesh.elements()[i], &self.mesh.elements()[j]);
        let (fa, fb) = (&self.scene.faces[ei.face], &self.scene.faces[ej.face]);
        if self.planner.same_plane(ei.face, ej.face) {
            return 0.0;
        }
        let tol = 1e-12 * ei.diameter().max(ej.diameter());
        let heights = |f: &crate::scene::Face, t: &[DVec3; 3]| t.map(|v| f.frame.height(v));
        let (hj, hi) = (heights(fa, &ej.vertices), heights(fb, &ei.vertices));
        if hj.iter().all(|&h| h <= tol) || hi.iter().all(|&h| h <= tol) {
            return 0.0; // one wholly behind the other's plane
        }
        let (box_i, box_j) = (bounding_box_3d(&ei.vertices), bounding_box_3d(&ej.vertices));
        let (a, b) = (ei.face, ej.face);
        // Found once for the face, by the first of its pairs that gets this far.
        let (mut occluders, hidden) = match between.get_or_insert_with(|| self.between(i, b)) {
            Between::Nothing => (Vec::new(), false),
            Between::Hidden => return 0.0,
            Between::Among(units) => self.planner.shaft_occluders_among(a, b, box_i, box_j, units),
            Between::Search => self.planner.shaft_occluders(a, b, box_i, box_j),
        };
        if hidden {
            return 0.0;
        }
        // In the order of their numbers, whichever search found them.
        occluders.sort_unstable();
        let in_front = |h: [f64; 3]| h.iter().all(|&h| h >= -tol);
        let pieces = self.smooth_pieces((i, j), !in_front(hi), &occluders, tol);
        // Each piece has its own occluders, among the pair's: a piece in the light of all of
        // them sees T_j whole (no per-point visibility), one behind an occluder that crosses
        // every segment to T_j sees nothing, and the others shadow T_j by their own occluders
        // only, without any search; where a plate of them leaves one opening, through that
        // opening and by the others.
        let shafts: Vec<Shaft> = pieces
            .into_iter()
            .filter_map(|piece| {
                let (blocking, hidden) = if occluders.is_empty() {
                    (Vec::new(), false)
                } else {
                    self.planner.polygon_shaft(ei.face, ej.face, &piece, &ej.vertices, &occluders)
                };
                if hidden {
                    return None;
                }
                let casters = |pieces: &[usize]| self.planner.casters(ei.face, ej.face, pieces);
                let opening =
                    Opening::find(&piece, &ej.vertices, &blocking, self.planner).map(|o| {
                        let others: Vec<usize> =
                            blocking.iter().copied().filter(|b| !o.pieces.contains(b)).collect();
                        (o, casters(&others))
                    });
                let casting = casters(&blocking);
                Some(Shaft { piece, blocking, casting, opening })
            })
            .collect();
        let parts: Vec<Part> = shafts
            .iter()
            .map(|shaft| Part {
                target: ej.vertices,
                target_box: box_j,
                target_area: ej.area(),
                clipped: !in_front(hj),
                poles: poles(
                    fa.frame.normal,
                    &shaft.piece,
                    &fb.frame,
                    &ej.vertices,
                    &shaft.blocking,
                    self.planner,
                    (ei.face, ej.face),
                ),
                obstacles: self.obstacles(i, &shaft.blocking),
                sight: if shaft.blocking.is_empty() && in_front(hj) {
                    Sight::Whole
                } else {
                    Sight::PerPoint(Among {
                        occluders: &shaft.casting,
                        opening: shaft.opening.as_ref().map(|(o, others)| (o, others.as_slice())),
                    })
                },
            })
            .collect();
        // Globally adaptive over the pair: the cell with the largest estimated error is split
        // until the estimates together are within the tolerance on F_ij. Patches that can hold
        // little of F_ij at most, the least first, take their bounds' share of the budget
        // ([`Context::bounded_cell`]); the others take the rules.
        let budget = self.options.tolerance * ei.area();
        let mut patches: Vec<(f64, usize, Patch)> = shafts
            .iter()
            .enumerate()
            .flat_map(|(k, shaft)| Patch::cover(&shaft.piece).into_iter().map(move |p| (k, p)))
            .map(|(k, patch)| (parts[k].most(&patch), k, patch))
            .collect();
        patches.sort_unstable_by(|a, b| a.0.total_cmp(&b.0));
        let mut bounded_share = BOUNDED_SHARE * budget;
        let mut cells = Cells::default();
        for (most, k, patch) in patches {
            let cell = if most <= bounded_share {
                bounded_share -= most;
                self.bounded_cell((i, j), patch, &parts[k], k, most, tally)
            } else {
                self.cell(i, j, patch, &parts[k], k, 0, rules, tally)
            };
            cells.place(cell);
        }
        // Settled cells (at the split limit, or certified) keep their error: the open ones are
        // refined until the two together meet the budget, or until they meet half of it where
        // the settled ones already take more than the other half (refining every open cell to
        // the limit would not help).
        while cells.open_error > (budget - cells.settled_error).max(0.5 * budget) {
            let Some(cell) = cells.open.pop() else { break };
            cells.open_error -= cell.error;
            let part = &parts[cell.part];
            if cell.refine == Refine::ByRules {
                cells.place(self.cell(i, j, cell.patch, part, cell.part, 0, rules, tally));
                continue;
            }
            for child in cell.patch.quarters() {
                cells.place(self.cell(i, j, child, part, cell.part, cell.depth + 1, rules, tally));
            }
        }
        let (value, error) = cells.total();
        tally.error = tally.error.max(error / ei.area());
        value / ei.area()
    }

    /// Element i of the pair `(i, j)` cut where the integrand is not smooth: behind element
    /// j's plane (when it reaches there, `behind`) it sees nothing, and across the event lines of
    /// the `occluders` the visible part of element j changes its shape.
    fn smooth_pieces(
        &self,
        (i, j): (usize, usize),
        behind: bool,
        occluders: &[usize],
        tol: f64,
    ) -> Vec<Vec<DVec3>> {
        let (ei, ej) = (&self.mesh.elements()[i], &self.mesh.elements()[j]);
        let (fa, fb) = (&self.scene.faces[ei.face], &self.scene.faces[ej.face]);
        let mut pieces = vec![ei.vertices.to_vec()];
        if behind {
            let (n, o) = (fb.frame.normal, fb.frame.origin);
            pieces = pieces.iter().filter_map(|p| clip_polygon_3d(p, n, -n.dot(o))).collect();
        }
        let (ti, tj) = ((&ei.vertices, &fa.frame), (&ej.vertices, &fb.frame));
        let events =
            event_planes(&ei.vertices, &ej.vertices, occluders, self.planner, (ei.face, ej.face));
        for event in contact_cuts(ti, tj, tol).into_iter().chain(events) {
            let mut next = Vec::with_capacity(pieces.len() + 1);
            for piece in pieces {
                if !event.crosses(&piece, fa.frame.normal) {
                    next.push(piece);
                    continue;
                }
                match split(&piece, event.normal, event.point) {
                    Some(parts) => next.extend(parts),
                    None => next.push(piece),
                }
            }
            pieces = next;
        }
        pieces
    }

    /// `Σ w (1/π) ∫ G V` over element `j` from the weighted points `(p, w)` of a piece of
    /// element `i`.
    pub(super) fn weighted_sum(
        &self,
        i: usize,
        j: usize,
        sight: Sight<'_>,
        points: &[(DVec3, f64)],
    ) -> (f64, Shapes) {
        let (mut sum, mut shapes) = (0.0, Shapes::None);
        self.point_values(i, j, sight, points, Some(&mut shapes), |_, v| sum += v);
        (sum / PI, shapes)
    }

    /// `(1/π) ∫ G V` over element `j` from each of the points `points` of element `i`, into
    /// `values`.
    fn values(&self, i: usize, j: usize, sight: Sight<'_>, points: &[DVec3], values: &mut [f64]) {
        let weighted: Vec<(DVec3, f64)> = points.iter().map(|&p| (p, 1.0)).collect();
        values.fill(0.0);
        self.point_values(i, j, sight, &weighted, None, |k, v| values[k] += v);
        values.iter_mut().for_each(|v| *v /= PI);
    }

    /// `w ∫ G V` over element `j` from each weighted point `(p, w)` of element `i`, seen as
    /// `sight` says, given to `sink` with the point's index (in parts): the closed forms of the
    /// whole element, or of the pieces of its visible part, eight at a time in vector lanes.
    /// Adds the shapes of the points' views to `shapes`, if asked.
    fn point_values(
        &self,
        i: usize,
        j: usize,
        sight: Sight<'_>,
        points: &[(DVec3, f64)],
        mut shapes: Option<&mut Shapes>,
        mut sink: impl FnMut(usize, f64),
    ) {
        let (el, basis) = (&self.disc.elements[j], &self.disc.bases[j]);
        let normal = self.scene.faces[self.mesh.elements()[i].face].frame.normal;
        let mut batch = lanes::Batch::<(usize, f64)>::default();
        let mut lane_sink = |(k, w): (usize, f64), v: f64| sink(k, w * v);
        for (k, &(p, w)) in points.iter().enumerate() {
            let view = match sight {
                Sight::Whole => PointView::Whole,
                Sight::PerPoint(among) => self.point_view(i, j, p, among),
            };
            if let Some(shapes) = shapes.as_deref_mut() {
                *shapes = shapes.with(&view);
            }
            let (added, taken) = match view {
                PointView::Nothing => continue,
                PointView::Whole => {
                    match self.integrator.full_pair(el, basis, p, normal) {
                        FullPair::Values(values) => lane_sink((k, w), values[0]),
                        FullPair::Lane(obs, tri) => batch.push((k, w), obs, tri, &mut lane_sink),
                    }
                    continue;
                }
                PointView::Signed { added, taken } => (added, taken),
            };
            match self.integrator.lane_observer(el, p, normal) {
                LaneObserver::Unseen => {}
                LaneObserver::Scalar => {
                    lane_sink((k, w), self.signed_integral(j, p, normal, added, taken));
                }
                LaneObserver::Lane(obs) => {
                    for (pieces, weight) in [(added, w), (taken, -w)] {
                        for piece in &pieces {
                            push_fan(el, obs, piece, ((k, weight), &mut batch), &mut lane_sink);
                        }
                    }
                }
            }
        }
        batch.flush(&mut lane_sink);
    }

    /// The shapes of the views of element `j` from the points `points` of element `i`.
    fn shapes_at(&self, i: usize, j: usize, sight: Sight<'_>, points: &[(DVec3, f64)]) -> Shapes {
        let Sight::PerPoint(among) = sight else { return Shapes::One(PointView::Whole.shape()) };
        points
            .iter()
            .fold(Shapes::None, |shapes, &(p, _)| shapes.with(&self.point_view(i, j, p, among)))
    }

    /// `(1/π) ∫ G V` over element `j` seen from the point `p` of element `i`, by the scalar
    /// closed forms: the reference that the tests hold the lanes of [`Context::values`] to.
    #[cfg(test)]
    pub(super) fn point_to_element(&self, i: usize, j: usize, p: DVec3, sight: Sight<'_>) -> f64 {
        let (el, basis) = (&self.disc.elements[j], &self.disc.bases[j]);
        let normal = self.scene.faces[self.mesh.elements()[i].face].frame.normal;
        let whole = || self.integrator.integrate(el, basis, p, normal, &Visibility::Full)[0] / PI;
        let Sight::PerPoint(among) = sight else { return whole() };
        match self.point_view(i, j, p, among) {
            PointView::Nothing => 0.0,
            PointView::Whole => whole(),
            PointView::Signed { added, taken } => {
                self.signed_integral(j, p, normal, added, taken) / PI
            }
        }
    }

    /// `∫ G` over the pieces `added` of element `j` less that over `taken`, from the point `p`
    /// with unit normal `normal`.
    fn signed_integral(
        &self,
        j: usize,
        p: DVec3,
        normal: DVec3,
        added: Vec<Vec<DVec2>>,
        taken: Vec<Vec<DVec2>>,
    ) -> f64 {
        let (el, basis) = (&self.disc.elements[j], &self.disc.bases[j]);
        let integral = |pieces| self.integrator.integrate(el, basis, p, normal, &pieces)[0];
        let taken = if taken.is_empty() { 0.0 } else { integral(Visibility::Partial(taken)) };
        integral(Visibility::Partial(added)) - taken
    }

    /// `∫ g dA` over the patch `patch` of the piece with `part`, and its estimated error:
    /// tanh-sinh on its triangles where it touches an obstacle (d log d behaviour at a common
    /// edge; its error [`kept_error`](super::outer::kept_error) of its last levels, to be split
    /// further if the pair needs it); where T_j is seen whole, Gauss of the order that the
    /// patch's separation asks for (settled, as the bound is trusted); otherwise that order and
    /// one more, the higher one's value with their difference as the error (which also catches
    /// what the separation does not: the curved events of three skew edges), to be split
    /// further if the pair needs it.
    #[allow(clippy::too_many_arguments)]
    fn cell(
        &self,
        i: usize,
        j: usize,
        patch: Patch,
        part: &Part,
        index: usize,
        depth: u32,
        rules: &OuterRules,
        tally: &mut Tally,
    ) -> Cell {
        let area = patch.area();
        let mut cell =
            Cell { patch, part: index, depth, value: 0.0, error: 0.0, refine: Refine::Settled };
        if area == 0.0 {
            return cell;
        }
        let size = patch.size();
        let (to_target, distance) = part.reach(patch.corners(), size);
        // Where T_j reaches behind T_i's plane, the line where the planes meet bounds what the
        // points see and the integrand is not analytic on it; where it touches T_i at a corner
        // it runs just outside the triangle, and the tanh-sinh levels collapsed there can agree
        // while missing (a partition's element under the louvre room's ceiling: estimate
        // 1.4e-8, 2.1e-6 off). The triangle's quarters check it. Where occluders alone shadow
        // T_j, the probe of views decides ([`Context::touching_triangle`]): checking all those
        // too took 7.13 M evaluations instead of 6.19 M on the louvre room at --tolerance 1e-6,
        // 16.6 M instead of 12.6 M at 1e-8, 11.3 M instead of 8.7 M on the furnished room at
        // 1e-8, with the same largest difference from a run at 1e-10.
        let checked = part.clipped && distance <= TOUCHING * size;
        let distance = distance.min(part.obstacle_distance(patch.corners()));
        // Where occluders shadow T_j the order is only a first guess, since the estimate with
        // one order more decides: it aims at the tolerance itself. Aiming lower costs higher
        // first orders, aiming higher costs more splits (on the occluded box either was
        // slower, for the same reciprocity).
        // The Bernstein bound is relative to the integrand's size, which from a patch at
        // distance d from T_j is at most A_j / (π d²) (cosines at most 1): the tolerance on
        // F_ij asks for that much less relative accuracy of a patch far from a small T_j.
        // Relaxed at most tenfold instead (a cap that once kept low first orders from failing
        // and splitting on five-piece, which no longer happens), the tessellated city 5 x 5
        // without its sky at --tolerance 1e-6 took 36.7 M evaluations instead of 30.5 M, every
        // entry within 8.4e-7 of a run at 1e-9 either way (6.1e-7 with the cap); five-piece
        // refine 3 at the default 2.61 M instead of 2.57 M, within 4.6e-13 of a run at 1e-13.
        let shadowed_target = self.options.tolerance / integrand_bound(to_target, part.target_area);
        if distance <= TOUCHING * size {
            for t in patch.triangles() {
                // A quadrilateral's half that touches nothing itself is a cell of its own.
                if matches!(patch, Patch::Quad(_)) && !self.touches(&t, part) {
                    let half =
                        self.cell(i, j, Patch::Triangle(t), part, index, depth, rules, tally);
                    cell.value += half.value;
                    cell.error += half.error;
                    continue;
                }
                // Two corners where occluders' edges meet T_i (a wall's foot between two
                // buildings' corners): its halves have one each.
                if let Some(halves) = self.between_obstacles(t, part)
                    && depth < MAX_SPLITS
                {
                    for half in halves {
                        let half = Patch::Triangle(half);
                        let half = self.cell(i, j, half, part, index, depth + 1, rules, tally);
                        cell.value += half.value;
                        cell.error += half.error;
                    }
                    continue;
                }
                let at_corner = match self.at_obstacle_corner(t, part) {
                    Some((t, distance)) => {
                        let q = rules.guessed_order(
                            Patch::Triangle(t).size(),
                            distance,
                            shadowed_target,
                        );
                        Some((t, q.unwrap_or(GAUSS_MAX - 1)))
                    }
                    None => self.at_target_corner(t, part, rules, shadowed_target),
                };
                let by_gauss = at_corner.map(|(t, q)| {
                    let t = Patch::Triangle(t);
                    let q = q.max(corner_order(self.options.tolerance));
                    (self.two_orders((i, j), &t, part, Some(q), rules, tally), t.area())
                });
                // Where the collapsed Gauss rule does not meet the tolerance on its own share,
                // the integrand is not analytic about the corner after all (an event plane
                // through it, outside the triangle but near): tanh-sinh takes it.
                let (value, error) = match by_gauss {
                    Some(((value, error), area)) if error <= self.options.tolerance * area => {
                        (value, error)
                    }
                    _ => {
                        let outsized = Patch::Triangle(t).size()
                            > OUTSIZED * Patch::Triangle(part.target).size();
                        let check = if part.narrow_contact(&t) || outsized {
                            Check::QuartersEveryLevel
                        } else if checked {
                            Check::Quarters
                        } else {
                            Check::Levels
                        };
                        self.touching_triangle(i, j, t, part, check, rules, tally)
                    }
                };
                cell.value += value;
                cell.error += error;
            }
            cell.refine = Refine::by_quarters_below_the_limit(depth);
            return cell;
        }
        let certified = matches!(part.sight, Sight::Whole);
        let target =
            if certified { certified_target(self.options.tolerance) } else { shadowed_target };
        let order = if certified {
            rules.bound_order(size, distance, target)
        } else {
            rules.guessed_order(size, distance, target)
        };
        if certified {
            match order {
                Some(q) => {
                    cell.value = self.gauss_sum((i, j), &cell.patch, q, part, rules, tally).0;
                    return cell;
                }
                // Too close to T_j for the bound: its quarters, settled together.
                None if depth < MAX_SPLITS => {
                    for child in patch.quarters() {
                        let c = self.cell(i, j, child, part, index, depth + 1, rules, tally);
                        cell.value += c.value;
                        cell.error += c.error;
                    }
                    return cell;
                }
                None => {}
            }
        }
        (cell.value, cell.error) = self.two_orders((i, j), &cell.patch, part, order, rules, tally);
        cell.refine = Refine::by_quarters_below_the_limit(depth);
        cell
    }

    /// `∫ g dA` over `patch` by the Gauss rule of order `q`, and the shapes of the views from
    /// its points.
    fn gauss_sum(
        &self,
        (i, j): (usize, usize),
        patch: &Patch,
        q: usize,
        part: &Part,
        rules: &OuterRules,
        tally: &mut Tally,
    ) -> (f64, Shapes) {
        let points = patch.gauss_points(&rules.gauss, q);
        tally.evaluations += points.len() as u64;
        self.weighted_sum(i, j, part.sight, &points)
    }

    /// `∫ g dA` over `patch` by the Gauss rule of order q + 1, and its estimated error: the
    /// difference from order q, and where the points see T_j in more than one shape, also the
    /// difference from order q + 2; where no order meets the a priori bound (`order` `None`: q
    /// is then the highest but one), the difference from the rule over its quarters.
    fn two_orders(
        &self,
        (i, j): (usize, usize),
        patch: &Patch,
        part: &Part,
        order: Option<usize>,
        rules: &OuterRules,
        tally: &mut Tally,
    ) -> (f64, f64) {
        let q = order.unwrap_or(GAUSS_MAX - 1);
        let mut estimate_on =
            |patch: &Patch, q: usize| self.gauss_sum((i, j), patch, q, part, rules, tally);
        let ((low, low_shapes), (high, high_shapes)) =
            (estimate_on(patch, q), estimate_on(patch, q + 1));
        let mut error = (high - low).abs();
        // Across an event that was not cut along (where three mutually skew edges line up, or
        // two parallel ones and a third), the points see T_j in more than one shape and the
        // two rules' difference can miss by far more than it says (an entry of city:4x4 was
        // 1.4e-9 off at the default tolerance). Across such a kink the rules' errors scatter
        // with the order instead of falling: order q + 2 is a third sample of that scatter,
        // and its difference from order q + 1 counts too. It took the place of the rule over
        // the patch's quarters of half the order (about as many points), which agreed by chance
        // with the two orders where the third order did not: on a patch of city:4x4 (pair
        // (244, 61), --tolerance 1e-8) orders 4 and 5 and the quarters agreed to 2.7e-9 of F
        // and missed it by 1.7e-8, and order 6 differed by 2.3e-8; city:4x4 at 1e-8 had 7
        // entries off by more than the tolerance (up to 2.0e-8) and now has one (1.4e-8),
        // for the same evaluations.
        // Where no order meets the a priori bound (a patch too near a point where the
        // integrand is not analytic: a chair's backrest whose corner stands 0.014 from the
        // seat, furnished room at --tolerance 1e-6, had orders 15 and 16 differ by 7.1e-7 and
        // miss by 1.2e-6), the quarters, which meet the singularity elsewhere, check it.
        let kinked = matches!(low_shapes.and(high_shapes), Shapes::Many);
        if kinked && q + 2 <= GAUSS_MAX {
            error = error.max((high - estimate_on(patch, q + 2).0).abs());
        } else if kinked || order.is_none() {
            let half = (q + 2) / 2;
            let quarters: f64 = patch.quarters().iter().map(|c| estimate_on(c, half).0).sum();
            error = error.max((high - quarters).abs());
        }
        (high, error)
    }

    /// `∫ g dA` over a patch that can hold at most `most` of it (`0 <= g <= most / area`), by
    /// its value at the centre: the integral lies between 0 and `most`, so the one-point rule
    /// is off by at most the larger of its value and `most` less it. A bound, not an estimate;
    /// where the pair's budget needs it, the rules take the patch after all ([`Refine::ByRules`]).
    /// Settled for good, such cells left the others half the budget: the louvre room and the
    /// furnished room at --tolerance 1e-8 took 9.36 M and 5.29 M evaluations instead of 9.31 M
    /// and 5.25 M (measured with a lowest Gauss order of 1).
    fn bounded_cell(
        &self,
        (i, j): (usize, usize),
        patch: Patch,
        part: &Part,
        index: usize,
        most: f64,
        tally: &mut Tally,
    ) -> Cell {
        let centre = centroid(patch.corners());
        tally.evaluations += 1;
        let (value, _) = self.weighted_sum(i, j, part.sight, &[(centre, patch.area())]);
        let error = value.max(most - value);
        Cell { patch, part: index, depth: 0, value, error, refine: Refine::ByRules }
    }

    /// Whether the triangle `t` touches T_j, an obstacle or a pole line beside it, as
    /// [`Context::cell`] measures a patch's distance from them.
    fn touches(&self, t: &[DVec3; 3], part: &Part) -> bool {
        let size = Patch::Triangle(*t).size();
        part.reach(t, size).1.min(part.obstacle_distance(t)) <= TOUCHING * size
    }

    /// The halves of the triangle `t` split at the middle of a side whose ends are both where
    /// occluders' edges meet T_i, if there is one.
    fn between_obstacles(&self, t: [DVec3; 3], part: &Part) -> Option<[[DVec3; 3]; 2]> {
        let near = TOUCHING * Patch::Triangle(t).size();
        let at = t.map(|v| part.obstacle_distance(&[v]) <= near);
        let k = (0..3).find(|&k| at[k] && at[(k + 1) % 3])?;
        let (a, b, c) = (t[k], t[(k + 1) % 3], t[(k + 2) % 3]);
        let middle = 0.5 * (a + b);
        Some([[a, middle, c], [middle, b, c]])
    }

    /// The triangle `t` with its first corner put where T_j touches it, if T_j touches it there
    /// alone (a corner of T_j, or a point of its edge, on T_i's plane), with no obstacle and no
    /// pole line along a side; and the order of the collapsed Gauss rule about that corner.
    /// Along each ray from the contact, the edges of T_j through it keep their plane with the
    /// point and subtend angles analytic in the distance, so the integrand is analytic in the
    /// collapsed coordinates (distance along the ray, direction) except where the point meets
    /// the rest of T_j, a pole or an obstacle (the distance), and where the ray's direction,
    /// complex, is parallel to a side through the contact of what it sees of T_j (one in T_i's
    /// plane inside the triangle's angle is a contact along a line: none). Where T_j reaches
    /// behind T_i's plane, that has a side on the line where the planes meet. A real direction
    /// pointing away from the side is no singularity (the side's angle times the unit normal of
    /// its plane with the point is analytic on its line beyond its ends). The rule then
    /// converges as on a patch apart, as at an obstacle's corner: on the louvre room at
    /// --tolerance 1e-6 such triangles took 1 000 points each by the tanh-sinh rule, and a
    /// slat's triangle touching a jamb, the planes' line along its side, 5 506.
    fn at_target_corner(
        &self,
        t: [DVec3; 3],
        part: &Part,
        rules: &OuterRules,
        target: f64,
    ) -> Option<([DVec3; 3], usize)> {
        let size = Patch::Triangle(t).size();
        let near = TOUCHING * size;
        let on_target = |x: DVec3| convex_polygons_distance(&[x], &part.target) <= near;
        let on_target: SmallVec<[usize; 3]> = (0..3).filter(|&k| on_target(t[k])).collect();
        let [k] = on_target[..] else { return None };
        let t = [t[k], t[(k + 1) % 3], t[(k + 2) % 3]];
        let contact = t[0];
        let elsewhere = |w: DVec3| w.distance(contact) > near;
        if part.target.iter().any(|&w| elsewhere(w) && convex_polygons_distance(&[w], &t) <= near)
            || part.pole_along_a_side(&t, size)
        {
            return None;
        }
        // The rest of T_j: its edges that do not pass through the contact; and the directions
        // from the contact along the sides of what it sees of T_j there (its edges through
        // the contact, and where T_j reaches behind T_i's plane, the line where the planes
        // meet): an edge's angle is analytic on its line beyond its ends, not along it.
        let (mut rest, mut along_sides) = (f64::INFINITY, SmallVec::<[DVec3; 4]>::new());
        let mut from_contact = |x: DVec3| {
            if x.distance(contact) > near {
                along_sides.push(x - contact);
            }
        };
        for l in 0..3 {
            let edge = [part.target[l], part.target[(l + 1) % 3]];
            if convex_polygons_distance(&[contact], &edge) <= near {
                edge.into_iter().for_each(&mut from_contact);
            } else {
                rest = rest.min(convex_polygons_distance(&t, &edge));
            }
        }
        if part.clipped {
            let normal = (t[1] - t[0]).cross(t[2] - t[0]);
            let h = part.target.map(|x| normal.dot(x - contact));
            for l in 0..3 {
                let (a, b, ha, hb) =
                    (part.target[l], part.target[(l + 1) % 3], h[l], h[(l + 1) % 3]);
                if (ha < 0.0) != (hb < 0.0) {
                    from_contact(a + (b - a) * (ha / (ha - hb)));
                }
            }
        }
        let apart = part.distance(&t, size, rest).min(part.obstacle_distance(&t));
        if apart <= near {
            return None;
        }
        let mut q = rules.guessed_order(size, apart, target)?;
        // The rule's rays from the contact run along w(y) = (b - a) + y (c - b), y in [0, 1];
        // w is parallel to the unit edge e where |w|² - (w·e)² = α y² + β y + γ vanishes.
        let (along, across) = (t[1] - t[0], t[2] - t[1]);
        for e in along_sides {
            let e = e.try_normalize()?;
            let alpha = across.length_squared() - across.dot(e).powi(2);
            let beta = 2.0 * (along.dot(across) - along.dot(e) * across.dot(e));
            let gamma = along.length_squared() - along.dot(e).powi(2);
            if alpha <= 0.0 {
                return None;
            }
            // The two roots are conjugate (the form is not negative for real y); a real one
            // where the ray points away from the side is no singularity.
            let root = DVec2::new(
                -beta / (2.0 * alpha),
                (4.0 * alpha * gamma - beta * beta).max(0.0).sqrt() / (2.0 * alpha),
            );
            let away = (along + root.x * across).dot(e) < 0.0;
            if root.y <= 1e-9 * root.x.abs().max(1.0) && away {
                continue;
            }
            q = q.max(rules.order_for(bernstein_rho(2.0 * root - DVec2::X), target)?);
        }
        Some((t, q))
    }

    /// The triangle `t` with its first corner put where an occluder's edge meets T_i, if that
    /// is the only place where it touches what makes the integrand not analytic, and its
    /// distance from the rest. Along each ray from that point the plane through the point and
    /// the occluder's edge stays the same, so the integrand is analytic in the collapsed
    /// coordinates about it (distance along the ray, direction), and the collapsed Gauss rule
    /// converges there as on a patch apart.
    fn at_obstacle_corner(&self, t: [DVec3; 3], part: &Part) -> Option<([DVec3; 3], f64)> {
        let size = Patch::Triangle(t).size();
        let near = TOUCHING * size;
        let to_target = convex_polygons_distance(&t, &part.target);
        let apart = part.distance(&t, size, to_target);
        if apart <= near {
            return None;
        }
        if part.pole_along_a_side(&t, size) {
            return None;
        }
        let k = (0..3).find(|&k| part.obstacle_distance(&[t[k]]) <= near)?;
        let t = [t[k], t[(k + 1) % 3], t[(k + 2) % 3]];
        let rest = part.obstacle_distance_past(&t, t[0], near);
        (rest > near).then_some((t, apart.min(rest)))
    }

    /// Where the occluders `blocking` make the integrand over a piece of element `i` not
    /// analytic: an occluder apart from T_i's plane, where the viewing point would reach it
    /// (its shadow runs off to infinity); for one that meets T_i's plane, the points where its
    /// edges meet that plane (a building's corners on the ground, a jamb's edge through a
    /// louvre's slat), where the shadow's limit depends on the direction the point comes from.
    /// Along the rest of the contact (a wall's foot) it hides a half-space, whatever the
    /// direction. A slat touching the jamb at its patch's corner took Gauss orders 5 and 6 that
    /// agreed to 1.7e-8 and missed the integral by 1.3e-6; a ground patch at a building's
    /// corner, 2e-6. Each with its box.
    fn obstacles(&self, i: usize, blocking: &[usize]) -> Vec<(Obstacle<'_>, (DVec3, DVec3))> {
        let frame = &self.scene.faces[self.mesh.elements()[i].face].frame;
        let tol = 1e-12 * self.mesh.elements()[i].diameter();
        let occluders = self.planner.occluders();
        let mut obstacles = Vec::new();
        for &o in blocking {
            let polygon = occluders[o].polygon.as_slice();
            let h: SmallVec<[f64; 8]> = polygon.iter().map(|&v| frame.height(v)).collect();
            if h.iter().all(|&x| x > tol) || h.iter().all(|&x| x < -tol) {
                obstacles.push(Obstacle::Polygon(polygon));
                continue;
            }
            let m = polygon.len();
            for k in 0..m {
                let (a, b, ha, hb) = (polygon[k], polygon[(k + 1) % m], h[k], h[(k + 1) % m]);
                if ha.abs() <= tol {
                    obstacles.push(Obstacle::Point(a));
                } else if (ha < 0.0) != (hb < 0.0) && hb.abs() > tol {
                    obstacles.push(Obstacle::Point(a + (b - a) * (ha / (ha - hb))));
                }
            }
        }
        obstacles.into_iter().map(|o| (o, bounding_box_3d(o.corners()))).collect()
    }

    /// `∫_t g dA` and its estimated error over a triangle `t` that touches an obstacle, by the
    /// tanh-sinh rule. The rule collapses the triangle at its last corner, where a point
    /// singularity (an integrand whose limit depends on the direction, as at a corner of T_j on
    /// T_i, or where an occluder's edge meets T_i) costs nothing: the corner nearest a corner
    /// of T_j or such a point is put there. Where it touches T_j and T_j reaches behind its
    /// plane, or where the views from a few points differ in shape, its quarters check the rule
    /// (`check`, [`Outer::integrate`]).
    #[allow(clippy::too_many_arguments)]
    fn touching_triangle(
        &self,
        i: usize,
        j: usize,
        t: [DVec3; 3],
        part: &Part,
        check: Check,
        rules: &OuterRules,
        tally: &mut Tally,
    ) -> (f64, f64) {
        let [a, b, c] = t;
        let area = 0.5 * (b - a).cross(c - a).length();
        if area == 0.0 {
            return (0.0, 0.0);
        }
        let corners = &self.mesh.elements()[j].vertices;
        let near = t.map(|v| {
            let corner = corners.iter().map(|&w| v.distance(w)).fold(f64::MAX, f64::min);
            corner.min(part.obstacle_distance(&[v]))
        });
        let k = (0..3).min_by(|&k, &l| near[k].total_cmp(&near[l])).unwrap_or(2);
        let t = [t[(k + 1) % 3], t[(k + 2) % 3], t[k]];
        // Where the views from a few points inside it differ in shape, an event that was not
        // cut along crosses it, and the levels of the rule can agree while missing (3.3e-9
        // against an estimate of 7e-11, a ground triangle at a building's corner on city:4x4):
        // its quarters check it. The rule's own points, crowded at the sides, would see
        // shapes that differ only by rounding there. Where T_j is seen whole there is one shape.
        let views_differ = |tally: &mut Tally| {
            let probe = Patch::Triangle(t).gauss_points(&rules.gauss, PROBE_ORDER);
            tally.evaluations += probe.len() as u64;
            matches!(self.shapes_at(i, j, part.sight, &probe), Shapes::Many)
        };
        let check = if check == Check::Levels
            && matches!(part.sight, Sight::PerPoint(_))
            && views_differ(tally)
        {
            Check::Quarters
        } else {
            check
        };
        let mut outer = Outer {
            rule: &rules.tanh_sinh,
            options: self.options,
            integrand: |points: &[DVec3], out: &mut [f64]| {
                self.values(i, j, part.sight, points, out)
            },
            evaluations: 0,
        };
        let (value, error) = outer.integrate(t, check);
        tally.evaluations += outer.evaluations;
        (area * value, area * error)
    }
}

/// The cells of a pair's outer integral: those that may still be split, worst first, and the
/// sum of those that are settled.
#[derive(Default)]
struct Cells {
    open: BinaryHeap<Cell>,
    /// Sum of the open cells' estimated errors.
    open_error: f64,
    settled: f64,
    settled_error: f64,
}

impl Cells {
    fn place(&mut self, cell: Cell) {
        if cell.refine != Refine::Settled {
            self.open_error += cell.error;
            self.open.push(cell);
        } else {
            self.settled += cell.value;
            self.settled_error += cell.error;
        }
    }

    /// `∫ g dA` over all cells and its estimated error.
    fn total(&self) -> (f64, f64) {
        let open: f64 = self.open.iter().map(|c| c.value).sum();
        let open_error: f64 = self.open.iter().map(|c| c.error).sum();
        (self.settled + open, self.settled_error + open_error)
    }
}

/// A patch of a pair's outer integral, with its estimate.
struct Cell {
    patch: Patch,
    /// Index of its piece's [`Part`].
    part: usize,
    /// Rounds of splitting that made it.
    depth: u32,
    /// `∫ g dA` over it.
    value: f64,
    /// Estimated |error| of `value`.
    error: f64,
    /// How it may be refined, if at all.
    refine: Refine,
}

/// How a [`Cell`] may be refined.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Refine {
    /// Not at all: certified, or at the split limit.
    Settled,
    /// By its quarters.
    ByQuarters,
    /// By the rules over it: its value is its centre's, with a bound for its error
    /// ([`Context::bounded_cell`]).
    ByRules,
}

impl Refine {
    /// By its quarters, where a cell made by `depth` rounds of splitting is below the limit.
    fn by_quarters_below_the_limit(depth: u32) -> Self {
        if depth < MAX_SPLITS { Refine::ByQuarters } else { Refine::Settled }
    }
}

impl PartialEq for Cell {
    fn eq(&self, other: &Self) -> bool {
        self.error.total_cmp(&other.error).is_eq()
    }
}

impl Eq for Cell {}

impl PartialOrd for Cell {
    fn partial_cmp(&self, other: &Self) -> Option<std::cmp::Ordering> {
        Some(self.cmp(other))
    }
}

impl Ord for Cell {
    /// By estimated error, so that the heap yields the worst cell.
    fn cmp(&self, other: &Self) -> std::cmp::Ordering {
        self.error.total_cmp(&other.error)
    }
}

/// A piece of a pair's outer element and what can come between it and the other element.
struct Shaft {
    piece: Vec<DVec3>,
    /// The pair's occluder pieces in its shaft.
    blocking: Vec<usize>,
    /// The same as they cast shadows.
    casting: Vec<Caster>,
    /// The opening that a plate of them leaves, if any, and the other pieces as they cast.
    opening: Option<(Opening, Vec<Caster>)>,
}

/// One piece of a pair's outer element: where its integrand stops being analytic, and how it
/// sees the other element.
struct Part<'a> {
    /// The other element's corners and box.
    target: [DVec3; 3],
    target_box: (DVec3, DVec3),
    /// The other element's area.
    target_area: f64,
    /// Whether part of the other element lies behind this one's plane.
    clipped: bool,
    /// Planes (unit normal, a point, the sine of their angle with T_i's plane) whose lines in
    /// T_i's plane may carry poles of the integrand.
    poles: Vec<(DVec3, DVec3, f64)>,
    /// Where its occluders make the integrand not analytic ([`Context::obstacles`]), with
    /// their boxes.
    obstacles: Vec<(Obstacle<'a>, (DVec3, DVec3))>,
    /// How its points see the other element.
    sight: Sight<'a>,
}

/// Where an occluder makes a piece's integrand not analytic: the whole occluder polygon, or a
/// point where an occluder's edge meets T_i's plane.
#[derive(Clone, Copy)]
enum Obstacle<'a> {
    Polygon(&'a [DVec3]),
    Point(DVec3),
}

impl Obstacle<'_> {
    fn corners(&self) -> &[DVec3] {
        match self {
            Obstacle::Polygon(polygon) => polygon,
            Obstacle::Point(point) => std::slice::from_ref(point),
        }
    }
}

impl Part<'_> {
    /// Whether T_j leaves a corner of the triangle `t` that it touches at a small angle
    /// ([`NARROW`]) to one of `t`'s sides without running along it: the integrand then varies
    /// on the scale of the gap between them, from the contact outwards, where the touching
    /// triangle's tanh-sinh rule, collapsed at the contact, expects it to be analytic. A 1 m x
    /// 25 m ground sliver whose corner touches a wall's foot 2.3 degrees off its long side had
    /// its rule's levels agree to 7e-7 while missing F_ij by 2.2e-3; the wall, integrated
    /// over, 2.5e-7 and 1.3e-6 where the sliver was 3.6 degrees off. Its quarters, which meet
    /// the gap at other scales, then check it.
    fn narrow_contact(&self, t: &[DVec3; 3]) -> bool {
        let near = TOUCHING * Patch::Triangle(*t).size();
        (0..3).any(|k| {
            let c = t[k];
            if convex_polygons_distance(&[c], &self.target) > near {
                return false;
            }
            let sides = [t[(k + 1) % 3] - c, t[(k + 2) % 3] - c].map(DVec3::normalize);
            self.target.iter().filter(|&&w| w.distance(c) > near).any(|&w| {
                let towards = (w - c).normalize();
                sides.iter().any(|side| {
                    let angle = side.dot(towards).clamp(-1.0, 1.0).acos();
                    angle > ALONG && angle < NARROW
                })
            })
        })
    }

    /// The distance from the convex polygon (or point) `corners` to the nearest of the
    /// piece's [`Obstacle`]s.
    fn obstacle_distance(&self, corners: &[DVec3]) -> f64 {
        self.nearest_obstacle(corners, |_| true)
    }

    /// The distance from the convex polygon `corners` to the nearest of the piece's obstacles
    /// that `counts`. An obstacle whose box is no nearer than the nearest found so far is passed
    /// over (the boxes' distance bounds that of what they hold from below): on city:4x4 at
    /// --tolerance 1e-3 the polygon distances took 0.65 G instructions instead of 1.77 G.
    fn nearest_obstacle(&self, corners: &[DVec3], counts: impl Fn(&Obstacle) -> bool) -> f64 {
        let own_box = bounding_box_3d(corners);
        let mut nearest = f64::INFINITY;
        for (obstacle, obstacle_box) in &self.obstacles {
            if box_distance(own_box, *obstacle_box) < nearest && counts(obstacle) {
                nearest = nearest.min(convex_polygons_distance(corners, obstacle.corners()));
            }
        }
        nearest
    }

    /// Whether a line that may carry poles (where a shadow's corner runs off to infinity) runs
    /// along a side of the triangle `t` (longest side `size`): the integrand is not analytic up
    /// to that side.
    fn pole_along_a_side(&self, t: &[DVec3; 3], size: f64) -> bool {
        self.poles.iter().any(|&(m, point, sin)| {
            let margin = TOUCHING * size * sin;
            t.iter().filter(|&&v| m.dot(v - point).abs() <= margin).count() >= 2
        })
    }

    /// The distance from the convex polygon `corners` to the nearest of the piece's
    /// [`Obstacle`]s that are further than `near` from the point `point`.
    fn obstacle_distance_past(&self, corners: &[DVec3], point: DVec3, near: f64) -> f64 {
        self.nearest_obstacle(corners, |o| convex_polygons_distance(&[point], o.corners()) > near)
    }

    /// The most that `∫ g dA` over `patch` can be: its area times the integrand's bound from
    /// its box's distance to T_j's ([`integrand_bound`]), which is no further than T_j.
    fn most(&self, patch: &Patch) -> f64 {
        let apart = box_distance(bounding_box_3d(patch.corners()), self.target_box);
        integrand_bound(apart, self.target_area) * patch.area()
    }

    /// Lower bounds of the distance from the outer patch with corners `corners` (longest side
    /// `size`) to T_j, and to the points where the integrand is not analytic besides the
    /// obstacles ([`Part::distance`]). Boxes apart bound the distance from below, as the Gauss
    /// order needs; where they overlap, the polygons' own distance tells touching from near.
    fn reach(&self, corners: &[DVec3], size: f64) -> (f64, f64) {
        let to_target = match box_distance(bounding_box_3d(corners), self.target_box) {
            0.0 => convex_polygons_distance(corners, &self.target),
            d => d,
        };
        (to_target, self.distance(corners, size, to_target))
    }

    /// A lower bound of the distance from the outer patch with corners `t` (longest side
    /// `size`) to the points where the integrand is not analytic, given its distance
    /// `to_target` from T_j itself (not from T_j's box: tilted elements' boxes overlap far
    /// apart, a louvre's slat and a wall, which made their patches touching).
    fn distance(&self, t: &[DVec3], size: f64, to_target: f64) -> f64 {
        self.poles
            .iter()
            .filter_map(|&(m, point, sin)| {
                // A line through a corner of the patch, up to rounding, passes through the
                // corner of the piece where event lines meet (in an axis-aligned scene they
                // often meet there): it crosses the piece, not its side.
                let margin = TOUCHING * size * sin;
                let h: SmallVec<[f64; 4]> = t.iter().map(|&v| m.dot(v - point)).collect();
                let one_side = h.iter().all(|&x| x > margin) || h.iter().all(|&x| x < -margin);
                one_side.then(|| h.iter().fold(f64::INFINITY, |d, x| d.min(x.abs())) / sin)
            })
            .fold(to_target, f64::min)
    }
}

/// Lowest order of the collapsed Gauss rule on a triangle at the point where an occluder's edge
/// meets T_i ([`Context::at_obstacle_corner`]): as many as the tolerance has digits, and at
/// least 3. The order from the patch's distance to the poles does not see the event planes
/// through that point outside the triangle: on city:4x4 at --tolerance 1e-6, from
/// order 2 a ground triangle at a building's corner had orders 3 and 4 agree while missing by
/// 1.6e-6, from 6 every entry was within 6.4e-7 of a run at 1e-12; at the default 1e-10, from 6
/// an entry of the louvre room was 2.2e-9 off, from 10 none more than with tanh-sinh there.
/// Such misses are far below a looser tolerance, which takes fewer orders: at least 6 at every
/// tolerance took city:4x4 at 1e-3 to 1.21 M evaluations, half of them at such corners.
fn corner_order(tolerance: f64) -> usize {
    ((-tolerance.log10()).ceil() as usize).clamp(3, GAUSS_MAX - 1)
}

/// Order of the Gauss rule whose points probe a touching triangle for events that were not
/// cut along (9 points).
const PROBE_ORDER: usize = 3;

/// How many times T_j's size a touching triangle must be for its quarters to check it: the
/// integrand changes its scale at T_j's size from the contact, inside such a triangle, where
/// the rule collapsed at the contact has few points. A wall triangle of city:4x4 touching a
/// ground triangle a quarter its size at one corner (integrated over the wall with
/// `--each-direction`) had its levels' estimate meet --tolerance 1e-8 while 1.5e-7 off. The
/// smaller element of a pair is integrated over unless both directions are asked for, so this
/// costs only those.
const OUTSIZED: f64 = 2.0;

/// The angle (radians) under which T_j leaves a corner of a touching triangle too close to one
/// of its sides for the tanh-sinh rule alone ([`Part::narrow_contact`]): 20 degrees.
const NARROW: f64 = 0.35;

/// The angle (radians) under which T_j runs along a side of a touching triangle, a contact
/// along a line that the rule's collapsed coordinates take as they are.
const ALONG: f64 = 1e-7;

/// Distance, relative to an outer patch's size, under which it touches what makes the
/// integrand non-analytic (tanh-sinh then takes it whole).
const TOUCHING: f64 = 1e-9;

/// The parameter of the Bernstein ellipse (foci -1 and 1) through the point `z` of the complex
/// plane: the sum of its semi-axes, a + sqrt(a² - 1) with a the half sum of the distances
/// from the foci.
fn bernstein_rho(z: DVec2) -> f64 {
    let a = 0.5 * ((z - DVec2::X).length() + (z + DVec2::X).length());
    a + (a * a - 1.0).max(0.0).sqrt()
}

/// Distance between two boxes (0 when they overlap or touch).
fn box_distance((alo, ahi): (DVec3, DVec3), (blo, bhi): (DVec3, DVec3)) -> f64 {
    (blo - ahi).max(alo - bhi).max(DVec3::ZERO).length()
}

/// An upper bound of the point-to-element factor `(1/π) ∫ cos cos / r² dA` over T_j (area
/// `area_j`) from the points of a patch at distance `d` from it: 1, or A_j / (π d²).
pub(super) fn integrand_bound(d: f64, area_j: f64) -> f64 {
    if d > 0.0 { (area_j / (PI * d * d)).min(1.0) } else { 1.0 }
}
