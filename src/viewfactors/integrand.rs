//! The outer integrand: the point-to-element factor `(1/π) ∫ G V` over T_j from points of T_i,
//! by the closed forms of the whole element or of its visible pieces, eight points at a time
//! in vector lanes.

use std::f64::consts::PI;

use glam::{DVec2, DVec3};

use super::context::Context;
use super::sight::{PointView, Shapes, Sight};
use crate::assembly::{FullPair, LaneObserver, push_fan};
use crate::kernels::lanes;
use crate::visibility::Visibility;

impl Context<'_> {
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
    pub(super) fn values(
        &self,
        i: usize,
        j: usize,
        sight: Sight<'_>,
        points: &[DVec3],
        values: &mut [f64],
    ) {
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
        let (el, basis) = (&self.disc.placed(j), self.disc.basis(j));
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
    pub(super) fn shapes_at(
        &self,
        i: usize,
        j: usize,
        sight: Sight<'_>,
        points: &[(DVec3, f64)],
    ) -> Shapes {
        let Sight::PerPoint(among) = sight else { return Shapes::One(PointView::Whole.shape()) };
        points
            .iter()
            .fold(Shapes::None, |shapes, &(p, _)| shapes.with(&self.point_view(i, j, p, among)))
    }

    /// `(1/π) ∫ G V` over element `j` seen from the point `p` of element `i`, by the scalar
    /// closed forms: the reference that the tests hold the lanes of [`Context::values`] to.
    #[cfg(test)]
    pub(super) fn point_to_element(&self, i: usize, j: usize, p: DVec3, sight: Sight<'_>) -> f64 {
        let (el, basis) = (&self.disc.placed(j), self.disc.basis(j));
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
        let (el, basis) = (&self.disc.placed(j), self.disc.basis(j));
        let integral = |pieces| self.integrator.integrate(el, basis, p, normal, &pieces)[0];
        let taken = if taken.is_empty() { 0.0 } else { integral(Visibility::Partial(taken)) };
        integral(Visibility::Partial(added)) - taken
    }
}
