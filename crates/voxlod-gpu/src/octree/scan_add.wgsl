// Exclusive prefix sum, pass 2: one invocation per value adds its block's offset (the
// exclusive scan of the block totals, done by the same two passes one level up).

@group(0) @binding(0) var<storage, read> params: Params;
@group(0) @binding(3) var<storage, read_write> data: array<u32>;
@group(0) @binding(4) var<storage, read> sums: array<u32>;

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
    data[i] = data[i] + sums[i / 512u];
}
