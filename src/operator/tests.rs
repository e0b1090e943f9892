//! The compressed operator against the dense matrix (the reference): same products to the
//! tolerance, exact where visibility is partial, nothing stored where nothing is seen.

use crate::progress::Silent;
use glam::DVec3;

use super::blocks::{BlockPlan, FacePairs};
use super::build::cluster_trees;
use super::compressed::{Block, block_stats};
use super::guard::MemoryGuard;
use super::stats::order_bytes;
use super::stored::BlockData;
use super::stored::{SparseRows, Values};
use super::*;
use crate::assembly::{
    AssemblyOptions, CollocationMatrix, PairEvaluation, PairIntegrator, Problem, assemble,
};
use crate::discretization::{Discretization, Method};
use crate::error::Error;
use crate::mesh::{Mesh, MeshKind};
use crate::scene::{Face, Scene, SurfaceParameters, baffled_box, cube, five_piece};

type Case = Problem;

pub(super) fn case(scene: Scene, method: Method, refine: u32) -> Case {
    let mesh = Mesh::new(&scene, &MeshKind::Uniform, refine).unwrap();
    let disc = Discretization::new(&scene, &mesh, method).unwrap();
    Problem::new(scene, mesh, disc)
}

fn compressed(c: &Case, tolerance: f64, leaf_size: usize) -> CompressedOperator {
    build(c, tolerance, leaf_size, false)
}

/// The operator, built block by block on the CPU or, with `batched`, through the batched path
/// with the CPU's pair evaluation.
fn build(c: &Case, tolerance: f64, leaf_size: usize, batched: bool) -> CompressedOperator {
    let options = CompressionOptions { tolerance, leaf_size, ..Default::default() };
    build_with(c, &options, batched)
}

/// The operator without shadowed blocks, whatever the faces' sizes.
fn plain(c: &Case, tolerance: f64, leaf_size: usize) -> CompressedOperator {
    let shadowed_blocks = ShadowedBlocks::Off;
    let options =
        CompressionOptions { tolerance, leaf_size, shadowed_blocks, ..Default::default() };
    build_with(c, &options, false)
}

pub(super) fn build_with(
    c: &Case,
    options: &CompressionOptions,
    batched: bool,
) -> CompressedOperator {
    let assembly = AssemblyOptions::default();
    let integrator = PairIntegrator::new(c.disc.method, &assembly);
    let cpu = crate::assembly::CpuPairs::new(&c.disc, &integrator);
    let batches = batched.then_some(&cpu as &dyn PairEvaluation);
    CompressedOperator::build(c, &assembly, options, batches, &Silent).unwrap()
}

fn dense(c: &Case) -> CollocationMatrix {
    assemble(c, &AssemblyOptions::default(), &Silent).unwrap().matrix
}

#[test]
fn five_piece_products_match_the_dense_matrix_to_the_tolerance() {
    let scene = || five_piece(SurfaceParameters::default()).unwrap();
    for (method, refine) in [(Method::Centroid, 3), (Method::linear(1.0 / 6.0).unwrap(), 2)] {
        let c = case(scene(), method, refine);
        let k = dense(&c);
        for tol in [1e-4, 1e-8] {
            let op = compressed(&c, tol, 8);
            let d = op.max_product_difference(&|x| k.apply(x));
            assert!(d <= 10.0 * tol, "{method}, tol {tol}: {d:.2e} ({:?})", op.stats);
            assert!(op.stats.far_blocks > 0 && op.stats.near_blocks > 0, "{:?}", op.stats);
            assert!(op.stats.max_rank > 0);
        }
    }
}

#[test]
fn batched_evaluation_builds_the_operator_of_the_block_by_block_path() {
    // The batched path (cross approximations in lockstep, exact blocks planned then evaluated)
    // through the CPU's pair evaluation: the same pair classes and products as block by block,
    // on a scene with shadows (the baffled box) and on the paper's surface (linear method).
    let linear = Method::linear(1.0 / 6.0).unwrap();
    let scenes = [
        (baffled_box().unwrap(), Method::Centroid, 3, false),
        (five_piece(SurfaceParameters::default()).unwrap(), linear, 2, true),
    ];
    for (scene, method, refine, compresses) in scenes {
        let c = case(scene, method, refine);
        let k = dense(&c);
        let (by_block, batched) = (build(&c, 1e-8, 8, false), build(&c, 1e-8, 8, true));
        assert_eq!(by_block.pairs, batched.pairs);
        assert_eq!(by_block.stats.near_blocks, batched.stats.near_blocks);
        assert_eq!(batched.stats.far_blocks > 0, compresses, "{:?}", batched.stats);
        let d = batched.max_product_difference(&|x| k.apply(x));
        assert!(d <= 1e-7, "{method}: {d:.2e} ({:?})", batched.stats);
        let between = batched.max_product_difference(&|x| by_block.apply(x));
        assert!(between <= 1e-7, "{method}: {between:.2e}");
    }
}

#[test]
fn partly_visible_leaves_are_exact() {
    // The baffled box: the plate casts shadows on every wall. Leaves hold partly visible pairs
    // (counted), and with the tolerance near rounding the products equal the dense ones.
    let c = case(baffled_box().unwrap(), Method::Centroid, 3);
    let k = dense(&c);
    let op = compressed(&c, 1e-13, 8);
    assert!(op.pairs.partial > 0 && op.pairs.hidden > 0, "{:?}", op.pairs);
    // Each view serves at least one pair of the exact blocks, and none of a node on the
    // face's plane or reflecting nothing.
    let p = &op.pairs;
    let most = p.total - p.same_plane - p.not_reflecting;
    let viewed = op.stats.faces_viewed;
    assert!(viewed > 0 && viewed <= most, "{viewed} views, at most {most}");
    let d = op.max_product_difference(&|x| k.apply(x));
    assert!(d <= 1e-12, "{d:.2e}");
}

#[test]
fn closed_boxes_keep_rows_summing_to_one() {
    // Lemma 2.1 through the compressed operator: K/rho applied to ones is 1 in every row.
    for (scene, name) in [(cube().unwrap(), "cube"), (baffled_box().unwrap(), "baffled box")] {
        let c = case(scene, Method::Centroid, 4);
        let tol = 1e-6;
        let op = compressed(&c, tol, 16);
        let ones = vec![1.0; op.dof()];
        let worst = op
            .apply(&ones)
            .iter()
            .zip(c.disc.nodes())
            .map(|(s, node)| (s / node.rho - 1.0).abs())
            .fold(0.0, f64::max);
        assert!(worst <= 10.0 * tol, "{name}: {worst:.2e}");
        assert!(op.stats.far_blocks > 0, "{name}: {:?}", op.stats);
    }
}

/// A unit square at height z, facing up (`up`) or down.
fn square(name: &str, z: f64, half: f64, up: bool) -> Face {
    let mut v = vec![
        DVec3::new(-half, -half, z),
        DVec3::new(half, -half, z),
        DVec3::new(half, half, z),
        DVec3::new(-half, half, z),
    ];
    if !up {
        v.reverse();
    }
    Face::new(name, v, 0.5).unwrap().with_emission(1.0).unwrap()
}

#[test]
fn hidden_and_facing_away_blocks_store_nothing() {
    // Two squares back to back: every pair faces away, nothing is stored.
    let scene = Scene::new(
        "back to back",
        vec![square("low", 0.0, 1.0, false), square("high", 1.0, 1.0, true)],
    )
    .unwrap();
    let c = case(scene, Method::Centroid, 3);
    let op = compressed(&c, 1e-6, 8);
    assert_eq!((op.stats.near_blocks, op.stats.far_blocks), (0, 0), "{:?}", op.stats);
    assert!(op.stats.empty_blocks > 0);

    // A floor and a ceiling far apart with a plate between them that hides each from the other:
    // the tree separates the floor from the rest, and no stored block pairs floor nodes with
    // ceiling elements only (those blocks are found empty and dropped).
    let scene = Scene::new(
        "hidden",
        vec![
            square("floor", 0.0, 1.0, true),
            square("ceiling", 10.0, 1.0, false),
            square("plate", 5.0, 4.0, false),
        ],
    )
    .unwrap();
    let c = case(scene, Method::Centroid, 2);
    let k = dense(&c);
    let op = compressed(&c, 1e-10, 8);
    assert!(op.max_product_difference(&|x| k.apply(x)) <= 1e-9);
    assert!(op.stats.empty_blocks > 0, "{:?}", op.stats);
    // The plate hides the ceiling from the floor entirely (dense matrix).
    for (i, node) in c.disc.nodes().enumerate().filter(|(_, n)| n.face() == 0) {
        for j in (0..c.disc.element_count()).filter(|&j| c.disc.face_of(j) == 1) {
            assert_eq!(k.get(i, j), 0.0, "node {i} at {:?} sees element {j}", node.position);
        }
    }
    let face_of_row = |r: usize| c.disc.node(op.node_order[r]).face();
    let face_of_col = |q: usize| c.disc.face_of(op.element_order[q]);
    let floor_to_ceiling = op.blocks.iter().filter(|b| {
        b.row_range().clone().all(|r| face_of_row(r) == 0)
            && b.col_range().clone().all(|q| face_of_col(q) == 1)
    });
    assert_eq!(floor_to_ceiling.count(), 0);
}

#[test]
fn bad_tolerances_are_refused_with_the_limit() {
    for tol in [0.0, 1.0, -1e-6, f64::NAN, 2.0] {
        let options = CompressionOptions { tolerance: tol, ..Default::default() };
        let e = options.validate().unwrap_err().to_string();
        assert!(e.contains("compression tolerance") && e.contains("(0, 1)"), "{e}");
    }
}

#[test]
fn an_operator_that_outgrows_the_memory_allowance_is_stopped_with_consistent_sizes() {
    let guard = MemoryGuard::with_allowance(491_520, Some(3.0 * (1u64 << 30) as f64));
    assert!(guard.check(2 << 30).is_ok());
    guard.add(2 << 30);
    assert!(!guard.is_over());
    guard.add(2 << 30);
    assert!(guard.is_over());
    let message = guard.check(0).unwrap_err().to_string();
    // What it had taken is above what it may take (the allowance less 16 MiB), and both are
    // named with the allowance.
    for needle in ["491520 unknowns", "taken 4.00 GiB", "than the 2.98 GiB", "take: the 3.00 GiB"] {
        assert!(message.contains(needle), "'{needle}' not in: {message}");
    }
    assert!(message.contains("--memory-limit"), "{message}");
    // Below a GiB, sizes are written in MiB; an allowance below the guard's margin says so.
    let small = MemoryGuard::with_allowance(100, Some(400.0 * (1u64 << 20) as f64));
    let message = small.check(500 << 20).unwrap_err().to_string();
    for needle in ["taken 500.0 MiB", "than the 384.0 MiB", "take: the 400.0 MiB"] {
        assert!(message.contains(needle), "'{needle}' not in: {message}");
    }
    let tiny = MemoryGuard::with_allowance(100, Some(1.0 * (1u64 << 20) as f64));
    let message = tiny.check(1).unwrap_err().to_string();
    assert!(message.contains("leaves nothing") && message.contains("1.0 MiB"), "{message}");
}

#[test]
fn a_build_whose_estimate_cannot_fit_is_refused_naming_both_sizes() {
    let estimate = MemoryEstimate {
        dof: 5_000,
        trees: 1 << 20,
        plan: 8 << 20,
        lists: 24 << 20,
        index: 16 << 20,
        exact: 300 << 20,
        factors: 100 << 20,
        orders: 60_000,
        views: 0,
        crossing: 1 << 20,
        solver: 1 << 20,
        rounds: 0,
        error: 2 << 20,
        samples: 4096,
        blocks: 10_000,
        ranks: 1,
        single: true,
    };
    let peak = estimate.peak_bytes() as f64;
    // It fits where its low end does.
    let roomy = MemoryGuard::with_allowance(5_000, Some(peak));
    assert!(roomy.refusal(&estimate, Some(2)).is_none());
    let tight = MemoryGuard::with_allowance(5_000, Some(100.0 * (1u64 << 20) as f64));
    let Some(Error::OperatorTooLarge { needed_gib, available_gib, .. }) =
        tight.refusal(&estimate, Some(2))
    else {
        panic!("not refused");
    };
    assert!(needed_gib > available_gib, "{needed_gib} <= {available_gib}");
    let message = tight.refusal(&estimate, Some(2)).unwrap().to_string();
    let needed = format!("would need about {}", crate::assembly::size_text(peak));
    for needle in ["5000 unknowns", &needed, "but 100.0 MiB may be used", "--refine 0"] {
        assert!(message.contains(needle), "'{needle}' not in: {message}");
    }
    // Without a limit known, nothing is refused.
    assert!(MemoryGuard::with_allowance(5_000, None).refusal(&estimate, None).is_none());
}

#[test]
fn the_memory_estimate_comes_near_what_the_build_stores() {
    // Scenes with exact blocks, low-rank ones and shadowed ones: the estimated stored operator
    // within a third of what the build stores.
    let scenes = [
        (five_piece(SurfaceParameters::default()).unwrap(), Method::Centroid, 4),
        (baffled_box().unwrap(), Method::linear(1.0 / 6.0).unwrap(), 2),
    ];
    for (scene, method, refine) in scenes {
        let c = case(scene, method, refine);
        let options =
            CompressionOptions { shadowed_blocks: ShadowedBlocks::On, ..Default::default() };
        let assembly = AssemblyOptions::default();
        let op = CompressedOperator::build(&c, &assembly, &options, None, &Silent).unwrap();
        let estimate = *op.memory_estimate.unwrap();
        let (estimated, stored) =
            (estimate.operator_bytes() as f64, op.stats.operator_bytes as f64);
        assert!(
            (estimated / stored - 1.0).abs() < 0.33,
            "{}: estimated {estimated}, stored {stored}: {estimate:?}",
            c.scene.name
        );
        assert!(estimate.peak_bytes() >= estimate.operator_bytes());
        assert_eq!(estimate.rounds, 0, "no device: no rounds of batches");
        // Entries evaluated in batches (by the CPU's evaluator here, as a device would): the
        // host's buffers of a round are among the build's peak.
        let batched = build_with(&c, &options, true).memory_estimate.unwrap();
        assert_eq!(batched.rounds, super::batched::ROUND_BYTES);
        assert!(batched.peak_bytes() >= estimate.peak_bytes() + batched.rounds / 2);
    }
}

#[test]
fn the_automatic_choice_keeps_small_faces_dense_and_compresses_large_ones() {
    let shape = |dof, elements, faces| ProblemShape { dof, elements, faces };
    // Small systems are dense, without a note.
    assert_eq!(OperatorChoice::Auto.decide(shape(9_616, 9_616, 1_200)), (false, None));
    // A city at refine 0: two elements per face (its dense matrix, 1.2 GiB, fits).
    let (compressed, why) = OperatorChoice::Auto.decide(shape(12_500, 12_500, 6_250));
    let why = why.unwrap();
    assert!(!compressed && why.contains("dense") && why.contains("2.0 elements per face"), "{why}");
    // The paper's surface at refine 6: thousands per face.
    let (compressed, why) = OperatorChoice::Auto.decide(shape(40_960, 40_960, 5));
    assert!(compressed && why.unwrap().contains("compressed"));
    // Asked for, either is built whatever the shape.
    assert_eq!(OperatorChoice::Compressed.decide(shape(100, 100, 50)), (true, None));
    assert_eq!(OperatorChoice::Dense.decide(shape(40_960, 40_960, 5)), (false, None));
}

#[test]
fn shadowed_blocks_are_chosen_where_faces_hold_many_elements() {
    let shape = |elements, faces| ProblemShape { dof: elements, elements, faces };
    // The lit city:4x4 at refine 3 (146 faces, 128 elements each): where they cost time.
    let (on, why) = ShadowedBlocks::Auto.decide(shape(18_688, 146));
    let why = why.unwrap();
    assert!(!on && why.contains("shadowed blocks off") && why.contains("128 elements"), "{why}");
    // The louvre window at refine 5: 2 048 elements a face.
    let (on, why) = ShadowedBlocks::Auto.decide(shape(40_960, 20));
    assert!(on && why.unwrap().contains("shadowed blocks on (2048 elements per face"));
    // From the threshold on, and as asked for whatever the shape.
    assert!(ShadowedBlocks::Auto.decide(shape(2_560, 5)).0);
    assert_eq!(ShadowedBlocks::On.decide(shape(100, 50)), (true, None));
    assert_eq!(ShadowedBlocks::Off.decide(shape(40_960, 20)), (false, None));
    assert_eq!(ShadowedBlocks::from(true), ShadowedBlocks::On);
}

#[test]
fn far_blocks_whose_boxes_clear_the_planes_have_no_pair_that_gives_nothing() {
    // `every_pair_gives` lets a cross approximation skip the test of each pair; wherever it
    // says so, the test of each pair must agree. The cube's faces meet along edges (blocks
    // beside them touch the other face's plane), the five-piece surface has its plate.
    let scenes = [(cube().unwrap(), 3), (five_piece(SurfaceParameters::default()).unwrap(), 3)];
    for (scene, refine) in scenes {
        let c = case(scene, Method::Centroid, refine);
        let options = CompressionOptions { leaf_size: 8, mixed_leaf_size: 8, ..Default::default() };
        let faces = FacePairs::new(&c.scene, &c.planner, &options, None);
        let (nodes, elements) = cluster_trees(&c.mesh, &c.disc, &options);
        let plan = BlockPlan::new(&nodes, &elements, &faces, &options, None, &Silent);
        let (mut clear, mut not) = (0, 0);
        for &(t, s) in &plan.far {
            let (tc, sc) = (&nodes.clusters[t], &elements.clusters[s]);
            if !faces.every_pair_gives(tc, sc) {
                not += 1;
                continue;
            }
            clear += 1;
            for &i in &nodes.order[tc.start..tc.end] {
                let node = &c.disc.node(i);
                for &j in &elements.order[sc.start..sc.end] {
                    let el = &c.mesh.elements()[j];
                    assert!(
                        !faces.nothing_between(node.face(), node.position, el),
                        "block ({t}, {s}): node {i}, element {j}"
                    );
                }
            }
        }
        assert!(clear > 0 && not > 0, "{clear} clear, {not} not");
    }
}

/// A dense block of `width` columns stored by its non-zero entries, in its own precision.
fn stored_sparse(data: &BlockData, width: usize) -> BlockData {
    let BlockData::Dense(d) = data else { panic!("not dense: {data:?}") };
    let mut values = Vec::new();
    d.extend_f64(&mut values);
    BlockData::Sparse(SparseRows::from_dense(&values, width, d.precision()))
}

#[test]
fn exact_blocks_are_stored_by_what_they_hold() {
    let block = |data: Vec<f64>| Block::new(0..3, 0..4, BlockData::exact(data));
    let x = [1.0, -2.0, 0.5, 3.0];
    // Mostly hidden: sparse rows, with the dense block's product.
    let entries = vec![0.0, 2.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.5, 0.0, 0.0, -1.0];
    let mut sparse = block(entries.clone());
    sparse.compact(Precision::F64);
    let BlockData::Sparse(rows) = &sparse.data else { panic!("{:?}", sparse.data) };
    assert_eq!(rows.csr(4), (vec![0, 1, 1, 3], vec![1, 0, 3]));
    assert!(sparse.bytes() < 8 * entries.len() as u64);
    let mut y = vec![10.0; 3];
    sparse.data.apply_add(&x, &mut y);
    let dense: Vec<f64> = entries
        .chunks(4)
        .map(|r| 10.0 + r.iter().zip(&x).map(|(a, b)| a * b).sum::<f64>())
        .collect();
    assert_eq!(y, dense);
    // Mostly seen: dense; all hidden: nothing stored.
    let mut seen = block((1..=12).map(f64::from).collect());
    seen.compact(Precision::F64);
    assert!(matches!(&seen.data, BlockData::Dense(Values::F64(d)) if d.len() == 12));
    let mut hidden = block(vec![0.0; 12]);
    hidden.compact(Precision::F64);
    assert!(matches!(&hidden.data, BlockData::Dense(d) if d.is_empty()) && hidden.bytes() == 0);
}

/// `op` written to bytes and read back, with the bytes.
fn written_and_read(op: &CompressedOperator) -> (CompressedOperator, Vec<u8>) {
    let mut out = BinaryWriter::new(Vec::new());
    op.write(&mut out).unwrap();
    let bytes = out.finish().unwrap();
    let mut input = BinaryReader::new(bytes.as_slice(), bytes.len() as u64, "op.bin");
    let read = CompressedOperator::read(&mut input).unwrap();
    input.finish().unwrap();
    (read, bytes)
}

#[test]
fn a_written_operator_reads_back_block_for_block() {
    // The five-piece surface has low-rank and dense blocks; one is stored sparse below. Values
    // in f64 (1e-8) and in f32 (1e-6). Without shadowed blocks, whose parts are written as
    // the low-rank and sparse blocks they stand for (`shadowed_blocks_of`).
    let c = case(five_piece(SurfaceParameters::default()).unwrap(), Method::Centroid, 4);
    for tolerance in [1e-8, 1e-6] {
        let mut op = plain(&c, tolerance, 16);
        // One block of each kind at least.
        let kinds = |op: &CompressedOperator| {
            let mut kinds = [0; 3];
            for b in &op.blocks {
                kinds[match b.data {
                    BlockData::Dense(_) => 0,
                    BlockData::Sparse(_) | BlockData::Leaf(_) => 1,
                    BlockData::LowRank(_) | BlockData::Seen(_) => 2,
                }] += 1;
            }
            kinds
        };
        if kinds(&op)[1] == 0 {
            // Store one exact block sparse, as a mostly hidden one would be.
            let b = op.blocks.iter_mut().find(|b| matches!(b.data, BlockData::Dense(_))).unwrap();
            b.data = stored_sparse(&b.data, b.col_range().len() * op.per);
            op.stats.operator_bytes =
                block_stats(&op.blocks, op.per).operator_bytes + order_bytes(op.dof, op.per);
        }
        assert!(kinds(&op).iter().all(|&k| k > 0), "{:?}", kinds(&op));
        // The factors' bytes, from the ranks and sizes, values in the tolerance's precision.
        let value_bytes = if tolerance < 1e-7 { 8 } else { 4 };
        let factor_bytes: usize = (op.blocks.iter())
            .filter_map(|b| match &b.data {
                BlockData::LowRank(f) => Some(f.rank() * (b.row_range().len() + f.columns())),
                _ => None,
            })
            .sum();
        assert_eq!(op.stats.low_rank_bytes, (factor_bytes * value_bytes) as u64);
        assert!(op.stats.low_rank_bytes < op.stats.operator_bytes);
        let (read, bytes) = written_and_read(&op);
        // What the build's walks cost is not saved.
        let stats = OperatorStats {
            faces_viewed: 0,
            faces_viewed_unseen: 0,
            faces_culled: 0,
            empty_block_pairs: 0,
            ..op.stats
        };
        assert_eq!((read.stats, read.pairs, read.zero_rows), (stats, op.pairs, op.zero_rows));
        assert_eq!(kinds(&read), kinds(&op));
        let x: Vec<f64> = (0..op.dof()).map(|i| (i as f64 * 0.7).sin()).collect();
        // Sums in parallel are not ordered: the products agree to rounding.
        let (a, b) = (read.apply(&x), op.apply(&x));
        let scale = b.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        assert!(a.iter().zip(&b).all(|(p, q)| (p - q).abs() <= 1e-14 * scale));

        // One bit changed anywhere: refused, by the checks of sizes or by the checksum.
        for at in (0..bytes.len()).step_by(bytes.len() / 97) {
            let mut damaged = bytes.clone();
            damaged[at] ^= 0x10;
            let mut input = BinaryReader::new(damaged.as_slice(), damaged.len() as u64, "op.bin");
            let read = CompressedOperator::read(&mut input).and_then(|_| input.finish());
            assert!(read.is_err(), "byte {at} of {}", bytes.len());
        }
    }
}

#[test]
fn products_of_many_vectors_are_each_vector_s_product() {
    // Linear method (three columns per element) on the five-piece surface: dense and low-rank
    // blocks, and one block stored sparse.
    let c =
        case(five_piece(SurfaceParameters::default()).unwrap(), Method::Linear { alpha: 0.2 }, 2);
    let mut op = compressed(&c, 1e-8, 8);
    let b = op.blocks.iter_mut().find(|b| matches!(b.data, BlockData::Dense(_))).unwrap();
    b.data = stored_sparse(&b.data, b.col_range().len() * op.per);
    assert!(op.blocks.iter().any(|b| matches!(b.data, BlockData::LowRank(_))));
    let n = op.dof();
    let xs: Vec<Vec<f64>> =
        (0..5).map(|v| (0..n).map(|i| ((i * (v + 2)) as f64 * 0.37).cos()).collect()).collect();
    let refs: Vec<&[f64]> = xs.iter().map(Vec::as_slice).collect();
    for (x, y) in xs.iter().zip(op.apply_many(&refs)) {
        let single = op.apply(x);
        let scale = single.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        let worst = y.iter().zip(&single).fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
        assert!(worst <= 1e-14 * scale, "{worst:.1e} of {scale:.1e}");
    }
}

#[test]
fn products_repeat_to_the_bit_under_a_parallel_load() {
    // Four threads, on which another thread keeps queueing work of its own: the blocks' work is
    // stolen differently each time, but their sums keep their grouping and order.
    use rayon::prelude::*;
    use std::sync::atomic::{AtomicBool, Ordering};
    let c = case(five_piece(SurfaceParameters::default()).unwrap(), Method::Centroid, 4);
    let op = compressed(&c, 1e-6, 8);
    assert!(op.blocks.len() > 400, "{} blocks: too few to split", op.blocks.len());
    let n = op.dof();
    let x: Vec<f64> = (0..n).map(|i| 1.0 + (i as f64 * 0.37).sin()).collect();
    let pool = rayon::ThreadPoolBuilder::new().num_threads(4).build().unwrap();
    let first = pool.install(|| op.apply(&x));
    let done = AtomicBool::new(false);
    std::thread::scope(|s| {
        s.spawn(|| {
            while !done.load(Ordering::Relaxed) {
                pool.install(|| {
                    (0..50_000u32)
                        .into_par_iter()
                        .with_max_len(64)
                        .map(|k| (k as f64).sqrt())
                        .sum::<f64>()
                });
            }
        });
        for round in 0..40 {
            let again = pool.install(|| op.apply(&x));
            let same = again.iter().zip(&first).all(|(a, b)| a.to_bits() == b.to_bits());
            if !same {
                done.store(true, Ordering::Relaxed);
            }
            assert!(same, "round {round}: the product changed in its last bits");
        }
        done.store(true, Ordering::Relaxed);
    });
}

#[test]
fn block_runs_cover_the_blocks_in_order_with_about_equal_bytes() {
    let c = case(five_piece(SurfaceParameters::default()).unwrap(), Method::Centroid, 3);
    let op = compressed(&c, 1e-6, 8);
    for count in [1, 2, 3, 7, 16, op.blocks.len(), op.blocks.len() + 5] {
        let runs = super::compressed::block_runs(&op.blocks, count);
        assert!(!runs.is_empty() && runs.len() <= count.max(1));
        assert_eq!(runs[0].start, 0);
        assert_eq!(runs.last().unwrap().end, op.blocks.len());
        assert!(runs.windows(2).all(|w| w[0].end == w[1].start));
        let bytes = |r: &std::ops::Range<usize>| -> u64 {
            op.blocks[r.clone()].iter().map(|b| b.data.bytes()).sum()
        };
        let total = bytes(&(0..op.blocks.len()));
        let largest = op.blocks.iter().map(|b| b.data.bytes()).max().unwrap();
        // No run holds more than its share and one block beyond it.
        for r in &runs {
            assert!(bytes(r) <= total / runs.len() as u64 + largest + 1, "{count} runs: {r:?}");
        }
    }
    assert_eq!(super::compressed::block_runs(&[], 4), vec![0..0]);
}

#[test]
fn an_operator_spread_over_ranks_equals_the_one_process_operator() {
    // Ranks as threads: the block plan walked in parts and gathered, each rank building its
    // share, the products summed over the ranks. The same blocks and pair classes as one
    // process's, products equal to rounding, and each rank holding a part of the blocks; on the
    // paper's surface and on a scene with shadows (the baffled box), both methods. GMRES over
    // the ranks, each holding its rows of the vectors, gives one process's solution.
    let linear = Method::linear(1.0 / 6.0).unwrap();
    let scenes = [
        (five_piece(SurfaceParameters::default()).unwrap(), Method::Centroid, 4),
        (five_piece(SurfaceParameters::default()).unwrap(), linear, 2),
        (baffled_box().unwrap(), Method::Centroid, 3),
    ];
    // The baffled box also with shadowed blocks, dealt out as units (leaves of 8, so that
    // the plate's blocks are large enough for shared factors to pay).
    let scenes = scenes.into_iter().map(|(s, m, r)| (s, m, r, false));
    let scenes = scenes.chain([(baffled_box().unwrap(), Method::Centroid, 4, true)]);
    for (scene, method, refine, shadowed_blocks) in scenes {
        let c = case(scene, method, refine);
        let leaves = if shadowed_blocks { 8 } else { CompressionOptions::default().leaf_size };
        let options = CompressionOptions {
            tolerance: 1e-8,
            shadowed_blocks: shadowed_blocks.into(),
            leaf_size: leaves,
            mixed_leaf_size: leaves,
            ..Default::default()
        };
        let assembly = AssemblyOptions::default();
        let silent = &crate::progress::Silent;
        let one = CompressedOperator::build(&c, &assembly, &options, None, silent).unwrap();
        let rho: Vec<f64> = c.disc.nodes().map(|n| n.rho).collect();
        let emission: Vec<f64> = (0..c.disc.dof()).map(|i| 1.0 + (i as f64 * 0.3).sin()).collect();
        let solver = crate::solve::SolverOptions { tolerance: 1e-12, ..Default::default() };
        let solve = |op: &CompressedOperator| {
            crate::solve::solve_by_products(op, &emission, (&rho, &rho), solver, 1e-8).unwrap()
        };
        let alone = solve(&one);
        for size in [2, 3] {
            let parts = crate::distributed::threads::run(size, |ranks| {
                let op =
                    CompressedOperator::build_shared(&c, &assembly, &options, None, silent, &ranks)
                        .unwrap();
                let d = op.max_product_difference(&|x| one.apply(x));
                let spread = solve(&op);
                let u =
                    spread.u.iter().zip(&alone.u).fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
                assert_eq!(spread.rows_eliminated, alone.rows_eliminated);
                assert!(spread.residual <= 1e-11, "residual {:.2e}", spread.residual);
                (op.stats, op.pairs, op.share.unwrap().operator_bytes, d.max(u))
            });
            for (rank, (stats, pairs, bytes, d)) in parts.iter().enumerate() {
                let what = format!("{method}, rank {rank} of {size}");
                assert_eq!(pairs, &one.pairs, "{what}");
                let s = &one.stats;
                assert_eq!(
                    (stats.near_entries, stats.near_blocks, stats.far_blocks, stats.empty_blocks),
                    (s.near_entries, s.near_blocks, s.far_blocks, s.empty_blocks),
                    "{what}"
                );
                // A shadowed block is dealt out whole: its factors are on one rank.
                assert_eq!(stats.low_rank_bytes, s.low_rank_bytes, "{what}");
                assert_eq!(stats.shadowed_blocks, s.shadowed_blocks, "{what}");
                assert_eq!(s.shadowed_blocks > 0, shadowed_blocks, "{what}");
                assert!(*d <= 1e-13, "{what}: products or solutions differ by {d:.2e}");
                assert!(*bytes < s.operator_bytes / 2 + s.operator_bytes / 4, "{what}: {bytes}");
            }
        }
    }
}

#[test]
fn shadowed_blocks_share_their_factors_and_keep_partly_visible_pairs_exact() {
    // The baffled box: its plate cuts admissible blocks between the walls. Their sub-blocks
    // seen whole and their leaves read one pair of factors per block; each part's product is
    // its standalone form's (the entries written out, as saved operators and devices keep
    // them), the leaves' partly visible entries are the dense matrix's, and the operator, its
    // products of many vectors and its saved copy match the dense products to the tolerance.
    let linear = Method::linear(1.0 / 6.0).unwrap();
    for (method, refine) in [(Method::Centroid, 4), (linear, 3)] {
        shadowed_blocks_of(case(baffled_box().unwrap(), method, refine));
    }
}

fn shadowed_blocks_of(c: Case) {
    let k = dense(&c);
    let tolerance = 1e-8;
    let options = CompressionOptions {
        tolerance,
        leaf_size: 8,
        mixed_leaf_size: 8,
        shadowed_blocks: ShadowedBlocks::On,
        ..Default::default()
    };
    let assembly = AssemblyOptions::default();
    let op = CompressedOperator::build(&c, &assembly, &options, None, &Silent).unwrap();
    let (mut seen, mut leaves, mut partial) = (0, 0, 0);
    for b in &op.blocks {
        let (rows, width) = (b.row_range().len(), b.col_range().len() * op.per);
        match &b.data {
            BlockData::Seen(_) => seen += 1,
            BlockData::Leaf(leaf) => {
                leaves += 1;
                let (starts, columns) = leaf.partial.csr(width);
                let mut values = Vec::new();
                leaf.partial.values.extend_f64(&mut values);
                for r in 0..rows {
                    let i = op.node_order[b.row_range().start + r];
                    for e in starts[r] as usize..starts[r + 1] as usize {
                        let q = columns[e] as usize;
                        let element = op.element_order[b.col_range().start + q / op.per];
                        let j = element * op.per + q % op.per;
                        let exact = k.get(i, j);
                        assert!((values[e] - exact).abs() <= 1e-14 * exact.abs(), "({i}, {j})");
                        partial += 1;
                    }
                }
            }
            _ => continue,
        }
        let x: Vec<f64> = (0..width).map(|q| (q as f64 * 0.37).cos()).collect();
        let (mut y, mut alone) = (vec![0.0; rows], vec![0.0; rows]);
        b.data.apply_add(&x, &mut y);
        b.data.standalone(rows, width).apply_add(&x, &mut alone);
        let scale = alone.iter().fold(1e-300f64, |m, v| m.max(v.abs()));
        let worst = y.iter().zip(&alone).fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
        assert!(worst <= 1e-13 * scale, "{:?}: {worst:.1e} of {scale:.1e}", b.data);
    }
    let what = format!("{}: {seen} seen, {leaves} leaves, {partial} partial", c.disc.method);
    assert!(seen > 0 && leaves > 0 && partial > 0, "{what}");
    assert!(op.pairs.partial > 0 && op.pairs.hidden > 0, "{:?}", op.pairs);
    let d = op.max_product_difference(&|x| k.apply(x));
    assert!(d <= 10.0 * tolerance, "{what}: {d:.2e} ({:?})", op.stats);

    let n = op.dof();
    let xs: Vec<Vec<f64>> =
        (0..3).map(|v| (0..n).map(|i| ((i * (v + 2)) as f64 * 0.37).cos()).collect()).collect();
    let refs: Vec<&[f64]> = xs.iter().map(Vec::as_slice).collect();
    let (read, _) = written_and_read(&op);
    // Read back, the parts are blocks of their own, and their bytes are counted as such.
    for s in [&op.stats, &read.stats] {
        assert!(0 < s.low_rank_bytes && s.low_rank_bytes < s.operator_bytes, "{s:?}");
    }
    assert!(op.stats.shadowed_blocks > 0 && read.stats.shadowed_blocks == 0, "{:?}", op.stats);
    for (x, y) in xs.iter().zip(op.apply_many(&refs)) {
        let single = op.apply(x);
        let scale = single.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        let from_file = read.apply(x);
        for other in [&y, &from_file] {
            let worst = other.iter().zip(&single).fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
            assert!(worst <= 1e-13 * scale, "{worst:.1e} of {scale:.1e}");
        }
    }
}
