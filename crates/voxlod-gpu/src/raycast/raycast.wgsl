// Closest-hit ray casting, one invocation per ray, through the traversal of bvh.wgsl (which
// this file is appended to).

struct Ray {
    origin: vec4<f32>, // w = t_min (>= 0)
    dir: vec4<f32>,    // w = t_max (< t_min: the ray is invalid and misses)
}

struct Params {
    counts: vec4<u32>, // x = rays, y = nodes, z = 0, w = 0
}

@group(0) @binding(0) var<storage, read> params: Params;
@group(0) @binding(3) var<storage, read> rays: array<Ray>;
@group(0) @binding(4) var<storage, read_write> hits: array<Hit>;

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
    let r = rays[index];
    var t_max = r.dir.w;
    if params.counts.y == 0u {
        t_max = -1.0; // no nodes: every ray misses
    }
    hits[index] = trace(r.origin.xyz, r.dir.xyz, r.origin.w, t_max, false);
}
