//! One piece of a pair's outer element ([`Part`]): what makes its integrand not analytic there
//! (T_j, pole lines, obstacles: [`Context::obstacles`]) and the distances and bounds that choose
//! its rules.

use std::f64::consts::PI;

use glam::DVec3;
use smallvec::SmallVec;

use super::context::Context;
use super::patch::Patch;
use super::sight::Sight;
use crate::geometry::{bounding_box_3d, convex_polygons_distance};

impl Context<'_> {
    /// Where the occluders `blocking` make the integrand over a piece of element `i` not
    /// analytic: an occluder apart from T_i's plane, where the viewing point would reach it
    /// (its shadow runs off to infinity); for one that meets T_i's plane, the points where its
    /// edges meet that plane (a building's corners on the ground, a jamb's edge through a
    /// louvre's slat), where the shadow's limit depends on the direction the point comes from.
    /// Along the rest of the contact (a wall's foot) it hides a half-space, whatever the
    /// direction. A slat touching the jamb at its patch's corner took Gauss orders 5 and 6 that
    /// agreed to 1.7e-8 and missed the integral by 1.3e-6; a ground patch at a building's
    /// corner, 2e-6. Each with its box.
    pub(super) fn obstacles(
        &self,
        i: usize,
        blocking: &[usize],
    ) -> Vec<(Obstacle<'_>, (DVec3, DVec3))> {
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
}

/// One piece of a pair's outer element: where its integrand stops being analytic, and how it
/// sees the other element.
pub(super) struct Part<'a> {
    /// The other element's corners and box.
    pub(super) target: [DVec3; 3],
    pub(super) target_box: (DVec3, DVec3),
    /// The other element's area.
    pub(super) target_area: f64,
    /// Whether part of the other element lies behind this one's plane.
    pub(super) clipped: bool,
    /// Planes (unit normal, a point, the sine of their angle with T_i's plane) whose lines in
    /// T_i's plane may carry poles of the integrand.
    pub(super) poles: Vec<(DVec3, DVec3, f64)>,
    /// Where its occluders make the integrand not analytic ([`Context::obstacles`]), with
    /// their boxes.
    pub(super) obstacles: Vec<(Obstacle<'a>, (DVec3, DVec3))>,
    /// How its points see the other element.
    pub(super) sight: Sight<'a>,
}

/// Where an occluder makes a piece's integrand not analytic: the whole occluder polygon, or a
/// point where an occluder's edge meets T_i's plane.
#[derive(Clone, Copy)]
pub(super) enum Obstacle<'a> {
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
    pub(super) fn narrow_contact(&self, t: &[DVec3; 3]) -> bool {
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

    /// The corners of the triangle `t` that lie on T_j (within [`TOUCHING`] of its size).
    pub(super) fn corners_on_target(&self, t: &[DVec3; 3]) -> SmallVec<[usize; 3]> {
        let near = TOUCHING * Patch::Triangle(*t).size();
        (0..3).filter(|&k| convex_polygons_distance(&[t[k]], &self.target) <= near).collect()
    }

    /// Whether T_j holds two corners of the triangle `t`: they touch along a side.
    pub(super) fn contact_along_a_side(&self, t: &[DVec3; 3]) -> bool {
        self.corners_on_target(t).len() >= 2
    }

    /// The distance from the convex polygon (or point) `corners` to the nearest of the
    /// piece's [`Obstacle`]s.
    pub(super) fn obstacle_distance(&self, corners: &[DVec3]) -> f64 {
        self.nearest_obstacle(corners, |_| true)
    }

    /// The distance from the convex polygon `corners` to the nearest of the piece's obstacles
    /// that `counts`. An obstacle whose box is no nearer than the nearest found so far is passed
    /// over (the boxes' distance bounds that of what they hold from below), so once a near
    /// obstacle is found most others are skipped without a polygon distance.
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
    pub(super) fn pole_along_a_side(&self, t: &[DVec3; 3], size: f64) -> bool {
        self.poles.iter().any(|&(m, point, sin)| {
            let margin = TOUCHING * size * sin;
            t.iter().filter(|&&v| m.dot(v - point).abs() <= margin).count() >= 2
        })
    }

    /// The distance from the convex polygon `corners` to the nearest of the piece's
    /// [`Obstacle`]s that are further than `near` from the point `point`.
    pub(super) fn obstacle_distance_past(&self, corners: &[DVec3], point: DVec3, near: f64) -> f64 {
        self.nearest_obstacle(corners, |o| convex_polygons_distance(&[point], o.corners()) > near)
    }

    /// The most that `∫ g dA` over `patch` can be: its area times the integrand's bound from
    /// its box's distance to T_j's ([`integrand_bound`]), which is no further than T_j.
    pub(super) fn most(&self, patch: &Patch) -> f64 {
        let apart = box_distance(bounding_box_3d(patch.corners()), self.target_box);
        integrand_bound(apart, self.target_area) * patch.area()
    }

    /// Lower bounds of the distance from the outer patch with corners `corners` (longest side
    /// `size`) to T_j, and to the points where the integrand is not analytic besides the
    /// obstacles ([`Part::distance`]). Boxes apart bound the distance from below, as the Gauss
    /// order needs; where they overlap, the polygons' own distance tells touching from near.
    pub(super) fn reach(&self, corners: &[DVec3], size: f64) -> (f64, f64) {
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
    pub(super) fn distance(&self, t: &[DVec3], size: f64, to_target: f64) -> f64 {
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

/// The angle (radians) under which T_j leaves a corner of a touching triangle too close to one
/// of its sides for the tanh-sinh rule alone ([`Part::narrow_contact`]): 20 degrees.
const NARROW: f64 = 0.35;

/// The angle (radians) under which T_j runs along a side of a touching triangle, a contact
/// along a line that the rule's collapsed coordinates take as they are.
const ALONG: f64 = 1e-7;

/// Distance, relative to an outer patch's size, under which it touches what makes the
/// integrand non-analytic (tanh-sinh then takes it whole).
pub(super) const TOUCHING: f64 = 1e-9;

/// Distance between two boxes (0 when they overlap or touch).
pub(super) fn box_distance((alo, ahi): (DVec3, DVec3), (blo, bhi): (DVec3, DVec3)) -> f64 {
    (blo - ahi).max(alo - bhi).max(DVec3::ZERO).length()
}

/// An upper bound of the point-to-element factor `(1/π) ∫ cos cos / r² dA` over T_j (area
/// `area_j`) from the points of a patch at distance `d` from it: 1, or A_j / (π d²).
pub(super) fn integrand_bound(d: f64, area_j: f64) -> f64 {
    if d > 0.0 { (area_j / (PI * d * d)).min(1.0) } else { 1.0 }
}
