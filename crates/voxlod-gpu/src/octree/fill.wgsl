// Fill: nodes `extra .. extra + n` get no child tile and an empty mask.

@group(0) @binding(0) var<storage, read> params: Params;
@group(0) @binding(2) var<storage, read_write> nodes: array<GpuNode>;

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
    nodes[params.extra + i] = GpuNode(NONE, 0u);
}
