//! Triangles of T_i that touch T_j or an obstacle: split between two obstacles' corners,
//! integrated by the Gauss rule collapsed at the one point they touch where that converges
//! ([`Context::at_target_corner`], [`Context::at_obstacle_corner`]), by tanh-sinh otherwise
//! ([`Context::touching_triangle`]).

use glam::{DVec2, DVec3};
use smallvec::SmallVec;

use super::context::Context;
use super::outer::{Check, Outer};
use super::outer_rules::{GAUSS_MAX, OuterRules};
use super::part::{Part, TOUCHING};
use super::patch::Patch;
use super::row::Tally;
use super::sight::{Shapes, Sight};
use crate::geometry::convex_polygons_distance;

impl Context<'_> {
    /// Whether the triangle `t` touches T_j, an obstacle or a pole line beside it, as
    /// [`Context::cell`] measures a patch's distance from them.
    pub(super) fn touches(&self, t: &[DVec3; 3], part: &Part) -> bool {
        let size = Patch::Triangle(*t).size();
        part.reach(t, size).1.min(part.obstacle_distance(t)) <= TOUCHING * size
    }

    /// The halves of the triangle `t` split at the middle of a side whose ends are both where
    /// occluders' edges meet T_i, if there is one.
    pub(super) fn between_obstacles(&self, t: [DVec3; 3], part: &Part) -> Option<[[DVec3; 3]; 2]> {
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
    /// converges as on a patch apart, as at an obstacle's corner, where the tanh-sinh rule,
    /// collapsed at the contact, would spend thousands of points on a direction that is no
    /// singularity.
    pub(super) fn at_target_corner(
        &self,
        t: [DVec3; 3],
        part: &Part,
        rules: &OuterRules,
        target: f64,
    ) -> Option<([DVec3; 3], usize)> {
        let size = Patch::Triangle(t).size();
        let near = TOUCHING * size;
        let [k] = part.corners_on_target(&t)[..] else { return None };
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
    pub(super) fn at_obstacle_corner(
        &self,
        t: [DVec3; 3],
        part: &Part,
    ) -> Option<([DVec3; 3], f64)> {
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

    /// `∫_t g dA` and its estimated error over a triangle `t` that touches an obstacle, by the
    /// tanh-sinh rule. The rule collapses the triangle at its last corner, where a point
    /// singularity (an integrand whose limit depends on the direction, as at a corner of T_j on
    /// T_i, or where an occluder's edge meets T_i) costs nothing: the corner nearest a corner
    /// of T_j or such a point is put there. Where it touches T_j and T_j reaches behind its
    /// plane, or where the views from a few points differ in shape, its quarters check the rule
    /// (`check`, [`Outer::integrate`]).
    #[allow(clippy::too_many_arguments)]
    pub(super) fn touching_triangle(
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

/// Lowest order of the collapsed Gauss rule on a triangle at the point where an occluder's edge
/// meets T_i ([`Context::at_obstacle_corner`]): as many as the tolerance has digits, and at
/// least 3. The order from the patch's distance to the poles does not see the event planes
/// through that point outside the triangle: on city:4x4 at --tolerance 1e-6, from
/// order 2 a ground triangle at a building's corner had orders 3 and 4 agree while missing by
/// 1.6e-6, from 6 every entry was within 6.4e-7 of a run at 1e-12; at the default 1e-10, from 6
/// an entry of the louvre room was 2.2e-9 off, from 10 none more than with tanh-sinh there.
/// Such misses are far below a looser tolerance, which takes fewer orders: a fixed floor of 6
/// would spend most of a loose run at such corners.
pub(super) fn corner_order(tolerance: f64) -> usize {
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
pub(super) const OUTSIZED: f64 = 2.0;

/// The parameter of the Bernstein ellipse (foci -1 and 1) through the point `z` of the complex
/// plane: the sum of its semi-axes, a + sqrt(a² - 1) with a the half sum of the distances
/// from the foci.
fn bernstein_rho(z: DVec2) -> f64 {
    let a = 0.5 * ((z - DVec2::X).length() + (z + DVec2::X).length());
    a + (a * a - 1.0).max(0.0).sqrt()
}
