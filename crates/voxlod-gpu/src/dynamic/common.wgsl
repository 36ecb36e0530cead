// Shared by the dynamic-scene kernels: the mirrors of voxlod_octree::dynamic's `Placed` and of
// `GpuDynamicParams` (checked for size and offsets by a test), the flat dispatch index, Morton
// codes of 10 bits per axis, a filter's corners, and exact 64-bit sums on u32 words.

// voxlod_octree::dynamic::Placed: where a moved voxel lands (nearest: the voxel; 8-neighbour:
// the lower corner), its fractions in sixty-fourths (8 bits per axis), its moved normal
// (snorm12), and 0 if placed, 1 if outside. 32 bytes.
struct Placed {
    cell: array<i32, 3>,
    frac: u32,
    normal: array<i32, 3>,
    status: u32,
}

// GpuDynamicParams: invocations, filter (0 nearest, 1 8-neighbour), log2 of the brick table's
// resolution per axis, a kernel-specific word; the world grid's dimensions; the occupancy
// threshold in 2^-18 voxel.
struct Params {
    n: u32,
    filter_mode: u32,
    brick_log2: u32,
    extra: u32,
    dims: vec3<u32>,
    min_weight: u32,
}

const WG: u32 = 64u;
const FULL: u32 = 262144u; // 2^18: a whole voxel's weight

fn flat_index(wg: vec3<u32>, nwg: vec3<u32>, li: u32) -> u32 {
    return (wg.y * nwg.x + wg.x) * WG + li;
}

// blend.rs's `corner`: world voxel (xyz) and weight (w) of corner k of a placed voxel.
fn corner(p: Placed, k: u32) -> vec4<i32> {
    let c = vec3<i32>(p.cell[0], p.cell[1], p.cell[2]);
    if params.filter_mode == 0u {
        return vec4<i32>(c, i32(FULL));
    }
    let f = vec3<u32>(p.frac & 0xffu, (p.frac >> 8u) & 0xffu, (p.frac >> 16u) & 0xffu);
    let up = vec3<u32>(k & 1u, (k >> 1u) & 1u, (k >> 2u) & 1u);
    let w = select(vec3<u32>(64u) - f, f, up == vec3<u32>(1u));
    return vec4<i32>(c + vec3<i32>(up), i32(w.x * w.y * w.z));
}

fn inside(c: vec3<i32>) -> bool {
    return all(c >= vec3<i32>(0)) && all(vec3<u32>(c) < params.dims);
}

// a·b as (low word, high word), exactly.
fn mul64(a: u32, b: u32) -> vec2<u32> {
    let a0 = a & 0xffffu;
    let a1 = a >> 16u;
    let b0 = b & 0xffffu;
    let b1 = b >> 16u;
    let p00 = a0 * b0;
    let p01 = a0 * b1;
    let p10 = a1 * b0;
    let p11 = a1 * b1;
    let mid = (p00 >> 16u) + (p01 & 0xffffu) + (p10 & 0xffffu);
    return vec2<u32>(a * b, p11 + (p01 >> 16u) + (p10 >> 16u) + (mid >> 16u));
}

// −x modulo 2^64.
fn neg64(x: vec2<u32>) -> vec2<u32> {
    return vec2<u32>(0u - x.x, 0u - x.y - select(0u, 1u, x.x != 0u));
}
