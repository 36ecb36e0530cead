// Cone tracing from shading points through a radiance octree in voxlod-octree's flat layout:
// a line-by-line port of voxlod-cone's `cone::march_cone` (with d0 = 0), `ConeTracer::
// ao_and_diffuse` / `specular` and voxlod-octree's `sample_at_level` / `sample_level` /
// `corners` / `find`, with FlatOctree's neighbour rule. The payload (`Payload`, `payload_zero`,
// `payload_add`, `payload_opacity_toward`) is defined by the source prepended to this one
// (isotropic.wgsl or directional.wgsl). Operations are written in the CPU's order (dot
// products x + y + z, products left to right) so that the two differ by rounding only.

struct Params {
    // Grid origin (f32) and, in w, the voxel size.
    grid: vec4<f32>,
    // Width of the image of shading points, point count, query bits (1 AO, 2 diffuse,
    // 4 specular), diffuse cones.
    size: vec4<u32>,
    // Octree depth, finest dense level, first row of this dispatch, rows of this dispatch.
    tree: vec4<u32>,
    // start_voxels, step_factor, opacity_cutoff, normal offset in world units.
    march: vec4<f32>,
    // 2·tan(θ/2) of the diffuse cones; the longest march in voxels for diffuse / specular
    // cones, and for AO-only cones; the AO radius in voxels.
    limits: vec4<f32>,
    // 1/n for the n diffuse cones; unused.
    extra: vec4<f32>,
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

struct Point {
    position: vec3<f32>,
    glossiness: f32,
    normal: vec3<f32>,
    // 1: position and normal usable (finite, normal not zero), 2: to_viewer usable.
    flags: u32,
    to_viewer: vec3<f32>,
    pad: u32,
}

struct Shade {
    // E/π (rgb) and AO (w).
    diffuse_ao: vec4<f32>,
    // Specular cone's radiance (rgb) and accumulated opacity (w).
    specular: vec4<f32>,
    // Octree samples of the diffuse cones, of the specular cone; unused ×2.
    steps: vec4<u32>,
}

@group(0) @binding(0) var<storage, read> params: Params;
@group(0) @binding(1) var<storage, read> levels: array<Level>;
@group(0) @binding(2) var<storage, read> nodes: array<Node>;
@group(0) @binding(3) var<storage, read> tiles: array<Tile>;
@group(0) @binding(4) var<storage, read> payload: array<Payload>;
@group(0) @binding(5) var<storage, read> directions: array<vec4<f32>>;
@group(0) @binding(6) var<storage, read> points: array<Point>;
@group(0) @binding(7) var<storage, read_write> shades: array<Shade>;

const NONE: u32 = 0xffffffffu;
// Stands for ±∞ (WGSL leaves infinities indeterminate): larger than every distance a march
// compares it with.
const BIG: f32 = 3.0e38;

fn dot3(a: vec3<f32>, b: vec3<f32>) -> f32 {
    return a.x * b.x + a.y * b.y + a.z * b.z;
}

fn length3(a: vec3<f32>) -> f32 {
    return sqrt(dot3(a, a));
}

// glam's `normalize`: `v · (1 / |v|)`.
fn normalize3(v: vec3<f32>) -> vec3<f32> {
    return v * (1.0 / length3(v));
}

// Octree::sample_level: trilinear sample of one level at grid position `pos` (the caller
// passes finite positions).
fn sample_level(pos: vec3<f32>, level: u32) -> Payload {
    var out = payload_zero();
    let depth = params.tree.x;
    let res = i32(1u << (depth - level));
    let u = pos * ldexp(1.0, -i32(level)) - 0.5;
    let lower = floor(u);
    if any(lower < vec3<f32>(-1.0)) || any(lower >= vec3<f32>(f32(res))) {
        return out;
    }
    let base = vec3<i32>(lower);
    let f = u - lower;
    let start = max(base, vec3<i32>(0));
    let s = vec3<u32>(start);
    var n = corners(level, s, u32(res));
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
        let w = wv.x * wv.y * wv.z;
        out = payload_add(out, payload[node], w);
    }
    return out;
}

// Octree::sample_at_level with `level` in [0, depth].
fn sample_at_level(pos: vec3<f32>, level: f32) -> Payload {
    let depth = params.tree.x;
    let l0 = u32(floor(level));
    let t = level - f32(l0);
    var out = sample_level(pos, l0);
    if t > 0.0 && l0 < depth {
        let upper = sample_level(pos, l0 + 1u);
        out = payload_add(payload_add(payload_zero(), out, 1.0 - t), upper, t);
    }
    return out;
}

// RadiancePayload::radiance: opacity-weighted mean radiance, zero where the opacity is.
fn payload_radiance(s: Payload) -> vec3<f32> {
    if s.opacity > 0.0 {
        return s.radiance_alpha / s.opacity;
    }
    return vec3<f32>(0.0);
}

// One axis of cone.rs's `slab` with IEEE semantics and ±∞ as ±BIG: `(lo − o)·(1/d)` and
// `(hi − o)·(1/d)`, min and max ignoring NaN (0·∞ where the origin is on a plane of a
// zero component). Returns (min, max, 1 if the min is NaN-free, 1 if the max is).
fn slab_axis(o: f32, d: f32, lo: f32, hi: f32) -> vec2<f32> {
    if d != 0.0 {
        let inv = 1.0 / d;
        let a = (lo - o) * inv;
        let b = (hi - o) * inv;
        return vec2<f32>(min(a, b), max(a, b));
    }
    // 1/±0 = ±∞: each product is ±∞ by the signs, or NaN for a zero factor.
    let negative_d = (bitcast<u32>(d) & 0x80000000u) != 0u;
    let sa = lo - o;
    let sb = hi - o;
    // ∞·sign: +BIG if the signs agree, −BIG if not; NaN (ignored) for sa == 0.
    let a = select(BIG, -BIG, (sa < 0.0) != negative_d);
    let b = select(BIG, -BIG, (sb < 0.0) != negative_d);
    if sa == 0.0 && sb == 0.0 {
        return vec2<f32>(0.0, 0.0); // unreachable: lo < hi
    }
    if sa == 0.0 {
        // min(NaN, b) = b, max(NaN, b) = b.
        return vec2<f32>(b, b);
    }
    if sb == 0.0 {
        return vec2<f32>(a, a);
    }
    return vec2<f32>(min(a, b), max(a, b));
}

struct ConeResult {
    radiance: vec3<f32>,
    opacity: f32,
    occlusion: f32,
    steps: u32,
}

// cone.rs's `march_cone` with d0 = 0: `apex` and `ao_point` in world units, unit `dir_in`,
// `two_tan` = 2·tan(θ/2), `max_voxels` = max_distance / voxel (BIG for none), `ao_radius`
// in voxels (0: no occlusion, no early stop).
fn march(
    apex: vec3<f32>,
    dir_in: vec3<f32>,
    two_tan: f32,
    max_voxels: f32,
    ao_world: vec3<f32>,
    ao_radius: f32,
) -> ConeResult {
    var out = ConeResult(vec3<f32>(0.0), 0.0, 0.0, 0u);
    let len = length3(dir_in);
    if !(len > 0.0) {
        return out;
    }
    let dir = dir_in * (1.0 / len); // normalize_or_zero
    let voxel = params.grid.w;
    let origin = (apex - params.grid.xyz) / voxel;
    let depth = params.tree.x;
    let res = f32(1u << depth);
    let sx = slab_axis(origin.x, dir.x, -1.0, res + 1.0);
    let sy = slab_axis(origin.y, dir.y, -1.0, res + 1.0);
    let sz = slab_axis(origin.z, dir.z, -1.0, res + 1.0);
    let enter = max(max(sx.x, sy.x), sz.x);
    let exit = min(min(sx.y, sy.y), sz.y);
    let max_t = min(max_voxels, exit);
    var t = max(max(params.march.x, 0.0), enter);
    var ao_point = origin;
    if ao_radius > 0.0 {
        ao_point = (ao_world - params.grid.xyz) / voxel;
    }
    let step_factor = params.march.y;
    let cutoff = params.march.z;
    let depth_f = f32(depth);
    var a = 0.0;
    while t <= max_t && a < cutoff {
        let d = max(two_tan * t, 1.0);
        let p = origin + dir * t;
        let level = min(log2(max(d, 1.0)), depth_f);
        let s = sample_at_level(p, level);
        out.steps += 1u;
        let step = step_factor * d;
        let alpha = clamp(payload_opacity_toward(s, dir), 0.0, 1.0);
        if alpha > 0.0 {
            let node = exp2(level);
            let crossed = min(step, max(exit - t, 0.0));
            let e = crossed / node;
            let base = 1.0 - alpha;
            // powf(x, 0) = 1 and powf(0, e > 0) = 0 without relying on log2(0) = −∞.
            var transmitted = 1.0;
            if e != 0.0 {
                if base > 0.0 {
                    transmitted = pow(base, e);
                } else {
                    transmitted = 0.0;
                }
            }
            let corrected = 1.0 - transmitted;
            let w = (1.0 - a) * clamp(corrected, 0.0, 1.0);
            if w > 0.0 {
                out.radiance += w * payload_radiance(s);
            }
            if ao_radius > 0.0 {
                let r = length3(p - ao_point);
                out.occlusion += w * clamp(1.0 - r / ao_radius, 0.0, 1.0);
            }
            a += w;
        }
        // cone.rs: the AO radius never ends a march (the AO-only march ends at max_t).
        t += step;
    }
    out.opacity = clamp(a, 0.0, 1.0);
    out.occlusion = clamp(out.occlusion, 0.0, 1.0);
    return out;
}

// tracer.rs's `basis` (Duff et al. 2017); the sign of n.z by its bit, as copysign reads it.
fn basis_t(n: vec3<f32>) -> vec3<f32> {
    let sign = select(1.0, -1.0, (bitcast<u32>(n.z) & 0x80000000u) != 0u);
    let a = -1.0 / (sign + n.z);
    let b = n.x * n.y * a;
    return vec3<f32>(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x);
}

fn basis_b(n: vec3<f32>) -> vec3<f32> {
    let sign = select(1.0, -1.0, (bitcast<u32>(n.z) & 0x80000000u) != 0u);
    let a = -1.0 / (sign + n.z);
    let b = n.x * n.y * a;
    return vec3<f32>(b, sign + n.y * n.y * a, -n.y);
}

@compute @workgroup_size(8, 8)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {
    let width = params.size.x;
    let row = params.tree.z + gid.y;
    if gid.x >= width || gid.y >= params.tree.w {
        return;
    }
    let i = row * width + gid.x;
    if i >= params.size.y {
        return;
    }
    let pt = points[i];
    let query = params.size.z;
    var shade = Shade(vec4<f32>(0.0, 0.0, 0.0, 1.0), vec4<f32>(0.0), vec4<u32>(0u));
    if (pt.flags & 1u) != 0u {
        let p = pt.position;
        let n = normalize3(pt.normal); // try_normalize (the host checked it succeeds)
        let offset = params.march.w;
        if (query & 3u) != 0u {
            // ConeTracer::ao_and_diffuse
            let ao = (query & 1u) != 0u;
            let diffuse = (query & 2u) != 0u;
            let apex = p + n * offset;
            let max_voxels = select(params.limits.z, params.limits.y, diffuse);
            let radius = select(0.0, params.limits.w, ao);
            let tb = basis_t(n);
            let bb = basis_b(n);
            var occ = 0.0;
            var l = vec3<f32>(0.0);
            var steps = 0u;
            for (var c = 0u; c < params.size.w; c += 1u) {
                let d = directions[c];
                let dir = normalize3(tb * d.x + bb * d.y + n * d.z);
                let r = march(apex, dir, params.limits.x, max_voxels, p, radius);
                occ += r.occlusion;
                l += r.radiance;
                steps += r.steps;
            }
            let inv = params.extra.x;
            shade.diffuse_ao = vec4<f32>(l * inv, clamp(1.0 - occ * inv, 0.0, 1.0));
            shade.steps.x = steps;
        }
        if (query & 4u) != 0u && (pt.flags & 2u) != 0u {
            // ConeTracer::specular, then ConeTracer::cone (which normalizes n again).
            let v = normalize3(pt.to_viewer);
            var r = (2.0 * dot3(n, v)) * n - v;
            let rl = length3(r);
            if rl > 0.0 {
                r = r * (1.0 / rl);
            } else {
                r = n;
            }
            let n2 = normalize3(n);
            let apex = p + n2 * offset;
            // specular_aperture: 30° − 29°·g (g clamped by the host), in radians, then the
            // march's 2·tan(θ/2) of the aperture clamped to [0, π].
            let g = pt.glossiness;
            let aperture = (30.0 - (30.0 - 1.0) * g) * 0.017453292;
            let two_tan = 2.0 * max(tan(0.5 * clamp(aperture, 0.0, 3.1415927)), 0.0);
            let c = march(apex, r, two_tan, params.limits.y, p, 0.0);
            shade.specular = vec4<f32>(c.radiance, c.opacity);
            shade.steps.y = c.steps;
        }
    }
    shades[i] = shade;
}
