// Evaluates one math-library function over an input array, for the ulp tests.
// Bindings: 0 params (which function, count), 1 inputs (pairs x, y), 2 outputs.
// One invocation per input pair.

struct MathParams {
    function: u32,
    count: u32,
    _pad0: u32,
    _pad1: u32,
}

@group(0) @binding(0) var<uniform> math_params: MathParams;
@group(0) @binding(1) var<storage, read> math_in: array<real>;
@group(0) @binding(2) var<storage, read_write> math_out: array<real>;

@compute @workgroup_size(64)
fn math_eval(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = gid.x;
    if (i >= math_params.count) {
        return;
    }
    let x = math_in[2u * i];
    let y = math_in[2u * i + 1u];
    var r: real;
    switch (math_params.function) {
        case 0u: { r = m_atan(x); }
        case 1u: { r = m_atan2(x, y); }
        case 2u: { r = m_log(x); }
        case 3u: { r = m_log1p(x); }
        case 4u: { r = m_exp(x); }
        case 5u: { r = m_sinh(x); }
        case 6u: { r = m_asinh(x); }
        default: { r = x; }
    }
    math_out[i] = r;
}
