//! The pair integrator: [`PairIntegrator`] evaluates the collocation integrals `∫ G φ_l` of one
//! (node, element) pair over the element's visible part, by the closed forms, the far-field
//! bands, the graded rule or the subdivision of thin elements, and hands what the centroid
//! method's closed form can evaluate in lanes to a [`lanes::Batch`]. The CPU assembly, the thin
//! columns, the listed pairs and the view factors all integrate through it.

use glam::DVec2;

use crate::discretization::{Method, Placed};
use crate::kernels::far_field::FarFieldRule;
use crate::kernels::graded::GradedRule;
use crate::kernels::{Affine2, Observer, exact, lanes};
use crate::quadrature::ImtRule;
use crate::visibility::Visibility;

use super::options::AssemblyOptions;

/// Evaluates the collocation integrals of one (node, element) pair.
pub struct PairIntegrator {
    method: Method,
    imt: ImtRule,
    far_field: Option<FarFieldRule>,
    graded: Option<GradedRule>,
    /// For thin elements ([`far_field::is_thin`]) under the exact method, unless the closed forms
    /// are asked for everywhere (`far_field` off).
    subdivision: Option<FarFieldRule>,
    /// Whether fully visible elements may be evaluated in lanes ([`PairIntegrator::full_pair`]).
    lanes: bool,
}

/// How a node's integrals over an element are evaluated ([`PairIntegrator::lane_observer`]).
pub(crate) enum LaneObserver {
    /// Not at all: the node is not above the element's plane, and they vanish.
    Unseen,
    /// By [`PairIntegrator::integrate`] (another rule than the closed form).
    Scalar,
    /// The centroid method's closed form in lanes, for this observer.
    Lane(Observer),
}

/// A fully visible element's integrals, or what to evaluate with others in lanes.
pub(crate) enum FullPair {
    /// Already evaluated (another rule than the closed form, or nothing to see).
    Values([f64; 3]),
    /// The centroid method's closed form for this observer and triangle (element units).
    Lane(Observer, [DVec2; 3]),
}

impl PairIntegrator {
    /// An integrator for `method`.
    pub fn new(method: Method, options: &AssemblyOptions) -> Self {
        let graded = options.quadrature.graded_rule();
        let far_field = (graded.is_none() && options.far_field)
            .then(|| FarFieldRule::for_weights(method.nodes_per_element()));
        Self {
            method,
            imt: ImtRule::new(options.imt_nodes.max(2)),
            far_field,
            graded,
            subdivision: options.far_field.then(FarFieldRule::standard),
            lanes: options.lanes
                && method == Method::Centroid
                && options.quadrature.graded_rule().is_none(),
        }
    }

    /// As [`PairIntegrator::new`], for values kept in single precision: the centroid method's
    /// closed form at every distance, in lanes. Its far band
    /// ([`crate::kernels::far_field::CONSTANT_WEIGHT_BANDS`]) keeps the last digits of f64
    /// beyond 100 radii, where the closed form loses about 1e-12 of its value (at 2e4 radii),
    /// which an f32 value does not hold, and its 25-point rule is evaluated pair by pair, not
    /// in lanes, so the closed form in lanes is both accurate enough and faster there. The
    /// linear method keeps its bands, which are also its fast path.
    pub fn for_single_precision(method: Method, options: &AssemblyOptions) -> Self {
        let mut integrator = Self::new(method, options);
        if method == Method::Centroid {
            integrator.far_field = None;
        }
        integrator
    }

    /// As [`PairIntegrator::integrate`] for a fully visible element, except that where the
    /// centroid method's closed form applies, the observer and triangle are handed back to be
    /// evaluated in lanes ([`crate::kernels::lanes`]).
    #[inline(always)]
    pub(crate) fn full_pair(
        &self,
        el: &Placed,
        basis: &[Affine2; 3],
        p: glam::DVec3,
        normal: glam::DVec3,
    ) -> FullPair {
        match self.lane_observer(el, p, normal) {
            LaneObserver::Unseen => FullPair::Values([0.0; 3]),
            LaneObserver::Scalar => {
                FullPair::Values(self.integrate(el, basis, p, normal, &Visibility::Full))
            }
            LaneObserver::Lane(obs) => FullPair::Lane(obs, el.scaled()),
        }
    }

    /// The integrals over element `el` seen as `visibility` from a node at `p` (unit normal
    /// `normal`): returned where they are evaluated at once, or handed to `batch` with `tag`
    /// where the centroid method's closed form applies, the element whole or each visible
    /// piece as the fan of triangles from its first corner, whose values `sink` must add up.
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    pub(crate) fn integrate_or_batch<T: Copy>(
        &self,
        el: &Placed,
        basis: &[Affine2; 3],
        p: glam::DVec3,
        normal: glam::DVec3,
        visibility: &Visibility,
        (tag, batch): (T, &mut lanes::Batch<T>),
        mut sink: impl FnMut(T, f64),
    ) -> Option<[f64; 3]> {
        let pieces = match visibility {
            Visibility::Skip(_) => return Some([0.0; 3]),
            Visibility::Full => match self.full_pair(el, basis, p, normal) {
                FullPair::Values(values) => return Some(values),
                FullPair::Lane(obs, tri) => {
                    batch.push(tag, obs, tri, sink);
                    return None;
                }
            },
            Visibility::Partial(pieces) => pieces,
        };
        match self.lane_observer(el, p, normal) {
            LaneObserver::Unseen => Some([0.0; 3]),
            LaneObserver::Scalar => Some(self.integrate(el, basis, p, normal, visibility)),
            LaneObserver::Lane(obs) => {
                for piece in pieces {
                    push_fan(el, obs, piece, (tag, batch), &mut sink);
                }
                None
            }
        }
    }

    /// Whether the centroid method's closed form over (any part of) element `el`, seen from a
    /// node at `p` with unit normal `normal`, may be evaluated in lanes, and the observer to
    /// give them with triangles in the element's units ([`Placed::to_scaled`]).
    #[inline(always)]
    pub(crate) fn lane_observer(
        &self,
        el: &Placed,
        p: glam::DVec3,
        normal: glam::DVec3,
    ) -> LaneObserver {
        if !self.lanes {
            return LaneObserver::Scalar;
        }
        let Some(obs) = self.observer(el, p, normal) else {
            return LaneObserver::Unseen;
        };
        let thin = self.subdivision.is_some() && el.thin;
        let banded =
            self.far_field.as_ref().is_some_and(|rule| rule.band(&obs, el.scaled_radius).is_some());
        if thin || banded { LaneObserver::Scalar } else { LaneObserver::Lane(obs) }
    }

    /// The node seen from the element's frame in the element's units
    /// ([`crate::discretization::Placed::unit`]), or `None` when the node is not above the
    /// element's plane.
    #[inline(always)]
    fn observer(&self, el: &Placed, p: glam::DVec3, normal: glam::DVec3) -> Option<Observer> {
        let obs = Observer {
            position: el.frame.to_local(p) * el.unit,
            normal: el.frame.dir_to_local(normal),
        };
        // The pair plan decided the node is above the face's plane in the face's frame; in the
        // element's frame (origin at its centroid) the height carries another rounding, and a
        // face that is planar only to within its tolerance (1e-9 of its size) can put the node
        // on the other side. Such a node is in the plane as far as the data can tell: G = 0.
        if obs.position.z.is_nan() || obs.position.z <= 0.0 {
            return None;
        }
        Some(obs)
    }

    /// `∫ G φ_l` over the visible part of element `el` for each of its basis functions, seen from a
    /// node at `p` with unit normal `normal`. Entries past the method's basis count are zero.
    pub fn integrate(
        &self,
        el: &Placed,
        basis: &[Affine2; 3],
        p: glam::DVec3,
        normal: glam::DVec3,
        visibility: &Visibility,
    ) -> [f64; 3] {
        if let Visibility::Skip(_) = visibility {
            return [0.0; 3];
        }
        let Some(obs) = self.observer(el, p, normal) else {
            return [0.0; 3];
        };
        let unit = el.unit;
        let basis = basis.map(|b| Affine2 { c0: b.c0, cx: b.cx / unit, cy: b.cy / unit });
        match visibility {
            Visibility::Partial(pieces) => {
                let shifted: Vec<Vec<DVec2>> = pieces
                    .iter()
                    .map(|piece| piece.iter().map(|&q| el.to_scaled(q)).collect())
                    .collect();
                let loops: Vec<&[DVec2]> = shifted.iter().map(Vec::as_slice).collect();
                self.integrate_loops(&obs, el, &loops, &basis)
            }
            _ => self.integrate_loops(&obs, el, &[&el.scaled()[..]], &basis),
        }
    }

    /// `∫ G φ_l` over `loops`: the visible convex pieces of element `el`, counter-clockwise, in
    /// its local coordinates and units ([`crate::discretization::Placed::scaled`]).
    fn integrate_loops(
        &self,
        obs: &Observer,
        el: &Placed,
        loops: &[&[DVec2]],
        basis: &[Affine2; 3],
    ) -> [f64; 3] {
        if let Some(rule) = &self.graded {
            return rule.integrate(obs, &el.scaled(), loops, basis);
        }
        if let Some(rule) = self.subdivision.as_ref().filter(|_| el.thin) {
            let near = |piece: &[DVec2; 3]| self.closed_forms(obs, &[&piece[..]], basis);
            return integrate_fan(loops, |tri| rule.integrate_subdivided(obs, tri, basis, near));
        }
        if let Some(band) =
            self.far_field.as_ref().and_then(|rule| rule.band(obs, el.scaled_radius))
        {
            return integrate_fan(loops, |tri| obs.integrate_by_rule(&band.rule, tri, basis));
        }
        self.closed_forms(obs, loops, basis)
    }

    /// The exact method's closed forms (and IMT quadrature) over `loops`.
    fn closed_forms(&self, obs: &Observer, loops: &[&[DVec2]], basis: &[Affine2; 3]) -> [f64; 3] {
        let loops = loops.iter().copied();
        match self.method {
            Method::Centroid => [exact::constant_weight(obs, loops), 0.0, 0.0],
            Method::Linear { .. } => exact::affine_weights(obs, loops, basis, &self.imt),
        }
    }
}

/// The sum of `part` over the fan triangles of every loop.
fn integrate_fan(loops: &[&[DVec2]], part: impl Fn(&[DVec2; 3]) -> [f64; 3]) -> [f64; 3] {
    let mut sum = [0.0; 3];
    for piece in loops {
        for k in 1..piece.len() - 1 {
            let values = part(&[piece[0], piece[k], piece[k + 1]]);
            sum.iter_mut().zip(values).for_each(|(s, v)| *s += v);
        }
    }
    sum
}

/// Hands the convex `piece` of element `el` (face coordinates, counter-clockwise) to `batch`
/// for the observer `obs`, as the fan of triangles from its first corner in the element's units,
/// each with `tag`: the values `sink` receives add up to the piece's closed form.
pub(crate) fn push_fan<T: Copy>(
    el: &Placed,
    obs: Observer,
    piece: &[DVec2],
    (tag, batch): (T, &mut lanes::Batch<T>),
    mut sink: impl FnMut(T, f64),
) {
    let first = el.to_scaled(piece[0]);
    for m in 1..piece.len().saturating_sub(1) {
        let tri = [first, el.to_scaled(piece[m]), el.to_scaled(piece[m + 1])];
        batch.push(tag, obs, tri, &mut sink);
    }
}
