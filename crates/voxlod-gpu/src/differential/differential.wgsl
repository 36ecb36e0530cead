// Differential cone tracing with coverage masks (Heitz and Neyret 2012) through a flat octree
// of MicrosurfacePayload: a line-by-line port of voxlod-cone's `DifferentialRenderer::pixel`
// (its march, shadow cones, mask table lookup and `local_illumination`), of voxlod-octree's
// quadrilinear sampling with `add_scaled_at` and `MicrosurfacePayload::decode`, and of the
// reference shader (`shade` with the visible colours, the convolved exponent and the ambient
// term on ā(v)). `smith.wgsl` and `shading.wgsl` are prepended. Operations follow the CPU's
// order (dot products x + y + z, glam's `normalize` as v·(1/|v|)).

struct Params {
    // Camera: forward (w: footprint per voxel of distance), right and up scaled by the field
    // of view (w: circle-of-confusion factor 2R/F, focus distance in voxels).
    forward: vec4<f32>,
    right: vec4<f32>,
    up: vec4<f32>,
    // The eye in grid coordinates (w: longest march in voxels, BIG for none).
    origin: vec4<f32>,
    // Grid origin in world units (w: voxel size).
    grid: vec4<f32>,
    // Light: direction toward it (directional) or position (point) (w: 1 for a point light);
    // irradiance or intensity (w: 1 if shadow cones are traced).
    light_a: vec4<f32>,
    light_b: vec4<f32>,
    // Ambient (w: element length over diameter); background (w: 1 for alpha blending).
    ambient: vec4<f32>,
    background: vec4<f32>,
    // Image width, height, first row of this dispatch, rows of this dispatch.
    size: vec4<u32>,
    // Octree depth, finest dense level; unused ×2.
    tree: vec4<u32>,
}

struct Level {
    first: u32,
    count: u32,
    res_log2: u32,
    dense: u32,
    first_tile: u32,
}

struct Node {
    child: u32,
    mask: u32,
}

struct Tile {
    links: array<u32, 3>,
}

struct Pixel {
    // Linear RGB with the background composited, and coverage.
    rgba: vec4<f32>,
    // Elements of the pixel's cone, shaded elements, shadow-cone elements; unused.
    counts: vec4<u32>,
}

@group(0) @binding(0) var<storage, read> params: Params;
@group(0) @binding(1) var<storage, read> levels: array<Level>;
@group(0) @binding(2) var<storage, read> nodes: array<Node>;
@group(0) @binding(3) var<storage, read> tiles: array<Tile>;
// MicrosurfacePayload, 22 f32 per node in its #[repr(C)] field order.
@group(0) @binding(4) var<storage, read> payload: array<f32>;
// The 256 × 256 mask table, row θ, column v.
@group(0) @binding(5) var<storage, read> masks: array<vec4<u32>>;
@group(0) @binding(6) var<storage, read_write> pixels: array<Pixel>;

const NONE: u32 = 0xffffffffu;
const BIG: f32 = 3.0e38;
const FIELDS: u32 = 22u;
const TABLE_SIDE: u32 = 256u;
const V_MAX: f32 = 1.4142135;
const TAU: f32 = 6.2831855;
const MAX_SLOPE_VARIANCE: f32 = 1e30;
const MIN_LOBE_VARIANCE: f32 = 1e-6;

fn dot3(a: vec3<f32>, b: vec3<f32>) -> f32 {
    return a.x * b.x + a.y * b.y + a.z * b.z;
}

fn length3(a: vec3<f32>) -> f32 {
    return sqrt(dot3(a, a));
}

fn normalize3(v: vec3<f32>) -> vec3<f32> {
    return v * (1.0 / length3(v));
}

fn cross3(a: vec3<f32>, b: vec3<f32>) -> vec3<f32> {
    return vec3<f32>(a.y * b.z - b.y * a.z, a.z * b.x - b.z * a.x, a.x * b.y - b.x * a.y);
}

// glam's Mat3 × Vec3 for the symmetric matrix (xx, yy, zz, xy, xz, yz).
fn sym_mul(m: array<f32, 6>, v: vec3<f32>) -> vec3<f32> {
    let c0 = vec3<f32>(m[0], m[3], m[4]);
    let c1 = vec3<f32>(m[3], m[1], m[5]);
    let c2 = vec3<f32>(m[4], m[5], m[2]);
    return c0 * v.x + c1 * v.y + c2 * v.z;
}

// glam's any_orthonormal_vector (Duff et al. 2017), the sign of z by its bit.
fn any_orthonormal(n: vec3<f32>) -> vec3<f32> {
    let sign = select(1.0, -1.0, (bitcast<u32>(n.z) & 0x80000000u) != 0u);
    let a = -1.0 / (sign + n.z);
    let b = n.x * n.y * a;
    return vec3<f32>(b, sign + n.y * n.y * a, -n.y);
}

// `acc += w·node` with the node moved to the sample point (MicrosurfacePayload::add_scaled_at):
// centroid·size − offset·coverage, variance·size².
fn add_at(acc: ptr<function, array<f32, 22>>, node: u32, w: f32, offset: vec3<f32>, size: f32) {
    let base = node * FIELDS;
    let c = payload[base];
    let moved = vec3<f32>(payload[base + 1u], payload[base + 2u], payload[base + 3u]) * size
        - offset * c;
    for (var k = 0u; k < FIELDS; k += 1u) {
        var v = payload[base + k];
        if k >= 1u && k <= 3u {
            v = moved[k - 1u];
        } else if k == 13u {
            v = v * (size * size);
        }
        (*acc)[k] += w * v;
    }
}

fn sample_level(acc: ptr<function, array<f32, 22>>, pos: vec3<f32>, level: u32, weight: f32) {
    let depth = params.tree.x;
    let res = i32(1u << (depth - level));
    let u = pos * ldexp(1.0, -i32(level)) - 0.5;
    let lower = floor(u);
    if any(lower < vec3<f32>(-1.0)) || any(lower >= vec3<f32>(f32(res))) {
        return;
    }
    let base = vec3<i32>(lower);
    let f = u - lower;
    let start = max(base, vec3<i32>(0));
    let s = vec3<u32>(start);
    var n = corners(level, s, u32(res));
    let node_size = f32(1u << level);
    for (var e = 0u; e < 8u; e += 1u) {
        let off = vec3<i32>(i32(e & 1u), i32((e >> 1u) & 1u), i32((e >> 2u) & 1u));
        let c = base + off;
        if any(c < vec3<i32>(0)) || any(c >= vec3<i32>(res)) {
            continue;
        }
        let d = c - start;
        let node = n[u32(d.x + 2 * d.y + 4 * d.z)];
        if node == NONE {
            continue;
        }
        let wv = select(1.0 - f, f, off != vec3<i32>(0));
        let w = (wv.x * wv.y) * wv.z;
        add_at(acc, node, w * weight, (f - vec3<f32>(off)) * node_size, node_size);
    }
}

// Octree::sample_at_level with `level` in [0, depth]: the two levels blended linearly.
fn sample_at_level(pos: vec3<f32>, level: f32) -> array<f32, 22> {
    var acc: array<f32, 22>;
    let depth = params.tree.x;
    let l0 = u32(floor(level));
    let t = level - f32(l0);
    if t > 0.0 && l0 < depth {
        var lower: array<f32, 22>;
        sample_level(&lower, pos, l0, 1.0);
        var upper: array<f32, 22>;
        sample_level(&upper, pos, l0 + 1u, 1.0);
        for (var k = 0u; k < FIELDS; k += 1u) {
            acc[k] = 0.0 + (1.0 - t) * lower[k];
            acc[k] += t * upper[k];
        }
    } else {
        sample_level(&acc, pos, l0, 1.0);
    }
    return acc;
}

// MicrosurfacePayload::decode (ok = false: no surface).
struct Micro {
    ok: bool,
    distance: f32,
    normal: vec3<f32>,
    moments: array<f32, 6>,
    albedo: vec3<f32>,
    slope: vec3<f32>,
    specular: f32,
    roughness: f32,
}

fn decode(s: array<f32, 22>) -> Micro {
    var m: Micro;
    let c = s[0];
    let g = vec3<f32>(s[4], s[5], s[6]);
    let len = length3(g);
    m.ok = c > 0.0 && len > 0.0 && len <= BIG;
    if !m.ok {
        return m;
    }
    let inv = 1.0 / c;
    m.normal = g / len;
    m.distance = -dot3(m.normal, vec3<f32>(s[1], s[2], s[3]) * inv);
    for (var k = 0u; k < 6u; k += 1u) {
        m.moments[k] = s[7u + k] * inv;
    }
    m.albedo = vec3<f32>(s[14], s[15], s[16]) * inv;
    m.slope = vec3<f32>(s[17], s[18], s[19]) * inv;
    m.specular = s[20] * inv;
    m.roughness = s[21] * inv;
    return m;
}

fn slope_variance_along(m: Micro, t: vec3<f32>) -> f32 {
    let along = dot3(m.normal, sym_mul(m.moments, m.normal));
    let across = max(dot3(t, sym_mul(m.moments, t)), 0.0);
    if along > 0.0 {
        return min(across / along, MAX_SLOPE_VARIANCE);
    }
    return MAX_SLOPE_VARIANCE;
}

fn slope_variance(m: Micro) -> f32 {
    let along = dot3(m.normal, sym_mul(m.moments, m.normal));
    let trace = m.moments[0] + m.moments[1] + m.moments[2];
    if along > 0.0 {
        return min(max(trace - along, 0.0) / (2.0 * along), MAX_SLOPE_VARIANCE);
    }
    return MAX_SLOPE_VARIANCE;
}

// shading.rs's lambda_toward.
fn lambda_toward(m: Micro, n: vec3<f32>, d: vec3<f32>) -> f32 {
    let cos_t = dot3(n, d);
    let sin_t = length3(cross3(n, d));
    if sin_t <= 0.0 || cos_t <= 0.0 {
        return lambda_cs(cos_t, max(sin_t, 0.0), 0.0);
    }
    let t = (d - n * cos_t) * (1.0 / sin_t);
    return lambda_cs(cos_t, sin_t, sqrt(slope_variance_along(m, t)));
}

// The light at world position p: direction, irradiance, distance (BIG for a directional
// light); ok = false at a point light's own position.
struct LightAt {
    ok: bool,
    dir: vec3<f32>,
    irradiance: vec3<f32>,
    distance: f32,
}

fn light_at(p: vec3<f32>) -> LightAt {
    var l: LightAt;
    if params.light_a.w == 0.0 {
        l.ok = true;
        l.dir = params.light_a.xyz;
        l.irradiance = params.light_b.xyz;
        l.distance = BIG;
        return l;
    }
    let d = params.light_a.xyz - p;
    let dist2 = dot3(d, d);
    l.ok = dist2 > 0.0;
    if l.ok {
        let dist = sqrt(dist2);
        l.dir = d / dist;
        l.irradiance = params.light_b.xyz / dist2;
        l.distance = dist;
    }
    return l;
}

fn world(p: vec3<f32>) -> vec3<f32> {
    return params.grid.xyz + p * params.grid.w;
}

// One slab axis of cone.rs's `slab` with ±∞ as ±BIG (cone.wgsl's slab_axis).
fn slab_axis(o: f32, d: f32, lo: f32, hi: f32) -> vec2<f32> {
    if d != 0.0 {
        let inv = 1.0 / d;
        let a = (lo - o) * inv;
        let b = (hi - o) * inv;
        return vec2<f32>(min(a, b), max(a, b));
    }
    let negative_d = (bitcast<u32>(d) & 0x80000000u) != 0u;
    let sa = lo - o;
    let sb = hi - o;
    let a = select(BIG, -BIG, (sa < 0.0) != negative_d);
    let b = select(BIG, -BIG, (sb < 0.0) != negative_d);
    if sa == 0.0 {
        return vec2<f32>(b, b);
    }
    if sb == 0.0 {
        return vec2<f32>(a, a);
    }
    return vec2<f32>(min(a, b), max(a, b));
}

fn footprint(d0: f32, spread: f32, coc: f32, focus: f32, t: f32) -> f32 {
    let d = d0 + spread * t + coc * abs(t - focus);
    return min(max(d, 0.0), BIG);
}

// MaskTable::lookup.
fn lookup(theta: f32, v: f32) -> vec4<u32> {
    if v < -V_MAX {
        return vec4<u32>(0u);
    }
    if v >= V_MAX {
        return vec4<u32>(0xffffffffu);
    }
    let n = f32(TABLE_SIDE);
    let turns0 = theta * (1.0 / TAU);
    let turns = turns0 - floor(turns0);
    let i = min(u32(turns * n), TABLE_SIDE - 1u);
    let j = min(u32((v + V_MAX) * (n / (2.0 * V_MAX))), TABLE_SIDE - 1u);
    return masks[i * TABLE_SIDE + j];
}

// MaskTable::element.
fn element_mask(n: vec3<f32>, h: f32, r: f32, l: f32) -> vec4<u32> {
    let rhs = l * abs(n.z) - h;
    let nxy = sqrt(n.x * n.x + n.y * n.y);
    let across = r * nxy;
    if across <= abs(rhs) * (1.0 / 65536.0) {
        return select(vec4<u32>(0u), vec4<u32>(0xffffffffu), rhs >= 0.0);
    }
    return lookup(atan2(n.y, n.x), rhs / across);
}

fn bits(m: vec4<u32>) -> u32 {
    return countOneBits(m.x) + countOneBits(m.y) + countOneBits(m.z) + countOneBits(m.w);
}

fn level_for(d: f32) -> f32 {
    return min(log2(max(d, 1.0)), f32(params.tree.x));
}

// DifferentialRenderer::shadow: visibility of the light from an element at p (grid) with
// shading normal n and footprint d; x: visibility, y: elements (as f32).
fn shadow(p: vec3<f32>, n: vec3<f32>, d: f32) -> vec2<f32> {
    let la = light_at(world(p));
    if !la.ok {
        return vec2<f32>(1.0, 0.0);
    }
    if dot3(n, la.dir) <= 0.0 || all(la.irradiance == vec3<f32>(0.0)) {
        return vec2<f32>(0.0, 0.0);
    }
    let apex = p + n * (1.5 * max(d, 1.0));
    let lb = light_at(world(apex));
    if !lb.ok {
        return vec2<f32>(1.0, 0.0);
    }
    let dir = lb.dir;
    var max_t = BIG;
    if lb.distance < BIG {
        max_t = max(lb.distance / params.grid.w - 1.0, 0.0);
    }
    let fx = any_orthonormal(dir);
    let fy = cross3(fx, dir);
    let res = f32(1u << params.tree.x);
    let sx = slab_axis(apex.x, dir.x, -1.0, res + 1.0);
    let sy = slab_axis(apex.y, dir.y, -1.0, res + 1.0);
    let sz = slab_axis(apex.z, dir.z, -1.0, res + 1.0);
    let enter = max(max(sx.x, sy.x), sz.x);
    let exit = min(min(sx.y, sy.y), sz.y);
    let end = min(max_t, exit);
    var t = max(enter, 0.0);
    var alpha = vec4<u32>(0u);
    var elements = 0u;
    let factor = params.ambient.w;
    let spread = params.forward.w;
    loop {
        if !(t <= end) {
            break;
        }
        let len = factor * max(footprint(d, spread, 0.0, 1.0, t), 1.0);
        let tc = t + 0.5 * len;
        let dc = footprint(d, spread, 0.0, 1.0, tc);
        let q = apex + dir * tc;
        elements += 1u;
        let m = decode(sample_at_level(q, level_for(dc)));
        if m.ok {
            let nl = vec3<f32>(dot3(m.normal, fx), dot3(m.normal, fy), dot3(m.normal, dir));
            let mask = element_mask(nl, m.distance, 0.5 * dc, 0.5 * len);
            if bits(mask & ~alpha) > 0u {
                alpha = alpha | mask;
                if all(alpha == vec4<u32>(0xffffffffu)) {
                    break;
                }
            }
        }
        t += len;
    }
    return vec2<f32>(1.0 - f32(bits(alpha)) / 128.0, f32(elements));
}

@compute @workgroup_size(8, 8)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {
    let width = params.size.x;
    let height = params.size.y;
    let y = params.size.z + gid.y;
    if gid.x >= width || gid.y >= params.size.w {
        return;
    }
    let x = gid.x;
    // DifferentialRenderer::ray_dir at the pixel's centre.
    let ndc_x = 2.0 * (f32(x) + 0.5) / f32(width) - 1.0;
    let ndc_y = 1.0 - 2.0 * (f32(y) + 0.5) / f32(height);
    let dir = normalize3(params.forward.xyz + params.right.xyz * ndc_x + params.up.xyz * ndc_y);
    // The footprint frame.
    var fx = normalize_or_zero(params.right.xyz - dir * dot3(params.right.xyz, dir));
    if all(fx == vec3<f32>(0.0)) {
        fx = any_orthonormal(dir);
    }
    let fy = cross3(fx, dir);
    let origin = params.origin.xyz;
    let spread = params.forward.w;
    let coc = params.right.w;
    let focus = params.up.w;
    let factor = params.ambient.w;
    let blend = params.background.w != 0.0;
    let shadows = params.light_b.w != 0.0;
    let res = f32(1u << params.tree.x);
    let sx = slab_axis(origin.x, dir.x, -1.0, res + 1.0);
    let sy = slab_axis(origin.y, dir.y, -1.0, res + 1.0);
    let sz = slab_axis(origin.z, dir.z, -1.0, res + 1.0);
    let enter = max(max(sx.x, sy.x), sz.x);
    let exit = min(min(sx.y, sy.y), sz.y);
    let end = min(params.origin.w, exit);
    var t = max(enter, 0.0);
    var alpha = vec4<u32>(0u);
    var a = 0.0;
    var radiance = vec3<f32>(0.0);
    var counts = vec4<u32>(0u);
    var cached = false;
    var cached_at = vec3<f32>(0.0);
    var cached_v = 1.0;
    loop {
        if !(t <= end) {
            break;
        }
        let len = factor * max(footprint(0.0, spread, coc, focus, t), 1.0);
        let tc = t + 0.5 * len;
        let d = footprint(0.0, spread, coc, focus, tc);
        let level = level_for(d);
        let p = origin + dir * tc;
        counts.x += 1u;
        let m = decode(sample_at_level(p, level));
        if m.ok {
            let nl = vec3<f32>(dot3(m.normal, fx), dot3(m.normal, fy), dot3(m.normal, dir));
            let mask = element_mask(nl, m.distance, 0.5 * d, 0.5 * len);
            var weight = 0.0;
            if blend {
                weight = (1.0 - a) * (f32(bits(mask)) / 128.0);
            } else {
                weight = f32(bits(mask & ~alpha)) / 128.0;
            }
            if weight > 0.0 {
                // local_illumination, then the reference shader.
                let v = -dir;
                let position = world(p);
                let la = light_at(position);
                var n = m.normal;
                if dot3(n, v) < 0.0 {
                    n = -n;
                }
                let lv = lambda_toward(m, n, v);
                var ll = 0.0;
                if la.ok {
                    ll = lambda_toward(m, n, la.dir);
                }
                let albedo = clamp(m.albedo + m.slope * attribute_factor(lv, ll), vec3<f32>(0.0), vec3<f32>(1.0));
                let ambient_albedo = clamp(m.albedo + m.slope * attribute_factor(lv, 0.0), vec3<f32>(0.0), vec3<f32>(1.0));
                var micro = 0.0;
                if la.ok {
                    micro = light_visibility(lv, ll);
                }
                let lobe = max(slope_variance(m) + m.roughness, MIN_LOBE_VARIANCE);
                let exponent = max(1.0 / lobe - 2.0, 0.0);
                var v_shadow = 1.0;
                if shadows && la.ok {
                    if cached && length3(cached_at - p) <= max(d, 1.0) {
                        v_shadow = cached_v;
                    } else {
                        let sh = shadow(p, n, d);
                        v_shadow = sh.x;
                        counts.z += u32(sh.y);
                        cached = true;
                        cached_at = p;
                        cached_v = sh.x;
                    }
                }
                var light: LightSample;
                light.to_light = la.dir;
                light.irradiance = select(vec3<f32>(0.0), la.irradiance, la.ok);
                var material: MaterialSample;
                material.albedo = albedo;
                material.specular = vec3<f32>(m.specular);
                material.shininess = exponent;
                let l = shade(material, n, v, light, micro * v_shadow, vec3<f32>(0.0))
                    + ambient_albedo * params.ambient.xyz;
                radiance += l * weight;
                counts.y += 1u;
                if blend {
                    a += weight;
                    if a >= 0.999 {
                        break;
                    }
                } else {
                    alpha = alpha | mask;
                    if all(alpha == vec4<u32>(0xffffffffu)) {
                        break;
                    }
                }
            }
        }
        t += len;
    }
    var coverage = clamp(a, 0.0, 1.0);
    if !blend {
        coverage = f32(bits(alpha)) / 128.0;
    }
    let rgb = radiance + (1.0 - coverage) * params.background.xyz;
    pixels[y * width + x] = Pixel(vec4<f32>(rgb, coverage), counts);
}
