// The exact-attenuation reference march (voxlod_cpu::volume::march::render_exact): one
// invocation per pixel in 8×8 workgroups. Each ray walks every voxel it crosses in order (a
// kept metavoxel voxel by voxel, an absent one in one step), with its exact segment length ℓ:
// colour += T · (1 − e^(−σℓ)) · radiance, T *= e^(−σℓ). The next cell is looked up a nudge
// (10⁻⁴ voxel) past the current one's exit, as on the CPU. Neighbouring rays cross the same
// cells: coherent reads; the walk's length varies per ray (divergence at silhouettes).

struct Params {
    eye: vec4<f32>,
    forward: vec4<f32>,
    right: vec4<f32>,
    up: vec4<f32>,
    origin: vec4<f32>,
    u: vec4<f32>,
    v: vec4<f32>,
    w: vec4<f32>,
    // The eye in voxel coordinates (xyz), w: the nudge in world units.
    eye_voxel: vec4<f32>,
    // x: width, y: height, z: K, w: M.
    dims: vec4<u32>,
    // x: unused, y: 1 if `depth` is a depth buffer.
    mode: vec4<u32>,
}

@group(0) @binding(0) var<storage, read> params: Params;
// K³ entries (key order (i·K + j)·K + k): the slot of a kept metavoxel, or 0xffffffff.
@group(0) @binding(1) var<storage, read> index: array<u32>;
@group(0) @binding(2) var<storage, read> voxels: array<vec4<f32>>;
@group(0) @binding(3) var<storage, read> depth: array<f32>;
@group(0) @binding(4) var<storage, read_write> image: array<vec4<f32>>;

fn slab(o: vec3<f32>, inv: vec3<f32>, lo: vec3<f32>, hi: vec3<f32>) -> vec2<f32> {
    let a = (lo - o) * inv;
    let b = (hi - o) * inv;
    let n = min(a, b);
    let f = max(a, b);
    return vec2<f32>(max(max(n.x, n.y), n.z), min(min(f.x, f.y), f.z));
}

@compute @workgroup_size(8, 8)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {
    let width = params.dims.x;
    let height = params.dims.y;
    if gid.x >= width || gid.y >= height {
        return;
    }
    let pixel = gid.y * width + gid.x;
    let px = vec2<f32>(f32(gid.x) + 0.5, f32(gid.y) + 0.5);
    let ndc_x = 2.0 * px.x / f32(width) - 1.0;
    let ndc_y = 1.0 - 2.0 * px.y / f32(height);
    let raw = params.forward.xyz + params.right.xyz * ndc_x + params.up.xyz * ndc_y;
    let world = raw * (1.0 / length(raw));
    let vs = params.origin.w;
    let d = vec3<f32>(dot(world, params.u.xyz), dot(world, params.v.xyz), dot(world, params.w.xyz)) / vs;
    let inv = vec3<f32>(1.0) / d;
    let o = params.eye_voxel.xyz;
    let nudge = params.eye_voxel.w;
    let k = params.dims.z;
    let m = params.dims.w;
    let mf = f32(m);
    let n = f32(k * m);
    var color = vec3<f32>(0.0);
    var trans = 1.0;
    let whole = slab(o, inv, vec3<f32>(0.0), vec3<f32>(n));
    if whole.x <= whole.y {
        var t1 = whole.y;
        if params.mode.y != 0u {
            let z = depth[pixel];
            t1 = min(t1, select(0.0, z, z >= 0.0));
        }
        var t = max(whole.x, 0.0);
        while t < t1 && trans > 0.0 {
            let g = clamp(floor(o + d * (t + nudge)), vec3<f32>(0.0), vec3<f32>(n - 1.0));
            let c = floor(g / mf);
            let cu = vec3<u32>(c);
            let slot = index[(cu.x * k + cu.y) * k + cu.z];
            var cell_lo = c * mf;
            var size = mf;
            var voxel = vec4<f32>(0.0);
            if slot != 0xffffffffu {
                let l = vec3<u32>(g - c * mf);
                cell_lo = g;
                size = 1.0;
                voxel = voxels[slot * m * m * m + (l.z * m + l.y) * m + l.x];
            }
            let s = slab(o, inv, cell_lo, cell_lo + vec3<f32>(size));
            var exit = t + nudge;
            if s.x <= s.y {
                exit = s.y;
            }
            let end = min(max(exit, t + nudge), t1);
            if end <= t {
                break;
            }
            if voxel.w > 0.0 {
                let b = exp(-(voxel.w * (end - t)));
                color = color + voxel.xyz * (trans * (1.0 - b));
                trans = trans * b;
            }
            t = end;
        }
    }
    image[pixel] = vec4<f32>(color, 1.0 - trans);
}
