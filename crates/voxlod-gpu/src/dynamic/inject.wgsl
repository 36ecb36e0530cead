// Inject: one invocation per leaf of a dynamic frame's geometry octree, the mirror of
// voxlod-cone's `inject`: the Lambert radiance `albedo/π · E · max(n·l, 0) · V` of the leaf
// (n = 0: max(n·l, 0) = ½), V from a shadow march through the geometry octree (the cone
// kernel's `march` with aperture 0, start 0, cutoff 0.999, from the leaf centre moved
// `offset` voxels along its normal, ending a voxel short of a point light), written in the
// Averages layout (radiance × opacity in the colour words) for the octree's pre-filter.
// Prepended: isotropic.wgsl and cone.wgsl's functions (its bindings 0–4: the cone `Params`,
// the geometry octree's levels, nodes, tiles and opacity payloads).

struct Leaf {
    color_alpha: array<f32, 3>,
    normal_alpha: array<f32, 3>,
    opacity: f32,
}

// GpuInjectParams.
struct InjectParams {
    // xyz: direction toward a directional light, or a point light's position; w: 1 for a
    // point light.
    light_a: vec4<f32>,
    // xyz: irradiance, or intensity; w: 1 to march shadows, 0 for none.
    light_b: vec4<f32>,
    // x: shadow ray offset (voxels); y, z, w unused.
    shadow: vec4<f32>,
    // x: leaves.
    counts: vec4<u32>,
}

@group(0) @binding(8) var<storage, read> ip: InjectParams;
@group(0) @binding(9) var<storage, read> leaf_coords: array<u32>;
@group(0) @binding(10) var<storage, read> leaves: array<Leaf>;
@group(0) @binding(11) var<storage, read_write> injected: array<Leaf>;

struct LightAt {
    dir: vec3<f32>,
    e: vec3<f32>,
    dist: f32,
    ok: bool,
}

// voxlod-cone's `Light::at` (BIG for the infinite distance of a directional light).
fn light_at(p: vec3<f32>) -> LightAt {
    if ip.light_a.w == 0.0 {
        return LightAt(normalize3(ip.light_a.xyz), ip.light_b.xyz, BIG, true);
    }
    let d = ip.light_a.xyz - p;
    let dist2 = dot3(d, d);
    if !(dist2 > 0.0) {
        return LightAt(vec3<f32>(0.0), vec3<f32>(0.0), 0.0, false);
    }
    let dist = sqrt(dist2);
    return LightAt(d / dist, ip.light_b.xyz / dist2, dist, true);
}

@compute @workgroup_size(64)
fn main(
    @builtin(workgroup_id) wg: vec3<u32>,
    @builtin(num_workgroups) nwg: vec3<u32>,
    @builtin(local_invocation_index) li: u32,
) {
    let i = (wg.y * nwg.x + wg.x) * 64u + li;
    if i >= ip.counts.x {
        return;
    }
    let p = leaves[i];
    let alpha = p.opacity;
    var out = Leaf(array<f32, 3>(0.0, 0.0, 0.0), array<f32, 3>(0.0, 0.0, 0.0), alpha);
    let c = vec3<f32>(f32(leaf_coords[3u * i]), f32(leaf_coords[3u * i + 1u]), f32(leaf_coords[3u * i + 2u]));
    let voxel = params.grid.w;
    let centre = params.grid.xyz + (c + 0.5) * voxel;
    let at = light_at(centre);
    if !at.ok {
        injected[i] = out;
        return;
    }
    let na = vec3<f32>(p.normal_alpha[0], p.normal_alpha[1], p.normal_alpha[2]);
    let nl = length3(na);
    var n = vec3<f32>(0.0);
    if nl > 0.0 {
        n = na * (1.0 / nl);
    }
    let zero_n = all(n == vec3<f32>(0.0));
    var ndl = 0.5;
    if !zero_n {
        ndl = max(dot3(n, at.dir), 0.0);
    }
    if ndl <= 0.0 || all(at.e == vec3<f32>(0.0)) {
        injected[i] = out;
        return;
    }
    var v = 1.0;
    if ip.light_b.w != 0.0 {
        let side = select(n, at.dir, zero_n);
        let apex = centre + side * (ip.shadow.x * voxel);
        let from_apex = light_at(apex);
        if from_apex.ok {
            var max_voxels = BIG;
            if from_apex.dist < BIG {
                max_voxels = max(from_apex.dist - voxel, 0.0) / voxel;
            }
            let r = march(apex, from_apex.dir, 0.0, max_voxels, apex, 0.0);
            v = 1.0 - r.opacity;
        }
    }
    var color = vec3<f32>(0.0);
    if alpha > 0.0 {
        color = vec3<f32>(p.color_alpha[0], p.color_alpha[1], p.color_alpha[2]) / alpha;
    }
    let radiance = color * 0.31830987 * at.e * (ndl * v);
    let ra = radiance * alpha;
    out.color_alpha = array<f32, 3>(ra.x, ra.y, ra.z);
    injected[i] = out;
}
