//! Whole scenes from arbitrary coordinates through the public entry points: validation either
//! rejects the input with an error or the pair plan and assembly give a matrix whose entries are
//! finite and whose rows of K/rho sum to at most 1 (to 1e-3). No input may panic.
//!
//! Shared by the fuzz target of the same name (`cargo +nightly fuzz run NAME` in `fuzz/`) and
//! by `tests/fuzz_replay.rs`, which replays it on stable over seeded and damaged inputs.

use glam::DVec3;
use radiosity::assembly::{AssemblyOptions, Problem, assemble};
use radiosity::discretization::{Discretization, Method};
use radiosity::mesh::{Mesh, MeshKind};
use radiosity::scene::{Face, Scene};

/// Checks one input: returns where the input is outside the contract, panics on a failure.
pub fn check(data: &[u8]) {
    let mut values = data.chunks_exact(8).map(|c| f64::from_le_bytes(c.try_into().unwrap()));
    let mut faces = Vec::new();
    // Up to four faces of three or four vertices; NaN and infinities reach validation as they are.
    for k in 0..4 {
        let count = if k % 2 == 0 { 3 } else { 4 };
        let vertices: Option<Vec<DVec3>> = (0..count)
            .map(|_| Some(DVec3::new(values.next()?, values.next()?, values.next()?)))
            .collect();
        let Some(vertices) = vertices else { break };
        if let Ok(face) = Face::new(format!("f{k}"), vertices, 0.5) {
            faces.push(face);
        }
    }
    let Ok(scene) = Scene::new("fuzz", faces) else { return };
    let Ok(mesh) = Mesh::new(&scene, &MeshKind::Uniform, 0) else { return };
    for method in [Method::Centroid, Method::Linear { alpha: 1.0 / 6.0 }] {
        let Ok(disc) = Discretization::new(&scene, &mesh, method) else { return };
        let problem = Problem::new(scene.clone(), mesh.clone(), disc);
        let options = AssemblyOptions::default();
        let Ok(a) = assemble(&problem, &options, &radiosity::progress::Silent) else { return };
        let disc = &problem.disc;
        for i in 0..disc.dof() {
            let row = a.matrix.row(i);
            assert!(row.iter().all(|v| v.is_finite()), "row {i}: {row:?}");
            // At most 1 (a node sees at most its hemisphere), up to the accuracy that the
            // geometry allows: fuzzed faces may touch face to face 1e-18 apart with a 5e-10 tilt,
            // where the entry's conditioning (h / distance) leaves about 5 digits.
            let sum: f64 = row.iter().sum::<f64>() / 0.5;
            assert!(sum <= 1.0 + 1e-3, "row {i}: K/rho sums to {sum}");
        }
    }
}
