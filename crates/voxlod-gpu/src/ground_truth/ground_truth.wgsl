// The ground-truth renderer (voxlod-cpu's render::ground_truth + render::surface), appended to
// random.wgsl, shading.wgsl, material.wgsl, bvh.wgsl and bvh_alpha.wgsl. One invocation per pixel
// in 8×8 tiles (neighbouring rays walk the same BVH nodes); a dispatch covers samples [first, end)
// of every pixel and adds them, in sample order, to the pixel's running sum, so a dispatch's length
// is bounded whatever the samples per pixel and the sum's order is the CPU's.

struct Params {
    eye: vec4<f32>,
    forward: vec4<f32>,
    right: vec4<f32>,        // scaled by tan(fov/2)·aspect
    up: vec4<f32>,           // scaled by tan(fov/2)
    background: vec4<f32>,
    ambient: vec4<f32>,
    light_a: vec4<f32>,      // directional: unit to_light; point: position
    light_b: vec4<f32>,      // directional: irradiance; point: intensity
    size: vec4<u32>,         // width, height, spp, flags (1: shadows, 2: point light, 4: alpha tests)
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
    uv01: vec4<f32>, // vertex UVs 0 (xy) and 1 (zw)
    uv2: vec4<f32>,  // vertex UV 2 (xy)
}

@group(0) @binding(0) var<storage, read> params: Params;
@group(0) @binding(3) var<storage, read> shade_tris: array<ShadeTri>;
@group(0) @binding(4) var<storage, read> materials: array<Material>;
@group(0) @binding(5) var<storage, read_write> sums: array<vec4<f32>>; // rgb sum, hits
@group(0) @binding(6) var<storage, read_write> gbuffer: array<GTexel>;
@group(0) @binding(7) var<storage, read> textures: Textures;
@group(0) @binding(8) var<storage, read> texels: array<u32>;

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

// voxlod-cpu's raycast::offset_origin: back along the ray that found `point` to `eps` above the
// triangle's plane (off every face through `point`), or along the normal when seen grazing.
fn offset_origin(t: ShadeTri, point: vec3<f32>, dir: vec3<f32>, to_viewer: vec3<f32>) -> vec3<f32> {
    let a = t.p0.xyz;
    let b = t.p1.xyz;
    let c = t.p2.xyz;
    let m = max(max(abs(a), abs(b)), abs(c));
    let eps = max(max(m.x, m.y), m.z) * (1.0 / 65536.0);
    var n = normalize_or_zero(cross(b - a, c - a));
    if all(n == vec3<f32>(0.0)) {
        n = normalize_or_zero(dir);
    } else {
        n = select(-n, n, dot(n, dir) >= 0.0);
    }
    let v = normalize_or_zero(to_viewer);
    let cos_v = dot(n, v);
    if cos_v >= 1.0 / 64.0 {
        return point + v * (eps / cos_v);
    }
    return point + n * eps;
}

struct Surface {
    position: vec3<f32>,
    normal: vec3<f32>,
    material: MaterialEval,
}

// Geometry::interpolate's UV: uv0·(1 − u − v) + uv1·u + uv2·v.
fn hit_uv(t: ShadeTri, u: f32, v: f32) -> vec2<f32> {
    let w = 1.0 - u - v;
    return t.uv01.xy * w + t.uv01.zw * u + t.uv2.xy * v;
}

// surface.rs `accepts`: whether a candidate hit counts for the ray (the alpha test).
fn accepts_hit(triangle: u32, u: f32, v: f32, ray: AlphaRay) -> bool {
    if (params.size.w & 4u) == 0u {
        return true;
    }
    let t = shade_tris[triangle];
    let m = bitcast<u32>(t.p0.w);
    let mode = materials[m].alpha_mode;
    if mode == 0u {
        return true;
    }
    let alpha = material_alpha(m, hit_uv(t, u, v));
    if mode == 2u {
        return rand_f32(ray.pixel, ray.sample, ray.key ^ triangle) < alpha;
    }
    return alpha > 0.0;
}

fn primary_ray(pixel: u32, sample: u32) -> AlphaRay {
    return AlphaRay(pixel, sample, params.streams.z);
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
    let m = bitcast<u32>(t.p0.w);
    out.material = material_sample(m, hit_uv(t, h.u, h.v));
    if materials[m].double_sided != 0u && dot(cross(b - a, c - a), dir) > 0.0 {
        normal = -normal;
    }
    out.normal = normal;
    return out;
}

// The sample index of the pixel-centre ray in the random streams (ground_truth.rs CENTRE_SAMPLE).
const CENTRE_SAMPLE: u32 = 0xffffffffu;

// The light seen from `position` (Light::sample).
fn light_at(position: vec3<f32>) -> LightSample {
    var light: LightSample;
    if (params.size.w & 2u) != 0u {
        let d = params.light_a.xyz - position;
        let dist = length(d);
        light.to_light = select(vec3<f32>(0.0, 1.0, 0.0), d / dist, dist > 0.0);
        let r = max(dist, 1e-4);
        light.irradiance = params.light_b.xyz / (r * r);
    } else {
        light.to_light = params.light_a.xyz;
        light.irradiance = params.light_b.xyz;
    }
    return light;
}

const CAMERA: u32 = 0u;
const SHADOW: u32 = 1u;
const CENTRE: u32 = 2u;

// One invocation per pixel. Its rays — per sample a camera ray, then its shadow ray when the
// light is above the horizon; then the pixel-centre ray on the last dispatch — go through ONE
// call of `trace_alpha` and one of `surface` in a loop: every call site of the traversal and
// of the texture sampling is inlined by the driver's compiler, and three copies of them made
// lavapipe's compile take minutes. The arithmetic per ray is surface.rs's.
@compute @workgroup_size(8, 8)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    let width = params.size.x;
    if id.x >= width || id.y >= params.size.y {
        return;
    }
    let pixel = id.y * width + id.x;
    let corner = vec2<f32>(f32(id.x), f32(id.y));
    let spp = params.size.z;
    let eye = params.eye.xyz;
    var acc = sums[pixel];
    var sum = acc.xyz;
    var hits = acc.w;
    var s = params.samples.x;
    var centre_pending = params.samples.z == 1u;
    // The camera sample waiting for its shadow ray.
    var shadow_pending = false;
    var origin = vec3<f32>(0.0);
    var shadow_t_max = F32_MAX;
    var dir = vec3<f32>(0.0);
    var normal = vec3<f32>(0.0);
    var light: LightSample;
    var m: MaterialSample;
    loop {
        var stage = CAMERA;
        var o = eye;
        var d = vec3<f32>(0.0);
        var t_max = F32_MAX;
        var ray = primary_ray(pixel, s);
        if shadow_pending {
            stage = SHADOW;
            o = origin;
            d = light.to_light;
            t_max = shadow_t_max;
            ray = AlphaRay(pixel, s, params.streams.w);
        } else if s < params.samples.y {
            let jitter = vec2<f32>(
                rand_f32(pixel, s, params.streams.x),
                rand_f32(pixel, s, params.streams.y),
            );
            dir = ray_dir(corner + stratified(s, spp, jitter));
            d = dir;
        } else if centre_pending {
            stage = CENTRE;
            dir = ray_dir(corner + vec2<f32>(0.5));
            d = dir;
            ray = primary_ray(pixel, CENTRE_SAMPLE);
        } else {
            break;
        }
        let h = trace_alpha(o, d, 0.0, t_max, stage == SHADOW, ray);
        var visibility = 1.0;
        if stage == SHADOW {
            shadow_pending = false;
            if h.triangle != MISS {
                visibility = 0.0;
            }
        } else if h.triangle == MISS {
            if stage == CENTRE {
                var g: GTexel;
                g.depth = bitcast<f32>(0x7f800000u); // +inf, as the CPU writes
                g.triangle = MISS;
                gbuffer[pixel] = g;
                centre_pending = false;
            } else {
                sum += params.background.xyz;
                s += 1u;
            }
            continue;
        } else {
            let sp = surface(h, dir);
            if stage == CENTRE {
                var g: GTexel;
                g.position = sp.position;
                g.depth = h.t;
                g.normal = sp.normal;
                g.coverage = 1.0;
                g.albedo = sp.material.albedo;
                g.triangle = h.triangle;
                gbuffer[pixel] = g;
                centre_pending = false;
                continue;
            }
            hits += 1.0;
            normal = sp.normal;
            m.albedo = sp.material.albedo;
            m.specular = sp.material.specular;
            m.shininess = sp.material.shininess;
            light = light_at(sp.position);
            // One shadow ray (surface.rs `radiance`), from the offset origin.
            if (params.size.w & 1u) != 0u && dot(normal, light.to_light) > 0.0 {
                origin = offset_origin(shade_tris[h.triangle], sp.position, light.to_light, -dir);
                shadow_t_max = F32_MAX;
                if (params.size.w & 2u) != 0u {
                    shadow_t_max = length(params.light_a.xyz - origin);
                }
                shadow_pending = true;
                continue;
            }
        }
        sum += shade(m, normal, -dir, light, visibility, params.ambient.xyz);
        s += 1u;
    }
    sums[pixel] = vec4<f32>(sum, hits);
}
