// Shared by the volume kernels: the particle record, the light-oriented frame and the
// displacement cube-map look-up, each the WGSL mirror of its voxlod-scene / voxlod-cpu
// counterpart (same operations in the same order as the CPU reference).

// voxlod_scene::particles::DisplacedSphere (64 bytes; checked by a layout test).
struct Sphere {
    center: vec3<f32>,
    inner: f32,
    color: vec3<f32>,
    amplitude: f32,
    color_outer: vec3<f32>,
    density: f32,
    rot_cos: f32,
    rot_sin: f32,
    color_mode: u32,
    flags: u32,
}

// voxlod_cpu::volume::LightSpace: origin (w = voxel size) and the basis u, v, w.
struct Frame {
    origin: vec4<f32>,
    u: vec4<f32>,
    v: vec4<f32>,
    w: vec4<f32>,
}

const FLAG_EMISSIVE: u32 = 1u;
const AO_FLOOR: f32 = 0.35;

// DisplacementMap::sample over `texels` (6 faces of n² texels, face-major, row-major).
fn cube_sample(dir: vec3<f32>, n: u32) -> f32 {
    let a = abs(dir);
    var face = 0u;
    var major = a.x;
    var pu = dir.y;
    var pv = dir.z;
    if a.x >= a.y && a.x >= a.z {
        face = select(0u, 1u, dir.x < 0.0);
    } else if a.y >= a.z {
        face = select(2u, 3u, dir.y < 0.0);
        major = a.y;
        pu = dir.z;
        pv = dir.x;
    } else {
        face = select(4u, 5u, dir.z < 0.0);
        major = a.z;
        pu = dir.x;
        pv = dir.y;
    }
    var u = 0.0;
    var v = 0.0;
    if major > 0.0 {
        u = pu / major;
        v = pv / major;
    }
    let nf = f32(n);
    let last = f32(n - 1u);
    let x = clamp((u + 1.0) * 0.5 * nf - 0.5, 0.0, last);
    let y = clamp((v + 1.0) * 0.5 * nf - 0.5, 0.0, last);
    let x0 = u32(x);
    let y0 = u32(y);
    let x1 = min(x0 + 1u, n - 1u);
    let y1 = min(y0 + 1u, n - 1u);
    let fx = x - f32(x0);
    let fy = y - f32(y0);
    let f = face * n * n;
    let a0 = texels[f + y0 * n + x0];
    let b0 = texels[f + y0 * n + x1];
    let a1 = texels[f + y1 * n + x0];
    let b1 = texels[f + y1 * n + x1];
    let r0 = a0 + (b0 - a0) * fx;
    let r1 = a1 + (b1 - a1) * fx;
    return r0 + (r1 - r0) * fy;
}

// DisplacedSphere::displacement: the offset rotated about +y by the particle's spin.
fn displacement(s: Sphere, o: vec3<f32>, n: u32) -> f32 {
    let c = s.rot_cos;
    let sn = s.rot_sin;
    return cube_sample(vec3<f32>(c * o.x + sn * o.z, o.y, c * o.z - sn * o.x), n);
}

// DisplacedSphere::color_at.
fn color_at(s: Sphere, dist: f32, n: f32) -> vec3<f32> {
    if s.color_mode == 1u {
        let outer = s.inner + s.amplitude;
        var t = 0.0;
        if outer > 0.0 {
            t = clamp(dist / outer, 0.0, 1.0);
        }
        return s.color + (s.color_outer - s.color) * t;
    }
    if s.color_mode == 2u {
        return s.color * (AO_FLOOR + (1.0 - AO_FLOOR) * n);
    }
    return s.color;
}
