// Leaves: one invocation per voxel finds its leaf (a descent to level 0) and counts it;
// a leaf reached twice means a voxel given twice (the host then names it). With
// `extra` = 1 the voxel's payload is also written to its leaf.

@group(0) @binding(0) var<storage, read> params: Params;
@group(0) @binding(3) var<storage, read> coords: array<u32>;
@group(0) @binding(4) var<storage, read_write> hits: array<atomic<u32>>;
@group(0) @binding(5) var<storage, read_write> duplicate: array<atomic<u32>>;

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
    let leaf = descend(voxel(i), 0u, params.first_dense);
    if leaf == NONE {
        atomicStore(&duplicate[1], 1u);
        return;
    }
    if atomicAdd(&hits[leaf - levels[0].first], 1u) != 0u {
        atomicStore(&duplicate[0], 1u);
    }
}
