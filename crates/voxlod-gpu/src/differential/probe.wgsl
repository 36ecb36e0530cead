// Smith's Λ and erfc evaluated on the GPU for the stability check against f64 on the CPU: one
// invocation per input (cos θ, sin θ, σ, x), writing (Λ, erfc(x)).

@group(0) @binding(0) var<storage, read> inputs: array<vec4<f32>>;
@group(0) @binding(1) var<storage, read_write> outputs: array<vec2<f32>>;

@compute @workgroup_size(64)
fn main(
    @builtin(global_invocation_id) gid: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
) {
    let i = gid.y * groups.x * 64u + gid.x;
    if i >= arrayLength(&inputs) {
        return;
    }
    let q = inputs[i];
    outputs[i] = vec2<f32>(lambda_cs(q.x, q.y, q.z), erfc_f32(q.w));
}
