// Conservative (and 6-separating thin) surface voxelization on the fixed-point lattice of
// voxlod-cpu's voxelize::lattice, with the exact integer tests of voxelize::overlap.
//
// One invocation per (triangle, column): a column is a voxel (iu, iv) of the triangle's clipped
// voxel range in the plane of the two axes other than its working axis w (the dominant axis of
// its normal). The plane gives the column's candidate voxels along w in f32, widened by a
// proven error bound (see mod.rs); each candidate is then decided by the exact test, so the f32
// estimate can only cost work, never change the answer. WGSL has no 64-bit integers: the i64
// and i128 arithmetic of the CPU reference is emulated on u32 words (two's complement,
// little-endian word order).

struct Tri {
    a: vec4<i32>,     // snapped vertex 0; w = working axis (0, 1, 2)
    b: vec4<i32>,     // snapped vertex 1; w = 1 if degenerate (scan the whole range along w)
    c: vec4<i32>,     // snapped vertex 2; w = triangle id
    lo: vec4<u32>,    // first voxel of the clipped range; w = columns along u
    hi: vec4<u32>,    // last voxel of the clipped range; w = 0
    plane: vec4<f32>, // (n_u / n_w, n_v / n_w, half width of the candidate interval, 0)
}

struct Params {
    dims: vec4<u32>,  // grid dims; w = mode (0 conservative, 1 thin)
    batch: vec4<u32>, // x = triangles in this batch, y = invocations, z = 1 to count, w = 0
}

@group(0) @binding(0) var<storage, read> params: Params;
@group(0) @binding(1) var<storage, read> tris: array<Tri>;
@group(0) @binding(2) var<storage, read> starts: array<u32>;
@group(0) @binding(3) var<storage, read_write> bits: array<atomic<u32>>;
@group(0) @binding(4) var<storage, read_write> counts: array<atomic<u32>>;

const VOXEL: i32 = 256;
const HALF: i32 = 128;

// ---- 64-bit integers as vec2<u32>(low, high) ----

fn i64_of(a: i32) -> vec2<u32> {
    return vec2<u32>(bitcast<u32>(a), select(0u, 0xffffffffu, a < 0));
}

fn add64(a: vec2<u32>, b: vec2<u32>) -> vec2<u32> {
    let lo = a.x + b.x;
    return vec2<u32>(lo, a.y + b.y + select(0u, 1u, lo < a.x));
}

fn neg64(a: vec2<u32>) -> vec2<u32> {
    return add64(~a, vec2<u32>(1u, 0u));
}

fn is_neg64(a: vec2<u32>) -> bool {
    return (a.y >> 31u) != 0u;
}

fn abs64(a: vec2<u32>) -> vec2<u32> {
    return select(a, neg64(a), is_neg64(a));
}

// a < b, signed.
fn lt64(a: vec2<u32>, b: vec2<u32>) -> bool {
    let ah = bitcast<i32>(a.y);
    let bh = bitcast<i32>(b.y);
    return ah < bh || (ah == bh && a.x < b.x);
}

// Unsigned 32 × 32 → 64.
fn umul32(a: u32, b: u32) -> vec2<u32> {
    let a0 = a & 0xffffu;
    let a1 = a >> 16u;
    let b0 = b & 0xffffu;
    let b1 = b >> 16u;
    let p00 = a0 * b0;
    let p01 = a0 * b1;
    let p10 = a1 * b0;
    let p11 = a1 * b1;
    let mid = p01 + p10;
    let mid_carry = select(0u, 0x10000u, mid < p01);
    let lo = p00 + (mid << 16u);
    let hi = p11 + (mid >> 16u) + mid_carry + select(0u, 1u, lo < p00);
    return vec2<u32>(lo, hi);
}

// |a| of an i32 as u32 (exact for every i32, including the most negative).
fn uabs(a: i32) -> u32 {
    return bitcast<u32>(abs(a));
}

// Signed 32 × 32 → 64.
fn mul64(a: i32, b: i32) -> vec2<u32> {
    let p = umul32(uabs(a), uabs(b));
    return select(p, neg64(p), (a < 0) != (b < 0));
}

// ---- 128-bit integers as vec4<u32> (word 0 lowest) ----

fn add128(a: vec4<u32>, b: vec4<u32>) -> vec4<u32> {
    let w0 = a.x + b.x;
    let c0 = select(0u, 1u, w0 < a.x);
    let s1 = a.y + b.y;
    let w1 = s1 + c0;
    let c1 = select(0u, 1u, s1 < a.y) + select(0u, 1u, w1 < s1);
    let s2 = a.z + b.z;
    let w2 = s2 + c1;
    let c2 = select(0u, 1u, s2 < a.z) + select(0u, 1u, w2 < s2);
    return vec4<u32>(w0, w1, w2, a.w + b.w + c2);
}

fn neg128(a: vec4<u32>) -> vec4<u32> {
    return add128(~a, vec4<u32>(1u, 0u, 0u, 0u));
}

// Signed i64 × i32 → i128 (|a| < 2^63).
fn mul128(a: vec2<u32>, b: i32) -> vec4<u32> {
    let m = abs64(a);
    let ub = uabs(b);
    let p0 = umul32(m.x, ub); // bits 0..64
    let p1 = umul32(m.y, ub); // bits 32..96
    let w1 = p0.y + p1.x;
    let w2 = p1.y + select(0u, 1u, w1 < p0.y);
    let p = vec4<u32>(p0.x, w1, w2, 0u);
    return select(p, neg128(p), is_neg64(a) != (b < 0));
}

// An unsigned 64-bit value times 2^7 (= HALF) as i128.
fn half128(a: vec2<u32>) -> vec4<u32> {
    return vec4<u32>(a.x << 7u, (a.y << 7u) | (a.x >> 25u), a.y >> 25u, 0u);
}

// -r <= d <= r for r >= 0.
fn within128(d: vec4<u32>, r: vec4<u32>) -> bool {
    let below = add128(r, neg128(d)); // r - d
    let above = add128(r, d);         // r + d
    return (below.w >> 31u) == 0u && (above.w >> 31u) == 0u;
}

// ---- the overlap tests of voxlod-cpu's voxelize::overlap ----

// Whether the interval of p misses [-r, r] strictly.
fn separated64(p0: vec2<u32>, p1: vec2<u32>, p2: vec2<u32>, r: vec2<u32>) -> bool {
    let nr = neg64(r);
    let all_above = lt64(r, p0) && lt64(r, p1) && lt64(r, p2);
    let all_below = lt64(p0, nr) && lt64(p1, nr) && lt64(p2, nr);
    return all_above || all_below;
}

fn separated32(p0: i32, p1: i32, p2: i32, r: i32) -> bool {
    return min(p0, min(p1, p2)) > r || max(p0, max(p1, p2)) < -r;
}

fn component(v: vec3<i32>, k: u32) -> i32 {
    return select(select(v.z, v.y, k == 1u), v.x, k == 0u);
}

// Projection of w onto the axis with components (a1, a2) in the plane of axes (k1, k2).
fn project(a1: i32, a2: i32, w: vec3<i32>, k1: u32, k2: u32) -> vec2<u32> {
    return add64(mul64(a1, component(w, k1)), mul64(a2, component(w, k2)));
}

// The normal e0 × e1 in i64.
fn cross64(e0: vec3<i32>, e1: vec3<i32>) -> array<vec2<u32>, 3> {
    return array<vec2<u32>, 3>(
        add64(mul64(e0.y, e1.z), neg64(mul64(e0.z, e1.y))),
        add64(mul64(e0.z, e1.x), neg64(mul64(e0.x, e1.z))),
        add64(mul64(e0.x, e1.y), neg64(mul64(e0.y, e1.x))),
    );
}

// Exact overlap of the closed triangle (a, b, c) with the closed box (thin = false) or the inner
// diamond (thin = true) of voxel `voxel`: overlap::box_overlap / overlap::diamond_overlap.
fn overlaps(a: vec3<i32>, b: vec3<i32>, c: vec3<i32>, voxel: vec3<i32>, thin: bool) -> bool {
    let centre = voxel * VOXEL + vec3<i32>(HALF);
    var w = array<vec3<i32>, 3>(a - centre, b - centre, c - centre);
    var e = array<vec3<i32>, 3>(w[1] - w[0], w[2] - w[1], w[0] - w[2]);
    for (var k = 0u; k < 3u; k++) {
        if separated32(component(w[0], k), component(w[1], k), component(w[2], k), HALF) {
            return false;
        }
    }
    for (var k = 0u; k < 3u; k++) {
        let k1 = (k + 1u) % 3u;
        let k2 = (k + 2u) % 3u;
        for (var i = 0u; i < 3u; i++) {
            let ei = e[i];
            var a1: i32;
            var a2: i32;
            var r: vec2<u32>;
            if thin {
                a1 = -component(ei, k2);
                a2 = component(ei, k1);
                r = umul32(max(uabs(a1), uabs(a2)), u32(HALF));
            } else {
                a1 = component(ei, k2);
                a2 = -component(ei, k1);
                r = umul32(uabs(a1) + uabs(a2), u32(HALF));
            }
            let p0 = project(a1, a2, w[0], k1, k2);
            let p1 = project(a1, a2, w[1], k1, k2);
            let p2 = project(a1, a2, w[2], k1, k2);
            if separated64(p0, p1, p2, r) {
                return false;
            }
        }
        if thin {
            let s0 = component(w[0], k1) + component(w[0], k2);
            let s1 = component(w[1], k1) + component(w[1], k2);
            let s2 = component(w[2], k1) + component(w[2], k2);
            let d0 = component(w[0], k1) - component(w[0], k2);
            let d1 = component(w[1], k1) - component(w[1], k2);
            let d2 = component(w[2], k1) - component(w[2], k2);
            if separated32(s0, s1, s2, HALF) || separated32(d0, d1, d2, HALF) {
                return false;
            }
        }
    }
    var n = cross64(e[0], e[1]);
    let d = add128(add128(mul128(n[0], w[0].x), mul128(n[1], w[0].y)), mul128(n[2], w[0].z));
    let m0 = abs64(n[0]);
    let m1 = abs64(n[1]);
    let m2 = abs64(n[2]);
    var norm: vec2<u32>;
    if thin {
        var big = m0;
        if lt64(big, m1) {
            big = m1;
        }
        if lt64(big, m2) {
            big = m2;
        }
        norm = big;
    } else {
        norm = add64(add64(m0, m1), m2);
    }
    return within128(d, half128(norm));
}

// ---- the kernel ----

fn axis_value(v: vec3<u32>, k: u32) -> u32 {
    return select(select(v.z, v.y, k == 1u), v.x, k == 0u);
}

fn set_voxel(v: vec3<u32>) {
    let dims = params.dims.xyz;
    let index = v.x + dims.x * (v.y + dims.y * v.z);
    atomicOr(&bits[index >> 5u], 1u << (index & 31u));
    if params.batch.z != 0u {
        atomicAdd(&counts[index], 1u);
    }
}

@compute @workgroup_size(64)
fn main(
    @builtin(workgroup_id) wg: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
    @builtin(local_invocation_index) local: u32,
) {
    let item = (wg.y * groups.x + wg.x) * 64u + local;
    if item >= params.batch.y {
        return;
    }
    // The triangle: the last whose start is <= item.
    var first = 0u;
    var count = params.batch.x;
    while count > 1u {
        let step = count / 2u;
        if starts[first + step] <= item {
            first += step;
            count -= step;
        } else {
            count = step;
        }
    }
    let t = tris[first];
    let local_item = item - starts[first];
    let axis = u32(t.a.w);
    let ku = (axis + 1u) % 3u;
    let kv = (axis + 2u) % 3u;
    let width = t.lo.w;
    let iu = axis_value(t.lo.xyz, ku) + local_item % width;
    let iv = axis_value(t.lo.xyz, kv) + local_item / width;
    var k0 = i32(axis_value(t.lo.xyz, axis));
    var k1 = i32(axis_value(t.hi.xyz, axis));
    if t.b.w == 0 {
        // The plane's interval along w, relative to the voxel of vertex a (mod.rs, "Candidates").
        let du = i32(iu) * VOXEL + HALF - component(t.a.xyz, ku);
        let dv = i32(iv) * VOXEL + HALF - component(t.a.xyz, kv);
        let aw = component(t.a.xyz, axis);
        let frac = f32(aw & (VOXEL - 1));
        let centre = (frac - f32(HALF) - (t.plane.x * f32(du) + t.plane.y * f32(dv))) / f32(VOXEL);
        let lo = clamp(floor(centre - t.plane.z), -1073741824.0, 1073741824.0);
        let hi = clamp(ceil(centre + t.plane.z), -1073741824.0, 1073741824.0);
        let base = aw >> 8u;
        k0 = max(k0, base + i32(lo));
        k1 = min(k1, base + i32(hi));
    }
    let thin = params.dims.w == 1u;
    for (var k = k0; k <= k1; k++) {
        var v: vec3<u32>;
        if axis == 0u {
            v = vec3<u32>(u32(k), iu, iv);
        } else if axis == 1u {
            v = vec3<u32>(iv, u32(k), iu);
        } else {
            v = vec3<u32>(iu, iv, u32(k));
        }
        if overlaps(t.a.xyz, t.b.xyz, t.c.xyz, vec3<i32>(v), thin) {
            set_voxel(v);
        }
    }
}
