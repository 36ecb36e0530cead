// The virtual mesh + opacity subgrid record (voxlod-cpu's appearance/vmesh.rs and
// appearance/subgrid.rs), read from the frozen 136-byte VirtualMeshRecord layout of
// voxlod-format (decoded here, byte by byte, with the host's tables for the sRGB and log-byte
// decoders): its radiance toward a viewer (shade_record) and its directional opacity
// (directional_opacity under the Lines or Circles rule, optionally times
// projected_area_ratio). Appended to shading.wgsl and filtered.wgsl; the bindings are in
// voxels.wgsl.
//
// Byte offsets of VirtualMeshRecord: axes 0..9 (snorm8×3×3), scales 9..12 (log bytes),
// colours 12..36 (sRGB8×3 per face), normals 36..108 (snorm8×3, 3 per face), distribution
// mask 108, sub-cell opacities 109..136 (unorm8, index x + 3y + 9z).

// One record as the host uploads it: the record's 136 bytes as 34 little-endian words, then
// the voxel's specular level and Blinn-Phong exponent (0 and 1 without specular records).
struct VmeshRecord {
    bytes: array<u32, 34>,
    specular: vec2<f32>,
}

// The record being evaluated by this invocation (loaded by vm_load).
var<private> vm: VmeshRecord;

fn vm_load(i: u32) {
    vm = vmesh[i];
}

fn vm_byte(b: u32) -> u32 {
    return (vm.bytes[b >> 2u] >> ((b & 3u) * 8u)) & 0xffu;
}

// quant::from_snorm8: max(b / 127, −1).
fn vm_snorm(b: u32) -> f32 {
    let s = i32(vm_byte(b) << 24u) >> 24u;
    return max(f32(s) * (1.0 / 127.0), -1.0);
}

// glam's normalize_or_zero (v · (1/|v|), zero where |v| is 0), with the zero vector tested
// first: an absent normal is (0, 0, 0) and WGSL need not give 1/0 = ∞.
fn unit_or_zero(v: vec3<f32>) -> vec3<f32> {
    let len = length(v);
    if !(len > 0.0) {
        return vec3<f32>(0.0);
    }
    let rcp = 1.0 / len;
    if !(rcp <= F32_MAX) {
        return vec3<f32>(0.0);
    }
    return v * rcp;
}

// quant::decode_dir of the three bytes at offset b.
fn vm_dir(b: u32) -> vec3<f32> {
    return unit_or_zero(vec3<f32>(vm_snorm(b), vm_snorm(b + 1u), vm_snorm(b + 2u)));
}

fn srgb_of(b: u32) -> f32 {
    return tables[b >> 2u][b & 3u];
}

// SCALE_RANGE.decode.
fn scale_of(b: u32) -> f32 {
    return tables[64u + (b >> 2u)][b & 3u];
}

fn vm_axis(k: u32) -> vec3<f32> {
    return vm_dir(3u * k);
}

fn vm_scale(k: u32) -> f32 {
    return scale_of(vm_byte(9u + k));
}

fn vm_color(f: u32) -> vec3<f32> {
    let o = 12u + 3u * f;
    return vec3<f32>(srgb_of(vm_byte(o)), srgb_of(vm_byte(o + 1u)), srgb_of(vm_byte(o + 2u)));
}

fn vm_normal(f: u32, i: u32) -> vec3<f32> {
    return vm_dir(36u + 9u * f + 3u * i);
}

fn vm_alpha(c: u32) -> u32 {
    return vm_byte(109u + c);
}

// ---- Shading (vmesh.rs shade_record).

// vmesh::FACES: vertex 2k = +T_k e_k, 2k+1 = −T_k e_k.
const FACES = array<vec3<u32>, 8>(
    vec3<u32>(0u, 2u, 4u),
    vec3<u32>(0u, 4u, 3u),
    vec3<u32>(0u, 3u, 5u),
    vec3<u32>(0u, 5u, 2u),
    vec3<u32>(1u, 2u, 5u),
    vec3<u32>(1u, 5u, 3u),
    vec3<u32>(1u, 3u, 4u),
    vec3<u32>(1u, 4u, 2u),
);

// glam's Vec3::cross, operand order included.
fn cross_glam(a: vec3<f32>, b: vec3<f32>) -> vec3<f32> {
    return vec3<f32>(a.y * b.z - b.y * a.z, a.z * b.x - b.z * a.x, a.x * b.y - b.x * a.y);
}

// vmesh::barycentric_point: the square-root warp of Hammersley point i of count.
fn barycentric_point(i: u32, count: u32) -> vec3<f32> {
    let ux = (f32(i) + 0.5) / f32(count);
    let uy = f32(reverseBits(i) >> 8u) * (1.0 / 16777216.0);
    let su = sqrt(ux);
    return vec3<f32>(1.0 - su, su * uy, su * (1.0 - uy));
}

fn vm_material(f: u32) -> MaterialSample {
    var m: MaterialSample;
    m.albedo = vm_color(f);
    m.specular = vec3<f32>(vm.specular.x);
    m.shininess = vm.specular.y;
    return m;
}

// The radiance of the loaded record toward `to_viewer` (vmesh.rs shading rules), with
// `samples_per_face` barycentric samples per distribution face (at least 1).
fn shade_vmesh(
    to_viewer: vec3<f32>,
    light: LightSample,
    visibility: f32,
    ambient: vec3<f32>,
    samples_per_face: u32,
) -> vec3<f32> {
    let v = normalize_or(to_viewer, vec3<f32>(0.0, 0.0, 1.0));
    let k = max(samples_per_face, 1u);
    var vertices: array<vec3<f32>, 6>;
    for (var i = 0u; i < 3u; i++) {
        let a = vm_axis(i) * vm_scale(i);
        vertices[2u * i] = a;
        vertices[2u * i + 1u] = -a;
    }
    let distribution = vm_byte(108u);
    var weighted = vec3<f32>(0.0);
    var area_sum = 0.0;
    var unweighted = vec3<f32>(0.0);
    var faces = 0u;
    for (var f = 0u; f < 8u; f++) {
        let n0 = vm_normal(f, 0u);
        let n1 = vm_normal(f, 1u);
        let n2 = vm_normal(f, 2u);
        if !(dot(n0, v) > 0.0 || dot(n1, v) > 0.0 || dot(n2, v) > 0.0) {
            continue;
        }
        let m = vm_material(f);
        var sum = vec3<f32>(0.0);
        var count = 0u;
        if ((distribution >> f) & 1u) == 1u {
            for (var i = 0u; i < k; i++) {
                let b = barycentric_point(i, k);
                let n = unit_or_zero(n0 * b.x + n1 * b.y + n2 * b.z);
                if dot(n, v) > 0.0 {
                    sum += shade(m, n, v, light, visibility, ambient);
                    count += 1u;
                }
            }
        } else {
            // A fixed set: each stored normal facing the viewer (an absent one is zero).
            var ns = array<vec3<f32>, 3>(n0, n1, n2);
            for (var i = 0u; i < 3u; i++) {
                if dot(ns[i], v) > 0.0 {
                    sum += shade(m, ns[i], v, light, visibility, ambient);
                    count += 1u;
                }
            }
        }
        if count == 0u {
            continue;
        }
        let face_value = sum / f32(count);
        let t = FACES[f];
        let a = vertices[t.x];
        let area = 0.5 * abs(dot(cross_glam(vertices[t.y] - a, vertices[t.z] - a), v));
        weighted += face_value * area;
        area_sum += area;
        unweighted += face_value;
        faces += 1u;
    }
    if faces > 0u {
        if area_sum > 0.0 {
            return weighted / area_sum;
        }
        return unweighted / f32(faces);
    }
    // ShadingFallback::Unshaded (flag 2): no radiance.
    if (params.vmesh.z & 2u) != 0u {
        return vec3<f32>(0.0);
    }
    // Fallback: every stored normal, no visibility filter.
    var sum = vec3<f32>(0.0);
    var count = 0u;
    for (var f = 0u; f < 8u; f++) {
        let m = vm_material(f);
        for (var i = 0u; i < 3u; i++) {
            let n = vm_normal(f, i);
            if any(n != vec3<f32>(0.0)) {
                sum += shade(m, n, v, light, visibility, ambient);
                count += 1u;
            }
        }
    }
    if count > 0u {
        return sum / f32(count);
    }
    return vec3<f32>(0.0);
}

// ---- Directional opacity (subgrid.rs).

const LINES: u32 = 32u;
// f32 constants as the CPU rounds them: f32 literals (suffix f) of 9 significant digits, each
// the decimal of one f32 (WGSL would fold `1.0 / 3.0` as an abstract float).
const ONE_BELOW: f32 = 9.999999404e-01f;     // 1 − 2⁻²⁴ (0x3f7fffff)
const CIRCLE_RADIUS: f32 = 2.598076165e-01f; // 0.9f32 × 0.288_675_13 (0x3e850581)
// Stands for ±∞ in the slab intervals: every crossing compared with it is at most the chord
// or at least 0 (see crossed_subcells).
const BIG: f32 = 1e30;

struct FaceChoice {
    k: u32,
    s: f32,
}

// sampler/lines.rs choose_face.
fn choose_face(d: vec3<f32>, u: f32) -> FaceChoice {
    let a = abs(d);
    let sum = a.x + a.y + a.z;
    if !(sum > 0.0 && sum <= F32_MAX) {
        return FaceChoice(2u, u);
    }
    let x = u * sum;
    let ab = a.x + a.y;
    let k = u32(x >= a.x) + u32(x >= ab);
    var belows = array<f32, 3>(0.0, a.x, ab);
    let below = belows[k];
    let share = a[k];
    if share > 0.0 {
        return FaceChoice(k, clamp((x - below) / share, 0.0, ONE_BELOW));
    }
    // glam's max_position: the first of equal maxima.
    var best = 0u;
    var top = a.x;
    if a.y > top {
        best = 1u;
        top = a.y;
    }
    if a.z > top {
        best = 2u;
    }
    return FaceChoice(best, u);
}

// sampler/lines.rs entry_point.
fn entry_point(d: vec3<f32>, k: u32, s: f32, t: f32) -> vec3<f32> {
    var e = vec3<f32>(0.0);
    e[k] = select(1.0, 0.0, d[k] > 0.0);
    e[(k + 1u) % 3u] = s;
    e[(k + 2u) % 3u] = t;
    return e;
}

// DirectionalRule::Lines for a unit d.
fn lines_opacity(d: vec3<f32>) -> f32 {
    let k_inv = 1.0 / f32(LINES);
    var sum = 0u;
    var count = 0u;
    for (var k = 0u; k < LINES; k++) {
        let fc = choose_face(d, (f32(k) + 0.5) * k_inv);
        let t = f32(reverseBits(k) >> 8u) * (1.0 / 16777216.0) + 0.5 * k_inv;
        let e = entry_point(d, fc.k, fc.s, t);
        var mask = crossed_subcells(e, d, chord_of(e, d));
        if mask == 0u {
            continue;
        }
        var top = 0u;
        // At most 7 bits: one per crossed sub-cell.
        for (var n = 0u; n < 27u && mask != 0u; n++) {
            top = max(top, vm_alpha(firstTrailingBit(mask)));
            mask &= mask - 1u;
        }
        sum += top;
        count += 1u;
    }
    if count == 0u {
        return 0.0;
    }
    return clamp(f32(sum) / (255.0 * f32(count)), 0.0, 1.0);
}

// subgrid::lens_area: the intersection of two discs.
fn lens_area(dist: f32, r1: f32, r2: f32) -> f32 {
    if dist >= r1 + r2 {
        return 0.0;
    }
    let small = min(r1, r2);
    if dist <= abs(r1 - r2) {
        return PI * small * small;
    }
    let a1 = r1 * r1 * acos(clamp((dist * dist + r1 * r1 - r2 * r2) / (2.0 * dist * r1), -1.0, 1.0));
    let a2 = r2 * r2 * acos(clamp((dist * dist + r2 * r2 - r1 * r1) / (2.0 * dist * r2), -1.0, 1.0));
    let k = (-dist + r1 + r2) * (dist + r1 - r2) * (dist - r1 + r2) * (dist + r1 + r2);
    return clamp(a1 + a2 - 0.5 * sqrt(max(k, 0.0)), 0.0, PI * small * small);
}

// DirectionalRule::Circles for a unit d.
fn circles_opacity(d: vec3<f32>) -> f32 {
    // subgrid::hughes_moeller: v ⟂ d (glam's normalize: v · (1/|v|)), u = v × d.
    var hv = vec3<f32>(0.0, -d.z, d.y);
    if abs(d.x) > abs(d.z) {
        hv = vec3<f32>(-d.y, d.x, 0.0);
    }
    let bv = hv * (1.0 / length(hv));
    let bu = cross_glam(bv, d);
    var lo = vec2<f32>(F32_MAX);
    var hi = vec2<f32>(-F32_MAX);
    for (var c = 0u; c < 8u; c++) {
        let p = vec3<f32>(f32(c & 1u), f32((c >> 1u) & 1u), f32((c >> 2u) & 1u));
        let q = vec2<f32>(dot(p, bu), dot(p, bv));
        lo = min(lo, q);
        hi = max(hi, q);
    }
    let step = (hi - lo) / 4.0;
    let rp = 0.5 * min(step.x, step.y);
    let pixel_area = PI * rp * rp;
    if !(pixel_area > 0.0) {
        return 0.0;
    }
    var centres: array<vec2<f32>, 27>;
    for (var c = 0u; c < 27u; c++) {
        let p = (vec3<f32>(f32(c % 3u), f32((c / 3u) % 3u), f32(c / 9u)) + 0.5) / 3.0;
        centres[c] = vec2<f32>(dot(p, bu), dot(p, bv));
    }
    var num = 0.0;
    var den = 0.0;
    for (var j = 0u; j < 4u; j++) {
        for (var i = 0u; i < 4u; i++) {
            let pixel = lo + vec2<f32>(f32(i) + 0.5, f32(j) + 0.5) * step;
            var best = 0.0;
            var solid = 0.0;
            for (var c = 0u; c < 27u; c++) {
                let cover = lens_area(length(centres[c] - pixel), CIRCLE_RADIUS, rp) / pixel_area;
                solid = max(solid, cover);
                best = max(best, f32(vm_alpha(c)) * (1.0 / 255.0) * cover);
            }
            num += best;
            den += solid;
        }
    }
    if den > 0.0 {
        return clamp(num / den, 0.0, 1.0);
    }
    return 0.0;
}

// vmesh::projected_area_ratio along dir.
fn projected_area_ratio(dir: vec3<f32>) -> f32 {
    let t = vec3<f32>(vm_scale(0u), vm_scale(1u), vm_scale(2u));
    let sigma = vec3<f32>(PI * t.y * t.z, PI * t.z * t.x, PI * t.x * t.y);
    let top = max(max(sigma.x, sigma.y), sigma.z);
    if !(top > 0.0) || !finite3(dir) {
        return 1.0;
    }
    var area2 = 0.0;
    for (var k = 0u; k < 3u; k++) {
        let x = sigma[k] * dot(vm_axis(k), dir);
        area2 += x * x;
    }
    return min(sqrt(area2) / top, 1.0);
}

// VirtualMeshRecord::opacity (an alpha) of the loaded record along dir: rule 0 Lines,
// 1 Circles; times the projected-area ratio if asked.
fn vmesh_opacity(dir: vec3<f32>, rule: u32, projected_area: bool) -> f32 {
    var lo = 255u;
    var hi = 0u;
    for (var c = 0u; c < 27u; c++) {
        let a = vm_alpha(c);
        lo = min(lo, a);
        hi = max(hi, a);
    }
    var alpha = 0.0;
    if hi == 0u {
        alpha = 0.0;
    } else if lo == 255u {
        alpha = 1.0;
    } else {
        let d = normalize_or(dir, vec3<f32>(0.0, 0.0, 1.0));
        if rule == 1u {
            alpha = circles_opacity(d);
        } else {
            alpha = lines_opacity(d);
        }
    }
    if projected_area {
        return alpha * projected_area_ratio(dir);
    }
    return alpha;
}
