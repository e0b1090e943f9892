//! Extreme geometry for the collocation integrals: one (node, element) pair per case, assembled by
//! the production path on each backend (pair plan, frames, tangent-plane clipping, kernels, the
//! far-field rule) and compared with the polar adaptive reference
//! ([`crate::kernels::reference::polar_integral`]).
//!
//! Each case is a two-face scene: the element's face, and a small receiver face through the node
//! with the node's normal, built so that its first node (centroid, or the linear node next to its
//! first vertex) is the node. Scaled cases use powers of two and offset cases subtract exactly
//! (Sterbenz), so the reference sees exactly the geometry the program was given.

use glam::{DVec2, DVec3};
use serde::Serialize;

use crate::assembly::AssemblyOptions;
use crate::discretization::{Discretization, Method};
use crate::error::Result;
use crate::gpu::Precision;
use crate::kernels::reference::{integral, polar_integral};
use crate::kernels::{Affine2, Observer};
use crate::mesh::{Mesh, MeshKind};
use crate::pipeline::{Backend, Problem, assemble_on};
use crate::progress::Silent;
use crate::quadrature::Tolerance;
use crate::scene::{Face, Scene};

/// One (node, element) configuration.
#[derive(Clone, Debug)]
pub struct ExtremeCase {
    /// Short name.
    pub name: String,
    /// Collocation method (which weights: constant, or the three linear basis functions).
    pub method: Method,
    /// The element (counter-clockwise seen from the side it radiates to).
    pub element: [DVec3; 3],
    /// The node.
    pub node: DVec3,
    /// The node's unit normal.
    pub normal: DVec3,
    /// Every coordinate is multiplied by this (a power of two)...
    pub scale: f64,
    /// ... and then shifted by this.
    pub offset: DVec3,
}

/// Where the reference comes from for a case.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum ReferenceKind {
    /// The node is on or behind the element's plane (up to rounding): the entry is 0 and the
    /// program must skip the pair.
    Zero,
    /// Near the element: the polar formulation (accurate at any distance, but its per-edge terms
    /// cancel for elements far away or thin as seen from the node).
    Polar,
    /// At least 5% of the element's diameter away, or a thin element: plain adaptive quadrature
    /// of the positive integrand over the element, which has no cancellation.
    Plain,
}

/// The bound claimed for a case on a backend, relative to the largest reference entry of the row
/// (absolute where the entry is 0): a few hundred ulps of the working precision, times the
/// problem's own condition `geometric_condition` (see there).
pub fn bound(backend: Backend, geometric_condition: f64) -> f64 {
    let unit = match backend {
        Backend::Cpu | Backend::Gpu(Precision::F64) => f64::EPSILON,
        Backend::Gpu(Precision::F32) => f32::EPSILON as f64,
    };
    512.0 * unit * geometric_condition
}

/// How much a rounding of the coordinates by ε (of the element's diameter h) can change the
/// entry, relatively: near an edge or vertex of the element at distance δ (3-D) the entry is a
/// function of the direction in which the node sees that edge, so it moves by about ε h / δ; 1
/// elsewhere.
///
/// The node's tangent plane bounds the integration region too where it cuts the element: its
/// computed trace on the element's plane carries a rounding of ε h, which a node at distance δ_L
/// from it feels as ε h / δ_L.
fn geometric_condition(node: DVec3, normal: DVec3, element: &[DVec3; 3]) -> f64 {
    let h = (0..3).map(|k| (element[k] - element[(k + 1) % 3]).length()).fold(0.0, f64::max);
    let edges = (0..3)
        .map(|k| point_segment_distance(node, element[k], element[(k + 1) % 3]))
        .fold(f64::INFINITY, f64::min);
    let plane_normal = (element[1] - element[0]).cross(element[2] - element[0]).normalize();
    let z = (node - element[0]).dot(plane_normal);
    let straddles = {
        let sides: Vec<f64> = element.iter().map(|&v| (v - node).dot(normal)).collect();
        sides.iter().any(|&s| s > 0.0) && sides.iter().any(|&s| s < 0.0)
    };
    let tilt = (normal - plane_normal * normal.dot(plane_normal)).length();
    let horizon = if straddles && tilt > 0.0 { z.abs() / tilt } else { f64::INFINITY };
    (h / edges.min(horizon)).max(1.0)
}

fn point_segment_distance(p: DVec3, a: DVec3, b: DVec3) -> f64 {
    let d = b - a;
    let t = ((p - a).dot(d) / d.length_squared()).clamp(0.0, 1.0);
    (p - (a + d * t)).length()
}

/// One row of the stability study.
#[derive(Clone, Debug, Serialize)]
pub struct ExtremeRow {
    /// Case name.
    pub case: String,
    /// `centroid` or `linear`.
    pub method: &'static str,
    /// `cpu` or `gpu`.
    pub backend: &'static str,
    /// `f64` or `f32`.
    pub precision: &'static str,
    /// The largest reference entry of the row (K includes rho/π; rho = 1).
    pub reference: f64,
    /// `max_l |K_l − ref_l| / max_l |ref_l|` (absolute when the reference is 0).
    pub relative_error: f64,
    /// The same with the paper's closed forms for every pair (`--no-far-field`): the digits the
    /// far-field and thin-element rules save (CPU rows only).
    pub closed_forms_error: Option<f64>,
    /// The bound claimed.
    pub bound: f64,
    /// `relative_error <= bound` and every entry finite.
    pub passed: bool,
}

const ALPHA: f64 = 1.0 / 6.0;

/// The element most cases use: generic, in the plane z = 0, radiating upward.
const ELEMENT: [DVec3; 3] =
    [DVec3::new(0.0, 0.0, 0.0), DVec3::new(1.0, 0.0, 0.0), DVec3::new(0.3, 0.9, 0.0)];

/// All cases: the geometric ones, then the generic and one near-edge case scaled and shifted.
pub fn cases() -> Vec<ExtremeCase> {
    let mut out = geometric_cases();
    let moved = moved_copies(&out);
    out.extend(moved);
    out
}

/// One (node, element) pair per extreme position, in the unit frame, for each method it applies
/// to.
fn geometric_cases() -> Vec<ExtremeCase> {
    let linear = Method::Linear { alpha: ALPHA };
    let both = [Method::Centroid, linear];
    let mut out = Vec::new();
    let mut add = |name: String, methods: &[Method], element, node, normal: DVec3| {
        for &method in methods {
            out.push(ExtremeCase {
                name: name.clone(),
                method,
                element,
                node,
                normal: normal.normalize(),
                scale: 1.0,
                offset: DVec3::ZERO,
            });
        }
    };
    let tilted = DVec3::new(0.3, -0.2, -0.9);
    add("generic".into(), &both, ELEMENT, DVec3::new(0.4, 0.3, 0.5), tilted);
    for e in [2, 5, 8, 12] {
        let h = 10f64.powi(-e);
        // Above the interior, on a tilted face (whose tangent plane cuts the element).
        add(format!("above interior, z = 1e-{e}"), &both, ELEMENT, DVec3::new(0.4, 0.3, h), tilted);
        // Fig. 4.1: on a perpendicular face that meets the element along its edge y = 0.
        add(
            format!("neighbour face, 1e-{e} from edge"),
            &both,
            ELEMENT,
            DVec3::new(0.4, 0.0, h),
            DVec3::Y,
        );
    }
    for e in [6, 10] {
        let h = 10f64.powi(-e);
        add(
            format!("45° face, 1e-{e} from edge"),
            &both,
            ELEMENT,
            DVec3::new(0.4, -h, h),
            DVec3::new(0.0, 1.0, -1.0),
        );
        add(
            format!("near vertex, 1e-{e}"),
            &both,
            ELEMENT,
            DVec3::new(-h, -h, h),
            DVec3::new(1.0, 1.0, -1.0),
        );
        add(
            format!("above edge line outside, 1e-{e}"),
            &[Method::Centroid],
            ELEMENT,
            DVec3::new(0.4, -h, 0.3),
            -DVec3::Z,
        );
    }
    add("in the plane, outside".into(), &both, ELEMENT, DVec3::new(0.4, -0.5, 0.0), DVec3::Y);
    add("at a vertex".into(), &[Method::Centroid], ELEMENT, ELEMENT[0], DVec3::new(1.0, 1.0, 0.0));
    add("behind".into(), &[Method::Centroid], ELEMENT, DVec3::new(0.4, 0.3, -0.5), DVec3::Z);
    let sliver = [DVec3::ZERO, DVec3::new(1.0, 0.0, 0.0), DVec3::new(0.5, 1e-6, 0.0)];
    add(
        "sliver 1e6, far".into(),
        &both,
        sliver,
        DVec3::new(0.5, 0.3, 0.2),
        DVec3::new(0.0, -0.6, -0.8),
    );
    add(
        "sliver 1e6, near".into(),
        &both,
        sliver,
        DVec3::new(0.5, -1e-3, 1e-3),
        DVec3::new(0.0, 1.0, -1.0),
    );
    add(
        "grazing, far along the plane".into(),
        &both,
        ELEMENT,
        DVec3::new(50.0, 0.3, 1e-3),
        -DVec3::X,
    );
    for d in [1e2, 1e3, 1e4] {
        let far = DVec3::new(0.3, 0.4, 0.9).normalize() * d;
        add(format!("far away ({d:.0e})"), &both, ELEMENT, far, -far);
    }
    out
}

/// Copies of the generic case and of the neighbour-face case 1e-5 from the edge, scaled by 2^-20
/// and 2^20 and moved 1e6 from the origin.
fn moved_copies(base: &[ExtremeCase]) -> Vec<ExtremeCase> {
    let generic = base.iter().filter(|c| c.name == "generic");
    let near_edge = base.iter().filter(|c| c.name == "neighbour face, 1e-5 from edge");
    let chosen: Vec<&ExtremeCase> = generic.chain(near_edge).collect();
    let mut out = Vec::new();
    for (label, scale, offset) in [
        ("scale 2^-20", 2f64.powi(-20), DVec3::ZERO),
        ("scale 2^20", 2f64.powi(20), DVec3::ZERO),
        ("offset 1e6", 1.0, DVec3::new(1e6, -2e6, 3e6)),
    ] {
        for c in &chosen {
            out.push(ExtremeCase {
                name: format!("{}, {label}", c.name),
                scale,
                offset,
                ..(*c).clone()
            });
        }
    }
    out
}

impl ExtremeCase {
    fn to_global(&self, p: DVec3) -> DVec3 {
        p * self.scale + self.offset
    }

    /// The two-face scene: receiver (face 0) and element (face 1).
    fn scene(&self) -> Result<Scene> {
        // Receiver: a small triangle in the node's tangent plane whose first node is the node.
        let n = self.normal;
        let e1 = n.any_orthonormal_vector();
        let e2 = n.cross(e1);
        let r = 1e-3;
        let d: Vec<DVec3> = [90f64, 210.0, 330.0]
            .iter()
            .map(|a| (e1 * a.to_radians().cos() + e2 * a.to_radians().sin()) * r)
            .collect();
        let kappa = match self.method {
            Method::Centroid => 0.0,
            Method::Linear { alpha } => 1.0 - 3.0 * alpha,
        };
        let centre = self.node - d[0] * kappa;
        let receiver = d.iter().map(|&v| self.to_global(centre + v)).collect();
        let element = self.element.iter().map(|&v| self.to_global(v)).collect();
        Scene::new(
            self.name.clone(),
            vec![Face::new("receiver", receiver, 1.0)?, Face::new("element", element, 1.0)?],
        )
    }

    /// Reference entries `K[node, element's dofs]` (rho/π with rho = 1) for the discretized node.
    fn reference(&self, scene: &Scene, disc: &Discretization) -> Vec<f64> {
        let node = &disc.node(0);
        // The scene may have been moved (exactly) to a local frame; the shift between the two
        // frames is small and exact, so nothing is rounded at the offset's magnitude.
        let shift = scene.origin - self.offset;
        let nominal = |q: DVec3| (q + shift) / self.scale;
        let p = nominal(node.position);
        let v = scene.faces[1].vertices.iter().map(|&v| nominal(v)).collect::<Vec<_>>();
        let normal = (v[1] - v[0]).cross(v[2] - v[0]).normalize();
        let e1 = (v[1] - v[0]).normalize();
        let e2 = normal.cross(e1);
        let local = |q: DVec3| {
            let d = q - v[0];
            DVec3::new(d.dot(e1), d.dot(e2), d.dot(normal))
        };
        let poly: Vec<DVec2> = v.iter().map(|&q| local(q).truncate()).collect();
        let position = local(p);
        let n_p = node.normal;
        let obs =
            Observer { position, normal: DVec3::new(n_p.dot(e1), n_p.dot(e2), n_p.dot(normal)) };
        let weights: Vec<Affine2> = match self.method {
            Method::Centroid => vec![Affine2::ONE],
            Method::Linear { alpha } => {
                // The nodes by their definition (2.9), from the exact vertices.
                let sum = poly[0] + poly[1] + poly[2];
                let nodes: Vec<DVec2> =
                    poly.iter().map(|&v| sum * alpha + v * (1.0 - 3.0 * alpha)).collect();
                lagrange_basis(&nodes)
            }
        };
        let kind = self.reference_kind(position, &poly);
        let tol = Tolerance { absolute: 1e-300, relative: 1e-15, max_intervals: 20000 };
        weights
            .iter()
            .map(|&w| {
                let integral = match kind {
                    ReferenceKind::Zero => 0.0,
                    ReferenceKind::Polar => polar_with_horizon(&obs, &poly, w, tol),
                    ReferenceKind::Plain => {
                        let visible = horizon_clip(&obs, &poly);
                        visible.map_or(0.0, |v| integral(&obs, &v, |q| w.eval(q), tol))
                    }
                };
                integral / std::f64::consts::PI
            })
            .collect()
    }

    /// Zero when the node is within rounding of the element's plane or behind it (the height test
    /// of the pair plan); plain quadrature when it is at least 5% of the diameter away.
    fn reference_kind(&self, position: DVec3, poly: &[DVec2]) -> ReferenceKind {
        let h = (0..3).map(|k| (poly[k] - poly[(k + 1) % 3]).length()).fold(0.0, f64::max);
        if position.z <= 1e-14 * h {
            return ReferenceKind::Zero;
        }
        let distance =
            crate::geometry::distance_to_convex(poly, position.truncate()).hypot(position.z);
        let thin = crate::kernels::far_field::is_thin(&[poly[0], poly[1], poly[2]]);
        if distance >= 0.05 * h || thin { ReferenceKind::Plain } else { ReferenceKind::Polar }
    }
}

/// The part of the element on the positive side of the node's tangent plane (the pair plan
/// clips there; the kernel is negative beyond it).
fn horizon_clip(obs: &Observer, poly: &[DVec2]) -> Option<Vec<DVec2>> {
    let n = obs.normal;
    // Points Q of the plane with (Q − P)·n_P >= 0: n.x X + n.y Y − n.x x − n.y y − n.z z >= 0.
    let hp = crate::geometry::HalfPlane {
        normal: DVec2::new(n.x, n.y),
        offset: -(n.x * obs.position.x + n.y * obs.position.y + n.z * obs.position.z),
    };
    crate::geometry::clip_convex(poly, &hp)
}

fn polar_with_horizon(obs: &Observer, poly: &[DVec2], w: Affine2, tol: Tolerance) -> f64 {
    horizon_clip(obs, poly).map_or(0.0, |v| polar_integral(obs, &v, w, tol))
}

/// The affine functions that are 1 at one node and 0 at the other two.
fn lagrange_basis(nodes: &[DVec2]) -> Vec<Affine2> {
    let [a, b, c] = [nodes[0], nodes[1], nodes[2]];
    let det = (b - a).perp_dot(c - a);
    (0..3)
        .map(|l| {
            let (p, q) = match l {
                0 => (b, c),
                1 => (c, a),
                _ => (a, b),
            };
            // φ(X) = (q − p) × (X − p) / det.
            let d = q - p;
            Affine2 { c0: -d.perp_dot(p) / det, cx: -d.y / det, cy: d.x / det }
        })
        .collect()
}

/// Runs every case on each backend.
pub fn run(backends: &[Backend]) -> Result<Vec<ExtremeRow>> {
    let mut rows = Vec::new();
    for case in cases() {
        let scene = case.scene()?;
        let mesh = Mesh::new(&scene, &MeshKind::Uniform, 0)?;
        let disc = Discretization::new(&scene, &mesh, case.method)?;
        let reference = case.reference(&scene, &disc);
        let condition = if reference.iter().all(|&r| r == 0.0) {
            1.0
        } else {
            geometric_condition(case.node, case.normal, &case.element)
        };
        let problem = Problem::new(scene, mesh, disc);
        let columns: Vec<usize> = match case.method {
            Method::Centroid => vec![1],
            Method::Linear { .. } => vec![3, 4, 5],
        };
        let scale = reference.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        let error_with = |backend: Backend, options: &AssemblyOptions| -> Result<f64> {
            let (a, _) = assemble_on(backend, &problem, options, &Silent)?;
            let got: Vec<f64> = columns.iter().map(|&j| a.matrix.get(0, j)).collect();
            let diff = got.iter().zip(&reference).fold(0.0f64, |m, (g, r)| m.max((g - r).abs()));
            Ok(match got.iter().all(|g| g.is_finite()) {
                true if scale > 0.0 => diff / scale,
                true => diff,
                false => f64::INFINITY,
            })
        };
        for &backend in backends {
            let relative_error = error_with(backend, &AssemblyOptions::default())?;
            let closed_forms_error = match backend {
                Backend::Cpu => Some(error_with(
                    backend,
                    &AssemblyOptions { far_field: false, ..Default::default() },
                )?),
                Backend::Gpu(_) => None,
            };
            let bound = bound(backend, condition);
            rows.push(ExtremeRow {
                case: case.name.clone(),
                method: case.method.name(),
                backend: backend.name(),
                precision: backend.precision().name(),
                reference: scale,
                relative_error,
                closed_forms_error,
                bound,
                passed: relative_error <= bound,
            });
        }
    }
    Ok(rows)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_lagrange_basis_interpolates_the_nodes() {
        let nodes = [DVec2::new(0.1, 0.2), DVec2::new(0.9, 0.1), DVec2::new(0.4, 0.8)];
        let basis = lagrange_basis(&nodes);
        for (l, phi) in basis.iter().enumerate() {
            for (m, &q) in nodes.iter().enumerate() {
                let want = if l == m { 1.0 } else { 0.0 };
                assert!((phi.eval(q) - want).abs() < 1e-14, "{l} at {m}: {}", phi.eval(q));
            }
        }
    }

    #[test]
    fn there_are_at_least_twenty_cases() {
        assert!(cases().len() >= 20);
    }
}
