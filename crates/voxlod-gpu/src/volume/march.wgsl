// The eye ray march (seed 001 Listing 5.3, §5.5.5): one invocation per pixel in 8×8
// workgroups (neighbouring rays cross the same metavoxels and voxels: coherent reads of the
// same cache lines). Every pixel walks the host's list of non-empty kept metavoxels in the
// chapter's sort order — far to near with over blending above the perpendicular, then near to
// far with under blending below it — and marches its segment through each one's marched box
// with the CPU reference's sample positions `t = (n + ½)·step` and nearest-voxel reads,
// stopping at the pixel's depth. The list is uniform across the workgroup (no divergence in
// the outer loop); rays that miss a metavoxel's box skip it after the slab test.

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
    // The eye in voxel coordinates (xyz), w: the step in world units.
    eye_voxel: vec4<f32>,
    // x: width, y: height, z: entries in `order`, w: M.
    dims: vec4<u32>,
    // x: attenuation (0 chapter, 1 Beer-Lambert), y: 1 if `depth` is a depth buffer.
    mode: vec4<u32>,
}

// One metavoxel in sort order: its box (base, base + M) and the box marched (lo, hi); x of
// `flags`: the slot (its voxels start at slot · M³), y: 1 for over blending.
struct Entry {
    base: vec4<f32>,
    lo: vec4<f32>,
    hi: vec4<f32>,
    flags: vec4<u32>,
}

@group(0) @binding(0) var<storage, read> params: Params;
@group(0) @binding(1) var<storage, read> order: array<Entry>;
@group(0) @binding(2) var<storage, read> voxels: array<vec4<f32>>;
@group(0) @binding(3) var<storage, read> depth: array<f32>;
@group(0) @binding(4) var<storage, read_write> image: array<vec4<f32>>;

fn transmittance(tau: f32) -> f32 {
    if params.mode.x == 0u {
        return 1.0 / (1.0 + tau);
    }
    return exp(-tau);
}

// Entry and exit t of the ray through [lo, hi] (t0 > t1 when it misses).
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
    // CameraFrame::ray_dir through the pixel centre, then LightSpace::dir_to_voxel.
    let px = vec2<f32>(f32(gid.x) + 0.5, f32(gid.y) + 0.5);
    let ndc_x = 2.0 * px.x / f32(width) - 1.0;
    let ndc_y = 1.0 - 2.0 * px.y / f32(height);
    let raw = params.forward.xyz + params.right.xyz * ndc_x + params.up.xyz * ndc_y;
    let world = raw * (1.0 / length(raw));
    let vs = params.origin.w;
    let d = vec3<f32>(dot(world, params.u.xyz), dot(world, params.v.xyz), dot(world, params.w.xyz)) / vs;
    let inv = vec3<f32>(1.0) / d;
    let o = params.eye_voxel.xyz;
    let step = params.eye_voxel.w;
    let m = params.dims.w;
    let mf = f32(m);
    let last = mf - 1.0;
    var limit = 3.0e38;
    if params.mode.y != 0u {
        let z = depth[pixel];
        limit = select(0.0, z, z >= 0.0);
    }
    var color = vec3<f32>(0.0);
    var trans = 1.0;
    for (var i = 0u; i < params.dims.z; i++) {
        let e = order[i];
        let s0 = slab(o, inv, e.base.xyz, e.base.xyz + vec3<f32>(mf));
        if !(s0.x <= s0.y) {
            continue;
        }
        let s1 = slab(o, inv, e.lo.xyz, e.hi.xyz);
        if !(s1.x <= s1.y) {
            continue;
        }
        let t0 = max(max(s0.x, s1.x), 0.0);
        let t1 = min(min(s0.y, s1.y), limit);
        if t0 >= t1 {
            continue;
        }
        let first = e.flags.x * m * m * m;
        var seg_color = vec3<f32>(0.0);
        var seg_t = 1.0;
        var n = max(ceil(t0 / step - 0.5), 0.0);
        loop {
            let t = (n + 0.5) * step;
            if t >= t1 {
                break;
            }
            if t >= t0 {
                let l = clamp(o + d * t - e.base.xyz, vec3<f32>(0.0), vec3<f32>(last));
                let q = vec3<u32>(l);
                let v = voxels[first + (q.z * m + q.y) * m + q.x];
                if v.w > 0.0 {
                    let b = transmittance(v.w * step);
                    seg_color = seg_color + v.xyz * (seg_t * (1.0 - b));
                    seg_t = seg_t * b;
                }
            }
            n = n + 1.0;
        }
        if e.flags.y != 0u {
            color = seg_color + color * seg_t;
        } else {
            color = color + seg_color * trans;
        }
        trans = trans * seg_t;
    }
    image[pixel] = vec4<f32>(color, 1.0 - trans);
}
