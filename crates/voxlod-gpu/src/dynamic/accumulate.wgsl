// Accumulate: one invocation per (moved voxel, corner) adds its contribution to its world
// voxel's sums — `extra` = 1 for the static cells instead, one per cell adding its precomputed
// sums. Sums are 64-bit (low word, high word) added with a carry, so the result is the exact
// sum modulo 2^64 in any order (blend.rs's `CellSums`, 16 words per voxel: weight, alpha,
// colour ×3, normal ×3). A world voxel's sums sit at 8·slot(brick) + octant.

@group(0) @binding(0) var<storage, read> params: Params;
@group(0) @binding(1) var<storage, read> placed: array<Placed>;
@group(0) @binding(2) var<storage, read> records: array<u32>;
@group(0) @binding(3) var<storage, read> slots: array<u32>;
@group(0) @binding(4) var<storage, read_write> sums: array<atomic<u32>>;
@group(0) @binding(5) var<storage, read> linear12: array<u32>;
@group(0) @binding(6) var<storage, read> static_cells: array<u32>;
@group(0) @binding(7) var<storage, read> static_sums: array<u32>;

fn add64(at: u32, v: vec2<u32>) {
    let old = atomicAdd(&sums[at], v.x);
    let hi = v.y + select(0u, 1u, old + v.x < old);
    if hi != 0u {
        atomicAdd(&sums[at + 1u], hi);
    }
}

fn base_of(c: vec3<u32>) -> u32 {
    return 16u * (8u * slots[morton(c >> vec3<u32>(1u))] + octant(c));
}

@compute @workgroup_size(64)
fn main(
    @builtin(workgroup_id) wg: vec3<u32>,
    @builtin(num_workgroups) nwg: vec3<u32>,
    @builtin(local_invocation_index) li: u32,
) {
    let i = flat_index(wg, nwg, li);
    if i >= params.n {
        return;
    }
    if params.extra == 1u {
        let c = vec3<u32>(static_cells[3u * i], static_cells[3u * i + 1u], static_cells[3u * i + 2u]);
        let base = base_of(c);
        for (var s = 0u; s < 8u; s += 1u) {
            add64(base + 2u * s, vec2<u32>(static_sums[16u * i + 2u * s], static_sums[16u * i + 2u * s + 1u]));
        }
        return;
    }
    let corners = select(1u, 8u, params.filter_mode == 1u);
    let v = i / corners;
    let p = placed[v];
    if p.status != 0u {
        return;
    }
    let k = corner(p, i % corners);
    if k.w == 0 || !inside(k.xyz) {
        return;
    }
    let base = base_of(vec3<u32>(k.xyz));
    let rec = records[2u * v];
    let w = u32(k.w);
    let wa = w * (rec >> 24u);
    add64(base, vec2<u32>(w, 0u));
    add64(base + 2u, vec2<u32>(wa, 0u));
    for (var ch = 0u; ch < 3u; ch += 1u) {
        add64(base + 4u + 2u * ch, mul64(wa, linear12[(rec >> (8u * ch)) & 0xffu]));
    }
    for (var a = 0u; a < 3u; a += 1u) {
        let n = p.normal[a];
        let m = mul64(wa, u32(abs(n)));
        add64(base + 10u + 2u * a, select(m, neg64(m), n < 0));
    }
}
