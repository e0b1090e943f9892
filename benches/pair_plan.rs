//! The pair plan of a generated city (occluders everywhere): the R*-tree with the view pyramid,
//! on a sample of nodes. `cargo bench --bench pair_plan`; `radiosity bench-plan` compares it with
//! the other ways of finding candidates.

use criterion::{Criterion, criterion_group, criterion_main};
use radiosity::scene::city;
use radiosity::visibility::bench_plan;

fn pair_plan(c: &mut Criterion) {
    let mut group = c.benchmark_group("pair plan");
    group.sample_size(10);
    let scene = city(10, 10).unwrap();
    group.bench_function(format!("city 10x10 ({} faces), 10 nodes", scene.faces.len()), |b| {
        b.iter(|| bench_plan(&scene, 10))
    });
    group.finish();
}

criterion_group!(benches, pair_plan);
criterion_main!(benches);
