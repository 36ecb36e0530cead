// Bricks: one invocation per brick of the table: a flagged brick records its Morton code at
// its slot (the exclusive prefix sum of the flags), so slots are in Morton order.

@group(0) @binding(0) var<storage, read> params: Params;
@group(0) @binding(1) var<storage, read> flags: array<u32>;
@group(0) @binding(2) var<storage, read> slots: array<u32>;
@group(0) @binding(3) var<storage, read_write> slot_code: array<u32>;

@compute @workgroup_size(64)
fn main(
    @builtin(workgroup_id) wg: vec3<u32>,
    @builtin(num_workgroups) nwg: vec3<u32>,
    @builtin(local_invocation_index) li: u32,
) {
    let b = flat_index(wg, nwg, li);
    if b >= params.n {
        return;
    }
    if flags[b] != 0u {
        slot_code[slots[b]] = b;
    }
}
