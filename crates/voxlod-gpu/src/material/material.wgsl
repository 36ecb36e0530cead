// Materials and textures (voxlod-scene's Material::sample and Texture::sample), for every kernel
// that evaluates a surface: base colour factor × bilinear RGBA8 texture sample (sRGB colour
// decoded through voxlod's own 256-entry table, alpha and linear textures through a c/255
// table, so decoding is bit for bit the CPU's), the alpha mode, clamped albedo.
//
// The includer declares three storage bindings (binding numbers of its choice):
//   var<storage, read> materials: array<Material>;
//   var<storage, read> textures: Textures;
//   var<storage, read> texels: array<u32>;   // RGBA8 texels, r in the low byte
//
// Texel addressing mirrors the CPU's f64 arithmetic exactly (x = uv·size − 0.5 in f64, floor,
// (x − x0) as f32, wrap) with 64-bit integers emulated on u32 pairs, for every |uv| < 2^23;
// beyond (uv ≥ 8 388 608, never produced by a real mesh) the fraction is 0 or 0.5 and the
// texel may differ from the CPU's in f64 ties (see `texel_axis`). The one inexact step is the
// lerp (a·(1 − s) + b·s, which a GPU compiler may fuse into an fma): 1 ULP.

struct Material {
    base_color: vec4<f32>, // linear RGBA factor
    specular: vec4<f32>,   // rgb ≥ 0; w = shininess ≥ 0
    texture: u32,          // index + 1 into textures.descs; 0: none
    alpha_mode: u32,       // 0 opaque, 1 mask, 2 blend
    cutoff: f32,           // mask cutoff
    double_sided: u32,     // 1 if double-sided
}

struct TextureDesc {
    offset: u32, // first texel in `texels`
    width: u32,
    height: u32,
    flags: u32,  // bit 0: sRGB colour; bits 1..3: wrap u; bits 3..5: wrap v (0 repeat, 1 clamp, 2 mirror)
}

struct Textures {
    srgb: array<f32, 256>,  // voxlod-format's srgb_to_linear_table, bit for bit
    byte_unit: array<f32, 256>, // c as f32 / 255.0, bit for bit
    descs: array<TextureDesc>,
}

// A material at one surface point (voxlod-scene's MaterialSample).
struct MaterialEval {
    albedo: vec3<f32>,
    alpha: f32, // 0 or 1 for mask, 1 for opaque
    specular: vec3<f32>,
    shininess: f32,
}

const WRAP_REPEAT: u32 = 0u;
const WRAP_CLAMP: u32 = 1u;

// ---- 64-bit integers as vec2<u32>(low, high), two's complement ----

fn i64_add(a: vec2<u32>, b: vec2<u32>) -> vec2<u32> {
    let lo = a.x + b.x;
    return vec2<u32>(lo, a.y + b.y + select(0u, 1u, lo < a.x));
}

fn i64_neg(a: vec2<u32>) -> vec2<u32> {
    return i64_add(~a, vec2<u32>(1u, 0u));
}

fn i64_negative(a: vec2<u32>) -> bool {
    return (a.y >> 31u) != 0u;
}

fn i64_pow2(k: u32) -> vec2<u32> {
    // 2^k, k < 64.
    if k < 32u {
        return vec2<u32>(1u << k, 0u);
    }
    return vec2<u32>(0u, 1u << (k - 32u));
}

// a >> k (arithmetic), 0 < k < 64.
fn i64_shr(a: vec2<u32>, k: u32) -> vec2<u32> {
    if k < 32u {
        return vec2<u32>((a.x >> k) | (a.y << (32u - k)), bitcast<u32>(bitcast<i32>(a.y) >> k));
    }
    let hi = bitcast<i32>(a.y);
    return vec2<u32>(bitcast<u32>(hi >> (k - 32u)), bitcast<u32>(hi >> 31u));
}

// a >> k (logical), 0 < k < 64.
fn u64_shr(a: vec2<u32>, k: u32) -> vec2<u32> {
    if k < 32u {
        return vec2<u32>((a.x >> k) | (a.y << (32u - k)), a.y >> k);
    }
    return vec2<u32>(a.y >> (k - 32u), 0u);
}

// The low k bits of a, 0 < k < 64.
fn u64_low(a: vec2<u32>, k: u32) -> vec2<u32> {
    if k < 32u {
        return vec2<u32>(a.x & ((1u << k) - 1u), 0u);
    }
    return vec2<u32>(a.x, a.y & ((1u << (k - 32u)) - 1u));
}

fn u64_less(a: vec2<u32>, b: vec2<u32>) -> bool {
    return a.y < b.y || (a.y == b.y && a.x < b.x);
}

// Index of the highest set bit of a non-zero a.
fn u64_lead(a: vec2<u32>) -> u32 {
    if a.y != 0u {
        return 32u + firstLeadingBit(a.y);
    }
    return firstLeadingBit(a.x);
}

// a (non-negative) rounded to `bits` significant bits, to nearest, ties to even (what
// converting it to a float with a `bits`-bit significand does).
fn u64_round(a: vec2<u32>, bits: u32) -> vec2<u32> {
    if all(a == vec2<u32>(0u)) || u64_lead(a) < bits {
        return a;
    }
    let s = u64_lead(a) + 1u - bits;
    let q = u64_shr(a, s);
    let rem = u64_low(a, s);
    let half = i64_pow2(s - 1u);
    var up = u64_less(half, rem);
    if all(rem == half) {
        up = (q.x & 1u) != 0u;
    }
    var r = q;
    if up {
        r = i64_add(q, vec2<u32>(1u, 0u));
    }
    // r · 2^s
    if s < 32u {
        return vec2<u32>(r.x << s, (r.y << s) | (r.x >> (32u - s)));
    }
    return vec2<u32>(0u, r.x << (s - 32u));
}

// 2^e as an f32, -126 ≤ e ≤ 127 (exact).
fn pow2f(e: i32) -> f32 {
    return bitcast<f32>(u32(e + 127) << 23u);
}

// a / 2^k rounded to f32 (nearest, ties to even), a < 2^63, 0 < k < 64.
fn u64_ratio_f32(a: vec2<u32>, k: u32) -> f32 {
    if all(a == vec2<u32>(0u)) {
        return 0.0;
    }
    let r = u64_round(a, 24u);
    // r has at most 24 significant bits: r = q · 2^s with q < 2^25.
    var s = 0u;
    if u64_lead(r) >= 24u {
        s = u64_lead(r) - 23u;
    }
    var q = r.x;
    if s > 0u {
        q = u64_shr(r, s).x;
    }
    return f32(q) * pow2f(i32(s) - i32(k));
}

// a mod m (Euclidean, m ≤ 2^16) of a signed 64-bit a.
fn i64_mod(a: vec2<u32>, m: u32) -> u32 {
    let neg = i64_negative(a);
    var b = a;
    if neg {
        b = i64_neg(a);
    }
    let p32 = (0xffffffffu % m + 1u) % m; // 2^32 mod m
    let r = ((b.y % m) * p32 + b.x % m) % m;
    if neg {
        return (m - r) % m;
    }
    return r;
}

// Texture::wrap of the signed 64-bit texel index a into 0..n.
fn wrap_i64(a: vec2<u32>, n: u32, mode: u32) -> u32 {
    if mode == WRAP_REPEAT {
        return i64_mod(a, n);
    }
    if mode == WRAP_CLAMP {
        if i64_negative(a) {
            return 0u;
        }
        if a.y != 0u || a.x >= n {
            return n - 1u;
        }
        return a.x;
    }
    let m = i64_mod(a, 2u * n);
    return select(2u * n - 1u - m, m, m < n);
}

// A residue r mod M (M = n or 2n) wrapped as wrap_i64 does.
fn wrap_residue(r: u32, n: u32, mode: u32) -> u32 {
    if mode == WRAP_REPEAT {
        return r;
    }
    return select(2u * n - 1u - r, r, r < n);
}

// One axis of the bilinear footprint: the two wrapped texel indices and the weight of the
// second (Texture::sample: x = uv·n − 0.5 in f64, x0 = floor x, f = (x − x0) as f32).
struct Axis {
    i0: u32,
    i1: u32,
    f: f32,
}

fn texel_axis(c: f32, n: u32, mode: u32) -> Axis {
    var out: Axis;
    let bits = bitcast<u32>(c);
    let neg = (bits >> 31u) != 0u;
    let biased = (bits >> 23u) & 0xffu;
    var m = bits & 0x7fffffu;
    var e = -149;
    if biased != 0u {
        m |= 0x800000u;
        e = i32(biased) - 150;
    }
    // P = m·n exactly (m < 2^24, n ≤ 2^15: P < 2^39).
    let a = (m & 0xffffu) * n;
    let b = (m >> 16u) * n;
    let p = i64_add(vec2<u32>(a, 0u), vec2<u32>(b << 16u, b >> 16u));
    let zero = all(p == vec2<u32>(0u));
    if zero || e < -63 {
        // x = ±P·2^e − 0.5 with P·2^e < 2^-24: x0 = −1 and f rounds to 0.5, except just
        // below −0.5 at k = 64 (f64 then f32 rounding of 0.5 − δ, worked out by hand).
        out.f = 0.5;
        if !zero && neg && e == -64 && u64_less(vec2<u32>(1024u, 64u), p) {
            out.f = 0.5 - 1.0 / 33554432.0;
        }
        let minus_one = vec2<u32>(0xffffffffu, 0xffffffffu);
        out.i0 = wrap_i64(minus_one, n, mode);
        out.i1 = wrap_i64(vec2<u32>(0u), n, mode);
        return out;
    }
    if e < 0 {
        // x·2^k = Q = ±P − 2^(k−1), k = −e ≤ 63, |Q| < 2^63; the f64 x keeps 53 bits of it.
        let k = u32(-e);
        var q = p;
        if neg {
            q = i64_neg(p);
        }
        q = i64_add(q, i64_neg(i64_pow2(k - 1u)));
        var mag = q;
        if i64_negative(q) {
            mag = i64_neg(q);
        }
        mag = u64_round(mag, 53u);
        if i64_negative(q) {
            q = i64_neg(mag);
        } else {
            q = mag;
        }
        let x0 = i64_shr(q, k);
        out.f = u64_ratio_f32(u64_low(q, k), k);
        out.i0 = wrap_i64(x0, n, mode);
        out.i1 = wrap_i64(i64_add(x0, vec2<u32>(1u, 0u)), n, mode);
        return out;
    }
    // |uv| ≥ 2^23: N = ±P·2^e is an integer ≥ 2^23 > n; x = N − 0.5. Exact while |N| < 2^52
    // (x0 = N − 1, f = 0.5); beyond, f64 rounds x to an integer (f = 0) and x0 is taken as N.
    if mode == WRAP_CLAMP {
        let i = select(n - 1u, 0u, neg);
        out.i0 = i;
        out.i1 = i;
        out.f = 0.5;
        return out;
    }
    let mm = select(n, 2u * n, mode != WRAP_REPEAT);
    var pe = 1u % mm;
    for (var i = 0; i < e; i++) {
        pe = (pe * 2u) % mm;
    }
    var r = (i64_mod(p, mm) * pe) % mm;
    if neg {
        r = (mm - r) % mm;
    }
    if u64_lead(p) + u32(e) < 52u {
        out.f = 0.5;
        out.i0 = wrap_residue((r + mm - 1u) % mm, n, mode);
        out.i1 = wrap_residue(r, n, mode);
    } else {
        out.f = 0.0;
        out.i0 = wrap_residue(r, n, mode);
        out.i1 = wrap_residue((r + 1u) % mm, n, mode);
    }
    return out;
}

// Texel (x, y) of texture d decoded to linear RGBA (Texture::texel).
fn texel(d: TextureDesc, x: u32, y: u32) -> vec4<f32> {
    let w = texels[d.offset + y * d.width + x];
    let c = vec4<u32>(w & 0xffu, (w >> 8u) & 0xffu, (w >> 16u) & 0xffu, w >> 24u);
    let a = textures.byte_unit[c.w];
    if (d.flags & 1u) != 0u {
        return vec4<f32>(textures.srgb[c.x], textures.srgb[c.y], textures.srgb[c.z], a);
    }
    return vec4<f32>(textures.byte_unit[c.x], textures.byte_unit[c.y], textures.byte_unit[c.z], a);
}

// glam's Vec4::lerp: a·(1 − s) + b·s.
fn lerp4(a: vec4<f32>, b: vec4<f32>, s: f32) -> vec4<f32> {
    return a * (1.0 - s) + b * s;
}

// Texture::sample: bilinear at uv (texel centres at half-integers, origin top-left), wrapped,
// interpolating decoded linear values; a non-finite uv samples at (0, 0).
fn texture_sample(index: u32, uv_in: vec2<f32>) -> vec4<f32> {
    let d = textures.descs[index];
    var uv = uv_in;
    let ub = bitcast<vec2<u32>>(uv) & vec2<u32>(0x7f800000u);
    if any(ub == vec2<u32>(0x7f800000u)) {
        uv = vec2<f32>(0.0);
    }
    let ax = texel_axis(uv.x, d.width, (d.flags >> 1u) & 3u);
    let ay = texel_axis(uv.y, d.height, (d.flags >> 3u) & 3u);
    let top = lerp4(texel(d, ax.i0, ay.i0), texel(d, ax.i1, ay.i0), ax.f);
    let bottom = lerp4(texel(d, ax.i0, ay.i1), texel(d, ax.i1, ay.i1), ax.f);
    return lerp4(top, bottom, ay.f);
}

// Material::sample of material `index` at uv.
fn material_sample(index: u32, uv: vec2<f32>) -> MaterialEval {
    let mat = materials[index];
    var color = mat.base_color;
    if mat.texture != 0u {
        color *= texture_sample(mat.texture - 1u, uv);
    }
    var out: MaterialEval;
    out.alpha = 1.0;
    if mat.alpha_mode == 1u {
        out.alpha = select(0.0, 1.0, color.w >= mat.cutoff);
    } else if mat.alpha_mode == 2u {
        out.alpha = clamp(color.w, 0.0, 1.0);
    }
    out.albedo = clamp(color.xyz, vec3<f32>(0.0), vec3<f32>(1.0));
    out.specular = mat.specular.xyz;
    out.shininess = mat.specular.w;
    return out;
}

// The alpha of material `index` at uv, without the colour: what an alpha test reads.
fn material_alpha(index: u32, uv: vec2<f32>) -> f32 {
    return material_sample(index, uv).alpha;
}
