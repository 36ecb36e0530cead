// The ground-truth renderer (voxlod-cpu's render::ground_truth + render::surface), appended to
// random.wgsl, shading.wgsl and bvh.wgsl. One invocation per pixel in 8×8 tiles (neighbouring
// rays walk the same BVH nodes); a dispatch covers samples [first, end) of every pixel and adds
// them, in sample order, to the pixel's running sum, so a dispatch's length is bounded whatever
// the samples per pixel and the sum's order is the CPU's.

struct Params {
    eye: vec4<f32>,
    forward: vec4<f32>,
    right: vec4<f32>,        // scaled by tan(fov/2)·aspect
    up: vec4<f32>,           // scaled by tan(fov/2)
    background: vec4<f32>,
    ambient: vec4<f32>,
    light_a: vec4<f32>,      // directional: unit to_light; point: position
    light_b: vec4<f32>,      // directional: irradiance; point: intensity
    size: vec4<u32>,         // width, height, spp, flags (1: shadows, 2: point light)
    samples: vec4<u32>,      // first sample, end sample, 1 to write the G-buffer, 0
    streams: vec4<u32>,      // jitter_x, jitter_y, alpha_primary, alpha_shadow keys
}

struct ShadeTri {
    p0: vec4<f32>, // w = material index (bits)
    p1: vec4<f32>,
    p2: vec4<f32>,
    n0: vec4<f32>, // vertex normals
    n1: vec4<f32>,
    n2: vec4<f32>,
}

struct Material {
    albedo: vec4<f32>,   // w = 1 if double-sided
    specular: vec4<f32>, // w = shininess
}

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(3) var<storage, read> shade_tris: array<ShadeTri>;
@group(0) @binding(4) var<storage, read> materials: array<Material>;
@group(0) @binding(5) var<storage, read_write> sums: array<vec4<f32>>; // rgb sum, hits
@group(0) @binding(6) var<storage, read_write> gbuffer: array<GTexel>;

// voxlod-cpu's GTexel: what the ray through the pixel centre sees (coverage is set on the host).
struct GTexel {
    position: vec3<f32>,
    depth: f32,
    normal: vec3<f32>,
    coverage: f32,
    albedo: vec3<f32>,
    triangle: u32,
}

const ONE_BELOW: f32 = 0.99999994; // the largest f32 below 1

fn isqrt(c: u32) -> u32 {
    var r = u32(sqrt(f32(c)));
    while r > 0u && r * r > c {
        r -= 1u;
    }
    while (r + 1u) * (r + 1u) <= c {
        r += 1u;
    }
    return r;
}

// voxlod-cpu's sampling::stratified: sample `sample` of `count` in the pixel, jittered.
fn stratified(sample: u32, count: u32, jitter: vec2<f32>) -> vec2<f32> {
    let rows = max(isqrt(count), 1u);
    let base = count / rows;
    let long = (count % rows) * (base + 1u);
    var n = base;
    var i = 0u;
    var before = 0u;
    if sample < long {
        n = base + 1u;
        i = sample % n;
        before = sample / n * n;
    } else {
        let s = sample - long;
        i = s % base;
        before = long + s / base * base;
    }
    let lo = vec2<f32>(f32(i) / f32(n), f32(before) / f32(count));
    let size = vec2<f32>(1.0 / f32(n), f32(n) / f32(count));
    return min(lo + jitter * size, vec2<f32>(ONE_BELOW));
}

fn ray_dir(p: vec2<f32>) -> vec3<f32> {
    let ndc_x = 2.0 * p.x / f32(params.size.x) - 1.0;
    let ndc_y = 1.0 - 2.0 * p.y / f32(params.size.y);
    return normalize_or_zero(params.forward.xyz + params.right.xyz * ndc_x + params.up.xyz * ndc_y);
}

// voxlod-cpu's raycast::offset_origin.
fn offset_origin(t: ShadeTri, point: vec3<f32>, dir: vec3<f32>) -> vec3<f32> {
    let a = t.p0.xyz;
    let b = t.p1.xyz;
    let c = t.p2.xyz;
    let m = max(max(abs(a), abs(b)), abs(c));
    let eps = max(max(m.x, m.y), m.z) * (1.0 / 65536.0);
    let n = normalize_or_zero(cross(b - a, c - a));
    if all(n == vec3<f32>(0.0)) {
        return point + normalize_or_zero(dir) * eps;
    }
    return point + select(-n, n, dot(n, dir) >= 0.0) * eps;
}

// The radiance a camera ray along `dir` brings back (the background on a miss); `hit` says
// whether it met the scene.
struct Sample {
    radiance: vec3<f32>,
    hit: bool,
}

struct Surface {
    position: vec3<f32>,
    normal: vec3<f32>,
}

// The surface point of hit `h` seen along `dir` (surface.rs `surface`).
fn surface(h: Hit, dir: vec3<f32>) -> Surface {
    let t = shade_tris[h.triangle];
    let a = t.p0.xyz;
    let b = t.p1.xyz;
    let c = t.p2.xyz;
    let w = 1.0 - h.u - h.v;
    var out: Surface;
    out.position = a * w + b * h.u + c * h.v;
    var normal = normalize_or_zero(t.n0.xyz * w + t.n1.xyz * h.u + t.n2.xyz * h.v);
    if all(normal == vec3<f32>(0.0)) {
        normal = normalize_or_zero(cross(b - a, c - a));
        if all(normal == vec3<f32>(0.0)) {
            normal = vec3<f32>(0.0, 0.0, 1.0);
        }
    }
    let mat = materials[bitcast<u32>(t.p0.w)];
    if mat.albedo.w != 0.0 && dot(cross(b - a, c - a), dir) > 0.0 {
        normal = -normal;
    }
    out.normal = normal;
    return out;
}

fn centre_texel(dir: vec3<f32>) -> GTexel {
    var g: GTexel;
    let h = trace(params.eye.xyz, dir, 0.0, F32_MAX, false);
    if h.triangle == MISS {
        g.depth = bitcast<f32>(0x7f800000u); // +inf, as the CPU writes
        g.triangle = MISS;
        return g;
    }
    let s = surface(h, dir);
    g.position = s.position;
    g.depth = h.t;
    g.normal = s.normal;
    g.coverage = 1.0;
    g.albedo = materials[bitcast<u32>(shade_tris[h.triangle].p0.w)].albedo.xyz;
    g.triangle = h.triangle;
    return g;
}

fn camera_sample(dir: vec3<f32>) -> Sample {
    var out: Sample;
    let eye = params.eye.xyz;
    let h = trace(eye, dir, 0.0, F32_MAX, false);
    if h.triangle == MISS {
        out.radiance = params.background.xyz;
        out.hit = false;
        return out;
    }
    out.hit = true;
    let t = shade_tris[h.triangle];
    let sp = surface(h, dir);
    let position = sp.position;
    let normal = sp.normal;
    let mat = materials[bitcast<u32>(t.p0.w)];
    // The light seen from the point (Light::sample).
    var light: LightSample;
    let point_light = (params.size.w & 2u) != 0u;
    if point_light {
        let d = params.light_a.xyz - position;
        let dist = length(d);
        light.to_light = select(vec3<f32>(0.0, 1.0, 0.0), d / dist, dist > 0.0);
        let r = max(dist, 1e-4);
        light.irradiance = params.light_b.xyz / (r * r);
    } else {
        light.to_light = params.light_a.xyz;
        light.irradiance = params.light_b.xyz;
    }
    // One shadow ray (surface.rs `radiance`).
    var visibility = 1.0;
    if (params.size.w & 1u) != 0u && dot(normal, light.to_light) > 0.0 {
        let origin = offset_origin(t, position, light.to_light);
        var t_max = F32_MAX;
        if point_light {
            t_max = length(params.light_a.xyz - origin);
        }
        if trace(origin, light.to_light, 0.0, t_max, true).triangle != MISS {
            visibility = 0.0;
        }
    }
    var m: MaterialSample;
    m.albedo = mat.albedo.xyz;
    m.specular = mat.specular.xyz;
    m.shininess = mat.specular.w;
    out.radiance = shade(m, normal, -dir, light, visibility, params.ambient.xyz);
    return out;
}

@compute @workgroup_size(8, 8)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    let width = params.size.x;
    if id.x >= width || id.y >= params.size.y {
        return;
    }
    let pixel = id.y * width + id.x;
    let corner = vec2<f32>(f32(id.x), f32(id.y));
    let spp = params.size.z;
    var acc = sums[pixel];
    var sum = acc.xyz;
    var hits = acc.w;
    for (var s = params.samples.x; s < params.samples.y; s++) {
        let jitter = vec2<f32>(
            rand_f32(pixel, s, params.streams.x),
            rand_f32(pixel, s, params.streams.y),
        );
        let dir = ray_dir(corner + stratified(s, spp, jitter));
        let r = camera_sample(dir);
        sum += r.radiance;
        hits += select(0.0, 1.0, r.hit);
    }
    sums[pixel] = vec4<f32>(sum, hits);
    if params.samples.z == 1u {
        gbuffer[pixel] = centre_texel(ray_dir(corner + vec2<f32>(0.5)));
    }
}
