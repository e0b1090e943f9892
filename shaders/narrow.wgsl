// A tile of K narrowed from f64 (as the kernels computed it) to f32 for storage on the device,
// with each row's sums of |K_ij| and of the rounding |K_ij - f32(K_ij)|: the error the storage
// adds, measured rather than assumed. One workgroup per row; lane 0 adds the lanes' sums in
// order.

struct Params {
    rows: u32,
    dof: u32,
    row_offset: u32,
    _pad: u32,
}

const LANES: u32 = 64u;

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var<storage, read> wide: array<f64>;
@group(0) @binding(2) var<storage, read_write> narrow: array<f32>;
// Per row of K: (sum of |K_ij|, sum of the rounding errors).
@group(0) @binding(3) var<storage, read_write> norms: array<f64>;

var<workgroup> sums: array<f64, 64>;
var<workgroup> errors: array<f64, 64>;

@compute @workgroup_size(64)
fn narrow_rows(@builtin(workgroup_id) group: vec3<u32>, @builtin(local_invocation_index) lane: u32) {
    let r = group.x;
    if r >= params.rows {
        return;
    }
    let start = r * params.dof;
    var sum: f64 = 0.0;
    var error: f64 = 0.0;
    for (var c = lane; c < params.dof; c += LANES) {
        let k = wide[start + c];
        let stored = f32(k);
        narrow[start + c] = stored;
        sum += abs(k);
        error += abs(k - f64(stored));
    }
    sums[lane] = sum;
    errors[lane] = error;
    workgroupBarrier();
    if lane == 0u {
        var row_sum: f64 = 0.0;
        var row_error: f64 = 0.0;
        for (var k = 0u; k < LANES; k++) {
            row_sum += sums[k];
            row_error += errors[k];
        }
        let at = 2u * (params.row_offset + r);
        norms[at] = row_sum;
        norms[at + 1u] = row_error;
    }
}
