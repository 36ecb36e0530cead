// The per-voxel ray sampler and its reductions (voxlod-cpu appearance/sampler.rs, subgrid.rs,
// averages.rs): one workgroup of 64 invocations per voxel, striding over the voxel's lines.
// Follows random.wgsl (rand_f32) and material.wgsl (material_sample: textures, alpha modes).

struct Params {
    // x = voxels in the voxelization, y = lines per voxel, z = first voxel of this dispatch,
    // w = flags (1: write every line to `lines`).
    counts: vec4<u32>,
    // x = first random dimension (8·seed, wrapping), y = voxels in this dispatch,
    // z = the blend key (sampler's blend_key(seed)).
    seed: vec4<u32>,
}

// One voxel: its range in `tris` and its random id x + X·(y + Y·z).
struct Voxel {
    first: u32,
    count: u32,
    id: u32,
    pad: u32,
}

// A triangle of one voxel in voxel-local coordinates, set up on the host in f64 exactly as the
// CPU sampler sets it up, then rounded to f32.
struct Tri {
    a: vec4<f32>,  // vertex 0; w = bits: flat-axis mask (bits 0..3), | 8 if alpha-filtered
    n: vec4<f32>,  // unit plane normal; w = offset (n·p = offset on the plane)
    bu: vec4<f32>, // barycentric plane of vertex 1; w = cu
    bv: vec4<f32>, // barycentric plane of vertex 2; w = cv
    ng: vec4<f32>, // world geometric normal (b−a)×(c−a); w = bits of the triangle id
}

// The ground-truth kernel's per-triangle shading data (ground_truth/mod.rs).
struct ShadeTri {
    p0: vec4<f32>, // w = bits of the material index
    p1: vec4<f32>,
    p2: vec4<f32>,
    n0: vec4<f32>,
    n1: vec4<f32>,
    n2: vec4<f32>,
    uv01: vec4<f32>, // vertex UVs 0 (xy) and 1 (zw)
    uv2: vec4<f32>,  // vertex UV 2 (xy)
}

// Per voxel: counts, the sums the Averages fit reads, and the 27 subgrid bytes.
struct VoxelOut {
    counts: vec4<u32>,   // occluded lines, case-(a) lines, marked sub-cells, lines
    albedo: vec4<f32>,   // Σ albedo; w = Σ specular level
    normal: vec4<f32>,   // Σ shading normal; w = Σ level·shininess
    scatter0: vec4<f32>, // Σ n nᵀ: xx, xy, xz, yy
    scatter1: vec4<f32>, // yz, zz, 0, 0
    subgrid: array<vec4<u32>, 2>, // byte c = sub-cell x + 3y + 9z, little-endian; then 0
}

// One line (only with flag 1).
struct LineOut {
    dir: vec4<f32>,    // w = chord
    entry: vec4<f32>,  // w = bits of the case: 0 miss, 1 occluded without surface, 2 surface
    point: vec4<f32>,  // hit point (voxel-local); w = bits of the triangle id (all ones: none)
    normal: vec4<f32>, // shading normal of a surface hit
    albedo: vec4<f32>, // textured albedo of a surface hit
}

@group(0) @binding(0) var<storage, read> params: Params;
@group(0) @binding(1) var<storage, read> voxels: array<Voxel>;
@group(0) @binding(2) var<storage, read> tris: array<Tri>;
@group(0) @binding(3) var<storage, read> shade: array<ShadeTri>;
@group(0) @binding(4) var<storage, read> materials: array<Material>;
@group(0) @binding(5) var<storage, read_write> out: array<VoxelOut>;
@group(0) @binding(6) var<storage, read_write> lines: array<LineOut>;
@group(0) @binding(7) var<storage, read> textures: Textures;
@group(0) @binding(8) var<storage, read> texels: array<u32>;

const WG: u32 = 64u;
const NONE: u32 = 0xffffffffu;
const F32_MAX: f32 = 3.402823466e+38f;
// f32 constants as the CPU rounds them (9 significant digits: the decimal of one f32; WGSL
// would fold `1.0 / 6.0` as an abstract float).
const FRAC_PI_2: f32 = 1.570796371e0f; // 0x3fc90fdb
const S3: f32 = -1.666666716e-1f;      // -1/6
const S5: f32 = 8.333333768e-3f;       // 1/120
const S7: f32 = -1.984127011e-4f;      // -1/5040
const S9: f32 = 2.755731884e-6f;       // 1/362880
const S11: f32 = -2.505210794e-8f;     // -1/39916800
const C4: f32 = 4.166666791e-2f;       // 1/24
const C6: f32 = -1.388888923e-3f;      // -1/720
const C8: f32 = 2.480158764e-5f;       // 1/40320
const C10: f32 = -2.755731998e-7f;     // -1/3628800
const C12: f32 = 2.087675588e-9f;      // 1/479001600
const HALF_STEP: f32 = 2.980232239e-8f; // 2^-25
const ONE_THIRD_MEAN: f32 = 3.333333433e-01f; // 1.0f32 / 3.0 (specular level)

// sampler/lines.rs sin_cos_turns: (sin 2πu, cos 2πu), the same polynomials and quadrant bits.
fn sin_cos_turns(u: f32) -> vec2<f32> {
    let q4 = 4.0 * u;
    let q = i32(q4);
    let x = (q4 - f32(q)) * FRAC_PI_2;
    let x2 = x * x;
    let s = x * (1.0 + x2 * (S3 + x2 * (S5 + x2 * (S7 + x2 * (S9 + x2 * S11)))));
    let c = 1.0 + x2 * (-0.5 + x2 * (C4 + x2 * (C6 + x2 * (C8 + x2 * (C10 + x2 * C12)))));
    let swap = 0u - (u32(q) & 1u);
    let sb = bitcast<u32>(s);
    let cb = bitcast<u32>(c);
    let s1 = (sb & ~swap) | (cb & swap);
    let c1 = (cb & ~swap) | ((sb ^ 0x80000000u) & swap);
    let flip = (u32(q) & 2u) << 30u;
    return vec2<f32>(bitcast<f32>(s1 ^ flip), bitcast<f32>(c1 ^ flip));
}

struct Line {
    d: vec3<f32>,
    e: vec3<f32>,
    chord: f32,
}

// sampler/lines.rs line_of, with the random numbers of sample_line.
fn sample_line(voxel: u32, ray: u32, base: u32) -> Line {
    let u0 = rand_f32(voxel, ray, base);
    let u1 = rand_f32(voxel, ray, base + 1u);
    let u2 = rand_f32(voxel, ray, base + 2u);
    let u3 = rand_f32(voxel, ray, base + 3u);
    let u4 = rand_f32(voxel, ray, base + 4u);
    let z = 1.0 - 2.0 * u0;
    let r = sqrt(max(1.0 - z * z, 0.0));
    let sc = sin_cos_turns(u1);
    let d = vec3<f32>(r * sc.y, r * sc.x, z);
    let a = abs(d);
    let x = u2 * (a.x + a.y + a.z);
    let past_x = x >= a.x;
    let past_y = x >= a.x + a.y;
    var share = a.x;
    if past_y {
        share = a.z;
    } else if past_x {
        share = a.y;
    }
    let dom_x = a.x >= a.y && a.x >= a.z;
    let dom_y = !dom_x && a.y >= a.z;
    let zero = !(share > 0.0);
    let fx = select(!past_x, dom_x, zero);
    let fy = select(past_x && !past_y, dom_y, zero);
    let s = u3 + HALF_STEP;
    let t = u4 + HALF_STEP;
    var e: vec3<f32>;
    if fx {
        e = vec3<f32>(select(1.0, 0.0, d.x > 0.0), s, t);
    } else if fy {
        e = vec3<f32>(t, select(1.0, 0.0, d.y > 0.0), s);
    } else {
        e = vec3<f32>(s, t, select(1.0, 0.0, d.z > 0.0));
    }
    return Line(d, e, chord_of(e, d));
}

fn dot3(a: vec3<f32>, b: vec3<f32>) -> f32 {
    // glam's order: (x·x' + y·y') + z·z'.
    return a.x * b.x + a.y * b.y + a.z * b.z;
}

struct Hit {
    t: f32,
    u: f32,
    v: f32,
    hit: bool,
}

// sampler/hits.rs LocalTriangle::intersect (the line in the triangle's plane misses).
fn intersect(tri: Tri, e: vec3<f32>, d: vec3<f32>) -> Hit {
    let den = dot3(tri.n.xyz, d);
    let t = (tri.n.w - dot3(tri.n.xyz, e)) / den;
    let p = e + d * t;
    let u = dot3(tri.bu.xyz, p) + tri.bu.w;
    let v = dot3(tri.bv.xyz, p) + tri.bv.w;
    let ok = den != 0.0 && abs(t) <= F32_MAX && u >= 0.0 && v >= 0.0 && u + v <= 1.0;
    return Hit(t, u, v, ok);
}

// Geometry::interpolate's UV: uv0·(1 − u − v) + uv1·u + uv2·v.
fn hit_uv(t: ShadeTri, u: f32, v: f32) -> vec2<f32> {
    let w = 1.0 - u - v;
    return t.uv01.xy * w + t.uv01.zw * u + t.uv2.xy * v;
}

// sampler.rs `accepts` (module docs: alpha): whether a hit at barycentrics (u, v) on triangle
// `triangle` counts for line `ray` of voxel `voxel`. Mask: the material's alpha at the hit's UV
// is > 0 (i.e. ≥ cutoff); blend: rand_f32(voxel, ray, key ^ triangle) < alpha.
fn accepts(triangle: u32, u: f32, v: f32, voxel: u32, ray: u32) -> bool {
    let st = shade[triangle];
    let m = bitcast<u32>(st.p0.w);
    let mode = materials[m].alpha_mode;
    if mode == 0u {
        return true;
    }
    let alpha = material_alpha(m, hit_uv(st, u, v));
    if mode == 2u {
        return rand_f32(voxel, ray, params.seed.z ^ triangle) < alpha;
    }
    return alpha > 0.0;
}

// subgrid.rs subcell_of.
fn subcell_of(p: vec3<f32>) -> u32 {
    let c = vec3<u32>(clamp(vec3<i32>(3.0 * p), vec3<i32>(0), vec3<i32>(2)));
    return c.x + 3u * c.y + 9u * c.z;
}


var<workgroup> cell_rays: array<atomic<u32>, 27>;
var<workgroup> cell_occluded: array<atomic<u32>, 27>;
// Occluded lines, case-(a) lines, marked sub-cells.
var<workgroup> totals: array<atomic<u32>, 3>;
var<workgroup> red: array<vec4<f32>, 256>;

@compute @workgroup_size(64)
fn main(
    @builtin(workgroup_id) wid: vec3<u32>,
    @builtin(num_workgroups) nwg: vec3<u32>,
    @builtin(local_invocation_index) lid: u32,
) {
    let local = wid.x + wid.y * nwg.x;
    if local >= params.seed.y {
        return; // the 2D dispatch's tail: uniform across the workgroup
    }
    let vi = params.counts.z + local;
    let vox = voxels[vi];
    if lid < 27u {
        atomicStore(&cell_rays[lid], 0u);
        atomicStore(&cell_occluded[lid], 0u);
    }
    if lid < 3u {
        atomicStore(&totals[lid], 0u);
    }
    let count = vox.count;
    workgroupBarrier(); // the counters are zero
    let rays = params.counts.y;
    let base = params.seed.x;
    let write_lines = (params.counts.w & 1u) != 0u;
    // This invocation's sums over its lines: albedo + level, normal + weighted, scatter.
    var s0 = vec4<f32>(0.0);
    var s1 = vec4<f32>(0.0);
    var s2 = vec4<f32>(0.0);
    var s3 = vec4<f32>(0.0);
    for (var first = 0u; first < rays; first += WG) {
        let j = first + lid;
        let line = sample_line(vox.id, j, base);
        var best_t = 0.0;
        var best_u = 0.0;
        var best_v = 0.0;
        var best_k = NONE;
        // Every invocation reads the same triangle at the same time: a uniform (broadcast)
        // load, served from cache, with no workgroup memory and no barrier.
        for (var k = 0u; k < count; k++) {
            let tri = tris[vox.first + k];
            let h = intersect(tri, line.e, line.d);
            // Strictly closer: a tie keeps the earlier triangle (the lowest id). A hit that the
            // material's alpha rejects does not occlude (the test runs only on closer hits of
            // alpha-filtered triangles, as on the CPU).
            if h.hit && (best_k == NONE || h.t < best_t)
                && ((bitcast<u32>(tri.a.w) & 8u) == 0u
                    || accepts(bitcast<u32>(tri.ng.w), h.u, h.v, vox.id, j)) {
                best_t = h.t;
                best_u = h.u;
                best_v = h.v;
                best_k = k;
            }
        }
        // The tail invocations of the last stride only skip the booking (no barrier in it).
        if j < rays {
            var case_id = 0u;
            var point = vec3<f32>(0.0);
            var normal = vec3<f32>(0.0);
            var albedo = vec3<f32>(0.0);
            var triangle = NONE;
            if best_k != NONE {
                case_id = 1u;
                let tri = tris[vox.first + best_k];
                triangle = bitcast<u32>(tri.ng.w);
                point = line.e + line.d * best_t;
                let flat = bitcast<u32>(tri.a.w);
                for (var a = 0u; a < 3u; a++) {
                    if ((flat >> a) & 1u) == 1u {
                        point[a] = tri.a[a]; // exact on axis-aligned triangles (voxel-face ties)
                    }
                }
                let inside = all(point >= vec3<f32>(0.0)) && all(point <= vec3<f32>(1.0));
                let st = shade[triangle];
                let mi = bitcast<u32>(st.p0.w);
                let double_sided = materials[mi].double_sided != 0u;
                let facing = dot3(tri.ng.xyz, line.d);
                if inside && (double_sided || facing < 0.0) {
                    case_id = 2u;
                    let w = 1.0 - best_u - best_v;
                    let ns = st.n0.xyz * w + st.n1.xyz * best_u + st.n2.xyz * best_v;
                    let len = sqrt(dot3(ns, ns));
                    let rcp = 1.0 / len;
                    if len > 0.0 && rcp <= F32_MAX {
                        normal = ns * rcp;
                    } else {
                        // Geometry::interpolate's fallback: the unit geometric normal, else +z.
                        let g = cross(st.p1.xyz - st.p0.xyz, st.p2.xyz - st.p0.xyz);
                        let gl = sqrt(dot3(g, g));
                        let ok = gl > 0.0 && 1.0 / gl <= F32_MAX;
                        normal = select(vec3<f32>(0.0, 0.0, 1.0), g / gl, ok);
                    }
                    if double_sided && facing > 0.0 {
                        normal = -normal;
                    }
                    // Material::sample at the interpolated UV: textured albedo, specular, exponent.
                    let m = material_sample(mi, hit_uv(st, best_u, best_v));
                    albedo = m.albedo;
                    let level = (m.specular.x + m.specular.y + m.specular.z) * ONE_THIRD_MEAN;
                    s0 += vec4<f32>(albedo, level);
                    s1 += vec4<f32>(normal, level * m.shininess);
                    let nx = normal.x * normal;
                    s2 += vec4<f32>(nx, normal.y * normal.y);
                    s3 += vec4<f32>(normal.y * normal.z, normal.z * normal.z, 0.0, 0.0);
                    atomicAdd(&totals[1], 1u);
                    atomicOr(&totals[2], 1u << subcell_of(point));
                }
                atomicAdd(&totals[0], 1u);
            }
            // Every line books one ray, and one occlusion if occluded, on the sub-cells it crosses;
            // the clearing of unmarked cells comes after all lines.
            var mask = crossed_subcells(line.e, line.d, line.chord);
            let occluded = u32(best_k != NONE);
            for (var b = 0u; b < 7u && mask != 0u; b++) {
                let c = firstTrailingBit(mask);
                atomicAdd(&cell_rays[c], 1u);
                atomicAdd(&cell_occluded[c], occluded);
                mask &= mask - 1u;
            }
            if write_lines {
                lines[vi * rays + j] = LineOut(
                    vec4<f32>(line.d, line.chord),
                    vec4<f32>(line.e, bitcast<f32>(case_id)),
                    vec4<f32>(point, bitcast<f32>(triangle)),
                    vec4<f32>(normal, 0.0),
                    vec4<f32>(albedo, 0.0),
                );
            }
        }
    }
    // The float sums, added by invocation 0 in invocation order (deterministic): one barrier,
    // where a tree would take six (each a costly coroutine switch on CPU implementations).
    red[lid * 4u] = s0;
    red[lid * 4u + 1u] = s1;
    red[lid * 4u + 2u] = s2;
    red[lid * 4u + 3u] = s3;
    workgroupBarrier();
    if lid == 0u {
        for (var i = 1u; i < WG; i++) {
            for (var q = 0u; q < 4u; q++) {
                red[q] += red[i * 4u + q];
            }
        }
    }
    if lid == 0u {
        let marked = atomicLoad(&totals[2]);
        var words = array<u32, 8>(0u, 0u, 0u, 0u, 0u, 0u, 0u, 0u);
        for (var c = 0u; c < 27u; c++) {
            let r = atomicLoad(&cell_rays[c]);
            let o = atomicLoad(&cell_occluded[c]);
            var byte = 0u;
            if ((marked >> c) & 1u) == 1u && r > 0u {
                // unorm8(o / r): round(clamp(x, 0, 1)·255) by truncating x·255 + 0.5.
                byte = u32(clamp(f32(o) / f32(r), 0.0, 1.0) * 255.0 + 0.5);
            }
            words[c / 4u] |= byte << (8u * (c % 4u));
        }
        out[vi] = VoxelOut(
            vec4<u32>(atomicLoad(&totals[0]), atomicLoad(&totals[1]), marked, rays),
            red[0],
            red[1],
            red[2],
            red[3],
            array<vec4<u32>, 2>(
                vec4<u32>(words[0], words[1], words[2], words[3]),
                vec4<u32>(words[4], words[5], words[6], words[7]),
            ),
        );
    }
}
