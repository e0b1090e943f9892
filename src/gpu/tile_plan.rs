//! The host's plan of a tile of rows for the GPU assembly: per (row, face) whether the row's node
//! sees the face and the node in the face's frame; for a face seen in part, either the view
//! itself (the tangent plane's clip and the shadows), whose elements the device clips
//! (shaders/clip.wgsl), or, where the host clips, the elements that are not fully visible with
//! their exact visible pieces. The host's work per tile then grows with the faces seen in part,
//! not with their elements.

use std::ops::Range;

use glam::DVec2;
use rayon::prelude::*;

use super::layout::VIEW_STRIDE;
use super::shaders::Precision;
use crate::discretization::Discretization;
use crate::mesh::Mesh;
use crate::scene::Scene;
use crate::visibility::{
    ElementBoxes, FaceSight, FaceView, PairPlanner, PairStats, RecentHiders, Views, Visibility,
};

/// Where the elements of a face seen in part are clipped to their visible pieces.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Clipping {
    /// On the host, one element at a time: their pieces are sent (f32 kernels).
    Host,
    /// On the device: the face's view is sent, once for all its elements (f64 kernels).
    Device,
}

/// What the geometry of a tile's plan is taken from.
#[derive(Clone, Copy)]
pub(super) struct Geometry<'a> {
    pub(super) scene: &'a Scene,
    pub(super) mesh: &'a Mesh,
    pub(super) disc: &'a Discretization,
    pub(super) boxes: &'a [ElementBoxes],
    pub(super) planner: &'a PairPlanner,
    /// Scene lengths times `unit` are what the device sees.
    pub(super) unit: f64,
    /// Where each face's element box tree starts on the device (with device clipping).
    pub(super) trees: &'a [u32],
}

/// The host's plan of one tile of rows.
pub(super) struct TilePlan {
    pub(super) rows: Range<usize>,
    /// VIEW_STRIDE reals per (row, face).
    pub(super) views: Vec<f64>,
    /// Clipped on the host: (row in tile, element, first piece, piece count), then (first
    /// vertex, count) per piece. Clipped on the device: the cut records (first pair, row in
    /// tile, first element of the face, offset of its view in `vertices`), then a last one
    /// holding the pass's pair count.
    pub(super) exceptions: Vec<u32>,
    pub(super) exception_count: u32,
    pub(super) piece_offset: u32,
    /// Piece vertices relative to their element's centroid, or the views of faces seen in part.
    pub(super) vertices: Vec<f64>,
    /// Cut records (none where the host clips).
    pub(super) cut_records: u32,
    /// (row, element) pairs the device clips.
    pub(super) cut_pairs: u64,
    /// Pairs of faces seen in part that the host clipped.
    pub(super) clipped_on_host: u64,
    /// The pairs classified on the host (those the device clips are counted by the device).
    pub(super) stats: PairStats,
}

impl TilePlan {
    /// Whether each of its per-tile buffers fits in one binding of `max_binding` bytes.
    pub(super) fn fits(&self, max_binding: u64, precision: Precision) -> bool {
        let reals = self.views.len().max(self.vertices.len()) * precision.bytes();
        reals.max(self.exceptions.len() * 4) as u64 <= max_binding
    }
}

/// The (row in tile, element) pairs of cut records (4 u32 each) that the device clips.
pub(super) fn record_pairs(records: &[u32], mesh: &Mesh, disc: &Discretization) -> Vec<(u32, u32)> {
    records
        .chunks_exact(4)
        .flat_map(|r| {
            let face = disc.face_of(r[2] as usize);
            mesh.face_range(face).map(move |el| (r[1], el as u32))
        })
        .collect()
}

/// Exception records and their pieces, as `assemble_pieces` reads them.
#[derive(Default)]
pub(super) struct PieceLists {
    records: Vec<u32>,
    piece_records: Vec<u32>,
    pub(super) vertices: Vec<f64>,
}

impl PieceLists {
    /// The pair (row in tile, element) with its pieces (relative to the element's centroid,
    /// times the unit); none: a hidden pair.
    fn push(&mut self, row: u32, element: u32, pieces: &[Vec<DVec2>]) {
        let first = (self.piece_records.len() / 2) as u32;
        self.records.extend_from_slice(&[row, element, first, pieces.len() as u32]);
        for piece in pieces {
            let start = (self.vertices.len() / 2) as u32;
            self.piece_records.extend_from_slice(&[start, piece.len() as u32]);
            self.vertices.extend(piece.iter().flat_map(|q| [q.x, q.y]));
        }
    }

    /// Records, their count, where the piece records start, and the vertices.
    pub(super) fn finish(mut self) -> (Vec<u32>, u32, u32, Vec<f64>) {
        let count = (self.records.len() / 4) as u32;
        let piece_offset = self.records.len() as u32;
        self.records.extend(self.piece_records);
        (self.records, count, piece_offset, self.vertices)
    }
}

/// The pieces of element `j` under `visibility` as the device integrates them: relative to the
/// element's centroid, times `unit`; the whole element where it is fully visible.
fn device_pieces(
    disc: &Discretization,
    j: usize,
    visibility: Visibility,
    unit: f64,
) -> Vec<Vec<DVec2>> {
    let el = disc.placed(j);
    let c = el.centroid_in_face;
    match visibility {
        Visibility::Skip(_) => Vec::new(),
        Visibility::Full => vec![el.local.iter().map(|&v| v * unit).collect()],
        Visibility::Partial(pieces) => {
            pieces.into_iter().map(|p| p.into_iter().map(|q| (q - c) * unit).collect()).collect()
        }
    }
}

/// The view of a face seen in part as `assemble_cuts` reads it (lengths times `unit`), with
/// where the face's element box tree starts.
pub(super) fn push_cut_view(view: &FaceView, unit: f64, tree: u32, out: &mut Vec<f64>) {
    let FaceView::Visible { clip, shadows } = view else {
        unreachable!("a face seen in part has a view")
    };
    let start = out.len();
    match clip {
        Some(hp) => out.extend_from_slice(&[1.0, hp.normal.x, hp.normal.y, hp.offset * unit]),
        None => out.extend_from_slice(&[0.0; 4]),
    }
    out.extend_from_slice(&[0.0, tree as f64]);
    for (shadow, (lo, hi)) in shadows.iter().zip(shadows.boxes()) {
        out.push(shadow.len() as f64);
        out.extend_from_slice(&[lo.x * unit, lo.y * unit, hi.x * unit, hi.y * unit]);
        out.extend(shadow.iter().flat_map(|q| [q.x * unit, q.y * unit]));
    }
    out[start + 4] = (out.len() - start) as f64;
}

/// A pair (row in tile, element) and its pieces as the device integrates them.
type PairPieces = (u32, u32, Vec<Vec<DVec2>>);

struct RowPlan {
    views: Vec<f64>,
    pieces: Vec<(u32, Vec<Vec<DVec2>>)>,
    /// Faces seen in part whose elements the device clips, with their view's offset in
    /// `cut_views`.
    cuts: Vec<(usize, usize)>,
    cut_views: Vec<f64>,
    /// Pairs of faces seen in part clipped here, element by element.
    clipped_here: u64,
    stats: PairStats,
}

fn plan_row(i: usize, g: Geometry, clipping: Clipping, hiders: &mut RecentHiders) -> RowPlan {
    let Geometry { scene, mesh, disc, boxes, planner, unit, trees } = g;
    let node = &disc.node(i);
    let faces = mesh.face_count();
    let mut plan = RowPlan {
        views: vec![0.0; faces * VIEW_STRIDE],
        pieces: Vec::new(),
        cuts: Vec::new(),
        cut_views: Vec::new(),
        clipped_here: 0,
        stats: PairStats::default(),
    };
    // A row that reflects nothing keeps every view "skipped" (all zeros): nothing is evaluated.
    let faces = (0..faces).map(|face| (face, mesh.face_range(face)));
    plan.stats =
        planner.walk_row(&node.viewer(), faces, Views::Fresh(hiders), |face, range, sight| {
            if let FaceSight::Hidden(_) = sight {
                return;
            }
            let frame = &scene.faces[face].frame;
            let (p, n) = (frame.to_local(node.position) * unit, frame.dir_to_local(node.normal));
            let scale = node.rho / std::f64::consts::PI;
            let view = &mut plan.views[face * VIEW_STRIDE..(face + 1) * VIEW_STRIDE];
            view[..7].copy_from_slice(&[p.x, p.y, p.z, n.x, n.y, n.z, scale]);
            let FaceSight::Part(mut part) = sight else { return };
            if clipping == Clipping::Device {
                view[7] = 1.0;
                plan.cuts.push((face, plan.cut_views.len()));
                push_cut_view(part.view(), unit, trees[face], &mut plan.cut_views);
                return;
            }
            plan.clipped_here += range.len() as u64;
            part.elements(&boxes[face], |k, visibility| {
                let j = range.start + k;
                if visibility != Visibility::Full {
                    plan.pieces.push((j as u32, device_pieces(disc, j, visibility, unit)));
                }
            });
        });
    plan
}

/// The plan of the tile `rows`: each row's on all cores, then joined.
pub(super) fn plan_tile(rows: Range<usize>, g: Geometry, clipping: Clipping) -> TilePlan {
    let row_plans: Vec<RowPlan> = rows
        .clone()
        .into_par_iter()
        .map_init(RecentHiders::default, |hiders, i| plan_row(i, g, clipping, hiders))
        .collect();
    let mut views = Vec::with_capacity(rows.len() * g.mesh.face_count() * VIEW_STRIDE);
    let mut lists = PieceLists::default();
    let mut cut_records = Vec::new();
    let mut cut_pairs = 0u64;
    let mut clipped_on_host = 0;
    let mut stats = PairStats::default();
    for (r, plan) in row_plans.into_iter().enumerate() {
        views.extend_from_slice(&plan.views);
        stats += plan.stats;
        clipped_on_host += plan.clipped_here;
        for (el, pieces) in &plan.pieces {
            lists.push(r as u32, *el, pieces);
        }
        let base = lists.vertices.len();
        for (face, offset) in plan.cuts {
            let range = g.mesh.face_range(face);
            let record = [cut_pairs as u32, r as u32, range.start as u32, (base + offset) as u32];
            cut_records.extend_from_slice(&record);
            cut_pairs += range.len() as u64;
        }
        lists.vertices.extend_from_slice(&plan.cut_views);
    }
    let (mut exceptions, exception_count, piece_offset, vertices) = lists.finish();
    let records = (cut_records.len() / 4) as u32;
    if clipping == Clipping::Device {
        exceptions = cut_records;
        exceptions.extend_from_slice(&[cut_pairs as u32, 0, 0, 0]);
    }
    TilePlan {
        rows,
        views,
        exceptions,
        exception_count,
        piece_offset,
        vertices,
        cut_records: records,
        cut_pairs,
        clipped_on_host,
        stats,
    }
}

/// The pairs `pairs` (row in the tile starting at `first_row`, element) of faces seen in part,
/// clipped on the host as the device would have, counted, as `assemble_pieces` reads them:
/// those the device's kernel left to the host.
pub(super) fn host_pieces(
    first_row: usize,
    pairs: &mut [(u32, u32)],
    g: Geometry,
) -> (PieceLists, PairStats) {
    let Geometry { mesh, disc, boxes, planner, unit, .. } = g;
    pairs.sort_unstable();
    let face_of = |el: u32| disc.face_of(el as usize);
    let groups: Vec<&[(u32, u32)]> =
        pairs.chunk_by(|a, b| a.0 == b.0 && face_of(a.1) == face_of(b.1)).collect();
    let planned: Vec<(Vec<PairPieces>, PairStats)> = groups
        .into_par_iter()
        .map_init(RecentHiders::default, |hiders, group| {
            let (row, face) = (group[0].0, face_of(group[0].1));
            let viewer = disc.node(first_row + row as usize).viewer();
            let view =
                planner.face_view_with(viewer.position, viewer.normal, viewer.face, face, hiders);
            let first = mesh.face_range(face).start;
            let mut stats = PairStats::default();
            let pieces = group
                .iter()
                .map(|&(_, el)| {
                    let visibility =
                        planner.visible(&view, boxes[face].polygon(el as usize - first));
                    stats.record(&visibility, 1);
                    (row, el, device_pieces(disc, el as usize, visibility, unit))
                })
                .collect();
            (pieces, stats)
        })
        .collect();
    let mut lists = PieceLists::default();
    let mut stats = PairStats::default();
    for (pairs, part_stats) in planned {
        stats += part_stats;
        for (row, el, pieces) in pairs {
            lists.push(row, el, &pieces);
        }
    }
    (lists, stats)
}
