// K x with K the compressed operator's blocks packed in flat arrays (src/operator/packed.rs has
// the layout): x in the blocks' column order, y in their row order. Three passes: V^T x of every
// low-rank block; every block's rows of its product into scratch; each row's contributions
// summed in block order (the same order every time). An operator too large for one binding is
// applied part by part, each part's sums added to y in part order (`accumulate`).

struct Params {
    blocks: u32,
    low_rank: u32,
    dof: u32,
    grid_x: u32,
    low_rank_at: u32,
    row_starts_at: u32,
    contributions_at: u32,
    accumulate: u32,
}

const LANES: u32 = 64u;
const DESCRIPTOR: u32 = 12u;
const DENSE: u32 = 0u;
const SPARSE: u32 = 1u;

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var<storage, read> values: array<f64>;
@group(0) @binding(2) var<storage, read> indices: array<u32>;
@group(0) @binding(3) var<storage, read> x: array<f64>;
@group(0) @binding(4) var<storage, read_write> scratch: array<f64>;
@group(0) @binding(5) var<storage, read_write> y: array<f64>;

fn field(b: u32, f: u32) -> u32 {
    return indices[b * DESCRIPTOR + f];
}

// V^T x of each low-rank block: a workgroup per block, its lanes over the rank.
@compute @workgroup_size(64)
fn low_rank_t(@builtin(workgroup_id) g: vec3<u32>, @builtin(local_invocation_index) lane: u32) {
    let n = g.x + g.y * params.grid_x;
    if n >= params.low_rank {
        return;
    }
    let b = indices[params.low_rank_at + n];
    let rows = field(b, 2u);
    let cols_start = field(b, 3u);
    let cols = field(b, 4u);
    let k = field(b, 5u);
    let v_at = field(b, 6u) + rows * k;
    let t_at = field(b, 8u);
    for (var q = lane; q < k; q += LANES) {
        var sum: f64 = 0.0;
        for (var c = 0u; c < cols; c++) {
            sum += values[v_at + c * k + q] * x[cols_start + c];
        }
        scratch[t_at + q] = sum;
    }
}

// Each block's rows of its product: a workgroup per block, its lanes over the rows.
@compute @workgroup_size(64)
fn block_rows(@builtin(workgroup_id) g: vec3<u32>, @builtin(local_invocation_index) lane: u32) {
    let b = g.x + g.y * params.grid_x;
    if b >= params.blocks {
        return;
    }
    let kind = field(b, 0u);
    let rows = field(b, 2u);
    let cols_start = field(b, 3u);
    let cols = field(b, 4u);
    let k = field(b, 5u);
    let at = field(b, 6u);
    let index_at = field(b, 7u);
    let t_at = field(b, 8u);
    let partial_at = field(b, 9u);
    for (var r = lane; r < rows; r += LANES) {
        var sum: f64 = 0.0;
        if kind == DENSE {
            let row = at + r * cols;
            for (var c = 0u; c < cols; c++) {
                sum += values[row + c] * x[cols_start + c];
            }
        } else if kind == SPARSE {
            let columns = index_at + rows + 1u;
            for (var j = indices[index_at + r]; j < indices[index_at + r + 1u]; j++) {
                sum += values[at + j] * x[cols_start + indices[columns + j]];
            }
        } else {
            let row = at + r * k;
            for (var q = 0u; q < k; q++) {
                sum += values[row + q] * scratch[t_at + q];
            }
        }
        scratch[partial_at + r] = sum;
    }
}

// Each row's sum of its blocks' contributions, in block order.
@compute @workgroup_size(64)
fn row_sums(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x + id.y * params.grid_x * LANES;
    if i >= params.dof {
        return;
    }
    let start = indices[params.row_starts_at + i];
    let end = indices[params.row_starts_at + i + 1u];
    var sum: f64 = 0.0;
    for (var j = start; j < end; j++) {
        sum += scratch[indices[params.contributions_at + j]];
    }
    if params.accumulate != 0u {
        y[i] += sum;
    } else {
        y[i] = sum;
    }
}
