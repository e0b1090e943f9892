//! Tests of the block plan: its walk against its budget, the descent that locates a pair, what
//! it counts before the build, and that it settles every pair once.

use super::blocks::{self, BlockPlan, FacePairs, Located, ShadowedPart};
use super::build::cluster_trees;
use super::entries::{Entries, NodeViews};
use super::guard::MemoryGuard;
use super::stored::Precision;
use super::tests::{build_with, case};
use super::*;
use crate::assembly::{AssemblyOptions, PairIntegrator};
use crate::discretization::Method;
use crate::progress::Silent;
use crate::scene::{SurfaceParameters, baffled_box, cube, five_piece};

#[test]
fn a_plan_whose_lists_pass_its_budget_stops_its_walk() {
    let c = case(five_piece(SurfaceParameters::default()).unwrap(), Method::Centroid, 3);
    let options = CompressionOptions { leaf_size: 8, mixed_leaf_size: 8, ..Default::default() };
    let faces = FacePairs::new(&c.scene, &c.planner, &options, None);
    let (nodes, elements) = cluster_trees(&c.mesh, &c.disc, &options);
    let whole = BlockPlan::new(&nodes, &elements, &faces, &options, None, &Silent);
    let roomy = blocks::PlanBudget::new(1 << 30);
    let plan = BlockPlan::new(&nodes, &elements, &faces, &options, Some(&roomy), &Silent);
    assert!(!roomy.is_over() && plan.near.len() == whole.near.len() && roomy.used() > 0);
    let tight = blocks::PlanBudget::new(1_000);
    let cut = BlockPlan::new(&nodes, &elements, &faces, &options, Some(&tight), &Silent);
    assert!(tight.is_over() && cut.near.len() + cut.far.len() < whole.near.len() + whole.far.len());
    // The guard's error names what the plan had reached above what may be used.
    let guard = MemoryGuard::with_allowance(640, Some(1_000.0));
    let message = guard.plan_too_large(&tight, 0).to_string();
    assert!(
        message.contains("block plan") && message.contains("more than the 1.0 KiB"),
        "{message}"
    );
}

#[test]
fn a_pair_is_located_in_the_block_of_the_plan_that_holds_it() {
    // Every pair of a small scene: the descent finds the block the walk put it in.
    let scenes = [(cube().unwrap(), 2), (five_piece(SurfaceParameters::default()).unwrap(), 2)];
    for (scene, refine) in scenes {
        let c = case(scene, Method::Centroid, refine);
        for shadowed_blocks in [ShadowedBlocks::On, ShadowedBlocks::Off] {
            let options = CompressionOptions {
                leaf_size: 4,
                mixed_leaf_size: 4,
                shadowed_blocks,
                ..Default::default()
            };
            let faces = FacePairs::new(&c.scene, &c.planner, &options, None);
            let (nodes, elements) = cluster_trees(&c.mesh, &c.disc, &options);
            let plan = BlockPlan::new(&nodes, &elements, &faces, &options, None, &Silent);
            let holds = |t: usize, s: usize, (k, l): (usize, usize)| {
                let (tc, sc) = (&nodes.clusters[t], &elements.clusters[s]);
                (tc.start..tc.end).contains(&k) && (sc.start..sc.end).contains(&l)
            };
            let mut kinds = [0; 4];
            for k in 0..nodes.order.len() {
                for l in 0..elements.order.len() {
                    let at = (k, l);
                    let found = match BlockPlan::locate(&nodes, &elements, &faces, &options, at) {
                        Located::Empty => {
                            kinds[0] += 1;
                            !plan.near.iter().any(|b| holds(b.t, b.s, at))
                                && !plan.far.iter().any(|&(t, s)| holds(t, s, at))
                        }
                        Located::Near { t, s, seen_whole } => {
                            kinds[1] += 1;
                            plan.near.contains(&blocks::NearBlock { t, s, seen_whole })
                        }
                        Located::Far { t, s } => {
                            kinds[2] += 1;
                            plan.far.contains(&(t, s))
                        }
                        Located::Shadowed { t, s, part } => {
                            kinds[3] += 1;
                            let b = plan.shadowed.iter().find(|b| (b.t, b.s) == (t, s));
                            b.is_some_and(|b| match part {
                                ShadowedPart::Seen(a, c) => b.seen.contains(&(a, c)),
                                ShadowedPart::Leaf(a, c) => b.leaves.contains(&(a, c)),
                                ShadowedPart::Empty => true,
                            })
                        }
                    };
                    assert!(found, "pair {at:?} on {}", c.scene.name);
                }
            }
            assert!(kinds[1] > 0 && kinds[2] > 0, "{kinds:?}");
        }
    }
}

#[test]
fn the_memory_counted_before_the_build_is_what_blocks_seen_whole_store() {
    // The up-front check counts the exact blocks seen whole, in the rows of nodes that reflect
    // (the sky's rows are zero); each such block stores exactly that many entries, and the
    // operator as a whole no fewer. A lit city (buildings hide each other, rho = 0 sky) and the
    // baffled box.
    let scenes = [(crate::scene::lit_city(3, 2).unwrap(), 1), (baffled_box().unwrap(), 3)];
    for (scene, refine) in scenes {
        let c = case(scene, Method::Centroid, refine);
        // Small leaves, so that both kinds of exact block occur.
        let options = CompressionOptions {
            tolerance: 1e-8,
            leaf_size: 8,
            mixed_leaf_size: 8,
            ..Default::default()
        };
        let faces = FacePairs::new(&c.scene, &c.planner, &options, None);
        let (nodes, elements) = cluster_trees(&c.mesh, &c.disc, &options);
        let plan = BlockPlan::new(&nodes, &elements, &faces, &options, None, &Silent);
        let reflects = |i: usize| c.disc.node_rho(i) != 0.0;
        let integrator = PairIntegrator::new(c.disc.method, &AssemblyOptions::default());
        let entries = Entries {
            mesh: &c.mesh,
            disc: &c.disc,
            planner: &c.planner,
            integrator: &integrator,
            nodes: &nodes,
            elements: &elements,
            per: 1,
            precision: Precision::F64,
            faces: Default::default(),
            sight: None,
        };
        let mut views = NodeViews::default();
        let (mut whole, mut mixed) = (0, 0);
        for b in &plan.near {
            let one = BlockPlan { near: vec![*b], ..Default::default() };
            let certain = one.certain_near_entries(&nodes, &elements, 1, reflects);
            let (block, _) = entries.exact_block(b.t, b.s, &mut views);
            let stored = block.bytes() / 8;
            if b.seen_whole {
                whole += 1;
                assert_eq!(stored, certain, "block ({}, {})", b.t, b.s);
            } else {
                mixed += 1;
                assert_eq!(certain, 0);
            }
        }
        assert!(whole > 0 && mixed > 0, "{}: {whole} seen whole, {mixed} mixed", c.scene.name);
        let assembly = AssemblyOptions::default();
        let op = CompressedOperator::build(&c, &assembly, &options, None, &Silent);
        let certain = plan.certain_near_entries(&nodes, &elements, 1, reflects);
        assert!(certain <= op.unwrap().stats.near_entries, "{}", c.scene.name);
    }
}
#[test]
fn the_plan_settles_every_pair_once_and_counts_the_culled_ones() {
    // Every (node, element) pair is in one block of the plan: the blocks' pairs, empty ones
    // included, make up the whole matrix, and the statistics count the empty blocks' pairs
    // (`empty_block_pairs`) apart from the pairs the exact blocks walk and the entries the
    // low-rank blocks stand for. The progress reported reaches its last step exactly.
    struct Steps(std::sync::atomic::AtomicUsize);
    impl crate::progress::Progress for Steps {
        fn start(&self, _: &str, _: usize) {}
        fn advance(&self, steps: usize) {
            self.0.fetch_add(steps, std::sync::atomic::Ordering::Relaxed);
        }
        fn finish(&self) {}
        fn note(&self, _: &str) {}
    }
    let scenes = [(crate::scene::lit_city(3, 2).unwrap(), 1), (baffled_box().unwrap(), 2)];
    for (scene, refine) in scenes {
        let c = case(scene, Method::Centroid, refine);
        for shadowed_blocks in [ShadowedBlocks::On, ShadowedBlocks::Off] {
            let options = CompressionOptions {
                tolerance: 1e-6,
                leaf_size: 8,
                mixed_leaf_size: 8,
                shadowed_blocks,
                ..Default::default()
            };
            let faces = FacePairs::new(&c.scene, &c.planner, &options, None);
            let (nodes, elements) = cluster_trees(&c.mesh, &c.disc, &options);
            let steps = Steps(Default::default());
            let plan = BlockPlan::new(&nodes, &elements, &faces, &options, None, &steps);
            let size =
                |t: usize, s: usize| (nodes.clusters[t].len() * elements.clusters[s].len()) as u64;
            // Top-level exact and low-rank blocks, the parts of shadowed blocks that hold
            // something, and the empty blocks (some of them parts of shadowed blocks).
            let near: u64 = plan.near.iter().map(|b| size(b.t, b.s)).sum();
            let far: u64 = plan.far.iter().map(|&(t, s)| size(t, s)).sum();
            let parts: u64 = plan
                .shadowed
                .iter()
                .flat_map(|b| b.seen.iter().chain(&b.leaves))
                .map(|&(t, s)| size(t, s))
                .sum();
            let all = (c.disc.dof() * c.disc.element_count()) as u64;
            let label = format!("{}, shadowed blocks {shadowed_blocks:?}", c.scene.name);
            assert_eq!(near + far + parts + plan.empty.pairs, all, "{label}");
            assert_eq!(steps.0.into_inner(), super::blocks::PLAN_STEPS, "{label}");
            let op = build_with(&c, &options, false);
            assert_eq!(op.stats.empty_block_pairs, plan.empty.pairs, "{label}");
            assert!(plan.empty.pairs > 0, "{label}");
            let on = shadowed_blocks == ShadowedBlocks::On;
            assert_eq!(!plan.shadowed.is_empty(), on, "{label}");
        }
    }
}

#[test]
fn culling_what_no_node_of_a_cluster_sees_changes_no_product() {
    use crate::scene::{generated, lit_city};
    let linear = Method::linear(1.0 / 6.0).unwrap();
    let cases = [
        (lit_city(4, 4).unwrap(), Method::Centroid, 1),
        (lit_city(4, 4).unwrap(), linear, 0),
        (generated::city(3), Method::Centroid, 1),
        (generated::louvre(1), Method::Centroid, 1),
    ];
    for (scene, method, refine) in cases {
        let label = format!("{} faces, {method:?}, refine {refine}", scene.faces.len());
        let c = case(scene, method, refine);
        let with = |face_culling: FaceCulling, batched: bool| {
            let options = CompressionOptions { face_culling, ..Default::default() };
            build_with(&c, &options, batched)
        };
        let x: Vec<f64> = (0..c.disc.dof()).map(|k| ((k * 7919) % 101) as f64 / 101.0).collect();
        let off = with(FaceCulling::Off, false);
        for batched in [false, true] {
            let on = with(FaceCulling::On, batched);
            let (a, b) = (on.apply(&x), off.apply(&x));
            let worst = a.iter().zip(&b).map(|(p, q)| (p - q).abs()).fold(0.0, f64::max);
            assert!(a == b, "{label}, batched {batched}: products differ by up to {worst:e}");
            let (a, b) = (on.stats, off.stats);
            assert_eq!((a.near_entries, a.far_blocks), (b.near_entries, b.far_blocks), "{label}");
            assert!(a.faces_viewed < b.faces_viewed && a.faces_culled > 0, "{label}: {a:?}");
            assert_eq!(b.faces_culled, 0);
            // Culling spares views that would have found nothing; some views still do.
            assert!(a.faces_viewed_unseen < b.faces_viewed_unseen, "{label}: {a:?} {b:?}");
            assert!(b.faces_viewed_unseen < b.faces_viewed, "{label}: {b:?}");
        }
    }
}

#[test]
fn faces_in_sight_are_found_on_scenes_of_many_faces_and_moderate_size() {
    let shape = |dof, faces| ProblemShape { dof, elements: dof, faces };
    assert!(!FaceCulling::Auto.decide(shape(23_812, 842)));
    assert!(FaceCulling::Auto.decide(shape(93_380, 3_406)));
    // city:200x200: its walks would delay the memory estimate's refusal by minutes.
    assert!(!FaceCulling::Auto.decide(shape(641_602, 240_001)));
    assert!(
        FaceCulling::On.decide(shape(100, 5)) && !FaceCulling::Off.decide(shape(93_380, 3_406))
    );
    assert_eq!(FaceCulling::from(true), FaceCulling::On);
}
