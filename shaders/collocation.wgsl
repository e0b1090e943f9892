// Collocation integrals on the GPU: the mirror of src/kernels/moments.rs, src/kernels/exact.rs and
// src/kernels/far_field.rs (same names, same loop structure). The host prepends
// `alias real = f64|f32;`, the math library of that precision (the m_* functions),
// `const PER_ELEMENT: u32 = 1u|3u;` (basis functions per element) and `const FAR_FIELD: bool`
// (whether the far-field rule may be used: linear method or f32), so each kernel carries only the
// code it can run: on lavapipe the dead weight of the second-order and IMT code alone made the
// centroid kernel five times slower.
//
// Coordinates are those of each face's frame (src/scene/face.rs), in which the face lies in the
// plane height = 0 with normal (0, 0, 1).
//
// Bindings (group 0):
//   0 params      uniform  tile description
//   1 views       storage  VIEW_STRIDE reals per (row, face) of the tile: the node in the face's
//                          frame (x, y, z, i, j, k) and rho/pi, or 0 where it sees nothing of the
//                          face; then 1 where `assemble_cuts` writes the face's pairs, else 0
//   2 elements    storage  ELEMENT_STRIDE reals per element: centroid (face coordinates), 3 vertices
//                          and 3 affine basis functions (c0, cx, cy) relative to the centroid, face
//                          (relative coordinates keep the basis well conditioned, as on the CPU)
//   3 tables      uniform  TABLE_SIZE vec4s: the IMT rule on [0, 1] (node, weight), then from
//                          params.rule_offset one header per far-field band ((ratio + 1)², first
//                          entry, point count) and the bands' (u, v, w) points on the unit triangle
//                          (kernels::far_field); read by all invocations alike, hence a uniform
//   4 exceptions  storage  4 u32 per exception (row, element, first piece, piece count), then
//                          2 u32 per piece (first vertex, vertex count) from params.piece_offset;
//                          for `assemble_pairs`, 4 u32 per listed pair (view, element, first
//                          piece, piece count or WHOLE_ELEMENT); for `assemble_cuts` its cut
//                          records (clip.wgsl)
//   5 vertices    storage  x, y per vertex of the visible pieces, relative to their element's
//                          centroid; for `assemble_cuts` the views of the faces seen in part
//                          (clip.wgsl)
//   6 out         storage  rows x dof of K (rho/pi included), row-major
//   7 near        storage  the deferred pairs: an atomic count, indirect dispatch arguments, the
//                          tallies of `assemble_cuts`, the count and dispatch of the pairs it
//                          defers to `assemble_deep_cuts`; then (row, element) of up to
//                          params.near_capacity near pairs, of the pairs `assemble_cuts` left to the
//                          host, and the pass indices of those it deferred
//
// Invocation contract: `assemble_full` runs on a grid of (element, row) with 64-wide workgroups
// along the elements, and writes every entry of the tile, evaluating the whole element wherever the
// node sees the face, except the pairs that need the IMT moment (linear method, near the node),
// which it appends to the near list: those few pairs lie scattered among cheap ones, and a SIMD
// batch with one of them would run the IMT loop for all its lanes. `prepare_near` (one invocation)
// writes the indirect dispatch arguments, and `assemble_near` evaluates the listed pairs, one per
// invocation; it leaves the pairs of faces seen in part to `assemble_cuts` (clip.wgsl), which
// clips them on the device. `assemble_pieces` then runs one invocation per exception (1-D index linearised by
// params.stride) and overwrites that pair's entries with the integral over its visible pieces
// (zero pieces: a hidden pair).
//
// `assemble_pairs` serves the compressed operator (src/operator): one invocation per listed pair
// of any nodes and elements, views indexed by the pair's record rather than by (row, face), and
// the values written one after another (out[pair * PER_ELEMENT + l]).

const VIEW_STRIDE: u32 = 8u;
const ELEMENT_STRIDE: u32 = 18u;
const WORKGROUP: u32 = 64u;
const TABLE_SIZE: u32 = 1024u;

struct Tables {
    entries: array<vec4<real>, TABLE_SIZE>,
}

struct Params {
    rows: u32,
    elements: u32,
    faces: u32,
    dof: u32,
    imt_count: u32,
    rule_offset: u32,
    band_count: u32,
    exception_count: u32,
    piece_offset: u32,
    stride: u32,
    near_capacity: u32,
    cut_records: u32,
    piece_limit: u32,
    overflow_capacity: u32,
    deep_capacity: u32,
    pair_cuts: u32,
}

// The deferred pairs of `assemble_full` and the indirect dispatch of `assemble_near`; the pairs
// `assemble_cuts` classified, by class, and those it left to the host (listed after the near pairs).
struct NearList {
    count: atomic<u32>,
    _pad0: u32,
    _pad1: u32,
    _pad2: u32,
    dispatch_x: u32,
    dispatch_y: u32,
    dispatch_z: u32,
    _pad3: u32,
    hidden: atomic<u32>,
    facing_away: atomic<u32>,
    full: atomic<u32>,
    partial: atomic<u32>,
    overflow: atomic<u32>,
    _pad4: u32,
    _pad5: u32,
    _pad6: u32,
    deep_count: atomic<u32>,
    _pad7: u32,
    _pad8: u32,
    _pad9: u32,
    deep_dispatch_x: u32,
    deep_dispatch_y: u32,
    deep_dispatch_z: u32,
    _pad10: u32,
    pairs: array<u32>,
}

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var<storage, read> views: array<real>;
@group(0) @binding(2) var<storage, read> elements: array<real>;
@group(0) @binding(3) var<uniform> tables: Tables;
@group(0) @binding(4) var<storage, read> exceptions: array<u32>;
@group(0) @binding(5) var<storage, read> vertices: array<real>;
@group(0) @binding(6) var<storage, read_write> out: array<real>;
@group(0) @binding(7) var<storage, read_write> near: NearList;

// A node seen from a face's frame (kernels::Observer), with the row's factor rho/pi. Kernels move
// it to an element's centroid with `relative_to`.
struct Observer {
    position: vec3<real>,
    normal: vec3<real>,
    scale: real,
}

fn element_centroid(el: u32) -> vec2<real> {
    let b = el * ELEMENT_STRIDE;
    return vec2<real>(elements[b], elements[b + 1u]);
}

fn element_vertex(el: u32, k: u32) -> vec2<real> {
    let b = el * ELEMENT_STRIDE + 2u + 2u * k;
    return vec2<real>(elements[b], elements[b + 1u]);
}

fn element_face(el: u32) -> u32 {
    return u32(elements[el * ELEMENT_STRIDE + 17u]);
}

fn relative_to(obs: Observer, el: u32) -> Observer {
    let c = element_centroid(el);
    return Observer(vec3<real>(obs.position.x - c.x, obs.position.y - c.y, obs.position.z), obs.normal, obs.scale);
}

fn observer(row: u32, face: u32) -> Observer {
    return view(row * params.faces + face);
}

// The view at `index` of the views binding.
fn view(index: u32) -> Observer {
    let b = index * VIEW_STRIDE;
    return Observer(
        vec3<real>(views[b], views[b + 1u], views[b + 2u]),
        vec3<real>(views[b + 3u], views[b + 4u], views[b + 5u]),
        views[b + 6u],
    );
}

// One polygon edge seen from O (kernels::moments::EdgeTerms).
struct EdgeTerms {
    valid: bool,
    h: real,
    nu: vec2<real>,
    e: vec2<real>,
    ta: real,
    tb: real,
    s2: real,
    a: real,
    b: real,
}

// ln(r_b / r_a), accurate for every ratio (moments::half_log_ratio).
fn half_log_ratio(s2: real, ta: real, tb: real, len: real) -> real {
    let ra2 = s2 + ta * ta;
    let rb2 = s2 + tb * tb;
    let ratio = rb2 / ra2;
    if (ratio >= 0.5 && ratio <= 2.0) {
        return 0.5 * m_log1p(len * (ta + tb) / ra2);
    }
    return 0.5 * m_log(ratio);
}

fn edge_terms(p: vec2<real>, q: vec2<real>, z2: real, with_log: bool) -> EdgeTerms {
    var t: EdgeTerms;
    let d = q - p;
    let len = sqrt(d.x * d.x + d.y * d.y);
    t.valid = len > 0.0;
    if (!t.valid) {
        return t;
    }
    t.e = d / len;
    t.nu = vec2<real>(t.e.y, -t.e.x);
    t.h = 0.5 * dot(p + q, t.nu);
    t.ta = dot(p, t.e);
    t.tb = dot(q, t.e);
    t.s2 = t.h * t.h + z2;
    let s = sqrt(t.s2);
    t.a = m_atan2(s * len, t.s2 + t.ta * t.tb) / s;
    if (with_log) {
        t.b = half_log_ratio(t.s2, t.ta, t.tb, len);
    }
    return t;
}

// [ln(1 + q)/q] r at w, with q = (h² + t²)/z², t = S sinh w, r = S cosh w (moments::log_integral):
// one exponential gives both t and r, and for q >= 1 ln(1 + q) = 2 ln(r/z)
// = 2 [ln(S/z) + |w| - ln 2 + ln(1 + m²)], m = e^-|w| <= 1, with ln(S/z) given per edge.
fn log_integrand(w: real, s: real, h2: real, z: real, log_s_over_z: real) -> real {
    let e = m_exp(w);
    let inv = 1.0 / e;
    let t = 0.5 * s * (e - inv);
    let r = 0.5 * s * (e + inv);
    let q = (h2 + t * t) / (z * z);
    var ratio: real;
    if (q < 1e-8) {
        ratio = 1.0 - q * (0.5 - q / 3.0);
    } else if (q < 1.0) {
        ratio = m_log1p(q) / q;
    } else {
        let m = min(e, inv);
        ratio = 2.0 * (log_s_over_z + abs(w) - LN2 + m_log1p_unit(m * m)) / q;
    }
    return ratio * r;
}

// Widest interval in w one application of the IMT rule covers (moments::LOG_PANEL_WIDTH).
const LOG_PANEL_WIDTH: real = 8.0;

// z L_e by the IMT rule in w with t = S sinh w, on equal panels of at most LOG_PANEL_WIDTH
// (moments::log_integral).
fn log_integral(edge: EdgeTerms, z: real) -> real {
    if (edge.h == 0.0) {
        return 0.0;
    }
    let s = sqrt(edge.s2);
    let z2 = z * z;
    let h2 = edge.h * edge.h;
    let wa = m_asinh(edge.ta / s);
    let wb = m_asinh(edge.tb / s);
    let log_s_over_z = m_log(s / z);
    let panels = u32((wb - wa) / LOG_PANEL_WIDTH) + 1u;
    let width = (wb - wa) / real(panels);
    var acc: real = 0.0;
    for (var p = 0u; p < panels; p = p + 1u) {
        let a = wa + width * real(p);
        for (var k = 0u; k < params.imt_count; k = k + 1u) {
            let node = tables.entries[k];
            acc = acc + node.y * log_integrand(a + width * node.x, s, h2, z, log_s_over_z);
        }
    }
    return 0.5 * edge.h * width * acc / z;
}

// Scaled moments of a region (kernels::Moments).
struct Moments {
    m00: real,
    m10: real,
    m01: real,
    bxx: real,
    bxy: real,
    byy: real,
    zn00: real,
}

fn add_edge(m: ptr<function, Moments>, p: vec2<real>, q: vec2<real>, z: real, second_order: bool, need_log: bool) {
    let edge = edge_terms(p, q, z * z, second_order);
    if (!edge.valid) {
        return;
    }
    (*m).m00 = (*m).m00 + 0.5 * edge.h * edge.a;
    (*m).m10 = (*m).m10 - 0.5 * z * edge.nu.x * edge.a;
    (*m).m01 = (*m).m01 - 0.5 * z * edge.nu.y * edge.a;
    if (!second_order) {
        return;
    }
    let xy = edge.nu * (edge.h * edge.a) + edge.e * edge.b;
    (*m).bxx = (*m).bxx + z * edge.nu.x * xy.x;
    (*m).bxy = (*m).bxy + z * edge.nu.y * xy.x;
    (*m).byy = (*m).byy + z * edge.nu.y * xy.y;
    if (need_log) {
        (*m).zn00 = (*m).zn00 + log_integral(edge, z);
    }
}

// The affine basis function l of element el: (c0, cx, cy); the constant 1 for the centroid method.
fn basis(el: u32, l: u32) -> vec3<real> {
    if (PER_ELEMENT == 1u) {
        return vec3<real>(1.0, 0.0, 0.0);
    }
    let b = el * ELEMENT_STRIDE + 8u + 3u * l;
    return vec3<real>(elements[b], elements[b + 1u], elements[b + 2u]);
}

// Whether any basis function needs the non-elementary moment (exact::affine_weights).
fn needs_log(obs: Observer, el: u32) -> bool {
    if (PER_ELEMENT == 1u) {
        return false;
    }
    var any = false;
    for (var l = 0u; l < 3u; l = l + 1u) {
        let w = basis(el, l);
        any = any || (obs.normal.x * w.y + obs.normal.y * w.z != 0.0);
    }
    return any;
}

// ∫ G φ from the moments (exact::constant_weight and exact::affine_weights).
fn combine(m: Moments, obs: Observer, w: vec3<real>) -> real {
    let x = obs.position.x;
    let y = obs.position.y;
    let z = obs.position.z;
    let i = obs.normal.x;
    let j = obs.normal.y;
    let k = obs.normal.z;
    let d0 = w.x + w.y * x + w.z * y;
    let zm20 = 0.5 * (m.zn00 - m.bxx);
    let zm11 = -0.5 * m.bxy;
    let zm02 = 0.5 * (m.zn00 - m.byy);
    return -k * d0 * m.m00 + (i * d0 - z * k * w.y) * m.m10 + (j * d0 - z * k * w.z) * m.m01
        + i * w.y * zm20 + (i * w.z + j * w.y) * zm11 + j * w.z * zm02;
}

fn write_pair(base: u32, el: u32, m: Moments, obs: Observer) {
    for (var l = 0u; l < PER_ELEMENT; l = l + 1u) {
        out[base + l] = obs.scale * combine(m, obs, basis(el, l));
    }
}

// G(P, Q) at an in-plane point (kernels::Observer::kernel).
fn kernel(obs: Observer, q: vec2<real>) -> real {
    let d = vec3<real>(q - obs.position.xy, -obs.position.z);
    let r2 = dot(d, d);
    return dot(d, obs.normal) * obs.position.z / (r2 * r2);
}

// The far-field band for a node and element (FarFieldRule::band): 1 + its index, or 0 for none.
fn far_field_band(obs: Observer, el: u32) -> u32 {
    if (!FAR_FIELD || params.band_count == 0u) {
        return 0u;
    }
    var r2: real = 0.0;
    for (var k = 0u; k < 3u; k = k + 1u) {
        let v = element_vertex(el, k);
        r2 = max(r2, dot(v, v));
    }
    let d2 = dot(obs.position, obs.position);
    var band = 0u;
    for (var b = 0u; b < params.band_count; b = b + 1u) {
        if (d2 >= tables.entries[params.rule_offset + b].x * r2) {
            band = b + 1u;
        }
    }
    return band;
}

// The band's rule over one triangle for the element's three weights (FarFieldRule::integrate):
// accumulates ∫ G, ∫ G X, ∫ G Y and applies the weights once.
fn far_field_triangle(band: u32, obs: Observer, el: u32, a: vec2<real>, b: vec2<real>, c: vec2<real>) -> vec3<real> {
    let header = tables.entries[params.rule_offset + band - 1u];
    let first = u32(header.y);
    let count = u32(header.z);
    let jacobian = (b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x);
    // Four points per iteration: independent divisions overlap (a third faster on lavapipe).
    var g = vec3<real>(0.0, 0.0, 0.0);
    var k = 0u;
    for (; k + 3u < count; k = k + 4u) {
        let p0 = tables.entries[first + k];
        let p1 = tables.entries[first + k + 1u];
        let p2 = tables.entries[first + k + 2u];
        let p3 = tables.entries[first + k + 3u];
        let q0 = a + (b - a) * p0.x + (c - a) * p0.y;
        let q1 = a + (b - a) * p1.x + (c - a) * p1.y;
        let q2 = a + (b - a) * p2.x + (c - a) * p2.y;
        let q3 = a + (b - a) * p3.x + (c - a) * p3.y;
        let g0 = p0.z * kernel(obs, q0);
        let g1 = p1.z * kernel(obs, q1);
        let g2 = p2.z * kernel(obs, q2);
        let g3 = p3.z * kernel(obs, q3);
        g = g + vec3<real>(g0 + g1 + g2 + g3, g0 * q0.x + g1 * q1.x + g2 * q2.x + g3 * q3.x, g0 * q0.y + g1 * q1.y + g2 * q2.y + g3 * q3.y);
    }
    for (; k < count; k = k + 1u) {
        let point = tables.entries[first + k];
        let q = a + (b - a) * point.x + (c - a) * point.y;
        g = g + (point.z * kernel(obs, q)) * vec3<real>(1.0, q.x, q.y);
    }
    return jacobian * vec3<real>(dot(basis(el, 0u), g), dot(basis(el, 1u), g), dot(basis(el, 2u), g));
}

fn write_values(base: u32, scale: real, values: vec3<real>) {
    for (var l = 0u; l < PER_ELEMENT; l = l + 1u) {
        out[base + l] = scale * values[l];
    }
}

@compute @workgroup_size(64)
fn assemble_full(@builtin(global_invocation_id) gid: vec3<u32>) {
    let el = gid.x;
    let row = gid.y;
    if (el >= params.elements || row >= params.rows) {
        return;
    }
    let seen = observer(row, element_face(el));
    if (seen.scale == 0.0) {
        let base = row * params.dof + el * PER_ELEMENT;
        for (var l = 0u; l < PER_ELEMENT; l = l + 1u) {
            out[base + l] = 0.0;
        }
        return;
    }
    if (views[(row * params.faces + element_face(el)) * VIEW_STRIDE + 7u] != 0.0) {
        return;
    }
    let obs = relative_to(seen, el);
    let base = row * params.dof + el * PER_ELEMENT;
    if (PER_ELEMENT == 3u && far_field_band(obs, el) == 0u && needs_log(obs, el)) {
        let slot = atomicAdd(&near.count, 1u);
        if (slot < params.near_capacity) {
            near.pairs[2u * slot] = row;
            near.pairs[2u * slot + 1u] = el;
            return;
        }
    }
    whole_element(base, el, obs);
}

// The whole element: the far-field rule where the node is far enough, else the closed forms.
fn whole_element(base: u32, el: u32, obs: Observer) {
    let band = far_field_band(obs, el);
    if (band > 0u) {
        let values = far_field_triangle(band, obs, el, element_vertex(el, 0u), element_vertex(el, 1u), element_vertex(el, 2u));
        write_values(base, obs.scale, values);
        return;
    }
    closed_form_pair(base, el, obs);
}

// The closed forms over the whole element (exact::constant_weight, exact::affine_weights).
fn closed_form_pair(base: u32, el: u32, obs: Observer) {
    let o = obs.position.xy;
    let need_log = needs_log(obs, el);
    let second_order = PER_ELEMENT == 3u;
    var m: Moments;
    for (var k = 0u; k < 3u; k = k + 1u) {
        add_edge(&m, element_vertex(el, k) - o, element_vertex(el, (k + 1u) % 3u) - o, obs.position.z, second_order, need_log);
    }
    write_pair(base, el, m, obs);
}

@compute @workgroup_size(1)
fn prepare_near() {
    let count = min(atomicLoad(&near.count), params.near_capacity);
    near.dispatch_x = (count + WORKGROUP - 1u) / WORKGROUP;
    near.dispatch_y = 1u;
    near.dispatch_z = 1u;
}

@compute @workgroup_size(64)
fn assemble_near(@builtin(global_invocation_id) gid: vec3<u32>) {
    let index = gid.x;
    if (index >= min(atomicLoad(&near.count), params.near_capacity)) {
        return;
    }
    let row = near.pairs[2u * index];
    let el = near.pairs[2u * index + 1u];
    closed_form_pair(row * params.dof + el * PER_ELEMENT, el, relative_to(observer(row, element_face(el)), el));
}

@compute @workgroup_size(64)
fn assemble_pieces(@builtin(global_invocation_id) gid: vec3<u32>) {
    let index = gid.x + gid.y * params.stride;
    if (index >= params.exception_count) {
        return;
    }
    let row = exceptions[4u * index];
    let el = exceptions[4u * index + 1u];
    let obs = relative_to(observer(row, element_face(el)), el);
    visible_pieces(row * params.dof + el * PER_ELEMENT, el, obs, exceptions[4u * index + 2u], exceptions[4u * index + 3u]);
}

// A piece count that stands for the whole element in `assemble_pairs`.
const WHOLE_ELEMENT: u32 = 0xffffffffu;

// One invocation per listed pair (1-D index linearised by params.stride): record
// (view, element, first piece, piece count or WHOLE_ELEMENT), its values to out[index * PER_ELEMENT].
@compute @workgroup_size(64)
fn assemble_pairs(@builtin(global_invocation_id) gid: vec3<u32>) {
    let index = gid.x + gid.y * params.stride;
    if (index >= params.exception_count) {
        return;
    }
    let el = exceptions[4u * index + 1u];
    let obs = relative_to(view(exceptions[4u * index]), el);
    let piece_count = exceptions[4u * index + 3u];
    if (piece_count == WHOLE_ELEMENT) {
        whole_element(index * PER_ELEMENT, el, obs);
    } else {
        visible_pieces(index * PER_ELEMENT, el, obs, exceptions[4u * index + 2u], piece_count);
    }
}

// The integral over the visible pieces of an element (none: a hidden pair), to out[base..].
fn visible_pieces(base: u32, el: u32, obs: Observer, first_piece: u32, piece_count: u32) {
    let band = far_field_band(obs, el);
    if (band > 0u) {
        var values = vec3<real>(0.0, 0.0, 0.0);
        for (var p = first_piece; p < first_piece + piece_count; p = p + 1u) {
            let start = exceptions[params.piece_offset + 2u * p];
            let count = exceptions[params.piece_offset + 2u * p + 1u];
            let v0 = vec2<real>(vertices[2u * start], vertices[2u * start + 1u]);
            for (var k = 1u; k + 1u < count; k = k + 1u) {
                let a = start + k;
                let va = vec2<real>(vertices[2u * a], vertices[2u * a + 1u]);
                let vb = vec2<real>(vertices[2u * a + 2u], vertices[2u * a + 3u]);
                values = values + far_field_triangle(band, obs, el, v0, va, vb);
            }
        }
        write_values(base, obs.scale, values);
        return;
    }
    let o = obs.position.xy;
    let need_log = needs_log(obs, el);
    let second_order = PER_ELEMENT == 3u;
    var m: Moments;
    for (var p = first_piece; p < first_piece + piece_count; p = p + 1u) {
        let start = exceptions[params.piece_offset + 2u * p];
        let count = exceptions[params.piece_offset + 2u * p + 1u];
        for (var k = 0u; k < count; k = k + 1u) {
            let a = start + k;
            let b = start + (k + 1u) % count;
            let va = vec2<real>(vertices[2u * a], vertices[2u * a + 1u]);
            let vb = vec2<real>(vertices[2u * b], vertices[2u * b + 1u]);
            add_edge(&m, va - o, vb - o, obs.position.z, second_order, need_log);
        }
    }
    write_pair(base, el, m, obs);
}
