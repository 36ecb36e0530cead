// Shared by the two eye marches (march.wgsl, the chapter's; march_exact.wgsl, the exact
// reference), which read the same parameters and bind the same voxels, depth and image.

struct Params {
    eye: vec4<f32>,
    forward: vec4<f32>,
    right: vec4<f32>,
    up: vec4<f32>,
    // The light-space frame: origin (w: voxel size), u, v, w.
    origin: vec4<f32>,
    u: vec4<f32>,
    v: vec4<f32>,
    w: vec4<f32>,
    // The eye in voxel coordinates (xyz), w: the step in world units (march.wgsl) or the
    // nudge past a cell's exit (march_exact.wgsl).
    eye_voxel: vec4<f32>,
    // x: width, y: height, z: entries in `order` (march.wgsl) or K (march_exact.wgsl), w: M.
    dims: vec4<u32>,
    // x: attenuation (0 chapter, 1 Beer-Lambert; unused by march_exact.wgsl), y: 1 if `depth`
    // is a depth buffer.
    mode: vec4<u32>,
}

@group(0) @binding(0) var<storage, read> params: Params;
@group(0) @binding(2) var<storage, read> voxels: array<vec4<f32>>;
@group(0) @binding(3) var<storage, read> depth: array<f32>;
@group(0) @binding(4) var<storage, read_write> image: array<vec4<f32>>;

// Entry and exit t of the ray through [lo, hi] (t0 > t1 when it misses).
fn slab(o: vec3<f32>, inv: vec3<f32>, lo: vec3<f32>, hi: vec3<f32>) -> vec2<f32> {
    let a = (lo - o) * inv;
    let b = (hi - o) * inv;
    let n = min(a, b);
    let f = max(a, b);
    return vec2<f32>(max(max(n.x, n.y), n.z), min(min(f.x, f.y), f.z));
}

