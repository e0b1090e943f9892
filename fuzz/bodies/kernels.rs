//! The collocation kernels on arbitrary finite input that meets their documented preconditions
//! (node above the element's plane, unit normal, a triangle with area, lengths in units of the
//! element's size as the assembly passes them): the result must be finite, and no input may panic.
//!
//! Shared by the fuzz target of the same name (`cargo +nightly fuzz run NAME` in `fuzz/`) and
//! by `tests/fuzz_replay.rs`, which replays it on stable over seeded and damaged inputs.

// `!(x > bound)` also returns on NaN, which is outside the contract.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

use glam::{DVec2, DVec3};
use radiosity::kernels::far_field::{FarFieldRule, is_thin};
use radiosity::kernels::{Affine2, Observer, exact};
use radiosity::quadrature::ImtRule;

/// Checks one input: returns where the input is outside the contract, panics on a failure.
pub fn check(data: &[u8]) {
    let mut values = data
        .chunks_exact(8)
        .map(|c| f64::from_le_bytes(c.try_into().unwrap()))
        .filter(|v| v.is_finite());
    let mut next = || values.next().unwrap_or(0.5).clamp(-1e6, 1e6);
    let tri = [DVec2::new(next(), next()), DVec2::new(next(), next()), DVec2::new(next(), next())];
    let area = 0.5 * (tri[1] - tri[0]).perp_dot(tri[2] - tri[0]);
    let diameter = (0..3).map(|k| (tri[k] - tri[(k + 1) % 3]).length()).fold(0.0, f64::max);
    if !(area > 1e-12 * diameter * diameter) {
        return; // not counter-clockwise with area: outside the kernels' contract
    }
    let z = next().abs();
    if !(z > 1e-12 * diameter) {
        return; // the pair plan skips nodes on or behind the plane
    }
    // The assembly integrates every pair in units of the element's size (a power of two); the
    // kernels' contract is that scale, with any relative position of the node.
    let unit = radiosity::geometry::power_of_two_unit(diameter);
    let tri = tri.map(|v| v * unit);
    let position = DVec3::new(next(), next(), z) * unit;
    if position.abs().max_element() > 1e60 {
        return; // beyond the scene's scale range (Scene::new), no node is this far away
    }
    let normal = DVec3::new(next(), next(), next()).normalize_or_zero();
    if normal == DVec3::ZERO {
        return;
    }
    let obs = Observer { position, normal };
    let weights = [Affine2::ONE, Affine2 { c0: next(), cx: next() / unit, cy: next() / unit }];
    let c = exact::constant_weight(&obs, [&tri[..]]);
    assert!(c.is_finite(), "constant weight {c} for {tri:?} from {obs:?}");
    let a = exact::affine_weights(&obs, [&tri[..]], &weights, &ImtRule::new(32));
    assert!(a.iter().all(|v| v.is_finite()), "affine weights {a:?} for {tri:?} from {obs:?}");
    if is_thin(&tri) {
        let imt = ImtRule::new(32);
        let near = |piece: &[DVec2; 3]| exact::affine_weights(&obs, [&piece[..]], &weights, &imt);
        let s = FarFieldRule::standard().integrate_subdivided(&obs, &tri, &weights, near);
        assert!(s.iter().all(|v| v.is_finite()), "subdivided {s:?} for {tri:?} from {obs:?}");
    }
}
