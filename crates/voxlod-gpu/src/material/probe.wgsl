
// The material test kernel (appended to material.wgsl): per query (u, v, material index), the
// material's texture sample (white when untextured) and its evaluation (albedo, alpha).

struct Params {
    counts: vec4<u32>, // x = number of queries
}

@group(0) @binding(0) var<storage, read> params: Params;
@group(0) @binding(1) var<storage, read> materials: array<Material>;
@group(0) @binding(2) var<storage, read> textures: Textures;
@group(0) @binding(3) var<storage, read> texels: array<u32>;
@group(0) @binding(4) var<storage, read> queries: array<vec4<f32>>; // u, v, material (bits), 0
@group(0) @binding(5) var<storage, read_write> results: array<vec4<f32>>;

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = id.y * groups.x * 64u + id.x;
    if i >= params.counts.x {
        return;
    }
    let q = queries[i];
    let index = bitcast<u32>(q.z);
    let mat = materials[index];
    var raw = vec4<f32>(1.0);
    if mat.texture != 0u {
        raw = texture_sample(mat.texture - 1u, q.xy);
    }
    let s = material_sample(index, q.xy);
    results[2u * i] = raw;
    results[2u * i + 1u] = vec4<f32>(s.albedo, s.alpha);
}
