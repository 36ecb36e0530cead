// Scatter: one invocation per voxel writes its payload to its leaf.

@group(0) @binding(0) var<storage, read> params: Params;
@group(0) @binding(3) var<storage, read> coords: array<u32>;
@group(0) @binding(4) var<storage, read> voxel_payload: array<Average>;
@group(0) @binding(5) var<storage, read_write> payload: array<Average>;

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
    if leaf != NONE {
        payload[leaf] = voxel_payload[i];
    }
}
