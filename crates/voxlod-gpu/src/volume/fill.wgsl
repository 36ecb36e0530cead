
// Fill (McNabb 2015, §5.5.2): one invocation per voxel of the kept metavoxels, 64 per workgroup
// along x (a row: neighbouring invocations write neighbouring voxels, coalesced). Each voxel
// walks its metavoxel's bin in particle order (the same list for the whole workgroup, so the
// particle loads are broadcasts and the loop trip count is uniform), with the CPU reference's
// per-voxel arithmetic: d² from the voxel centre, early reject beyond r_hi, early accept within
// max(inner, r_lo) unless the colour needs the displacement, else the cube-map look-up and
// d² ≤ r². Density is the sum in particle order (the CPU's order), colour the max. The box of
// covered voxels goes to `boxes` by atomic min/max.

struct Params {
    // x: M, y: kept metavoxels, z: cube-map face size, w: 1 if some particle is emissive.
    dims: vec4<u32>,
    frame: Frame,
}

// Per particle, computed on the host with the CPU reference's f32 operations.
struct Prep {
    // Centre in voxel coordinates, w: inner radius in voxels.
    center: vec4<f32>,
    // x: amplitude in voxels, y: accept² (max(inner, r_lo)²), z: reject² (r_hi²), w: unused.
    radii: vec4<f32>,
}

// One kept metavoxel: its coordinate (w: first entry in `lists`), x of `range`: entries.
struct Slot {
    coord: vec4<u32>,
    range: vec4<u32>,
}

@group(0) @binding(0) var<storage, read> params: Params;
@group(0) @binding(1) var<storage, read> spheres: array<Sphere>;
@group(0) @binding(2) var<storage, read> preps: array<Prep>;
@group(0) @binding(3) var<storage, read> slots: array<Slot>;
@group(0) @binding(4) var<storage, read> lists: array<u32>;
@group(0) @binding(5) var<storage, read> texels: array<f32>;
@group(0) @binding(6) var<storage, read_write> voxels: array<vec4<f32>>;
@group(0) @binding(7) var<storage, read_write> emission: array<vec4<f32>>;
@group(0) @binding(8) var<storage, read_write> boxes: array<atomic<u32>>;

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let m = params.dims.x;
    let m3 = m * m * m;
    let item = gid.x + gid.y * nwg.x * 64u;
    if item >= m3 * params.dims.y {
        return;
    }
    let slot_index = item / m3;
    let local = item % m3;
    let a = local % m;
    let b = (local / m) % m;
    let c = local / (m * m);
    let slot = slots[slot_index];
    let base = vec3<f32>(slot.coord.xyz) * f32(m);
    let f = params.frame;
    let vs = f.origin.w;
    let n_face = params.dims.z;
    var voxel = vec4<f32>(0.0);
    var emitted = vec3<f32>(0.0);
    var covered_any = false;
    for (var e = 0u; e < slot.range.x; e++) {
        let pi = lists[slot.coord.w + e];
        let p = preps[pi];
        let qx = base.x + f32(a) + 0.5 - p.center.x;
        let qy = base.y + f32(b) + 0.5 - p.center.y;
        let qz = base.z + f32(c) + 0.5 - p.center.z;
        let d2 = qx * qx + qy * qy + qz * qz;
        if d2 > p.radii.z {
            continue; // early reject
        }
        let s = spheres[pi];
        let needs_n = s.color_mode == 2u;
        let inside = d2 <= p.radii.y;
        var n = 0.0;
        var covered = inside;
        if !inside || needs_n {
            // LightSpace::offset_to_world of the voxel-space offset.
            let vy = f.v.xyz * qy;
            let wz = f.w.xyz * qz;
            let o = (f.u.xyz * qx + vy + wz) * vs;
            let nn = displacement(s, o, n_face);
            let r = p.center.w + p.radii.x * nn;
            covered = inside || d2 <= r * r;
            n = select(select(nn, 0.0, inside), nn, needs_n);
        }
        if !covered {
            continue;
        }
        covered_any = true;
        var dist = 0.0;
        if s.color_mode == 1u {
            dist = sqrt(d2) * vs;
        }
        let col = color_at(s, dist, n);
        voxel.w = voxel.w + s.density;
        if (s.flags & FLAG_EMISSIVE) != 0u {
            emitted = max(emitted, col);
        } else {
            voxel = vec4<f32>(max(col, voxel.xyz), voxel.w);
        }
    }
    voxels[item] = voxel;
    if params.dims.w != 0u {
        emission[item] = vec4<f32>(emitted, 0.0);
    }
    if covered_any {
        let box = slot_index * 6u;
        atomicMin(&boxes[box + 0u], a);
        atomicMin(&boxes[box + 1u], b);
        atomicMin(&boxes[box + 2u], c);
        atomicMax(&boxes[box + 3u], a + 1u);
        atomicMax(&boxes[box + 4u], b + 1u);
        atomicMax(&boxes[box + 5u], c + 1u);
    }
}
