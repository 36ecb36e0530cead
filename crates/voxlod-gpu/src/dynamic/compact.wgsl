// Occupancy (`extra` = 0) and compact (`extra` = 1): one invocation per world-voxel slot
// (8 per allocated brick). A slot is occupied when its covered volume reaches the threshold
// and its alpha sum is not zero (blend.rs's `resolve`). Occupancy writes 1 or 0 per slot;
// compact writes each occupied slot, at the exclusive prefix sum of the occupancy, as a leaf:
// its coordinates, its Averages payload (blend.rs's `CellSums::payload`, in f32) and its raw
// sums. Slots are in Morton order, so the leaves are.

// voxlod_octree::AveragePayload.
struct Average {
    color_alpha: array<f32, 3>,
    normal_alpha: array<f32, 3>,
    opacity: f32,
}

@group(0) @binding(0) var<storage, read> params: Params;
@group(0) @binding(1) var<storage, read> sums: array<u32>;
@group(0) @binding(2) var<storage, read> slot_code: array<u32>;
@group(0) @binding(3) var<storage, read_write> occupied: array<u32>;
@group(0) @binding(4) var<storage, read_write> coords: array<u32>;
@group(0) @binding(5) var<storage, read_write> payload: array<Average>;
@group(0) @binding(6) var<storage, read_write> leaf_sums: array<u32>;

fn to_f32(lo: u32, hi: u32) -> f32 {
    return f32(hi) * 4294967296.0 + f32(lo);
}

fn signed_f32(lo: u32, hi: u32) -> f32 {
    if (hi & 0x80000000u) != 0u {
        let m = neg64(vec2<u32>(lo, hi));
        return -to_f32(m.x, m.y);
    }
    return to_f32(lo, hi);
}

fn is_occupied(s: u32) -> bool {
    let b = 16u * s;
    let heavy = sums[b + 1u] != 0u || sums[b] >= params.min_weight;
    return heavy && (sums[b + 2u] | sums[b + 3u]) != 0u;
}

@compute @workgroup_size(64)
fn main(
    @builtin(workgroup_id) wg: vec3<u32>,
    @builtin(num_workgroups) nwg: vec3<u32>,
    @builtin(local_invocation_index) li: u32,
) {
    let s = flat_index(wg, nwg, li);
    if s >= params.n {
        return;
    }
    if params.extra == 0u {
        occupied[s] = select(0u, 1u, is_occupied(s));
        return;
    }
    if !is_occupied(s) {
        return;
    }
    let out = occupied[s];
    let k = s & 7u;
    let c = (demorton(slot_code[s / 8u]) << vec3<u32>(1u)) + vec3<u32>(k & 1u, (k >> 1u) & 1u, (k >> 2u) & 1u);
    coords[3u * out] = c.x;
    coords[3u * out + 1u] = c.y;
    coords[3u * out + 2u] = c.z;
    let b = 16u * s;
    for (var w = 0u; w < 16u; w += 1u) {
        leaf_sums[16u * out + w] = sums[b + w];
    }
    let a = to_f32(sums[b + 2u], sums[b + 3u]);
    let opacity = min(1.0, a / (255.0 * 262144.0));
    let color = vec3<f32>(to_f32(sums[b + 4u], sums[b + 5u]), to_f32(sums[b + 6u], sums[b + 7u]), to_f32(sums[b + 8u], sums[b + 9u])) / (4095.0 * a);
    var n = vec3<f32>(signed_f32(sums[b + 10u], sums[b + 11u]), signed_f32(sums[b + 12u], sums[b + 13u]), signed_f32(sums[b + 14u], sums[b + 15u]));
    let len = sqrt((n.x * n.x + n.y * n.y) + n.z * n.z);
    if len > 0.0 {
        n = n * (1.0 / len);
    } else {
        n = vec3<f32>(0.0);
    }
    let ca = color * opacity;
    let na = n * opacity;
    payload[out] = Average(array<f32, 3>(ca.x, ca.y, ca.z), array<f32, 3>(na.x, na.y, na.z), opacity);
}
