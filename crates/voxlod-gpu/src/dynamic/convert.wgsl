// Convert: one invocation per octree node, from the Averages layout the octree build fills to
// the cone kernel's isotropic payload (radiance × opacity, opacity): `extra` = 0 keeps the
// opacity only (the geometry octree, for shadow marches), 1 reads the colour words as
// radiance (a radiance octree built through the Averages layout).

struct Average {
    color_alpha: array<f32, 3>,
    normal_alpha: array<f32, 3>,
    opacity: f32,
}

struct Radiance {
    radiance_alpha: vec3<f32>,
    opacity: f32,
}

@group(0) @binding(0) var<storage, read> params: Params;
@group(0) @binding(1) var<storage, read> average: array<Average>;
@group(0) @binding(2) var<storage, read_write> radiance: array<Radiance>;

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
    let a = average[i];
    var r = vec3<f32>(0.0);
    if params.extra == 1u {
        r = vec3<f32>(a.color_alpha[0], a.color_alpha[1], a.color_alpha[2]);
    }
    radiance[i] = Radiance(r, a.opacity);
}
