// The filtered voxel renderer for Averages and [VJK21] (SGGX) records (voxlod-cpu's
// render::filtered with appearance::averages, appearance::sggx and appearance::transmittance), and
// the baseline renderer of opaque voxels (render::baseline), appended to shading.wgsl. One
// invocation per pixel in 8×8 tiles; each pixel sends the 4 rays of PATTERN_4 through the grid with
// the DDA of render/dda.rs (the same plane expression, tie rule and clipping), composites the
// voxels with a record front to back until T < 0.001, and evaluates every voxel it meets per hit:
// radiance and opacity for the voxel-centre-to-camera direction, and the voxel's shadow ray, are
// functions of the voxel alone, so they equal the CPU's cached values (see mod.rs).

struct Params {
    eye: vec4<f32>,
    eye_grid: vec4<f32>,     // eye in grid coordinates (host: f64 → f32, as Dda::new); w = 1/voxel size
    forward: vec4<f32>,
    right: vec4<f32>,        // scaled by tan(fov/2)·aspect
    up: vec4<f32>,           // scaled by tan(fov/2)
    background: vec4<f32>,
    ambient: vec4<f32>,
    light_a: vec4<f32>,      // directional: unit to_light; point: position
    light_b: vec4<f32>,      // directional: irradiance; point: intensity
    grid: vec4<f32>,         // origin (f32), w = voxel size (f32)
    dims: vec4<u32>,         // grid dims, w = flags (1: shadows, 2: point light)
    size: vec4<u32>,         // width, height, max DDA steps, kind (0 Averages, 1 [VJK21], 2 baseline,
                             // 3 virtual mesh, 4 Adaptive)
    brick_dims: vec4<u32>,   // bricks per axis, 0
    vmesh: vec4<u32>,        // virtual mesh: rule (0 Lines, 1 Circles), samples per face,
                             // projected area (0/1), voxels with a record (voxels.wgsl)
}

// One allocated brick: occupancy in linear order (bit x + 8y + 64z of the 512, 16 words), and
// the rank (index into `slots`) of the first occupied voxel of each word.
struct Brick {
    mask: array<u32, 16>,
    before: array<u32, 16>,
}

// A record decoded on the host by voxlod-format's decoders.
// Averages: a = (albedo, opacity), b = (mean normal (zero: none), 0), c.w = specular level,
// d.w = shininess. [VJK21]: a = (albedo, σ), b.w = γ, the SGGX matrix's columns in b, c, d.
// Baseline: a = (albedo, 1): an opaque cube, so a shadow ray's transmittance drops to 0 at the
// first voxel it counts (the CPU's "blocked").
struct Record {
    a: vec4<f32>,
    b: vec4<f32>,
    c: vec4<f32>,
    d: vec4<f32>,
}

@group(0) @binding(0) var<storage, read> params: Params;
@group(0) @binding(1) var<storage, read> brick_table: array<u32>;
@group(0) @binding(2) var<storage, read> bricks: array<Brick>;
@group(0) @binding(3) var<storage, read> slots: array<u32>;
@group(0) @binding(4) var<storage, read> records: array<Record>;
@group(0) @binding(5) var<storage, read_write> pixels: array<vec4<f32>>;

const NONE: u32 = 0xffffffffu;
const MIN_TRANSMITTANCE: f32 = 0.001;
const F32_MIN_POSITIVE: f32 = 1.17549435e-38;
// Voxels whose centres are closer than 1.5 voxel sizes to a shadow ray's start are ignored.
const SHADOW_SKIP_SQ: i32 = 2;

const PATTERN_4 = array<vec2<f32>, 4>(
    vec2<f32>(0.375, 0.125),
    vec2<f32>(0.875, 0.375),
    vec2<f32>(0.125, 0.625),
    vec2<f32>(0.625, 0.875),
);

fn finite3(v: vec3<f32>) -> bool {
    return all(abs(v) <= vec3<f32>(F32_MAX));
}

// ---- The DDA of render/dda.rs, with its empty-space skipping (`walk_next`, below).

struct Dda {
    origin: vec3<f32>,
    inv: vec3<f32>,
    dir: vec3<f32>,
    step: vec3<i32>,
    dims: vec3<i32>,
    cell: vec3<i32>,
    t: f32,
    t_end: f32,
    t_base: f32,
    // Outward normal of the face the current voxel was entered through (0: started inside).
    entry: vec3<i32>,
    done: bool,
    // The brick of the last look-up and its ordinal (NONE: unallocated), as Dda's
    // cached_brick / cached_index.
    brick: vec3<i32>,
    brick_index: u32,
    // Iterations left: every loop of a walk is bounded by the voxels a ray can visit.
    budget: u32,
}

fn plane(d: Dda, a: u32, k: i32) -> f32 {
    return (f32(k) - d.origin[a]) * d.inv[a];
}

// Dda::next_t: a parallel axis never crosses (F32_MAX stands for +∞: every crossing is below).
fn next_t(d: Dda, a: u32, c: i32) -> f32 {
    if d.step[a] == 1 {
        return plane(d, a, c + 1);
    }
    if d.step[a] == -1 {
        return plane(d, a, c);
    }
    return F32_MAX;
}

// Dda::locate: the voxel holding the ray at t, searched in [lo, hi].
fn locate(d: Dda, t: f32, lo: vec3<i32>, hi: vec3<i32>) -> vec3<i32> {
    let p = d.origin + d.dir * t;
    var c = clamp(vec3<i32>(p), lo, hi);
    for (var a = 0u; a < 3u; a++) {
        let s = d.step[a];
        if s == 0 {
            continue;
        }
        var near_end = lo[a];
        var far_end = hi[a];
        if s < 0 {
            near_end = hi[a];
            far_end = lo[a];
        }
        // Bounded by the box: each loop moves c[a] monotonically toward an end.
        loop {
            if c[a] == far_end || next_t(d, a, c[a]) > t {
                break;
            }
            c[a] += s;
        }
        loop {
            if c[a] == near_end {
                break;
            }
            let enter = select(c[a] + 1, c[a], s > 0);
            if plane(d, a, enter) <= t {
                break;
            }
            c[a] -= s;
        }
    }
    return c;
}

// Dda::new for a ray already in grid coordinates (origin o, direction dir/voxel size).
fn dda_new(o: vec3<f32>, dir: vec3<f32>, t_min: f32, t_max: f32) -> Dda {
    var s: Dda;
    s.dims = vec3<i32>(params.dims.xyz);
    s.done = true;
    s.brick = vec3<i32>(-1);
    s.brick_index = NONE;
    s.budget = params.size.z;
    if !(finite3(o) && finite3(dir) && t_min <= t_max) {
        return s;
    }
    let parallel = abs(dir) < vec3<f32>(F32_MIN_POSITIVE);
    let d = select(dir, vec3<f32>(0.0), parallel);
    if all(d == vec3<f32>(0.0)) {
        return s;
    }
    s.step = select(vec3<i32>(sign(d)), vec3<i32>(0), parallel);
    s.inv = select(1.0 / d, vec3<f32>(0.0), parallel);
    s.dir = d;
    var t0 = t_min;
    var t1 = t_max;
    var entry_axis = 3u;
    for (var a = 0u; a < 3u; a++) {
        if parallel[a] {
            if !(o[a] >= 0.0 && o[a] < f32(s.dims[a])) {
                return s;
            }
            continue;
        }
        var near = 0.0;
        var far = f32(s.dims[a]);
        if d[a] < 0.0 {
            near = far;
            far = 0.0;
        }
        let tn = (near - o[a]) * s.inv[a];
        let tf = (far - o[a]) * s.inv[a];
        if tn > t0 {
            t0 = tn;
            entry_axis = a;
        }
        t1 = min(t1, tf);
    }
    if t0 >= t1 {
        return s;
    }
    let start = select(0.0, t0, abs(t0) <= F32_MAX);
    s.origin = select(o + d * start, o, parallel);
    if entry_axis < 3u {
        s.origin[entry_axis] = select(f32(s.dims[entry_axis]), 0.0, d[entry_axis] > 0.0);
    }
    s.t_base = start;
    s.t = t0 - start;
    s.t_end = t1 - start;
    s.cell = locate(s, s.t, vec3<i32>(0), s.dims - vec3<i32>(1));
    if entry_axis < 3u {
        s.entry[entry_axis] = -s.step[entry_axis];
    }
    s.done = false;
    return s;
}

struct Step {
    voxel: vec3<i32>,
    t_enter: f32,
    t_exit: f32,
    normal: vec3<i32>,
}

// Dda::normal_for: the entry normal for crossing the planes of `axes` (the largest |dir|
// among them, the first on ties).
fn normal_for(d: Dda, axes: vec3<i32>) -> vec3<i32> {
    var best = 0u;
    var best_d = -1.0;
    for (var a = 0u; a < 3u; a++) {
        if axes[a] != 0 && abs(d.dir[a]) > best_d {
            best = a;
            best_d = abs(d.dir[a]);
        }
    }
    var n = vec3<i32>(0);
    n[best] = -d.step[best];
    return n;
}

// Dda::emit_and_advance: the current voxel, then the walk moves past it.
fn dda_next(s: ptr<function, Dda>) -> Step {
    let d = *s;
    let ts = vec3<f32>(next_t(d, 0u, d.cell.x), next_t(d, 1u, d.cell.y), next_t(d, 2u, d.cell.z));
    let tn = min(min(ts.x, ts.y), ts.z);
    let axes = select(vec3<i32>(0), vec3<i32>(1), ts == vec3<f32>(tn));
    var out: Step;
    out.voxel = d.cell;
    out.t_enter = d.t_base + d.t;
    out.t_exit = d.t_base + min(tn, d.t_end);
    out.normal = d.entry;
    let cell = d.cell + d.step * axes;
    if tn >= d.t_end || any(cell < vec3<i32>(0)) || any(cell >= d.dims) {
        (*s).done = true;
    } else {
        (*s).entry = normal_for(d, axes);
        (*s).cell = cell;
        (*s).t = tn;
    }
    return out;
}

// ---- Empty-space skipping: Dda::next_occupied_voxel of render/dda.rs. Empty 8³ bricks and
// empty 2³ blocks are crossed in one jump each; the exit planes come from the one plane
// expression and the cell entered from the same tie rules, so the walk meets the voxels with
// a record that plain stepping meets, with the same t and entry normals (proptested on the CPU).

fn brick_at(b: vec3<i32>) -> u32 {
    let u = vec3<u32>(b);
    let bd = params.brick_dims.xyz;
    return brick_table[u.x + bd.x * (u.y + bd.y * u.z)];
}

// Dda::next_crossing: the earliest plane crossing after `cell`, and the axes crossing there.
struct Crossing {
    t: f32,
    axes: vec3<bool>,
}

fn next_crossing(d: Dda, cell: vec3<i32>) -> Crossing {
    let ts = vec3<f32>(next_t(d, 0u, cell.x), next_t(d, 1u, cell.y), next_t(d, 2u, cell.z));
    let t = min(min(ts.x, ts.y), ts.z);
    return Crossing(t, ts == vec3<f32>(t));
}

fn axes_i(axes: vec3<bool>) -> vec3<i32> {
    return select(vec3<i32>(0), vec3<i32>(1), axes);
}

// Dda::enter_at: into the cell of [lo, hi] holding the ray at t, crossed at t through the
// planes of `axes` and of every axis whose entry plane lies exactly at t.
fn enter_at(s: ptr<function, Dda>, t: f32, axes: vec3<bool>, lo: vec3<i32>, hi: vec3<i32>) {
    let d = *s;
    let cell = locate(d, t, lo, hi);
    var entered = axes;
    for (var a = 0u; a < 3u; a++) {
        let st = d.step[a];
        let enter = select(cell[a] + 1, cell[a], st > 0);
        if st != 0 && plane(d, a, enter) == t {
            entered[a] = true;
        }
    }
    (*s).cell = cell;
    (*s).entry = normal_for(d, axes_i(entered));
    (*s).t = t;
}

// Dda::skip_empty_bricks: from the unallocated brick `start`, brick by brick to the first
// allocated one, entered where the ray enters it. False (walk ended) past the grid or t_end.
fn skip_empty_bricks(s: ptr<function, Dda>, start: vec3<i32>) -> bool {
    let bd = vec3<i32>(params.brick_dims.xyz);
    var b = start;
    // Each pass moves b one brick along the ray: at most bd.x + bd.y + bd.z passes.
    for (var i = 0; i <= bd.x + bd.y + bd.z; i++) {
        let d = *s;
        let lo = b * 8;
        let hi = min(lo + vec3<i32>(8), d.dims) - vec3<i32>(1);
        let c = next_crossing(d, select(lo, hi, d.step > vec3<i32>(0)));
        b += d.step * axes_i(c.axes);
        if c.t >= d.t_end || any(b < vec3<i32>(0)) || any(b >= bd) {
            break;
        }
        let index = brick_at(b);
        if index == NONE {
            continue;
        }
        let lo_b = b * 8;
        enter_at(s, c.t, c.axes, lo_b, min(lo_b + vec3<i32>(8), d.dims) - vec3<i32>(1));
        (*s).brick = b;
        (*s).brick_index = index;
        return true;
    }
    (*s).done = true;
    return false;
}

// Dda::enter_brick: looks the current cell's brick up if it changed; skips it and every
// following empty brick if it is unallocated.
fn enter_brick(s: ptr<function, Dda>) -> bool {
    let b = (*s).cell / 8; // cells are ≥ 0: division is the floor
    if any(b != (*s).brick) {
        (*s).brick = b;
        (*s).brick_index = brick_at(b);
        if (*s).brick_index == NONE {
            return skip_empty_bricks(s, b);
        }
    }
    return true;
}

// Dda::skip_block: leaves the empty 2³ block of the current cell into the cell the ray enters
// at the block's exit; on the axes it does not exit, the side of the block's middle plane the
// ray is on at that t (crossed at or before it: the far half, as locate decides).
fn skip_block(s: ptr<function, Dda>) {
    let d = *s;
    let lo = (d.cell / 2) * 2;
    let hi = min(lo + vec3<i32>(1), d.dims - vec3<i32>(1));
    let up = d.step > vec3<i32>(0);
    let exit_cell = select(lo, hi, up);
    let c = next_crossing(d, exit_cell);
    let next = exit_cell + d.step * axes_i(c.axes);
    if c.t >= d.t_end || any(next < vec3<i32>(0)) || any(next >= d.dims) {
        (*s).done = true;
        return;
    }
    let parallel = d.step == vec3<i32>(0);
    let mid = select((vec3<f32>(lo + vec3<i32>(1)) - d.origin) * d.inv, vec3<f32>(F32_MAX), parallel);
    let t = vec3<f32>(c.t);
    let near = select(lo + vec3<i32>(1), lo, up);
    let inside = near + d.step * axes_i(mid <= t);
    let stay = select(inside, d.cell, parallel);
    (*s).cell = select(stay, next, c.axes);
    (*s).entry = normal_for(d, axes_i(c.axes | (mid == t)));
    (*s).t = c.t;
}

// A voxel with a record met by a walk, and the record's index (NONE: the walk ended).
struct Hit {
    step: Step,
    index: u32,
}

// Dda::next_occupied_voxel + the rank look-up of render/filtered/lookup.rs: the next voxel
// with a record. Inside an allocated brick the occupancy mask is tested per voxel visited;
// a 2³ block with no occupied voxel (its 8 bits: 0x303 << ((x & 6) + 16·((y >> 1) & 1)) in
// the words of its two z layers) is left in one jump.
fn walk_next(s: ptr<function, Dda>) -> Hit {
    var out: Hit;
    out.index = NONE;
    loop {
        if (*s).done || (*s).budget == 0u {
            break;
        }
        (*s).budget -= 1u;
        if !enter_brick(s) {
            break;
        }
        let bi = (*s).brick_index;
        let l = vec3<u32>((*s).cell - (*s).brick * 8);
        let lin = l.x | (l.y << 3u) | (l.z << 6u);
        let w = lin >> 5u;
        let bit = lin & 31u;
        let word = bricks[bi].mask[w];
        if ((word >> bit) & 1u) != 0u {
            out.step = dda_next(s);
            out.index = slots[bricks[bi].before[w] + countOneBits(word & ((1u << bit) - 1u))];
            return out;
        }
        let bw = (l.y >> 2u) + 4u * (l.z >> 1u);
        let block = (bricks[bi].mask[bw] | bricks[bi].mask[bw + 2u]) >> ((l.x & 6u) + 16u * ((l.y >> 1u) & 1u));
        if (block & 0x303u) != 0u {
            dda_next(s);
        } else {
            skip_block(s);
        }
    }
    return out;
}

// ---- Per-voxel values (render/filtered/mod.rs `view`, `shadow`; appearance/averages.rs).

struct Lit {
    light: LightSample,
    distance: f32,
}

// Light::sample at p.
fn light_at(p: vec3<f32>) -> Lit {
    var out: Lit;
    if (params.dims.w & 2u) != 0u {
        let d = params.light_a.xyz - p;
        let dist = length(d);
        out.light.to_light = select(vec3<f32>(0.0, 1.0, 0.0), d / dist, dist > 0.0);
        let r = max(dist, 1e-4);
        out.light.irradiance = params.light_b.xyz / (r * r);
        out.distance = dist;
    } else {
        out.light.to_light = params.light_a.xyz;
        out.light.irradiance = params.light_b.xyz;
        out.distance = F32_MAX;
    }
    return out;
}

// GridSpec::voxel_center in f32 (the CPU rounds once from f64: the centres agree to ~1 ULP).
fn centre_of(c: vec3<i32>) -> vec3<f32> {
    return params.grid.xyz + (vec3<f32>(c) + 0.5) * params.grid.w;
}

fn is_vjk() -> bool {
    return params.size.w == 1u;
}

// ---- [VJK21] transmittance (appearance/transmittance.rs).

fn vjk_f(tau: f32, gamma: f32) -> f32 {
    return gamma * exp(-tau) + (1.0 - gamma) * max(1.0 - 0.5 * tau, 0.0);
}

fn vjk_df(tau: f32, gamma: f32) -> f32 {
    return -gamma * exp(-tau) - select(0.0, 0.5 * (1.0 - gamma), tau < 2.0);
}

fn vjk_f_inv(t_in: f32, gamma_in: f32) -> f32 {
    let t = clamp(t_in, 0.0, 1.0);
    let gamma = clamp(gamma_in, 0.0, 1.0);
    if t >= 1.0 {
        return 0.0;
    }
    if gamma <= 0.0 {
        return 2.0 * (1.0 - t);
    }
    if t <= gamma * exp(-2.0) {
        if t <= 0.0 {
            return F32_MAX; // +∞: f is then 0
        }
        return log(gamma / t);
    }
    var tau = 0.0;
    for (var i = 0; i < 8; i++) {
        tau -= (vjk_f(tau, gamma) - t) / vjk_df(tau, gamma);
    }
    return clamp(tau, 0.0, 2.0);
}

// Opacity::apply: the transmittance after crossing the voxel of record r over `chord` voxels.
fn apply_opacity(t: f32, r: Record, chord: f32) -> f32 {
    return apply_params(t, is_vjk(), vec2<f32>(r.a.w, r.b.w), chord);
}

// Opacity::apply from its parameters: the [VJK21] update with (σ, γ) = p when `vjk`, else
// alpha p.x.
fn apply_params(t: f32, vjk: bool, p: vec2<f32>, chord: f32) -> f32 {
    if vjk {
        let tau = max(p.x, 0.0) * max(chord, 0.0);
        if tau == 0.0 {
            return t;
        }
        return min(t, vjk_f(vjk_f_inv(t, p.y) + tau, p.y));
    }
    return t * (1.0 - clamp(p.x, 0.0, 1.0));
}

// ---- SGGX shading (appearance/sggx.rs `shade_record`: 16 fixed VNDF samples).

const TAU: f32 = 6.28318530717958647692;

fn normalize_or(v: vec3<f32>, fallback: vec3<f32>) -> vec3<f32> {
    let n = normalize_or_zero(v);
    return select(n, fallback, all(n == vec3<f32>(0.0)));
}

fn shade_sggx(
    r: Record,
    m: MaterialSample,
    to_viewer: vec3<f32>,
    light: LightSample,
    visibility: f32,
    ambient: vec3<f32>,
) -> vec3<f32> {
    let s = mat3x3<f32>(r.b.xyz, r.c.xyz, r.d.xyz);
    let v = normalize_or(to_viewer, vec3<f32>(0.0, 0.0, 1.0));
    // basis(v), Duff et al. 2017.
    let sign = select(-1.0, 1.0, v.z >= 0.0);
    let ba = -1.0 / (sign + v.z);
    let bb = v.x * v.y * ba;
    let wk = vec3<f32>(1.0 + sign * v.x * v.x * ba, sign * bb, -sign * v.x);
    let wj = vec3<f32>(bb, sign + v.y * v.y * ba, -v.y);
    let wi = v;
    let skk = dot(wk, s * wk);
    let sjj = dot(wj, s * wj);
    let sii = dot(wi, s * wi);
    let skj = dot(wk, s * wj);
    let ski = dot(wk, s * wi);
    let sji = dot(wj, s * wi);
    let det = skk * sjj * sii - skj * skj * sii - ski * ski * sjj - sji * sji * skk
        + 2.0 * skj * ski * sji;
    let inv_sqrt_sii = 1.0 / sqrt(max(sii, F32_MIN_POSITIVE));
    let tmp = sqrt(max(sjj * sii - sji * sji, F32_MIN_POSITIVE));
    let mk = vec3<f32>(sqrt(abs(det)) / tmp, 0.0, 0.0);
    let mj = vec3<f32>(-inv_sqrt_sii * (ski * sji - skj * sii) / tmp, inv_sqrt_sii * tmp, 0.0);
    let mi = vec3<f32>(ski, sji, sii) * inv_sqrt_sii;
    let frame = mat3x3<f32>(wk, wj, wi);
    let mm = mat3x3<f32>(mk, mj, mi);
    var sum = vec3<f32>(0.0);
    for (var i = 0u; i < 16u; i++) {
        let u = vec2<f32>((f32(i) + 0.5) / 16.0, f32(reverseBits(i) >> 8u) * (1.0 / 16777216.0));
        let rr = sqrt(max(u.x, 0.0));
        let phi = TAU * u.y;
        let h = vec3<f32>(rr * cos(phi), rr * sin(phi), sqrt(max(1.0 - u.x, 0.0)));
        let wm = normalize_or(mm * h, vec3<f32>(0.0, 0.0, 1.0));
        let n = normalize_or(frame * wm, wi);
        sum += shade(m, n, v, light, visibility, ambient);
    }
    return sum / 16.0;
}

// The transmittance of the shadow ray of voxel c toward the light `lit` seen from its centre.
fn shadow(c: vec3<i32>, lit: Lit) -> f32 {
    let size = params.grid.w;
    // From the centre exactly, c + ½ in grid coordinates, as the CPU starts it.
    let o = vec3<f32>(c) + 0.5;
    var dda = dda_new(o, lit.light.to_light / size, 0.0, lit.distance);
    var t = 1.0;
    for (var h = walk_next(&dda); h.index != NONE; h = walk_next(&dda)) {
        let v = h.step;
        let offset = v.voxel - c;
        if dot(offset, offset) <= SHADOW_SKIP_SQ {
            continue;
        }
        t = apply_opacity(t, records[h.index], (v.t_exit - v.t_enter) * params.eye_grid.w);
        if t < MIN_TRANSMITTANCE {
            break;
        }
    }
    return t;
}

// averages.rs `shading_normal`: the mean normal turned toward the viewer, or the viewer's
// direction where there is none.
fn shading_normal(n: vec3<f32>, v: vec3<f32>) -> vec3<f32> {
    if all(n == vec3<f32>(0.0)) {
        return v;
    }
    if dot(n, v) < 0.0 {
        return -n;
    }
    return n;
}

// averages.rs `shading_normal_with`: flag 4 keeps the mean normal as stored
// (`AveragesNormal::AsStored`), else `shading_normal`.
fn averages_normal(n: vec3<f32>, v: vec3<f32>) -> vec3<f32> {
    if (params.dims.w & 4u) != 0u {
        return select(n, v, all(n == vec3<f32>(0.0)));
    }
    return shading_normal(n, v);
}

// The radiance voxel c (record `index`) sends toward the eye.
fn radiance(index: u32, c: vec3<i32>) -> vec3<f32> {
    let r = records[index];
    let centre = centre_of(c);
    var to_eye = normalize_or_zero(params.eye.xyz - centre);
    if all(to_eye == vec3<f32>(0.0)) {
        to_eye = vec3<f32>(0.0, 0.0, 1.0);
    }
    let lit = light_at(centre);
    var m: MaterialSample;
    m.albedo = r.a.xyz;
    m.specular = vec3<f32>(r.c.w);
    m.shininess = r.d.w;
    let shadows = (params.dims.w & 1u) != 0u;
    if is_vjk() {
        // SggxRecord keeps the default needs_visibility: always traced with shadows on.
        var visibility = 1.0;
        if shadows {
            visibility = shadow(c, lit);
        }
        return shade_sggx(r, m, to_eye, lit.light, visibility, params.ambient.xyz);
    }
    let n = averages_normal(r.b.xyz, to_eye);
    var visibility = 1.0;
    // Appearance::needs_visibility: no shadow ray where the normal faces away from the light.
    if shadows && dot(n, lit.light.to_light) > 0.0 {
        visibility = shadow(c, lit);
    }
    return shade(m, n, to_eye, lit.light, visibility, params.ambient.xyz);
}

// ---- The baseline renderer (render/baseline/mod.rs `trace`): the first voxel stops the ray.

// started_inside_normal: the face opposite the ray's dominant direction.
fn started_inside_normal(dir: vec3<f32>) -> vec3<f32> {
    let a = abs(dir);
    var axis = vec3<f32>(0.0, 0.0, 1.0);
    if a.x >= a.y && a.x >= a.z {
        axis = vec3<f32>(1.0, 0.0, 0.0);
    } else if a.y >= a.z {
        axis = vec3<f32>(0.0, 1.0, 0.0);
    }
    // f32::signum: +1 for +0.
    return -axis * select(-1.0, 1.0, dot(dir, axis) >= 0.0);
}

// The radiance of the opaque voxel `v` (record r) hit by the camera ray along unit `dir`: shaded
// at the entry point with the entry face's normal; the voxel's shadow ray (from its centre, as
// the CPU's cached visibility) only where that normal faces the light.
fn baseline_radiance(r: Record, v: Step, dir: vec3<f32>) -> vec3<f32> {
    var n = vec3<f32>(v.normal);
    if all(v.normal == vec3<i32>(0)) {
        n = started_inside_normal(dir);
    }
    let lit = light_at(params.eye.xyz + dir * v.t_enter);
    var visibility = 1.0;
    if (params.dims.w & 1u) != 0u && dot(n, lit.light.to_light) > 0.0 {
        visibility = shadow(v.voxel, light_at(centre_of(v.voxel)));
    }
    var m: MaterialSample;
    m.albedo = r.a.xyz;
    return shade(m, n, -dir, lit.light, visibility, params.ambient.xyz);
}

// ---- Camera rays.

fn ray_dir(p: vec2<f32>) -> vec3<f32> {
    let ndc_x = 2.0 * p.x / f32(params.size.x) - 1.0;
    let ndc_y = 1.0 - 2.0 * p.y / f32(params.size.y);
    return normalize_or_zero(params.forward.xyz + params.right.xyz * ndc_x + params.up.xyz * ndc_y);
}

// Composited radiance (rgb) and transmittance (w) of the camera ray along unit `dir`.
fn trace(dir: vec3<f32>) -> vec4<f32> {
    var dda = dda_new(params.eye_grid.xyz, dir / params.grid.w, 0.0, F32_MAX);
    var t = 1.0;
    var sum = vec3<f32>(0.0);
    for (var h = walk_next(&dda); h.index != NONE; h = walk_next(&dda)) {
        let v = h.step;
        let index = h.index;
        if params.size.w == 2u {
            return vec4<f32>(baseline_radiance(records[index], v, dir), 0.0);
        }
        let c = radiance(index, v.voxel);
        let next = apply_opacity(t, records[index], (v.t_exit - v.t_enter) * params.eye_grid.w);
        sum += (t - next) * c;
        t = next;
        if t < MIN_TRANSMITTANCE {
            break;
        }
    }
    return vec4<f32>(sum, t);
}

@compute @workgroup_size(8, 8)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    let width = params.size.x;
    if id.x >= width || id.y >= params.size.y {
        return;
    }
    let corner = vec2<f32>(f32(id.x), f32(id.y));
    var sum = vec4<f32>(0.0);
    for (var s = 0u; s < 4u; s++) {
        let r = trace(ray_dir(corner + PATTERN_4[s]));
        sum += vec4<f32>(r.xyz + r.w * params.background.xyz, 1.0 - r.w);
    }
    pixels[id.y * width + id.x] = sum / 4.0;
}
