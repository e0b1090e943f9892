//! Data shared with the shaders: flat arrays of reals (f64 or f32) with fixed strides, mirrored by
//! the constants of shaders/collocation.wgsl (checked by a test), and the uniform [`Params`].

use bytemuck::{Pod, Zeroable};

use super::shaders::Precision;
use crate::discretization::Discretization;

/// Reals per (row, face) view: the node in the face's frame (x, y, z, i, j, k), rho/π (0 where
/// the node sees nothing of the face), and 1 where the device clips the face's elements
/// (`assemble_cuts`), else 0.
pub const VIEW_STRIDE: usize = 8;
/// Reals per element: centroid in the face's frame, three vertices and three affine basis
/// functions relative to the centroid, face.
pub const ELEMENT_STRIDE: usize = 18;
/// Invocations per workgroup.
pub const WORKGROUP: u32 = 64;
/// Entries (4 reals each) of the uniform tables of IMT nodes and far-field rules.
pub const TABLE_SIZE: usize = 1024;

/// Mirrors `struct Params` of shaders/collocation.wgsl.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Pod, Zeroable)]
pub struct Params {
    /// Rows in the tile.
    pub rows: u32,
    /// Elements n.
    pub elements: u32,
    /// Faces.
    pub faces: u32,
    /// Unknowns (row length).
    pub dof: u32,
    /// IMT nodes.
    pub imt_count: u32,
    /// Index in the rules array of the far-field band headers.
    pub rule_offset: u32,
    /// Far-field bands (0: the rule is off).
    pub band_count: u32,
    /// Exceptions in the tile.
    pub exception_count: u32,
    /// Index of the first piece record in the exceptions array.
    pub piece_offset: u32,
    /// Invocations per row of the exceptions' dispatch grid.
    pub stride: u32,
    /// Pairs the near list can hold.
    pub near_capacity: u32,
    /// Cut records in the tile (shaders/clip.wgsl), not counting the last, which holds only the
    /// pass's pair count.
    pub cut_records: u32,
    /// Pieces the clipping kernel's stack may hold (at most [`MAX_PIECES`]): a pair that needs
    /// more is left to the host.
    pub piece_limit: u32,
    /// Pairs left to the host that the near list holds after its near pairs.
    pub overflow_capacity: u32,
    /// Pairs a shadow cuts that the near list holds after those, for `assemble_deep_cuts`.
    pub deep_capacity: u32,
    /// Non-zero where the clipping kernel's records are listed pairs' (src/gpu/pair_cuts.rs),
    /// not a tile's rows.
    pub pair_cuts: u32,
}

/// Bytes of the near list before its pairs: count, padding, indirect dispatch arguments, padding,
/// the clipping kernel's tallies (hidden, facing away, full, partial, left to the host), padding,
/// the count of the pairs it defers, padding, their dispatch's arguments, padding.
pub const NEAR_HEADER_BYTES: u64 = 96;
/// Byte offset of the deferred cut pairs' indirect dispatch arguments in the near list.
pub const DEEP_DISPATCH_OFFSET: u64 = 80;
/// Byte offset of the indirect dispatch arguments in the near list.
pub const NEAR_DISPATCH_OFFSET: u64 = 16;
/// Index (in u32) of the clipping kernel's first tally in the near list.
pub const CUT_TALLY_INDEX: usize = 8;
/// The clipping kernel's stack of pieces (`MAX_PIECES` of shaders/clip.wgsl).
pub const MAX_PIECES: u32 = 8;
/// Reals of a cut view before its shadows (clip.wgsl).
pub const CUT_VIEW_HEADER: usize = 6;
/// Reals of a shadow before its corners in a cut view (clip.wgsl).
pub const SHADOW_HEADER: usize = 5;
/// Reals per node of a face's element box tree (clip.wgsl).
pub const BOX_NODE_STRIDE: usize = 7;

/// The element box trees of every face after `packed` (as [`pack_elements`] leaves it), lengths
/// times `unit`, BOX_NODE_STRIDE reals per node: box (lo x, lo y, hi x, hi y), first position,
/// positions, index of the node past its subtree (in the face's tree); returns where each
/// face's tree starts.
pub fn pack_box_trees<'t>(
    trees: impl IntoIterator<Item = &'t crate::visibility::ElementBoxes>,
    unit: f64,
    packed: &mut Vec<f64>,
) -> Vec<u32> {
    trees
        .into_iter()
        .map(|tree| {
            let start = packed.len() as u32;
            for (range, (lo, hi), past) in tree.nodes() {
                packed.extend_from_slice(&[lo.x * unit, lo.y * unit, hi.x * unit, hi.y * unit]);
                packed.extend_from_slice(&[range.start as f64, range.len() as f64, past as f64]);
            }
            start
        })
        .collect()
}

const _: () = assert!(std::mem::size_of::<Params>() == 64);

/// Elements, ELEMENT_STRIDE reals each: the discretization's element-local data and the centroid,
/// lengths in units of `1 / unit` (a power of two; basis gradients scaled inversely).
pub fn pack_elements(disc: &Discretization, unit: f64) -> Vec<f64> {
    let mut v = Vec::with_capacity(disc.element_count() * ELEMENT_STRIDE);
    for j in 0..disc.element_count() {
        let (el, basis) = (disc.placed(j), disc.basis(j));
        let c = el.centroid_in_face * unit;
        v.extend_from_slice(&[c.x, c.y]);
        for p in el.local {
            v.extend_from_slice(&[p.x * unit, p.y * unit]);
        }
        for b in basis {
            v.extend_from_slice(&[b.c0, b.cx / unit, b.cy / unit]);
        }
        v.push(el.face() as f64);
    }
    v
}

/// The bytes of reals in the given precision.
pub fn real_bytes(values: &[f64], precision: Precision) -> Vec<u8> {
    match precision {
        Precision::F64 => bytemuck::cast_slice(values).to_vec(),
        Precision::F32 => {
            let v: Vec<f32> = values.iter().map(|&x| x as f32).collect();
            bytemuck::cast_slice(&v).to_vec()
        }
    }
}

/// The bytes of `values` in the given precision, borrowed where they are f64 already (no copy
/// of a batch's views on their way to the device).
pub fn reals_as_bytes(values: &[f64], precision: Precision) -> std::borrow::Cow<'_, [u8]> {
    match precision {
        Precision::F64 => std::borrow::Cow::Borrowed(bytemuck::cast_slice(values)),
        Precision::F32 => std::borrow::Cow::Owned(real_bytes(values, precision)),
    }
}

/// Reals from bytes in the given precision.
pub fn reals_from_bytes(bytes: &[u8], precision: Precision) -> Vec<f64> {
    match precision {
        Precision::F64 => bytemuck::pod_collect_to_vec::<u8, f64>(bytes),
        Precision::F32 => {
            bytemuck::pod_collect_to_vec::<u8, f32>(bytes).into_iter().map(f64::from).collect()
        }
    }
}
