//! The collocation integrals on the CPU, one (node, element) pair at a time: the production closed
//! form (constant and affine weights), Lambert's contour formula, the paper's right-triangle
//! formula, and the far-field rule; and the vectorised kernels against their scalar references:
//! the constant weight eight pairs at a time, the far-field rule's moments four points at a time,
//! and an edge's log moment (the IMT sum of the affine weights) eight nodes at a time.
//! `cargo bench --bench kernels`.

use criterion::{Criterion, criterion_group, criterion_main};
use glam::{DVec2, DVec3};
use radiosity::kernels::far_field::FarFieldRule;
use radiosity::kernels::{
    Affine2, Observer, by_rule, edge_log_moment, exact, lambert, lanes, paper_closed_form,
};
use radiosity::quadrature::ImtRule;
use std::hint::black_box;

fn kernels(c: &mut Criterion) {
    let tri = [DVec2::new(0.0, 0.0), DVec2::new(1.0, 0.0), DVec2::new(0.3, 0.8)];
    // A node above and beside the element, its face tilted: every term of the closed forms works.
    let near = Observer {
        position: DVec3::new(0.4, -0.3, 0.5),
        normal: DVec3::new(0.3, 0.4, -0.866_025_403_784_438_6),
    };
    let far = Observer { position: DVec3::new(6.0, 4.0, 3.0), normal: DVec3::new(-0.6, 0.0, -0.8) };
    let weights = [
        Affine2 { c0: 1.0, cx: -1.0, cy: -0.5 },
        Affine2 { c0: 0.0, cx: 1.0, cy: -0.375 },
        Affine2 { c0: 0.0, cx: 0.0, cy: 1.25 },
    ];
    let imt = ImtRule::new(128);
    let loops = [&tri[..]];
    let mut group = c.benchmark_group("kernels");
    group.bench_function("closed form, constant weight", |b| {
        b.iter(|| exact::constant_weight(black_box(&near), loops))
    });
    group.bench_function("closed form, three affine weights", |b| {
        b.iter(|| exact::affine_weights(black_box(&near), loops, &weights, &imt))
    });
    group.bench_function("Lambert contour, constant weight", |b| {
        b.iter(|| lambert::constant_weight(black_box(&near), loops))
    });
    group.bench_function("paper right triangles (4.10), constant weight", |b| {
        b.iter(|| paper_closed_form::constant_weight(black_box(&near), &tri))
    });
    let four = [near, Observer { position: DVec3::new(-0.2, 0.9, 0.1), ..near }, far, near];
    let observers: [Observer; lanes::LANES] = std::array::from_fn(|l| four[l % 4]);
    let triangles = [tri; lanes::LANES];
    let pairs = lanes::LANES;
    group.bench_function(format!("closed form, constant weight, {pairs} pairs scalar"), |b| {
        b.iter(|| black_box(&observers).map(|o| exact::constant_weight(&o, loops)))
    });
    group.bench_function(format!("closed form, constant weight, {pairs} pairs in lanes"), |b| {
        b.iter(|| lanes::constant_weight(black_box(&observers), &triangles))
    });
    let (p, q) = (tri[0] - near.position.truncate(), tri[1] - near.position.truncate());
    let z = near.position.z;
    group.bench_function("log moment of an edge, scalar", |b| {
        b.iter(|| edge_log_moment(black_box(p), q, z, &imt, false))
    });
    group.bench_function("log moment of an edge, in lanes", |b| {
        b.iter(|| edge_log_moment(black_box(p), q, z, &imt, true))
    });
    let rule = FarFieldRule::standard();
    let nearest_band = &rule.bands[0].rule;
    group.bench_function("far-field moments, 11 x 11 points, scalar", |b| {
        b.iter(|| nearest_band.moments(&tri, |q| black_box(&far).kernel(q)))
    });
    group.bench_function("far-field moments, 11 x 11 points, in lanes", |b| {
        b.iter(|| by_rule::kernel_moments(black_box(&far), nearest_band, &tri))
    });
    group.bench_function("far-field rule, three affine weights", |b| {
        b.iter(|| {
            rule.integrate_subdivided(black_box(&far), &tri, &weights, |t| {
                exact::affine_weights(&far, [&t[..]], &weights, &imt)
            })
        })
    });
    group.finish();
}

criterion_group!(benches, kernels);
criterion_main!(benches);
