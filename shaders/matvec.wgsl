// y = K x on the device, K stored by tiles of rows (row-major, `real` entries): one workgroup per
// row of a tile, its lanes summing strided parts of the row in f64, then lane 0 adding the
// lanes' sums in order (a fixed order: the same sums at every run). `vectors` products at once, each vector
// `dof` long in x and y.

struct Params {
    rows: u32,
    dof: u32,
    row_offset: u32,
    vectors: u32,
}

const LANES: u32 = 64u;

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var<storage, read> matrix: array<real>;
@group(0) @binding(2) var<storage, read> x: array<f64>;
@group(0) @binding(3) var<storage, read_write> y: array<f64>;

var<workgroup> partial: array<f64, 64>;

@compute @workgroup_size(64)
fn matvec(@builtin(workgroup_id) group: vec3<u32>, @builtin(local_invocation_index) lane: u32) {
    let r = group.x;
    if r >= params.rows {
        return;
    }
    let start = r * params.dof;
    for (var v = 0u; v < params.vectors; v++) {
        let at = v * params.dof;
        var sum: f64 = 0.0;
        for (var c = lane; c < params.dof; c += LANES) {
            sum += f64(matrix[start + c]) * x[at + c];
        }
        partial[lane] = sum;
        // One barrier, then lane 0 adds the lanes' sums in order (64 adds next to the row's
        // dof loads).
        workgroupBarrier();
        if lane == 0u {
            var total: f64 = 0.0;
            for (var k = 0u; k < LANES; k++) {
                total += partial[k];
            }
            y[at + params.row_offset + r] = total;
        }
        workgroupBarrier();
    }
}
