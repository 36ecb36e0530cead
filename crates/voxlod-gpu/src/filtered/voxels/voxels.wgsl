// The filtered renderer for virtual-mesh grids and Adaptive (mixed) grids, appended to
// shading.wgsl, filtered.wgsl (Params, the DDA, the voxel look-up, [VJK21] transmittance, SGGX
// shading) and vmesh.wgsl. Three dispatches per frame, in this order:
//   light_pass  one invocation per voxel with a record: its opacity for the direction the
//               light travels at its centre (the CPU's light-opacity slot);
//   view_pass   one invocation per voxel: its radiance toward the eye, with the visibility of
//               its shadow ray read from light_pass's opacities, and its opacity toward the
//               eye (the CPU's view and shadow slots);
//   composite   one invocation per pixel in 8×8 tiles: the 4 rays of PATTERN_4 through the
//               grid, compositing the voxels' cached values front to back until T < 0.001.
// Every cached value is a function of the voxel alone (its record, centre, the eye, the light,
// the ambient term), so computing each once per voxel gives what the CPU's lazily filled cache
// holds for every voxel a ray reaches.

// sRGB8 → linear (entries 0..256) and SCALE_RANGE log byte → semi-axis (256..512), tabulated
// on the host by voxlod-format's own decoders.
@group(0) @binding(6) var<uniform> tables: array<vec4<f32>, 128>;
// Per voxel (the records' brick-map order): its grid coordinates, and its tag
// (AdaptiveRef: kind in bits 30–31 (0 Averages, 1 [VJK21], 2 virtual mesh), index in the low
// 30; Averages and [VJK21] index `records`, the virtual mesh indexes `vmesh`).
@group(0) @binding(7) var<storage, read> voxels: array<vec4<u32>>;
@group(0) @binding(8) var<storage, read> vmesh: array<VmeshRecord>;
// Per voxel two entries: [2i] = radiance toward the eye (rgb); [2i + 1] = opacity toward the
// eye (x, y) and for the light (z, w): (α, 0) or (σ, γ) by the voxel's kind.
@group(0) @binding(9) var<storage, read_write> cache: array<vec4<f32>>;

const KIND_AVERAGE: u32 = 0u;
const KIND_SGGX: u32 = 1u;
const KIND_VMESH: u32 = 2u;

fn kind_of(tag: u32) -> u32 {
    return tag >> 30u;
}

fn index_of_tag(tag: u32) -> u32 {
    return tag & 0x3fffffffu;
}

fn voxel_index(wg: vec3<u32>, groups: vec3<u32>, local: u32) -> u32 {
    return (wg.y * groups.x + wg.x) * 64u + local;
}

// The opacity (two parameters) of voxel `tag` along `dir`.
fn opacity_of(tag: u32, dir: vec3<f32>) -> vec2<f32> {
    let kind = kind_of(tag);
    let i = index_of_tag(tag);
    if kind == KIND_VMESH {
        vm_load(i);
        return vec2<f32>(vmesh_opacity(dir, params.vmesh.x, (params.vmesh.z & 1u) != 0u), 0.0);
    }
    let r = records[i];
    if kind == KIND_SGGX {
        return vec2<f32>(r.a.w, r.b.w);
    }
    return vec2<f32>(r.a.w, 0.0);
}

// Opacity::apply for a voxel of `kind` with parameters `p`.
fn apply_kind(t: f32, kind: u32, p: vec2<f32>, chord: f32) -> f32 {
    return apply_params(t, kind == KIND_SGGX, p, chord);
}

@compute @workgroup_size(64)
fn light_pass(
    @builtin(workgroup_id) wg: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
    @builtin(local_invocation_index) local: u32,
) {
    let i = voxel_index(wg, groups, local);
    if i >= params.vmesh.w {
        return;
    }
    let v = voxels[i];
    let lit = light_at(centre_of(vec3<i32>(v.xyz)));
    let p = opacity_of(v.w, -lit.light.to_light);
    cache[2u * i + 1u].z = p.x;
    cache[2u * i + 1u].w = p.y;
}

// The transmittance of voxel c's shadow ray toward `lit` (filtered.wgsl `shadow`), each voxel
// crossed applying its light-direction opacity from light_pass.
fn shadow_cached(c: vec3<i32>, lit: Lit) -> f32 {
    let size = params.grid.w;
    // From the centre exactly, c + ½ in grid coordinates, as the CPU starts it.
    let o = vec3<f32>(c) + 0.5;
    var dda = dda_new(o, lit.light.to_light / size, 0.0, lit.distance);
    var t = 1.0;
    for (var h = walk_next(&dda); h.index != NONE; h = walk_next(&dda)) {
        let v = h.step;
        let index = h.index;
        let offset = v.voxel - c;
        if dot(offset, offset) <= SHADOW_SKIP_SQ {
            continue;
        }
        let p = cache[2u * index + 1u].zw;
        t = apply_kind(t, kind_of(voxels[index].w), p, (v.t_exit - v.t_enter) * params.eye_grid.w);
        if t < MIN_TRANSMITTANCE {
            break;
        }
    }
    return t;
}

@compute @workgroup_size(64)
fn view_pass(
    @builtin(workgroup_id) wg: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
    @builtin(local_invocation_index) local: u32,
) {
    let i = voxel_index(wg, groups, local);
    if i >= params.vmesh.w {
        return;
    }
    let v = voxels[i];
    let c = vec3<i32>(v.xyz);
    let kind = kind_of(v.w);
    let ri = index_of_tag(v.w);
    let centre = centre_of(c);
    var to_eye = normalize_or_zero(params.eye.xyz - centre);
    if all(to_eye == vec3<f32>(0.0)) {
        to_eye = vec3<f32>(0.0, 0.0, 1.0);
    }
    let lit = light_at(centre);
    let shadows = (params.dims.w & 1u) != 0u;
    let ambient = params.ambient.xyz;
    var radiance = vec3<f32>(0.0);
    var p = vec2<f32>(0.0);
    if kind == KIND_VMESH {
        vm_load(ri);
        // The virtual mesh keeps the default needs_visibility: always traced with shadows on.
        var visibility = 1.0;
        if shadows {
            visibility = shadow_cached(c, lit);
        }
        radiance = shade_vmesh(to_eye, lit.light, visibility, ambient, params.vmesh.y);
        p = vec2<f32>(vmesh_opacity(to_eye, params.vmesh.x, (params.vmesh.z & 1u) != 0u), 0.0);
    } else {
        let r = records[ri];
        var m: MaterialSample;
        m.albedo = r.a.xyz;
        m.specular = vec3<f32>(r.c.w);
        m.shininess = r.d.w;
        if kind == KIND_SGGX {
            var visibility = 1.0;
            if shadows {
                visibility = shadow_cached(c, lit);
            }
            radiance = shade_sggx(r, m, to_eye, lit.light, visibility, ambient);
            p = vec2<f32>(r.a.w, r.b.w);
        } else {
            let n = shading_normal(r.b.xyz, to_eye);
            var visibility = 1.0;
            // Appearance::needs_visibility: no shadow ray where the normal faces away.
            if shadows && dot(n, lit.light.to_light) > 0.0 {
                visibility = shadow_cached(c, lit);
            }
            radiance = shade(m, n, to_eye, lit.light, visibility, ambient);
            p = vec2<f32>(r.a.w, 0.0);
        }
    }
    cache[2u * i] = vec4<f32>(radiance, 0.0);
    cache[2u * i + 1u].x = p.x;
    cache[2u * i + 1u].y = p.y;
}

// Composited radiance (rgb) and transmittance (w) of the camera ray along unit `dir`.
fn trace_cached(dir: vec3<f32>) -> vec4<f32> {
    var dda = dda_new(params.eye_grid.xyz, dir / params.grid.w, 0.0, F32_MAX);
    var t = 1.0;
    var sum = vec3<f32>(0.0);
    for (var h = walk_next(&dda); h.index != NONE; h = walk_next(&dda)) {
        let v = h.step;
        let index = h.index;
        let p = cache[2u * index + 1u].xy;
        let kind = kind_of(voxels[index].w);
        let next = apply_kind(t, kind, p, (v.t_exit - v.t_enter) * params.eye_grid.w);
        sum += (t - next) * cache[2u * index].xyz;
        t = next;
        if t < MIN_TRANSMITTANCE {
            break;
        }
    }
    return vec4<f32>(sum, t);
}

@compute @workgroup_size(8, 8)
fn composite(@builtin(global_invocation_id) id: vec3<u32>) {
    let width = params.size.x;
    if id.x >= width || id.y >= params.size.y {
        return;
    }
    let corner = vec2<f32>(f32(id.x), f32(id.y));
    var sum = vec4<f32>(0.0);
    for (var s = 0u; s < 4u; s++) {
        let r = trace_cached(ray_dir(corner + PATTERN_4[s]));
        sum += vec4<f32>(r.xyz + r.w * params.background.xyz, 1.0 - r.w);
    }
    pixels[id.y * width + id.x] = sum / 4.0;
}
