//! Closed enclosures (Lemma 2.1): inside a closed surface, `∫_S G V dS = π` at every point, so every
//! row of K/rho sums to 1 — with and without internal occluders, for both collocation methods (the
//! linear basis functions of an element sum to 1).

use super::*;
use crate::discretization::{Discretization, Method};
use crate::mesh::{Mesh, MeshKind};
use crate::scene::{Scene, baffled_box, cube};
use crate::visibility::{PairPlanner, PairStats};

fn row_sum_range(scene: &Scene, method: Method, refine: u32) -> (f64, f64, PairStats) {
    let mesh = Mesh::new(scene, &MeshKind::Uniform, refine).unwrap();
    let disc = Discretization::new(scene, &mesh, method).unwrap();
    let problem = Problem::new(scene.clone(), mesh, disc);
    let a = assemble(&problem, &AssemblyOptions::default(), &crate::progress::Silent).unwrap();
    let disc = &problem.disc;
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for (i, node) in disc.nodes().enumerate() {
        let s: f64 = a.matrix.row(i).iter().sum::<f64>() / node.rho;
        lo = lo.min(s);
        hi = hi.max(s);
    }
    (lo, hi, a.stats)
}

#[test]
fn cube_rows_sum_to_one() {
    for (method, refine) in [(Method::Centroid, 2), (Method::linear(1.0 / 6.0).unwrap(), 1)] {
        let (lo, hi, stats) = row_sum_range(&cube().unwrap(), method, refine);
        assert!((lo - 1.0).abs() < 1e-12 && (hi - 1.0).abs() < 1e-12, "{method}: [{lo}, {hi}]");
        assert_eq!(stats.hidden + stats.partial, 0, "no occlusion in a cube: {stats:?}");
    }
}

#[test]
fn baffled_box_rows_sum_to_one_with_exact_visibility() {
    for (method, refine) in [(Method::Centroid, 2), (Method::linear(1.0 / 6.0).unwrap(), 1)] {
        let (lo, hi, stats) = row_sum_range(&baffled_box().unwrap(), method, refine);
        assert!((lo - 1.0).abs() < 1e-11 && (hi - 1.0).abs() < 1e-11, "{method}: [{lo}, {hi}]");
        assert!(stats.partial > 0 && stats.hidden > 0, "{stats:?}");
        assert_eq!(
            stats.total,
            stats.same_plane
                + stats.facing_away
                + stats.hidden
                + stats.not_reflecting
                + stats.full
                + stats.partial
        );
    }
}

/// The largest difference between two matrices, relative to each row's largest entry.
fn max_row_relative_difference(a: &CollocationMatrix, b: &CollocationMatrix) -> f64 {
    (0..a.dof())
        .map(|i| {
            let (ra, rb) = (a.row(i), b.row(i));
            let scale = ra.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
            let diff = ra.iter().zip(rb).fold(0.0_f64, |m, (x, y)| m.max((x - y).abs()));
            if scale > 0.0 { diff / scale } else { diff }
        })
        .fold(0.0, f64::max)
}

/// The accelerated pair plan (occluder index, pair tables, occluders that hid earlier faces tried
/// first, buildings found whole, the candidates of large views nearest first) assembles the same
/// matrix as the core solver's plan (every occluder in the box of the node and the face), entry
/// by entry, in cities with the pair table (313 and 170 faces, several elements per face) and
/// without it (545 and 546 faces, the second under a sky that sees the whole city).
#[test]
fn accelerated_plan_assembles_the_core_solvers_matrix() {
    use crate::visibility::Acceleration;
    for (blocks, refine, lit) in [(6, 0, false), (3, 1, false), (8, 0, false), (8, 0, true)] {
        let scene = match lit {
            false => crate::scene::city(blocks, blocks).unwrap(),
            true => crate::scene::lit_city(blocks, blocks).unwrap(),
        };
        let mesh = Mesh::new(&scene, &MeshKind::Uniform, refine).unwrap();
        let disc = Discretization::new(&scene, &mesh, Method::Centroid).unwrap();
        let options = AssemblyOptions::default();
        let assembled = |acceleration| {
            let planner = PairPlanner::with_acceleration(&scene, acceleration);
            let problem =
                Problem::with_planner(scene.clone(), mesh.clone(), disc.clone(), planner, 0.0);
            assemble(&problem, &options, &crate::progress::Silent).unwrap()
        };
        let (fast, core) = (assembled(Acceleration::Tree), assembled(Acceleration::BoxScan));
        assert!(fast.stats.hidden > 0 && fast.stats.partial > 0, "{:?}", fast.stats);
        let diff = max_row_relative_difference(&fast.matrix, &core.matrix);
        assert!(diff <= 1e-13, "city {blocks}x{blocks} refine {refine}: {diff:e}");
    }
}

/// The centroid method's closed forms in vector lanes assemble the scalar reference's matrix to a
/// few ulps, with full, partly visible (each visible piece as a fan of triangles) and far-field
/// (banded) pairs all present.
#[test]
fn lanes_assemble_the_scalar_matrix() {
    let room =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/furnished-room.toml");
    for (scene, refine) in [
        (crate::scene::five_piece(Default::default()).unwrap(), 2),
        (baffled_box().unwrap(), 2),
        // Pieces seen past furniture, shadowed by several occluders at once.
        (crate::scene::load(&room).unwrap(), 1),
    ] {
        let mesh = Mesh::new(&scene, &MeshKind::Uniform, refine).unwrap();
        let disc = Discretization::new(&scene, &mesh, Method::Centroid).unwrap();
        let problem = Problem::new(scene, mesh, disc);
        let assembled = |lanes| {
            let options = AssemblyOptions { lanes, ..Default::default() };
            assemble(&problem, &options, &crate::progress::Silent).unwrap()
        };
        let (vector, scalar) = (assembled(true), assembled(false));
        assert_eq!(vector.stats, scalar.stats);
        let diff = max_row_relative_difference(&vector.matrix, &scalar.matrix);
        assert!(diff <= 1e-13, "{}: {diff:e}", problem.scene.name);
        assert!(diff > 0.0, "{}: the lanes were not used", problem.scene.name);
    }
}

/// FNV-1a over the bytes of the entries (little-endian), row by row.
fn fingerprint(matrix: &CollocationMatrix) -> u64 {
    let mut hash = 0xcbf2_9ce4_8422_2325u64;
    for byte in matrix.as_slice().iter().flat_map(|v| v.to_le_bytes()) {
        hash = (hash ^ u64::from(byte)).wrapping_mul(0x0100_0000_01b3);
    }
    hash
}

#[test]
#[cfg(all(target_arch = "x86_64", target_os = "linux"))]
fn the_row_walk_keeps_every_matrix_bit_for_bit() {
    // Fingerprints of K as `radiosity assemble` wrote it before the pair plan's row walk was made
    // one (x86-64, glibc's libm): a change in how any pair is classified, or in the order of the
    // arithmetic, shows here. A change that is meant to alter the matrices updates them (the
    // centroid cases when partly visible elements' pieces went into the lanes; the furnished
    // room, the occluded box and the city when a solid in front of a face's plane cast the
    // face's part in its cone from the point, entries within 7.1e-16 of before; those and the
    // baffled box last when a shadow apart from an element stopped cutting it into pieces that
    // make it up again, entries within 3.5e-17 of before).
    let example = |name: &str| {
        crate::scene::load(&std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join(name)).unwrap()
    };
    let five = || crate::scene::five_piece(Default::default()).unwrap();
    let linear = Method::linear(1.0 / 6.0).unwrap();
    let cases: [(&str, Scene, Method, u32, u64); 6] = [
        ("five-piece", five(), Method::Centroid, 3, 0x6f0a_70c2_9d99_dc4c),
        ("five-piece linear", five(), linear, 2, 0xca39_1789_78e4_cbb1),
        (
            "furnished room",
            example("examples/furnished-room.toml"),
            Method::Centroid,
            1,
            0xfa0a_974f_a666_7c0a,
        ),
        (
            "occluded box",
            example("examples/occluded-box.toml"),
            Method::Centroid,
            1,
            0x8a40_c68d_48db_ced0,
        ),
        ("city 4x4", crate::scene::city(4, 4).unwrap(), Method::Centroid, 0, 0x9ade_1a3e_5ef1_0278),
        ("baffled box linear", baffled_box().unwrap(), linear, 2, 0x60e4_2d16_54f3_8eca),
    ];
    for (name, scene, method, refine, expected) in cases {
        let mesh = Mesh::new(&scene, &MeshKind::Uniform, refine).unwrap();
        let disc = Discretization::new(&scene, &mesh, method).unwrap();
        let problem = Problem::new(scene, mesh, disc);
        let a = assemble(&problem, &AssemblyOptions::default(), &crate::progress::Silent).unwrap();
        let found = fingerprint(&a.matrix);
        assert_eq!(found, expected, "{name}: fingerprint {found:#x}, expected {expected:#x}");
    }
}
