//! The build of a compressed operator: the cluster trees, the block plan walked, the memory
//! guarded, and the blocks computed (on the CPU block by block, or in batches by the GPU).

use rayon::prelude::*;

use super::blocks::{BlockPlan, FacePairs, PLAN_STEPS};
use super::built::{Built, by_node_cluster, kept_blocks};
use super::cluster::{ClusterTree, Item};
use super::compressed::{Block, CompressedOperator, RankShare};
use super::entries::{Entries, FaceTally};
use super::guard::MemoryGuard;
use super::options::{CompressionOptions, ProblemShape};
use super::sampling::{build_list_bytes, estimate_memory};
use super::sight::ClusterSight;
use super::stats::{order_bytes, summed_over};
use super::stored::{Precision, precision_for};
use super::{batched, shadowed, share};
use crate::assembly::{AssemblyOptions, PairEvaluation, PairIntegrator, Problem};
use crate::discretization::Discretization;
use crate::distributed::Ranks;
use crate::error::Result;
use crate::mesh::Mesh;
use crate::progress::{Progress, in_stage};

impl CompressedOperator {
    /// Builds K for `problem`; `progress` counts the blocks (stage
    /// `compression`). With `batches` (the GPU's pair kernel), the entries are evaluated by it in
    /// batches (the exact blocks' pairs planned on the host, the cross approximations in
    /// lockstep), else on the CPU block by block.
    pub fn build(
        problem: &Problem,
        assembly: &AssemblyOptions,
        options: &CompressionOptions,
        batches: Option<&dyn PairEvaluation>,
        progress: &dyn Progress,
    ) -> Result<Self> {
        Self::build_with(problem, assembly, options, batches, progress, None)
    }

    /// As [`CompressedOperator::build`], this rank's part of the operator spread over `ranks`
    /// ([`crate::distributed`]): every rank calls it with the same problem. The block plan is
    /// walked in parts and gathered, each rank builds its share of the blocks, and the
    /// products sum the ranks' parts, so that every rank gets the whole `K x`.
    pub fn build_shared(
        problem: &Problem,
        assembly: &AssemblyOptions,
        options: &CompressionOptions,
        batches: Option<&dyn PairEvaluation>,
        progress: &dyn Progress,
        ranks: &Ranks,
    ) -> Result<Self> {
        Self::build_with(problem, assembly, options, batches, progress, Some(ranks))
    }

    pub(super) fn build_with(
        problem: &Problem,
        assembly: &AssemblyOptions,
        options: &CompressionOptions,
        batches: Option<&dyn PairEvaluation>,
        progress: &dyn Progress,
        ranks: Option<&Ranks>,
    ) -> Result<Self> {
        let Problem { scene, mesh, disc, planner, .. } = problem;
        let waited_before = ranks.map(|r| r.traffic().seconds);
        options.validate()?;
        assembly.quadrature.validate()?;
        let (shadowed, why) = options.shadowed_blocks.decide(ProblemShape::of(problem));
        if let Some(why) = why {
            progress.note(&why);
        }
        let options = &CompressionOptions { shadowed_blocks: shadowed.into(), ..*options };
        let per = disc.method.nodes_per_element();
        // Everything the build holds counts from here on (the guard's look at the resident
        // memory): the cluster trees, the plan, the lists, the blocks.
        let mut guard = MemoryGuard::new(disc.dof());
        let precision = precision_for(options.tolerance);
        let integrator = match precision {
            Precision::F32 => PairIntegrator::for_single_precision(disc.method, assembly),
            Precision::F64 => PairIntegrator::new(disc.method, assembly),
        };
        let (nodes, elements) =
            in_stage(progress, "clusters", || cluster_trees(mesh, disc, options));
        let sight = options
            .face_culling
            .decide(ProblemShape::of(problem))
            .then(|| ClusterSight::new(planner, disc, &nodes, progress));
        if let Some(sight) = &sight {
            progress.note(&sight.note());
        }
        let faces = FacePairs::new(scene, planner, options, sight.as_ref());
        let entries = Entries {
            mesh,
            disc,
            planner,
            integrator: &integrator,
            nodes: &nodes,
            elements: &elements,
            per,
            precision,
            faces: FaceTally::default(),
            sight: sight.as_ref(),
        };
        // Before the plan is walked and its blocks built, what they will hold is estimated from
        // a sample of it, and a run that cannot fit is refused now rather than after minutes.
        let size = ranks.map_or(1, |r| r.size());
        let mut estimate = in_stage(progress, "memory estimate", || {
            estimate_memory(&entries, &faces, options, scene.faces.len(), size)
        });
        if batches.is_some() {
            estimate.rounds = batched::ROUND_BYTES;
        }
        // What each cluster and node may see is held beside the trees, the same on every rank.
        estimate.trees += sight.as_ref().map_or(0, |s| s.bytes() as u64);
        progress.note(&estimate.note());
        guard.estimate = Some(estimate);
        let refusal = guard.refusal(&estimate, options.refine);
        let mine = u64::from(refusal.is_some());
        // Every rank refuses if one does (the others would wait for it in the collectives).
        if ranks.map_or(mine == 1, |r| r.gather(&[mine]).iter().any(|v| v[0] == 1)) {
            return Err(refusal.unwrap_or_else(|| guard.refused_elsewhere(&estimate)));
        }
        // The plan stops where its lists pass what the trees leave of the allowance.
        let budget = guard.plan_budget(estimate.trees);
        progress.start("block plan", PLAN_STEPS);
        let plan = match ranks {
            Some(ranks) => BlockPlan::new_shared(
                &nodes,
                &elements,
                &faces,
                options,
                &**ranks,
                budget.as_ref(),
                progress,
            ),
            None => BlockPlan::new(&nodes, &elements, &faces, options, budget.as_ref(), progress),
        };
        progress.finish();
        if let Some(budget) = &budget {
            let over = budget.is_over();
            let over =
                ranks.map_or(over, |r| r.gather(&[u64::from(over)]).iter().any(|v| v[0] == 1));
            if over {
                return Err(guard.plan_too_large(budget, estimate.trees));
            }
        }
        let tolerance = options.tolerance;
        let build = |plan: &BlockPlan, stage: &str| -> Result<Built> {
            // What the exact blocks store for certain, with the build's lists and the blocks'
            // slots, must fit before any is computed (counting every exact block in full would
            // refuse runs that fit: a partly visible block stores anything from none to all of
            // its entries, and on a city most store few); then every block built counts, and
            // the build stops where it would pass the allowance.
            let reflects = |i: usize| disc.node_rho(i) != 0.0;
            let certain = plan.certain_near_entries(&nodes, &elements, per, reflects);
            guard.check(precision.bytes() as u64 * certain + build_list_bytes(plan))?;
            let sub_blocks = shadowed::sub_blocks(&plan.shadowed);
            progress.start(stage, plan.near.len() + plan.far.len() + sub_blocks);
            let built = match batches {
                Some(evaluator) => batched::build_blocks(
                    &entries, plan, &faces, tolerance, evaluator, &guard, progress,
                )?,
                None => build_block_by_block(&entries, plan, &faces, tolerance, &guard, progress)?,
            };
            progress.finish();
            Ok(built)
        };
        let (built, empty) = match ranks {
            None => (build(&plan, "compression")?, plan.empty),
            Some(ranks) => {
                // The shadowed blocks first; then, in rounds, from what each rank's blocks
                // turned out to hold, the rest dealt so that the ranks' bytes come out about
                // equal.
                let (rank, size) = (ranks.rank(), ranks.size());
                let mine = share::shadowed_share(&plan, &nodes, &elements, per, (rank, size));
                let mut built = build(&mine, "shadowed blocks")?;
                let rounds = share::rest_rounds(&plan, &nodes, &elements, per);
                let empty = if rank == 0 { plan.empty } else { Default::default() };
                drop(plan);
                for round in rounds {
                    let held: u64 = built.blocks.iter().map(Block::bytes).sum();
                    let held: Vec<u64> = ranks.gather(&[held]).iter().map(|v| v[0]).collect();
                    let mine = share::dealt(round, &held, precision.bytes() as u64, rank);
                    built = built.joined(build(&mine, "compression")?);
                }
                (built, empty)
            }
        };

        let (blocks, mut stats, mut pairs) = kept_blocks(built, empty.blocks, per);
        stats.empty_block_pairs = empty.pairs;
        stats.faces_viewed = entries.faces.viewed();
        stats.faces_viewed_unseen = entries.faces.viewed_unseen();
        stats.faces_culled = entries.faces.culled();
        stats.operator_bytes += order_bytes(disc.dof(), per);
        let share = ranks.map(|ranks| {
            let operator_bytes = stats.operator_bytes;
            (stats, pairs) = summed_over(&**ranks, stats, pairs);
            let waited_seconds = ranks.traffic().seconds - waited_before.unwrap_or(0.0);
            let replicated_bytes = guard.resident_at_start().unwrap_or(0)
                + estimate.trees
                + estimate.plan
                + estimate.orders;
            RankShare { ranks: ranks.clone(), operator_bytes, waited_seconds, replicated_bytes }
        });
        let zero_rows = disc.nodes().filter(|n| n.rho == 0.0).count();
        Ok(Self {
            dof: disc.dof(),
            per,
            node_order: nodes.order,
            element_order: elements.order,
            blocks,
            stats,
            pairs,
            zero_rows,
            device: None,
            share,
            memory_estimate: Some(Box::new(estimate)),
        })
    }
}

/// The cluster trees of the nodes (points) and of the elements (their bounding boxes).
pub(super) fn cluster_trees(
    mesh: &Mesh,
    disc: &Discretization,
    options: &CompressionOptions,
) -> (ClusterTree, ClusterTree) {
    let node_items: Vec<Item> = disc
        .nodes()
        .map(|n| Item { point: n.position, lo: n.position, hi: n.position, face: n.face() })
        .collect();
    let element_items: Vec<Item> = mesh
        .elements()
        .iter()
        .map(|e| {
            let [a, b, c] = e.vertices;
            Item { point: e.centroid(), lo: a.min(b).min(c), hi: a.max(b).max(c), face: e.face }
        })
        .collect();
    let leaf = options.mixed_leaf_size.min(options.leaf_size);
    (ClusterTree::new(&node_items, leaf), ClusterTree::new(&element_items, leaf))
}

/// The blocks of `plan` on the CPU, block by block: near ones exact, far ones compressed to
/// `tolerance` or exact when their rank would not pay.
pub(super) fn build_block_by_block(
    entries: &Entries,
    plan: &BlockPlan,
    faces: &FacePairs,
    tolerance: f64,
    guard: &MemoryGuard,
    progress: &dyn Progress,
) -> Result<Built> {
    // Admissible blocks too small for a low rank to pay are exact from the start.
    let (small, far): (Vec<_>, Vec<_>) =
        plan.far.iter().partition(|&&(t, s)| entries.useful_rank(t, s).is_none());
    let exact: Vec<(usize, usize, bool)> = plan
        .near
        .iter()
        .map(|b| (b.t, b.s, false))
        .chain(small.into_iter().map(|(t, s)| (t, s, true)))
        .collect();
    let groups = by_node_cluster(&exact);
    // Each block is written into its own slot of the one list the operator keeps: a million
    // blocks gathered in parts and then joined were the peak of the furnished room's build.
    let shadowed_slots = shadowed::sub_blocks(&plan.shadowed);
    let mut blocks: Vec<Block> =
        (0..exact.len() + far.len() + shadowed_slots).map(|_| Block::nothing()).collect();
    let (near_slots, rest) = blocks.split_at_mut(exact.len());
    let (far_slots, shadowed_slots) = rest.split_at_mut(far.len());
    let mut slots_of_groups = Vec::with_capacity(groups.len());
    let mut near_rest = near_slots;
    for group in &groups {
        let (slots, after) = std::mem::take(&mut near_rest).split_at_mut(group.len());
        slots_of_groups.push((group, slots));
        near_rest = after;
    }
    // The shadowed blocks first: compressing one (a face against a face) holds its crosses and
    // their QR factors for a while, which adds least to the peak before the other blocks exist.
    let shadowed =
        shadowed::build(entries, &plan.shadowed, faces, tolerance, guard, progress, shadowed_slots);
    // The exact blocks of one node cluster together: each node's views of the faces are found
    // once for all of them.
    let near = slots_of_groups.into_par_iter().map(|(group, slots)| {
        let mut views = entries.node_views();
        let mut met = Built::default();
        for (&(t, s, incompressible), slot) in group.iter().zip(slots) {
            if guard.is_over() {
                break;
            }
            let (block, stats) = entries.exact_block(t, s, &mut views);
            guard.add(block.bytes());
            met.add(stats, incompressible);
            *slot = block;
        }
        progress.advance(group.len());
        met
    });
    let far = far_slots.par_iter_mut().zip(far).map(|(slot, (t, s))| {
        let mut met = Built::default();
        if !guard.is_over() {
            *slot = entries.compressed_or_exact(t, s, faces, tolerance, &mut met);
            guard.add(slot.bytes());
        }
        progress.advance(1);
        met
    });
    let met = near.chain(far).reduce(Built::default, Built::merged).merged(shadowed);
    guard.check(0)?;
    Ok(Built { blocks, ..met })
}
