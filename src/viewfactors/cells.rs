//! The cells of a pair's outer integral: a patch's `∫ g dA` and its estimated error
//! ([`Context::cell`]: Gauss orders, a bound for small patches, tanh-sinh on touching
//! triangles), and the cells kept open for refinement, worst first ([`Cells`]).

use std::collections::BinaryHeap;

use super::context::Context;
use super::events::centroid;
use super::options::MAX_SPLITS;
use super::outer::Check;
use super::outer_rules::{GAUSS_MAX, OuterRules, certified_target};
use super::part::{Part, TOUCHING, integrand_bound};
use super::patch::Patch;
use super::row::Tally;
use super::sight::{Shapes, Sight};
use super::touching::{OUTSIZED, corner_order};

impl Context<'_> {
    /// `∫ g dA` over the patch `patch` of the piece with `part`, and its estimated error:
    /// tanh-sinh on its triangles where it touches an obstacle (d log d behaviour at a common
    /// edge; its error [`kept_error`](super::outer::kept_error) of its last levels, to be split
    /// further if the pair needs it); where T_j is seen whole, Gauss of the order that the
    /// patch's separation asks for (settled, as the bound is trusted, with the bound's target as
    /// its error); otherwise that order and
    /// one more, the higher one's value with their difference as the error, and where a curved
    /// event of three skew edges crosses the patch (which the separation does not see) the
    /// rule over its quarters ([`Context::two_orders`]), to be split further if the pair needs
    /// it.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn cell(
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
        // too would cost a quarters rule per triangle and catch no miss the probe lets through.
        let checked = part.clipped && distance <= TOUCHING * size;
        let distance = distance.min(part.obstacle_distance(patch.corners()));
        // Where occluders shadow T_j the order is only a first guess, since the estimate with
        // one order more decides: it aims at the tolerance itself. Aiming lower costs higher
        // first orders, aiming higher costs more splits (on the occluded box either was
        // slower, for the same reciprocity).
        // The Bernstein bound is relative to the integrand's size, which from a patch at
        // distance d from T_j is at most A_j / (π d²) (cosines at most 1): the tolerance on
        // F_ij asks for that much less relative accuracy of a patch far from a small T_j.
        // Not capped: a first order is checked against one order more, so relaxing it does not
        // make patches fail and split; it only saves evaluations.
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
                    // A narrow contact varies on the scale of its gap in the collapsed rule's
                    // direction too: the Bernstein bound and two orders agreed while missing
                    // (a wall touching a generated sliver at a corner, 5.4 degrees off its
                    // foot: 1.5e-8 off under an estimate of 5.7e-9 at --tolerance 1e-6).
                    None if part.narrow_contact(&t) => None,
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
                        } else if checked || part.contact_along_a_side(&t) {
                            // Along a shared side the levels agreed while missing too: two
                            // triangles of adjacent faces of the cube met 1e-6 by their levels
                            // and were 7.3e-7 off under an estimate of 3.9e-7.
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
                    // Trusted, not measured: the bound's own error counts in the estimate,
                    // which would otherwise promise nothing but rounding for a pair seen whole
                    // (two triangles 1e-5 of their size apart: 1.3e-11 off under an estimate
                    // of 9e-20 at --tolerance 1e-4).
                    cell.error = target * integrand_bound(to_target, part.target_area) * area;
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
    /// difference from order q. Where the points see T_j in more than one shape, or points just
    /// inside its rim see another shape than theirs, by that rule over its quarters instead,
    /// whose difference from the whole counts too; where no order meets the a priori bound
    /// (`order` `None`: q is then the highest but one), checked by the rule over its quarters
    /// at half the order.
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
        // Across an event that was not cut along (the curved event where three mutually skew
        // edges line up), the points see T_j in more than one shape, the rules' errors scatter
        // with the order instead of falling, and two or three orders can agree by chance: on
        // a patch of city:4x4 (pair (129, 226), --tolerance 1e-8) orders 3, 4 and 5 differed
        // by 6.9e-9 and 8.1e-9 of F while order 4 was 9.3e-9 off. The rule over the patch's
        // quarters at order q + 1 samples the kink where it is four times smaller (0.9e-9 off
        // there) and takes the value; its difference from the whole (1.0e-8) counts in the
        // estimate with that of the two orders. Neither alone held on the generated cities.
        let shapes = low_shapes.and(high_shapes);
        let (band, probes) = self.band_at_the_rim((i, j), patch, part, shapes, high);
        let kinked = matches!(shapes, Shapes::Many) || band > 0.0;
        let value = if kinked {
            let quarters: f64 = patch.quarters().iter().map(|c| estimate_on(c, q + 1).0).sum();
            error = error.max((high - quarters).abs()).max(band);
            quarters
        } else {
            high
        };
        // Where no order meets the a priori bound (a patch too near a point where the
        // integrand is not analytic: a chair's backrest whose corner stands 0.014 from the
        // seat, furnished room at --tolerance 1e-6, had orders 15 and 16 differ by 7.1e-7 and
        // miss by 1.2e-6), the quarters, which meet the singularity elsewhere, check it.
        if order.is_none() && !kinked {
            let half = (q + 2) / 2;
            let quarters: f64 = patch.quarters().iter().map(|c| estimate_on(c, half).0).sum();
            error = error.max((high - quarters).abs());
        }
        tally.evaluations += probes;
        (value, error)
    }

    /// Where the Gauss points of `patch` all see T_j in one shape (`shapes`), whether a band of
    /// another shape lies along its rim, between its outermost points and its sides, and what
    /// it may hold: the views at points just inside its corners and the middles of its sides
    /// ([`RIM_INSET`]). A curved event can leave such a band that no point of any order sees
    /// (tessellated city 3 x 3, pair (1141, 1494) at --tolerance 1e-8: every point of a patch
    /// saw nothing, a band along one side saw slivers of T_j, and F_ij was 2.4e-8 off under an
    /// estimate of 1e-19). Where a probe sees another shape, the band may hold up to
    /// [`BAND_SHARE`] of the patch's area with the integrand as far from the patch's mean as
    /// at that probe; returns that bound (0 where every probe sees the points' shape) and the
    /// probes taken.
    fn band_at_the_rim(
        &self,
        (i, j): (usize, usize),
        patch: &Patch,
        part: &Part,
        shapes: Shapes,
        integral: f64,
    ) -> (f64, u64) {
        if !matches!(part.sight, Sight::PerPoint(_)) || !matches!(shapes, Shapes::One(_)) {
            return (0.0, 0);
        }
        let corners = patch.corners();
        let (centre, m, area) = (centroid(corners), corners.len(), patch.area());
        let rim = (0..m).flat_map(|k| [corners[k], 0.5 * (corners[k] + corners[(k + 1) % m])]);
        let mut band = 0.0f64;
        for at in rim {
            let probe = [(at + RIM_INSET * (centre - at), area)];
            let (g, shape) = self.weighted_sum(i, j, part.sight, &probe);
            if matches!(shapes.and(shape), Shapes::Many) {
                band = band.max(BAND_SHARE * (g - integral).abs());
            }
        }
        (band, 2 * m as u64)
    }

    /// `∫ g dA` over a patch that can hold at most `most` of it (`0 <= g <= most / area`), by
    /// its value at the centre: the integral lies between 0 and `most`, so the one-point rule
    /// is off by at most the larger of its value and `most` less it. A bound, not an estimate;
    /// where the pair's budget needs it, the rules take the patch after all ([`Refine::ByRules`]).
    /// Settled for good, such cells leave the others at least half the pair's budget, so the
    /// rules on patches that hold F_ij need not tighten for cells that hold little of it.
    pub(super) fn bounded_cell(
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
}

/// How far inside a patch, as a share of the way from its rim to its centre, the probes of
/// [`Context::band_at_the_rim`] stand.
const RIM_INSET: f64 = 0.02;

/// The share of a patch that a band along its rim, unseen by its Gauss points, is taken to
/// hold: about the share outside its outermost points at the low orders that shadowed
/// patches take (order 3: 11 % of each side's width; order 5: 5 %). On the two cities that
/// `radiosity study estimates` checks, the full area kept the pairs at 1e-8 at the split limit
/// (estimates 6.2e-8 and 4.5e-8, errors at most 7.3e-9); a tenth of it met the tolerance with
/// errors at most 0.22 of the estimates.
const BAND_SHARE: f64 = 0.1;

/// The cells of a pair's outer integral: those that may still be split, worst first, and the
/// sum of those that are settled.
#[derive(Default)]
pub(super) struct Cells {
    pub(super) open: BinaryHeap<Cell>,
    /// Sum of the open cells' estimated errors.
    pub(super) open_error: f64,
    pub(super) settled: f64,
    pub(super) settled_error: f64,
}

impl Cells {
    pub(super) fn place(&mut self, cell: Cell) {
        if cell.refine != Refine::Settled {
            self.open_error += cell.error;
            self.open.push(cell);
        } else {
            self.settled += cell.value;
            self.settled_error += cell.error;
        }
    }

    /// `∫ g dA` over all cells and its estimated error.
    pub(super) fn total(&self) -> (f64, f64) {
        let open: f64 = self.open.iter().map(|c| c.value).sum();
        let open_error: f64 = self.open.iter().map(|c| c.error).sum();
        (self.settled + open, self.settled_error + open_error)
    }
}

/// A patch of a pair's outer integral, with its estimate.
pub(super) struct Cell {
    pub(super) patch: Patch,
    /// Index of its piece's [`Part`].
    pub(super) part: usize,
    /// Rounds of splitting that made it.
    pub(super) depth: u32,
    /// `∫ g dA` over it.
    pub(super) value: f64,
    /// Estimated |error| of `value`.
    pub(super) error: f64,
    /// How it may be refined, if at all.
    pub(super) refine: Refine,
}

/// How a [`Cell`] may be refined.
#[derive(Clone, Copy, PartialEq, Eq)]
pub(super) enum Refine {
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
