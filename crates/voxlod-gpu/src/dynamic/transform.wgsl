// Transform: one invocation per cached voxel (all objects' caches concatenated), the mirror of
// voxlod_octree::dynamic::transform_voxel in its f32 operations and order (a compiler may fuse
// multiply-adds: the equivalence suite bounds what that moves).

struct Affine {
    m: array<f32, 12>,
}

// GpuObject: the object's anchor cell, its first matrix, 1 if skinned, 1 if outside.
struct Object {
    anchor: array<i32, 3>,
    first_matrix: u32,
    skinned: u32,
    outside: u32,
    pad: array<u32, 2>,
}

@group(0) @binding(0) var<storage, read> params: Params;
@group(0) @binding(1) var<storage, read> positions: array<u32>;
@group(0) @binding(2) var<storage, read> records: array<u32>;
@group(0) @binding(3) var<storage, read> skins: array<u32>;
@group(0) @binding(4) var<storage, read> object_of: array<u32>;
@group(0) @binding(5) var<storage, read> objects: array<Object>;
@group(0) @binding(6) var<storage, read> matrices: array<Affine>;
@group(0) @binding(7) var<storage, read_write> placed: array<Placed>;

const MAX_OFFSET: f32 = 8388608.0; // 2^23

// snorm8 of byte `b` of `w`: max(b/127, −1).
fn snorm8(w: u32, b: u32) -> f32 {
    let v = i32(w << (24u - 8u * b)) >> 24u;
    return max(f32(v) * (1.0 / 127.0), -1.0);
}

fn quantize(v: vec3<f32>) -> array<i32, 3> {
    let len = sqrt((v.x * v.x + v.y * v.y) + v.z * v.z);
    if len > 0.0 {
        let q = vec3<i32>(floor(v / len * 2047.0 + 0.5));
        let c = clamp(q, vec3<i32>(-2047), vec3<i32>(2047));
        return array<i32, 3>(c.x, c.y, c.z);
    }
    return array<i32, 3>(0, 0, 0);
}

@compute @workgroup_size(64)
fn main(
    @builtin(workgroup_id) wg: vec3<u32>,
    @builtin(num_workgroups) nwg: vec3<u32>,
    @builtin(local_invocation_index) li: u32,
) {
    let v = flat_index(wg, nwg, li);
    if v >= params.n {
        return;
    }
    var out = Placed(array<i32, 3>(0, 0, 0), 0u, array<i32, 3>(0, 0, 0), 1u);
    let o = objects[object_of[v]];
    if o.outside != 0u {
        placed[v] = out;
        return;
    }
    // The voxel's matrix: its object's, or the blend of its joints' (slot order, from zero).
    var m: array<f32, 12>;
    if o.skinned == 0u {
        m = matrices[o.first_matrix].m;
    } else {
        for (var e = 0u; e < 12u; e += 1u) {
            m[e] = 0.0;
        }
        let joints = skins[2u * v];
        let weights = skins[2u * v + 1u];
        for (var k = 0u; k < 4u; k += 1u) {
            let wb = (weights >> (8u * k)) & 0xffu;
            if wb == 0u {
                continue;
            }
            let w = f32(wb) / 255.0;
            let j = matrices[o.first_matrix + ((joints >> (8u * k)) & 0xffu)].m;
            for (var e = 0u; e < 12u; e += 1u) {
                m[e] += w * j[e];
            }
        }
    }
    let pos = positions[v];
    let i = vec3<f32>(vec3<u32>(pos & 1023u, (pos >> 10u) & 1023u, (pos >> 20u) & 1023u));
    var r: vec3<f32>;
    for (var c = 0u; c < 3u; c += 1u) {
        r[c] = ((m[c] * i.x + m[3u + c] * i.y) + m[6u + c] * i.z) + m[9u + c];
    }
    if !all(abs(r) < vec3<f32>(MAX_OFFSET)) {
        placed[v] = out;
        return;
    }
    // The record's normal (snorm8 × 3 in bytes 0..2 of its second word), normalized, moved.
    let nw = records[2u * v + 1u];
    var n = vec3<f32>(snorm8(nw, 0u), snorm8(nw, 1u), snorm8(nw, 2u));
    let nl = sqrt((n.x * n.x + n.y * n.y) + n.z * n.z);
    if nl > 0.0 {
        n = n * (1.0 / nl);
    } else {
        n = vec3<f32>(0.0);
    }
    var moved: vec3<f32>;
    for (var c = 0u; c < 3u; c += 1u) {
        moved[c] = (m[c] * n.x + m[3u + c] * n.y) + m[6u + c] * n.z;
    }
    out.normal = quantize(moved);
    let anchor = vec3<i32>(o.anchor[0], o.anchor[1], o.anchor[2]);
    var cell: vec3<i32>;
    if params.filter_mode == 0u {
        cell = vec3<i32>(floor(r));
    } else {
        let q = r - 0.5;
        let fl = floor(q);
        cell = vec3<i32>(fl);
        let f = min(vec3<u32>(floor((q - fl) * 64.0 + 0.5)), vec3<u32>(64u));
        out.frac = f.x | (f.y << 8u) | (f.z << 16u);
    }
    cell += anchor;
    out.cell = array<i32, 3>(cell.x, cell.y, cell.z);
    out.status = 0u;
    placed[v] = out;
}
