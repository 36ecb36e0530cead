// Slicemap rasterization: a render pipeline whose fragment stage ORs its slice bits into a
// storage buffer (WebGPU has no logic-op blending). Mirrors voxlod_cpu::voxelize::slicemap.
//
// Window coordinates arrive snapped to 1/256 pixel (host-side preparation). The vertex stage
// turns them into clip coordinates that the viewport transform maps back exactly: the render
// target is P×P (P a power of two), the map sits at offset (GUARD, GUARD) inside it, and
// X = x/(128·P) − 1 is exact in f32, so the rasterizer sees the host's snapped positions
// bit for bit and its coverage (pixel centres, top-left rule, 8 sub-pixel bits) is the
// reference's. The depth parameter q is not interpolated by the rasterizer: the fragment stage
// evaluates the triangle's plane at the pixel centre in the reference's order of operations.

struct SliceTri {
    x0: i32,
    y0: i32,
    x1: i32,
    y1: i32,
    x2: i32,
    y2: i32,
    q0: f32,
    q1: f32,
    q2: f32,
    dqdx: f32,
    dqdy: f32,
    flags: u32,
    id: u32,
}

struct Params {
    width: u32,
    height: u32,
    target_side: u32,
    slices: u32,
    words: u32,
    // bit 0 perspective, bit 1 local slicing, bit 2 front/back layers
    mode: u32,
    // 0: depth-range pass (local slicing), 1: slice pass
    pass_kind: u32,
    near: f32,
    span: f32,
    pad0: u32,
    pad1: u32,
    pad2: u32,
}

@group(0) @binding(0) var<storage, read> params: Params;
@group(0) @binding(1) var<storage, read> tris: array<SliceTri>;
@group(0) @binding(2) var<storage, read_write> bits: array<atomic<u32>>;
// Per column: [lo, hi] of d = z − near as f32 bits (d ≥ 0, so integer order is float order).
@group(0) @binding(3) var<storage, read_write> ranges: array<atomic<u32>>;

// Pixels between the render target's corner and the map (the host's guard band fits in it).
const GUARD: u32 = 2u;
const SUB: f32 = 256.0;

struct VOut {
    @builtin(position) pos: vec4<f32>,
    @location(0) @interpolate(flat) tri: u32,
}

// Clip position of window point (x, y) in sub-pixel units of the map.
fn clip_of(x: i32, y: i32) -> vec4<f32> {
    let s = 1.0 / (128.0 * f32(params.target_side));
    let g = i32(GUARD) * 256;
    return vec4<f32>(f32(x + g) * s - 1.0, 1.0 - f32(y + g) * s, 0.5, 1.0);
}

@vertex
fn vs_standard(@builtin(vertex_index) vi: u32) -> VOut {
    let t = tris[vi / 3u];
    let k = vi % 3u;
    var out: VOut;
    if k == 0u {
        out.pos = clip_of(t.x0, t.y0);
    } else if k == 1u {
        out.pos = clip_of(t.x1, t.y1);
    } else {
        out.pos = clip_of(t.x2, t.y2);
    }
    out.tri = vi / 3u;
    return out;
}

// The conservative emulation draws each triangle's pixel-aligned bounding quad: the pixels
// whose closed squares meet its bounding box, every centre strictly inside (no ties).
@vertex
fn vs_conservative(@builtin(vertex_index) vi: u32) -> VOut {
    let t = tris[vi / 6u];
    let k = vi % 6u;
    let lo = vec2<i32>(min(min(t.x0, t.x1), t.x2), min(min(t.y0, t.y1), t.y2));
    let hi = vec2<i32>(max(max(t.x0, t.x1), t.x2), max(max(t.y0, t.y1), t.y2));
    let size = vec2<i32>(i32(params.width), i32(params.height));
    let p0 = max((lo - vec2<i32>(1)) >> vec2<u32>(8u), vec2<i32>(0));
    let p1 = min(hi >> vec2<u32>(8u), size - vec2<i32>(1)) + vec2<i32>(1);
    var c = p0;
    if k == 1u || k == 3u {
        c = vec2<i32>(p1.x, p0.y);
    } else if k == 2u || k == 5u {
        c = vec2<i32>(p0.x, p1.y);
    } else if k == 4u {
        c = p1;
    }
    var out: VOut;
    // An empty span (p1 ≤ p0) gives a quad of zero or negative area: culled or no centre.
    out.pos = clip_of(c.x * 256, c.y * 256);
    if any(p1 <= p0) {
        out.pos = clip_of(p0.x * 256, p0.y * 256);
    }
    out.tri = vi / 6u;
    return out;
}

fn d_of_q(q: f32) -> f32 {
    var z = q;
    if (params.mode & 1u) != 0u {
        z = 1.0 / q;
    }
    return z - params.near;
}

fn normalized(d: f32, lo: f32, hi: f32) -> f32 {
    let r = hi - lo;
    if r > 0.0 {
        return clamp((d - lo) / r, 0.0, 1.0);
    }
    return 0.0;
}

fn slice_of(z: f32) -> u32 {
    return min(u32(z * f32(params.slices)), params.slices - 1u);
}

fn word_mask(first: u32, last: u32, w: u32) -> u32 {
    let lo = w * 32u;
    let hi = lo + 31u;
    if last < lo || first > hi {
        return 0u;
    }
    let a = max(first, lo) - lo;
    let b = min(last, hi) - lo;
    return (0xffffffffu >> (31u - b)) & (0xffffffffu << a);
}

// One fragment of column `col` with depths [d_lo, d_hi] (already in [0, span]).
fn fragment(col: vec2<u32>, t: SliceTri, d_lo: f32, d_hi: f32) {
    let c = col.y * params.width + col.x;
    if params.pass_kind == 0u {
        atomicMin(&ranges[2u * c], bitcast<u32>(d_lo));
        atomicMax(&ranges[2u * c + 1u], bitcast<u32>(d_hi));
        return;
    }
    var lo = 0.0;
    var hi = params.span;
    if (params.mode & 2u) != 0u {
        lo = bitcast<f32>(atomicLoad(&ranges[2u * c]));
        hi = bitcast<f32>(atomicLoad(&ranges[2u * c + 1u]));
    }
    if !(d_hi >= lo && d_lo <= hi) {
        return;
    }
    let first = slice_of(normalized(max(d_lo, lo), lo, hi));
    let last = slice_of(normalized(min(d_hi, hi), lo, hi));
    var layer = 0u;
    if (params.mode & 4u) != 0u && (t.flags & 1u) == 0u {
        layer = 1u;
    }
    let base = ((layer * params.height + col.y) * params.width + col.x) * params.words;
    for (var w = first / 32u; w <= last / 32u; w++) {
        atomicOr(&bits[base + w], word_mask(first, last, w));
    }
}

fn column_of(pos: vec4<f32>) -> vec2<u32> {
    return vec2<u32>(u32(pos.x) - GUARD, u32(pos.y) - GUARD);
}

@fragment
fn fs_standard(in: VOut) -> @location(0) vec4<f32> {
    let col = column_of(in.pos);
    if col.x >= params.width || col.y >= params.height {
        discard;
    }
    let t = tris[in.tri];
    let dx = (f32(col.x) + 0.5) - f32(t.x0) / SUB;
    let dy = (f32(col.y) + 0.5) - f32(t.y0) / SUB;
    let q = (t.q0 + t.dqdx * dx) + t.dqdy * dy;
    let d = d_of_q(q);
    if d >= 0.0 && d <= params.span {
        fragment(col, t, d, d);
    }
    discard;
}

// ---- Exact integer geometry for the conservative rule: 64-bit values as vec2<u32> (lo, hi),
// two's complement; operands are differences of sub-pixel coordinates, |v| < 2^23.

fn umul32(a: u32, b: u32) -> vec2<u32> {
    let a0 = a & 0xffffu;
    let a1 = a >> 16u;
    let b0 = b & 0xffffu;
    let b1 = b >> 16u;
    let p00 = a0 * b0;
    let mid = a0 * b1 + (p00 >> 16u);
    let mid2 = (mid & 0xffffu) + a1 * b0;
    let lo = (mid2 << 16u) | (p00 & 0xffffu);
    let hi = a1 * b1 + (mid >> 16u) + (mid2 >> 16u);
    return vec2<u32>(lo, hi);
}

fn neg64(a: vec2<u32>) -> vec2<u32> {
    let lo = ~a.x + 1u;
    return vec2<u32>(lo, ~a.y + select(0u, 1u, lo == 0u));
}

fn add64(a: vec2<u32>, b: vec2<u32>) -> vec2<u32> {
    let lo = a.x + b.x;
    return vec2<u32>(lo, a.y + b.y + select(0u, 1u, lo < a.x));
}

fn mul64(a: i32, b: i32) -> vec2<u32> {
    let p = umul32(u32(abs(a)), u32(abs(b)));
    if (a < 0) != (b < 0) {
        return neg64(p);
    }
    return p;
}

fn is_neg64(a: vec2<u32>) -> bool {
    return i32(a.y) < 0;
}

// a ≤ b (signed).
fn le64(a: vec2<u32>, b: vec2<u32>) -> bool {
    return !is_neg64(add64(b, neg64(a)));
}

// An edge E(p) = a·(x − xa) + b·(y − ya), positive inside.
struct Edge {
    a: i32,
    b: i32,
    xa: i32,
    ya: i32,
}

fn edge(from_: vec2<i32>, to: vec2<i32>) -> Edge {
    return Edge(-(to.y - from_.y), to.x - from_.x, from_.x, from_.y);
}

fn edge_at(e: Edge, x: i32, y: i32) -> vec2<u32> {
    return add64(mul64(e.a, x - e.xa), mul64(e.b, y - e.ya));
}

fn sign_at(e: Edge, x: i32, y: i32) -> i32 {
    let v = edge_at(e, x, y);
    if is_neg64(v) {
        return -1;
    }
    if v.x == 0u && v.y == 0u {
        return 0;
    }
    return 1;
}

@fragment
fn fs_conservative(in: VOut) -> @location(0) vec4<f32> {
    let col = column_of(in.pos);
    if col.x >= params.width || col.y >= params.height {
        discard;
    }
    let t = tris[in.tri];
    var v = array<vec2<i32>, 3>(vec2<i32>(t.x0, t.y0), vec2<i32>(t.x1, t.y1), vec2<i32>(t.x2, t.y2));
    var q = array<f32, 3>(t.q0, t.q1, t.q2);
    let area = add64(mul64(v[1].x - v[0].x, v[2].y - v[0].y), neg64(mul64(v[2].x - v[0].x, v[1].y - v[0].y)));
    let degenerate = area.x == 0u && area.y == 0u;
    var o1 = v[1];
    var o2 = v[2];
    if is_neg64(area) {
        o1 = v[2];
        o2 = v[1];
    }
    var e = array<Edge, 3>(edge(v[0], o1), edge(o1, o2), edge(o2, v[0]));
    let s0 = vec2<i32>(i32(col.x) * 256, i32(col.y) * 256);
    let s1 = s0 + vec2<i32>(256);
    // Separating axes: the bounding quad already overlaps the square; the edge lines.
    for (var i = 0; i < 3; i++) {
        let ed = e[i];
        if !degenerate {
            var cx = s0.x;
            if ed.a > 0 {
                cx = s1.x;
            }
            var cy = s0.y;
            if ed.b > 0 {
                cy = s1.y;
            }
            if sign_at(ed, cx, cy) < 0 {
                discard;
            }
        } else if ed.a != 0 || ed.b != 0 {
            let c0 = sign_at(ed, s0.x, s0.y);
            let c1 = sign_at(ed, s1.x, s0.y);
            let c2 = sign_at(ed, s0.x, s1.y);
            let c3 = sign_at(ed, s1.x, s1.y);
            if !(min(min(c0, c1), min(c2, c3)) <= 0 && max(max(c0, c1), max(c2, c3)) >= 0) {
                discard;
            }
        }
    }
    // The range of q over triangle ∩ square from its extreme candidates.
    var lo = 1e38;
    var hi = -1e38;
    for (var i = 0; i < 3; i++) {
        if all(v[i] >= s0) && all(v[i] <= s1) {
            lo = min(lo, q[i]);
            hi = max(hi, q[i]);
        }
    }
    if !degenerate {
        var corners = array<vec2<i32>, 4>(s0, vec2<i32>(s1.x, s0.y), vec2<i32>(s0.x, s1.y), s1);
        for (var k = 0; k < 4; k++) {
            let c = corners[k];
            if sign_at(e[0], c.x, c.y) >= 0 && sign_at(e[1], c.x, c.y) >= 0 && sign_at(e[2], c.x, c.y) >= 0 {
                let dx = f32(c.x - v[0].x) / SUB;
                let dy = f32(c.y - v[0].y) / SUB;
                let qc = (t.q0 + t.dqdx * dx) + t.dqdy * dy;
                lo = min(lo, qc);
                hi = max(hi, qc);
            }
        }
    }
    for (var i = 0; i < 3; i++) {
        let a = v[i];
        let b = v[(i + 1) % 3];
        let qa = q[i];
        let qb = q[(i + 1) % 3];
        for (var axis = 0; axis < 2; axis++) {
            // axis 0: vertical sides x = s (bounds on y); axis 1: horizontal sides y = s.
            let ua = select(a.y, a.x, axis == 0);
            let ub = select(b.y, b.x, axis == 0);
            let wa = select(a.x, a.y, axis == 0);
            let wb = select(b.x, b.y, axis == 0);
            let side0 = select(s0.y, s0.x, axis == 0);
            let side1 = select(s1.y, s1.x, axis == 0);
            let other0 = select(s0.x, s0.y, axis == 0);
            let other1 = select(s1.x, s1.y, axis == 0);
            let den = ub - ua;
            if den == 0 {
                continue;
            }
            for (var j = 0; j < 2; j++) {
                let s = select(side1, side0, j == 0);
                let num = s - ua;
                var n = num;
                var d = den;
                if den < 0 {
                    n = -num;
                    d = -den;
                }
                if n < 0 || n > d {
                    continue;
                }
                let wn = mul64(wb - wa, n);
                if le64(mul64(other0 - wa, d), wn) && le64(wn, mul64(other1 - wa, d)) {
                    let qx = qa + (qb - qa) * (f32(num) / f32(den));
                    lo = min(lo, qx);
                    hi = max(hi, qx);
                }
            }
        }
    }
    if lo > hi {
        discard;
    }
    let qmin = min(min(q[0], q[1]), q[2]);
    let qmax = max(max(q[0], q[1]), q[2]);
    lo = clamp(lo, qmin, qmax);
    hi = clamp(hi, qmin, qmax);
    var d_lo = d_of_q(lo);
    var d_hi = d_of_q(hi);
    if (params.mode & 1u) != 0u {
        d_lo = d_of_q(hi);
        d_hi = d_of_q(lo);
    }
    if d_hi >= 0.0 && d_lo <= params.span {
        fragment(col, t, max(d_lo, 0.0), min(d_hi, params.span));
    }
    discard;
}
