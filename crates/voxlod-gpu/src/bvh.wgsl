// The BVH traversal shared by the kernels that cast rays (raycast.wgsl, ground_truth.wgsl):
// obvhs's compressed wide BVH (CWBVH), the mirror of voxlod-cpu's raycast::traverse (explicit
// stack, nearest child first) and raycast::triangle (Woop-Benthin-Wald watertight test). Child
// boxes come decompressed to f32 planes rounded outward, as on the CPU. The loop has no
// recursion and a fixed 32-entry stack in private memory. A kernel that includes this file
// binds `nodes` at binding 1 and `tris` at binding 2 of group 0.

struct Node {
    planes: array<vec4<f32>, 12>, // [2·axis + (0 min, 1 max)] × [children 0..4, 4..8]
    meta_lo: u32,                 // child_meta bytes 0..4
    meta_hi: u32,                 // child_meta bytes 4..8
    imask: u32,
    child_base: u32,
    primitive_base: u32,
    pad0: u32,
    pad1: u32,
    pad2: u32,
}

struct Tri {
    v0: vec4<f32>, // w = original triangle id (bits)
    v1: vec4<f32>,
    v2: vec4<f32>,
}

struct Hit {
    t: f32,
    triangle: u32, // 0xffffffff: miss
    u: f32,
    v: f32,
}

@group(0) @binding(1) var<storage, read> nodes: array<Node>;
@group(0) @binding(2) var<storage, read> tris: array<Tri>;

const STACK_SIZE: u32 = 32u;
const EXIT_SLACK: f32 = 1.000000953674316; // 1 + 2^-20
const MISS: u32 = 0xffffffffu;

struct BoxRay {
    origin: vec3<f32>,
    inv_dir: vec3<f32>,
    near: vec3<u32>, // per axis: 1 if the ray enters through the max plane
    oct_inv4: u32,
}

fn box_ray(origin: vec3<f32>, dir_in: vec3<f32>) -> BoxRay {
    let dir = select(dir_in, vec3<f32>(0.0), dir_in == vec3<f32>(0.0)); // -0 -> +0
    let negative = dir < vec3<f32>(0.0);
    let clamped = max(abs(dir), vec3<f32>(1e-20));
    let inv = vec3<f32>(1.0) / clamped;
    var r: BoxRay;
    r.origin = origin;
    r.inv_dir = select(inv, -inv, negative);
    r.near = select(vec3<u32>(0u), vec3<u32>(1u), negative);
    r.oct_inv4 = select(0x04040404u, 0u, negative.x) | select(0x02020202u, 0u, negative.y)
        | select(0x01010101u, 0u, negative.z);
    return r;
}

fn plane(n: u32, k: u32, child: u32) -> f32 {
    return nodes[n].planes[k * 2u + child / 4u][child % 4u];
}

// The CWBVH hit mask of node n: bits 24..32 inner children in traversal order, bits 0..24 leaf
// primitives (obvhs's get_child_and_index_bits, byte by byte).
fn intersect_node(n: u32, ray: BoxRay, t_min: f32, t_max: f32) -> u32 {
    let meta_lo = nodes[n].meta_lo;
    let meta_hi = nodes[n].meta_hi;
    let oct = ray.oct_inv4 & 0xffu;
    var hit_mask = 0u;
    for (var c = 0u; c < 8u; c++) {
        let b = (select(meta_hi, meta_lo, c < 4u) >> (8u * (c % 4u))) & 0xffu;
        if b == 0u {
            continue; // empty slot (its box is inverted anyway)
        }
        let tx0 = (plane(n, ray.near.x, c) - ray.origin.x) * ray.inv_dir.x;
        let ty0 = (plane(n, 2u + ray.near.y, c) - ray.origin.y) * ray.inv_dir.y;
        let tz0 = (plane(n, 4u + ray.near.z, c) - ray.origin.z) * ray.inv_dir.z;
        let tx1 = (plane(n, 1u - ray.near.x, c) - ray.origin.x) * ray.inv_dir.x;
        let ty1 = (plane(n, 3u - ray.near.y, c) - ray.origin.y) * ray.inv_dir.y;
        let tz1 = (plane(n, 5u - ray.near.z, c) - ray.origin.z) * ray.inv_dir.z;
        let near = max(max(max(tx0, ty0), tz0), t_min);
        let far = min(min(min(tx1, ty1), tz1) * EXIT_SLACK, t_max);
        if near <= far {
            let inner = ((b & (b << 1u)) & 0x10u) != 0u;
            let bit_index = (b ^ select(0u, oct, inner)) & 0x1fu;
            let child_bits = b >> 5u;
            hit_mask |= child_bits << bit_index;
        }
    }
    return hit_mask;
}

struct TriHit {
    ok: bool,
    t: f32,
    u: f32,
    v: f32,
}

// Watertight ray/triangle test with the ray's dominant axis kz and shear s; both faces,
// edges and vertices count, a zero-area (in ray space) triangle misses.
fn intersect_tri(i: u32, o: vec3<f32>, kz: u32, s: vec3<f32>, t_min: f32, t_max: f32) -> TriHit {
    var out: TriHit;
    out.ok = false;
    let tri = tris[i];
    let x = vec3<f32>(tri.v0.x, tri.v1.x, tri.v2.x) - vec3<f32>(o.x);
    let y = vec3<f32>(tri.v0.y, tri.v1.y, tri.v2.y) - vec3<f32>(o.y);
    let z = vec3<f32>(tri.v0.z, tri.v1.z, tri.v2.z) - vec3<f32>(o.z);
    var px = x;
    var py = y;
    var pz = z;
    if kz == 0u {
        px = y;
        py = z;
        pz = x;
    } else if kz == 1u {
        px = z;
        py = x;
        pz = y;
    }
    let ax = px - s.x * pz;
    let ay = py - s.y * pz;
    let uvw = ax.zxy * ay.yzx - ay.zxy * ax.yzx;
    let negative = any(uvw < vec3<f32>(0.0));
    let positive = any(uvw > vec3<f32>(0.0));
    if negative && positive {
        return out;
    }
    let det = uvw.x + uvw.y + uvw.z;
    if det == 0.0 {
        return out;
    }
    let az = s.z * pz;
    let big_t = uvw.x * az.x + uvw.y * az.y + uvw.z * az.z;
    let inv_det = 1.0 / det;
    let t = big_t * inv_det;
    if !(t >= t_min && t <= t_max) {
        return out;
    }
    out.ok = true;
    out.t = t;
    out.u = uvw.y * inv_det;
    out.v = uvw.z * inv_det;
    return out;
}

// The closest hit of the ray o + t·d, t in [t_min, t_max_in] (t_min > t_max: a miss), or with
// `any_hit` the first hit found (shadow rays: only whether there is one matters).
fn trace(o: vec3<f32>, d: vec3<f32>, t_min: f32, t_max_in: f32, any_hit: bool) -> Hit {
    var best: Hit;
    best.t = 0.0;
    best.triangle = MISS;
    best.u = 0.0;
    best.v = 0.0;
    var t_max = t_max_in;
    if t_min > t_max || arrayLength(&nodes) == 0u {
        return best;
    }
    let ray = box_ray(o, d);
    let a = abs(d);
    var kz = 2u;
    if a.x >= a.y && a.x >= a.z {
        kz = 0u;
    } else if a.y >= a.z {
        kz = 1u;
    }
    let kx = (kz + 1u) % 3u;
    let ky = (kz + 2u) % 3u;
    let s = vec3<f32>(d[kx] / d[kz], d[ky] / d[kz], 1.0 / d[kz]);

    var stack: array<vec2<u32>, 32>;
    var sp = 0u;
    var current = vec2<u32>(0u, 0x80000000u);
    var prims = vec2<u32>(0u, 0u);
    loop {
        while prims.y != 0u {
            let local_bit = firstLeadingBit(prims.y);
            prims.y &= ~(1u << local_bit);
            let slot = prims.x + local_bit;
            let h = intersect_tri(slot, o, kz, s, t_min, t_max);
            if h.ok {
                let id = bitcast<u32>(tris[slot].v0.w);
                if best.triangle == MISS || h.t < best.t || (h.t == best.t && id < best.triangle) {
                    best.t = h.t;
                    best.triangle = id;
                    best.u = h.u;
                    best.v = h.v;
                    t_max = h.t;
                    if any_hit {
                        return best;
                    }
                }
            }
        }
        if (current.y & 0xff000000u) != 0u {
            let hits_mask = current.y;
            let offset = firstLeadingBit(hits_mask);
            current.y &= ~(1u << offset);
            if (current.y & 0xff000000u) != 0u {
                stack[sp] = current;
                sp = min(sp + 1u, STACK_SIZE - 1u);
            }
            let slot = (offset - 24u) ^ (ray.oct_inv4 & 0xffu);
            let relative = countOneBits(hits_mask & ~(0xffffffffu << slot));
            let n = current.x + relative;
            let hit_mask = intersect_node(n, ray, t_min, t_max);
            current = vec2<u32>(nodes[n].child_base, (hit_mask & 0xff000000u) | nodes[n].imask);
            prims = vec2<u32>(nodes[n].primitive_base, hit_mask & 0x00ffffffu);
        } else {
            current = vec2<u32>(0u, 0u);
        }
        if prims.y == 0u && (current.y & 0xff000000u) == 0u {
            if sp == 0u {
                break;
            }
            sp -= 1u;
            current = stack[sp];
        }
    }
    return best;
}
