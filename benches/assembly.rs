//! Assembly of the five-piece surface's centroid matrix (refine 3 and 4: n = 640, 2 560) on the
//! CPU and, where an adapter with f64 exists, on the GPU. `cargo bench --bench assembly`.
//! `radiosity bench` times whole runs; this times the assembly alone, with criterion's statistics.

use criterion::{Criterion, criterion_group, criterion_main};
use radiosity::assembly::{AssemblyOptions, Problem, assemble};
use radiosity::discretization::{Discretization, Method};
use radiosity::gpu::{self, GpuAssembler, Precision};
use radiosity::mesh::{Mesh, MeshKind};
use radiosity::scene::{BuiltinScene, SurfaceParameters};

fn assembly(c: &mut Criterion) {
    let mut group = c.benchmark_group("assembly five-piece centroid");
    group.sample_size(10);
    let scene = BuiltinScene::FivePiece.build(SurfaceParameters::default()).unwrap();
    let ctx = match gpu::context_for(Precision::F64) {
        Ok(ctx) => Some(ctx),
        Err(e) => {
            eprintln!("GPU cases left out: {e}");
            None
        }
    };
    for refine in [3, 4] {
        let mesh = Mesh::new(&scene, &MeshKind::Uniform, refine).unwrap();
        let disc = Discretization::new(&scene, &mesh, Method::Centroid).unwrap();
        let problem = Problem::new(scene.clone(), mesh.clone(), disc.clone());
        let options = AssemblyOptions::default();
        let n = mesh.len();
        group.bench_function(format!("cpu n = {n}"), |b| {
            b.iter(|| assemble(&problem, &options, &radiosity::progress::Silent).unwrap())
        });
        if let Some(ctx) = ctx {
            let assembler = GpuAssembler::new(ctx, Precision::F64, Method::Centroid).unwrap();
            group.bench_function(format!("gpu n = {n} ({})", ctx.adapter.name), |b| {
                b.iter(|| {
                    assembler.assemble(&problem, &options, &radiosity::progress::Silent).unwrap()
                })
            });
        }
    }
    group.finish();
}

criterion_group!(benches, assembly);
criterion_main!(benches);
