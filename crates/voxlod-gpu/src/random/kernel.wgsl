// Evaluates the RNG of random.wgsl (to which this file is appended) on a list of counters:
// the equivalence suite compares the results with voxlod-cpu's, bit for bit.

struct Params {
    counts: vec4<u32>, // x = inputs
}

@group(0) @binding(0) var<storage, read> params: Params;
@group(0) @binding(1) var<storage, read> inputs: array<vec4<u32>>;   // (id, sample, dim, 0)
@group(0) @binding(2) var<storage, read_write> outputs: array<vec4<u32>>; // pcg3d, rand_f32 bits

@compute @workgroup_size(64)
fn main(
    @builtin(workgroup_id) wg: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
    @builtin(local_invocation_index) local: u32,
) {
    let index = (wg.y * groups.x + wg.x) * 64u + local;
    if index >= params.counts.x {
        return;
    }
    let c = inputs[index];
    let v = pcg3d(c.x, c.y, c.z);
    outputs[index] = vec4<u32>(v, bitcast<u32>(rand_f32(c.x, c.y, c.z)));
}
