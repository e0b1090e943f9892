// The elements of faces seen in part, clipped and integrated on the device: the mirror of
// PairPlanner::visible (src/visibility/visible_part.rs) and of the convex polygon operations it
// uses (src/geometry/polygon.rs: clip_convex, convex_apart, convex_contains, subtract_convex),
// with the same tests, tolerances and order of operations, so that the pieces are the host's up to
// rounding. Appended to collocation.wgsl, whose bindings and integrals it uses.
//
// The host sends, per (row, face) of a tile that the row's node sees in part, a cut record of
// 4 u32 in `exceptions`: (first pair of the record in the pass, row in the tile, first element of
// the face, offset of the face's view in `vertices`); a last record holds only the pass's pair
// count. For listed pairs (params.pair_cuts, src/gpu/pair_cuts.rs) a record is (first pair, index
// of the node's view in `views`, offset in `exceptions` of the face's listed elements, offset of
// the face's view), a pair's entries go to out[pair * PER_ELEMENT], and the box trees are in
// `vertices`; an element listed as LEFT_TO_HOST is written as zeros and not tallied. A view in `vertices` (lengths times the tile's unit, face coordinates): a clip flag, the
// tangent plane's half-plane (normal x, y, offset), the view's length in reals, where the face's
// element box tree starts in `elements`, then per shadow its vertex count m, its box (lo x, lo y,
// hi x, hi y) and m vertices (x, y), counter-clockwise. A box tree (ElementBoxes) holds
// BOX_NODE_STRIDE reals per node, depth first: box, first position, positions, the node past its
// subtree.
//
// As on the host (PartSight::elements), a pair takes the class of the largest box of its face's
// tree that the view sees whole or not at all (PairPlanner::visible_in_box); only the elements
// of the leaves it does not are clipped one by one.
//
// `assemble_cuts` runs one invocation per (record, element of the face) and writes that pair's
// entries. The visible part is element ∩ clip minus each shadow in turn; a piece a shadow cuts
// is integrated at once where no later shadow may cut it, and kept on a stack with the first that
// may otherwise, depth first. A pair with a piece of more than MAX_VERTICES corners or more pieces
// kept than params.piece_limit (at most MAX_PIECES) is left to the host: the pair goes on the
// overflow list after the near pairs, with zero entries, and the host writes it from its own
// pieces. The pass tallies the pairs it classifies in the near list's header.

const MAX_VERTICES: u32 = 8u;
const MAX_PIECES: u32 = 8u;
// geometry::polygon::ON_LINE and visibility::face_view::PLANE_TOLERANCE.
const ON_LINE: real = 1e-13;
const PLANE_TOLERANCE: real = 1e-12;
// Reals of a view before its shadows, and of a shadow before its vertices.
const CUT_VIEW_HEADER: u32 = 6u;
const SHADOW_HEADER: u32 = 5u;
const BOX_NODE_STRIDE: u32 = 7u;
// ElementBoxes::LEAF: most positions of a node without halves.
const BOX_LEAF: u32 = 4u;
// A listed element the host evaluates itself (a thin element's pair, src/gpu/pair_cuts.rs).
const LEFT_TO_HOST: u32 = 0xffffffffu;

struct Polygon {
    v: array<vec2<real>, MAX_VERTICES>,
    n: u32,
}

// Pieces cut and not yet done with: their corners, and the offset of the next shadow to try. A
// function's variable, made (and zeroed) only for a pair that a shadow cuts.
struct Stack {
    pieces: array<Polygon, MAX_PIECES>,
    next: array<u32, MAX_PIECES>,
    top: u32,
}

// Whether this pair outgrew the kernel's limits.
var<private> overflowed: bool;

var<workgroup> tally_hidden: atomic<u32>;
var<workgroup> tally_facing_away: atomic<u32>;
var<workgroup> tally_full: atomic<u32>;
var<workgroup> tally_partial: atomic<u32>;

fn push_vertex(p: ptr<function, Polygon>, x: vec2<real>) {
    if ((*p).n == MAX_VERTICES) {
        overflowed = true;
        return;
    }
    (*p).v[(*p).n] = x;
    (*p).n = (*p).n + 1u;
}

fn polygon_box(p: ptr<function, Polygon>) -> vec4<real> {
    var lo = (*p).v[0];
    var hi = (*p).v[0];
    for (var k = 1u; k < (*p).n; k = k + 1u) {
        lo = min(lo, (*p).v[k]);
        hi = max(hi, (*p).v[k]);
    }
    return vec4<real>(lo, hi);
}

fn length_squared(d: vec2<real>) -> real {
    return d.x * d.x + d.y * d.y;
}

fn scale_squared(p: ptr<function, Polygon>) -> real {
    let b = polygon_box(p);
    return length_squared(b.zw - b.xy);
}

fn perp_dot(a: vec2<real>, b: vec2<real>) -> real {
    return a.x * b.y - a.y * b.x;
}

fn boxes_overlap(a: vec4<real>, b: vec4<real>) -> bool {
    return a.x < b.z && b.x < a.z && a.y < b.w && b.y < a.w;
}

// HalfPlane::left_of as (normal x, normal y, offset), and its value at x.
fn left_of(p: vec2<real>, q: vec2<real>) -> vec3<real> {
    let d = q - p;
    let normal = vec2<real>(-d.y, d.x);
    return vec3<real>(normal, -(normal.x * p.x + normal.y * p.y));
}

fn eval_half_plane(h: vec3<real>, x: vec2<real>) -> real {
    return (h.x * x.x + h.y * x.y) + h.z;
}

fn signed_area(p: ptr<function, Polygon>) -> real {
    var s: real = 0.0;
    for (var k = 0u; k < (*p).n; k = k + 1u) {
        s = s + perp_dot((*p).v[k], (*p).v[(k + 1u) % (*p).n]);
    }
    return 0.5 * s;
}

// polygon::clean: repeated corners dropped; whether three corners and some area are left.
fn clean(p: ptr<function, Polygon>, eps2: real) -> bool {
    var m = 0u;
    for (var k = 0u; k < (*p).n; k = k + 1u) {
        if (m == 0u || length_squared((*p).v[k] - (*p).v[m - 1u]) > eps2) {
            (*p).v[m] = (*p).v[k];
            m = m + 1u;
        }
    }
    while (m > 1u && length_squared((*p).v[0] - (*p).v[m - 1u]) <= eps2) {
        m = m - 1u;
    }
    (*p).n = m;
    return m >= 3u && abs(signed_area(p)) > eps2;
}

// polygon::line_values, into d (negated when `flip`).
fn line_values(p: ptr<function, Polygon>, h: vec3<real>, scale2: real, d: ptr<function, array<real, MAX_VERTICES>>) {
    let eps2 = ON_LINE * ON_LINE * scale2 * (h.x * h.x + h.y * h.y);
    for (var k = 0u; k < (*p).n; k = k + 1u) {
        let v = eval_half_plane(h, (*p).v[k]);
        if (v * v <= eps2) {
            (*d)[k] = 0.0;
        } else {
            (*d)[k] = v;
        }
    }
}

// polygon::keep_side: the part of `p` where the values `d` (times `sign`) are non-negative.
fn keep_side(p: ptr<function, Polygon>, d: ptr<function, array<real, MAX_VERTICES>>, sign: real, scale2: real, out: ptr<function, Polygon>) -> bool {
    (*out).n = 0u;
    var all_in = true;
    var all_out = true;
    for (var k = 0u; k < (*p).n; k = k + 1u) {
        let v = sign * (*d)[k];
        all_in = all_in && v >= 0.0;
        all_out = all_out && v <= 0.0;
    }
    if (all_in) {
        *out = *p;
    } else if (all_out) {
        return false;
    } else {
        let n = (*p).n;
        for (var k = 0u; k < n; k = k + 1u) {
            let a = (*p).v[k];
            let b = (*p).v[(k + 1u) % n];
            let da = sign * (*d)[k];
            let db = sign * (*d)[(k + 1u) % n];
            if (da >= 0.0) {
                push_vertex(out, a);
            }
            if ((da > 0.0 && db < 0.0) || (da < 0.0 && db > 0.0)) {
                push_vertex(out, a + (b - a) * (da / (da - db)));
            }
        }
    }
    return clean(out, ON_LINE * ON_LINE * scale2);
}

fn shadow_corners(shadow: u32) -> u32 {
    return u32(vertices[shadow]);
}

fn shadow_box(shadow: u32) -> vec4<real> {
    return vec4<real>(vertices[shadow + 1u], vertices[shadow + 2u], vertices[shadow + 3u], vertices[shadow + 4u]);
}

fn shadow_vertex(shadow: u32, k: u32) -> vec2<real> {
    let at = shadow + SHADOW_HEADER + 2u * (k % shadow_corners(shadow));
    return vec2<real>(vertices[at], vertices[at + 1u]);
}

// polygon::convex_apart: a side of the shadow has every corner of `p` strictly outside.
fn convex_apart(p: ptr<function, Polygon>, shadow: u32) -> bool {
    for (var k = 0u; k < shadow_corners(shadow); k = k + 1u) {
        let outside = left_of(shadow_vertex(shadow, k), shadow_vertex(shadow, k + 1u));
        var all = true;
        for (var i = 0u; i < (*p).n; i = i + 1u) {
            all = all && eval_half_plane(outside, (*p).v[i]) < 0.0;
        }
        if (all) {
            return true;
        }
    }
    return false;
}

// polygon::convex_contains: every corner of `p` in the shadow, up to the relative tolerance.
fn convex_contains(shadow: u32, p: ptr<function, Polygon>) -> bool {
    let b = shadow_box(shadow);
    let eps2 = ON_LINE * ON_LINE * length_squared(b.zw - b.xy);
    for (var k = 0u; k < shadow_corners(shadow); k = k + 1u) {
        let a = shadow_vertex(shadow, k);
        let e = shadow_vertex(shadow, k + 1u) - a;
        let margin2 = eps2 * length_squared(e);
        for (var i = 0u; i < (*p).n; i = i + 1u) {
            let cross = perp_dot(e, (*p).v[i] - a);
            if (!(cross >= 0.0 || cross * cross <= margin2)) {
                return false;
            }
        }
    }
    return true;
}

fn push_piece(stack: ptr<function, Stack>, p: ptr<function, Polygon>, next: u32) {
    if ((*stack).top >= params.piece_limit) {
        overflowed = true;
        return;
    }
    (*stack).pieces[(*stack).top] = *p;
    (*stack).next[(*stack).top] = next;
    (*stack).top = (*stack).top + 1u;
}

// polygon::subtract_convex: the pieces of `piece` outside the shadow pushed, each with `next`.
// polygon::subtract_convex: the pieces of `piece` outside the shadow handed to `emit_piece`, each
// with `next`, the shadow after this one. Returns false where it leaves `piece` as it is (one
// piece, equal to it: nothing is handed on), true otherwise (also where nothing is left). The
// last piece cut is held back until another is cut or the walk ends: until then it may be the
// only one.
fn subtract_shadow(stack: ptr<function, Stack>, piece: ptr<function, Polygon>, shadow: u32, next: u32) -> bool {
    var current = *piece;
    var inside_part: Polygon;
    var outside_part: Polygon;
    var held: Polygon;
    var held_count = 0u;
    var d: array<real, MAX_VERTICES>;
    var kept = false;
    for (var k = 0u; k < shadow_corners(shadow); k = k + 1u) {
        let inside = left_of(shadow_vertex(shadow, k), shadow_vertex(shadow, k + 1u));
        var piece_inside = true;
        for (var i = 0u; i < (*piece).n; i = i + 1u) {
            piece_inside = piece_inside && eval_half_plane(inside, (*piece).v[i]) >= 0.0;
        }
        if (piece_inside) {
            continue;
        }
        let scale2 = scale_squared(&current);
        line_values(&current, inside, scale2, &d);
        var all_in = true;
        for (var i = 0u; i < current.n; i = i + 1u) {
            all_in = all_in && d[i] >= 0.0;
        }
        if (kept && all_in) {
            continue;
        }
        if (keep_side(&current, &d, -1.0, scale2, &outside_part)) {
            // A second piece: the one held is not the only one.
            if (held_count > 0u) {
                emit_piece(stack, &held, next);
            }
            held = outside_part;
            held_count = held_count + 1u;
        }
        if (!keep_side(&current, &d, 1.0, scale2, &inside_part)) {
            break;
        }
        current = inside_part;
        kept = true;
    }
    if (held_count == 1u && same_polygon(&held, piece)) {
        return false;
    }
    if (held_count > 0u) {
        emit_piece(stack, &held, next);
    }
    return true;
}

// What the pass knows of the pair it clips: the node, the element and its centroid, the
// far-field band, whether the log moment is needed, the end of the view's shadows; the pieces
// integrated so far and their count.
struct CutContext {
    obs: Observer,
    el: u32,
    c: vec2<real>,
    band: u32,
    need_log: bool,
    end: u32,
}

var<private> cut_context: CutContext;
var<private> cut_integral: Integral;
var<private> cut_piece_count: u32;

// A piece that no shadow from `next` on may cut is integrated at once (the host's walk keeps it
// past each of them); another goes on the stack with the first that may.
fn emit_piece(stack: ptr<function, Stack>, p: ptr<function, Polygon>, next: u32) {
    let bounds = polygon_box(p);
    var shadow = next;
    while (shadow < cut_context.end) {
        if (boxes_overlap(bounds, shadow_box(shadow)) && !convex_apart(p, shadow)) {
            break;
        }
        shadow = shadow + SHADOW_HEADER + 2u * shadow_corners(shadow);
    }
    if (shadow < cut_context.end) {
        push_piece(stack, p, shadow);
        return;
    }
    cut_piece_count = cut_piece_count + 1u;
    let cx = cut_context;
    var acc = cut_integral;
    add_piece(&acc, p, cx.obs, cx.el, cx.c, cx.band, cx.need_log);
    cut_integral = acc;
}

fn same_polygon(a: ptr<function, Polygon>, b: ptr<function, Polygon>) -> bool {
    if ((*a).n != (*b).n) {
        return false;
    }
    for (var k = 0u; k < (*a).n; k = k + 1u) {
        if (any((*a).v[k] != (*b).v[k])) {
            return false;
        }
    }
    return true;
}

// What the pass found of one pair.
const CUT_HIDDEN: u32 = 0u;
const CUT_FACING_AWAY: u32 = 1u;
const CUT_FULL: u32 = 2u;
const CUT_PARTIAL: u32 = 3u;
const CUT_OVERFLOW: u32 = 4u;
const CUT_UNKNOWN: u32 = 5u;
const CUT_DEFERRED: u32 = 6u;

// PairPlanner::visible_in_box: the class of every polygon in the box (lo, hi) under the view at
// `view`, where the box alone tells; CUT_UNKNOWN otherwise.
fn visible_in_box(view: u32, lo: vec2<real>, hi: vec2<real>) -> u32 {
    var corners: Polygon;
    corners.n = 4u;
    corners.v[0] = lo;
    corners.v[1] = vec2<real>(hi.x, lo.y);
    corners.v[2] = hi;
    corners.v[3] = vec2<real>(lo.x, hi.y);
    if (vertices[view] != 0.0) {
        let h = vec3<real>(vertices[view + 1u], vertices[view + 2u], vertices[view + 3u]);
        let eps2 = PLANE_TOLERANCE * PLANE_TOLERANCE * length_squared(hi - lo) * (h.x * h.x + h.y * h.y);
        var all_behind = true;
        var all_clear = true;
        for (var k = 0u; k < 4u; k = k + 1u) {
            let v = eval_half_plane(h, corners.v[k]);
            all_behind = all_behind && v <= 0.0;
            all_clear = all_clear && v > 0.0 && v * v > eps2;
        }
        if (all_behind) {
            return CUT_FACING_AWAY;
        }
        if (!all_clear) {
            return CUT_UNKNOWN;
        }
    }
    let bounds = vec4<real>(lo, hi);
    let end = view + u32(vertices[view + 4u]);
    var clear = true;
    for (var shadow = view + CUT_VIEW_HEADER; shadow < end; shadow = shadow + SHADOW_HEADER + 2u * shadow_corners(shadow)) {
        if (boxes_overlap(bounds, shadow_box(shadow))) {
            if (convex_contains(shadow, &corners)) {
                return CUT_HIDDEN;
            }
            clear = false;
        }
    }
    if (clear) {
        return CUT_FULL;
    }
    return CUT_UNKNOWN;
}

// The class the face's box tree gives the element at `position` of its face's list: that of its
// largest box the view sees whole or not at all, or CUT_UNKNOWN where none is.
fn class_by_boxes(view: u32, position: u32) -> u32 {
    let tree = u32(vertices[view + 5u]);
    var node = 0u;
    var found = CUT_UNKNOWN;
    loop {
        let b = tree + BOX_NODE_STRIDE * node;
        let lo = vec2<real>(tree_value(b), tree_value(b + 1u));
        let hi = vec2<real>(tree_value(b + 2u), tree_value(b + 3u));
        found = visible_in_box(view, lo, hi);
        let count = u32(tree_value(b + 5u));
        if (found != CUT_UNKNOWN || count <= BOX_LEAF) {
            break;
        }
        // The halves split the node's positions at the middle; the second follows the first's
        // subtree.
        let middle = u32(tree_value(b + 4u)) + count / 2u;
        if (position < middle) {
            node = node + 1u;
        } else {
            node = u32(tree_value(tree + BOX_NODE_STRIDE * (node + 1u) + 6u));
        }
    }
    return found;
}

// A real of the box trees: uploaded after the elements for a tile's faces, or sent with the
// views of listed pairs (whose trees hold the listed elements of a face only).
fn tree_value(at: u32) -> real {
    if (params.pair_cuts != 0u) {
        return vertices[at];
    }
    return elements[at];
}

// The integral over the pieces found so far: moments, or the far-field rule's sums.
struct Integral {
    m: Moments,
    far: vec3<real>,
}

// A piece (face coordinates) of element el, whose centroid is c, added to the integral.
fn add_piece(acc: ptr<function, Integral>, piece: ptr<function, Polygon>, obs: Observer, el: u32, c: vec2<real>, band: u32, need_log: bool) {
    if (band > 0u) {
        let v0 = (*piece).v[0] - c;
        for (var k = 1u; k + 1u < (*piece).n; k = k + 1u) {
            (*acc).far = (*acc).far + far_field_triangle(band, obs, el, v0, (*piece).v[k] - c, (*piece).v[k + 1u] - c);
        }
        return;
    }
    let o = obs.position.xy;
    var m = (*acc).m;
    for (var k = 0u; k < (*piece).n; k = k + 1u) {
        let a = (*piece).v[k] - c;
        let b = (*piece).v[(k + 1u) % (*piece).n] - c;
        add_edge(&m, a - o, b - o, obs.position.z, PER_ELEMENT == 3u, need_log);
    }
    (*acc).m = m;
}

fn write_integral(base: u32, el: u32, acc: ptr<function, Integral>, obs: Observer, band: u32) {
    if (band > 0u) {
        write_values(base, obs.scale, (*acc).far);
    } else {
        write_pair(base, el, (*acc).m, obs);
    }
}

// The pieces of `one` (face coordinates) left by the shadows from `first` (the first that may cut
// it) to `end`, depth first: integrated into out[base..]; the pair's class.
fn cut_pieces(base: u32, el: u32, obs: Observer, one: ptr<function, Polygon>, first: u32, end: u32, clipped: bool) -> u32 {
    let band = far_field_band(obs, el);
    cut_context = CutContext(obs, el, element_centroid(el), band, needs_log(obs, el), end);
    cut_integral = Integral();
    cut_piece_count = 0u;
    var stack: Stack;
    var cut = false;
    // The element's part first, then the pieces on the stack, each from the first shadow that
    // may cut it.
    var piece = *one;
    var shadow = first;
    loop {
        let bounds = polygon_box(&piece);
        var gone = false;
        while (shadow < end) {
            let next = shadow + SHADOW_HEADER + 2u * shadow_corners(shadow);
            if (!boxes_overlap(bounds, shadow_box(shadow)) || convex_apart(&piece, shadow)) {
                shadow = next;
                continue;
            }
            if (convex_contains(shadow, &piece)) {
                gone = true;
                break;
            }
            if (!subtract_shadow(&stack, &piece, shadow, next)) {
                shadow = next;
                continue;
            }
            cut = true;
            gone = true;
            break;
        }
        if (!gone) {
            cut_piece_count = cut_piece_count + 1u;
            var acc = cut_integral;
            add_piece(&acc, &piece, obs, el, cut_context.c, band, cut_context.need_log);
            cut_integral = acc;
        }
        if (stack.top == 0u || overflowed) {
            break;
        }
        stack.top = stack.top - 1u;
        piece = stack.pieces[stack.top];
        shadow = stack.next[stack.top];
    }
    if (overflowed) {
        return CUT_OVERFLOW;
    }
    if (cut_piece_count == 0u) {
        return CUT_HIDDEN;
    }
    if (!cut && !clipped) {
        whole_element(base, el, obs);
        return CUT_FULL;
    }
    var acc = cut_integral;
    write_integral(base, el, &acc, obs, band);
    return CUT_PARTIAL;
}

// The pair (row, el) under the view at `view`: its entries to out[base..], and its class. Most
// elements of a face seen in part are seen whole or not at all, which the shadows' boxes and
// sides tell before any piece is cut.
fn cut_pair(base: u32, seen: Observer, el: u32, position: u32, view: u32, index: u32, defer: bool) -> u32 {
    overflowed = false;
    let obs = relative_to(seen, el);
    let by_boxes = class_by_boxes(view, position);
    if (by_boxes == CUT_FULL) {
        whole_element(base, el, obs);
    }
    if (by_boxes != CUT_UNKNOWN) {
        return by_boxes;
    }
    let c = element_centroid(el);
    var one: Polygon;
    one.n = 3u;
    for (var k = 0u; k < 3u; k = k + 1u) {
        one.v[k] = c + element_vertex(el, k);
    }
    var clipped = false;
    if (vertices[view] != 0.0) {
        let h = vec3<real>(vertices[view + 1u], vertices[view + 2u], vertices[view + 3u]);
        let b = polygon_box(&one);
        let eps2 = PLANE_TOLERANCE * PLANE_TOLERANCE * length_squared(b.zw - b.xy) * (h.x * h.x + h.y * h.y);
        var all_within = true;
        var any_below = false;
        for (var k = 0u; k < 3u; k = k + 1u) {
            let v = eval_half_plane(h, one.v[k]);
            all_within = all_within && (v <= 0.0 || v * v <= eps2);
            any_below = any_below || (v < 0.0 && v * v > eps2);
        }
        if (all_within) {
            return CUT_FACING_AWAY;
        }
        if (any_below) {
            var d: array<real, MAX_VERTICES>;
            var part: Polygon;
            let scale2 = scale_squared(&one);
            line_values(&one, h, scale2, &d);
            if (!keep_side(&one, &d, 1.0, scale2, &part)) {
                return CUT_FACING_AWAY;
            }
            one = part;
            clipped = true;
        }
    }
    let end = view + u32(vertices[view + 4u]);
    let bounds = polygon_box(&one);
    var shadow = view + CUT_VIEW_HEADER;
    while (shadow < end) {
        if (boxes_overlap(bounds, shadow_box(shadow)) && !convex_apart(&one, shadow)) {
            break;
        }
        shadow = shadow + SHADOW_HEADER + 2u * shadow_corners(shadow);
    }
    if (shadow < end) {
        if (convex_contains(shadow, &one)) {
            return CUT_HIDDEN;
        }
        // Few pairs are cut, scattered among many that are not: a SIMD batch with one of them
        // would clip for all its lanes. They are listed for a pass of their own.
        if (defer) {
            let slot = atomicAdd(&near.deep_count, 1u);
            if (slot < params.deep_capacity) {
                near.pairs[2u * (params.near_capacity + params.overflow_capacity) + slot] = index;
                return CUT_DEFERRED;
            }
        }
        return cut_pieces(base, el, obs, &one, shadow, end, clipped);
    }
    if (!clipped) {
        whole_element(base, el, obs);
        return CUT_FULL;
    }
    var acc: Integral;
    let band = far_field_band(obs, el);
    add_piece(&acc, &one, obs, el, c, band, needs_log(obs, el));
    write_integral(base, el, &acc, obs, band);
    return CUT_PARTIAL;
}

// The cut record holding pass pair `index` (the last whose first pair is at most `index`).
fn cut_record(index: u32) -> u32 {
    var lo = 0u;
    var hi = params.cut_records;
    while (hi - lo > 1u) {
        let middle = (lo + hi) / 2u;
        if (exceptions[4u * middle] <= index) {
            lo = middle;
        } else {
            hi = middle;
        }
    }
    return lo;
}

// Pair `index` of the pass: clipped (or listed for `assemble_deep_cuts` where `defer`), written,
// and tallied in the workgroup's counts.
fn cut_and_tally(index: u32, defer: bool) {
    let r = cut_record(index);
    let position = index - exceptions[4u * r];
    // The pair's element, the node's view of its face, where its entries go, and what names
    // the pair on the list of those left to the host (with the element).
    var el: u32;
    var seen: Observer;
    var base: u32;
    var key: u32;
    if (params.pair_cuts != 0u) {
        el = exceptions[exceptions[4u * r + 2u] + position];
        base = index * PER_ELEMENT;
        key = index;
        if (el == LEFT_TO_HOST) {
            zero_pair(base);
            return;
        }
        seen = view(exceptions[4u * r + 1u]);
    } else {
        key = exceptions[4u * r + 1u];
        el = exceptions[4u * r + 2u] + position;
        base = key * params.dof + el * PER_ELEMENT;
        seen = observer(key, element_face(el));
    }
    let found = cut_pair(base, seen, el, position, exceptions[4u * r + 3u], index, defer);
    if (found == CUT_DEFERRED) {
        return;
    }
    if (found != CUT_FULL && found != CUT_PARTIAL) {
        zero_pair(base);
    }
    switch found {
        case CUT_HIDDEN: { atomicAdd(&tally_hidden, 1u); }
        case CUT_FACING_AWAY: { atomicAdd(&tally_facing_away, 1u); }
        case CUT_FULL: { atomicAdd(&tally_full, 1u); }
        case CUT_PARTIAL: { atomicAdd(&tally_partial, 1u); }
        default: {
            let slot = atomicAdd(&near.overflow, 1u);
            if (slot < params.overflow_capacity) {
                near.pairs[2u * (params.near_capacity + slot)] = key;
                near.pairs[2u * (params.near_capacity + slot) + 1u] = el;
            }
        }
    }
}

fn zero_pair(base: u32) {
    for (var l = 0u; l < PER_ELEMENT; l = l + 1u) {
        out[base + l] = 0.0;
    }
}

fn clear_tallies(lane: u32) {
    if (lane == 0u) {
        atomicStore(&tally_hidden, 0u);
        atomicStore(&tally_facing_away, 0u);
        atomicStore(&tally_full, 0u);
        atomicStore(&tally_partial, 0u);
    }
}

fn add_tallies(lane: u32) {
    if (lane == 0u) {
        atomicAdd(&near.hidden, atomicLoad(&tally_hidden));
        atomicAdd(&near.facing_away, atomicLoad(&tally_facing_away));
        atomicAdd(&near.full, atomicLoad(&tally_full));
        atomicAdd(&near.partial, atomicLoad(&tally_partial));
    }
}

@compute @workgroup_size(64)
fn assemble_cuts(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(local_invocation_index) lane: u32) {
    clear_tallies(lane);
    workgroupBarrier();
    let index = gid.x + gid.y * params.stride;
    if (index < exceptions[4u * params.cut_records]) {
        cut_and_tally(index, true);
    }
    workgroupBarrier();
    add_tallies(lane);
}

@compute @workgroup_size(1)
fn prepare_deep_cuts() {
    let count = min(atomicLoad(&near.deep_count), params.deep_capacity);
    near.deep_dispatch_x = (count + WORKGROUP - 1u) / WORKGROUP;
    near.deep_dispatch_y = 1u;
    near.deep_dispatch_z = 1u;
}

// The pairs `assemble_cuts` listed, one per invocation.
@compute @workgroup_size(64)
fn assemble_deep_cuts(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(local_invocation_index) lane: u32) {
    clear_tallies(lane);
    workgroupBarrier();
    if (gid.x < min(atomicLoad(&near.deep_count), params.deep_capacity)) {
        cut_and_tally(near.pairs[2u * (params.near_capacity + params.overflow_capacity) + gid.x], false);
    }
    workgroupBarrier();
    add_tallies(lane);
}
