// Light propagation (McNabb 2015, Listing 5.2): one invocation per voxel column, M² per column of
// metavoxels, 64 per workgroup (consecutive invocations are consecutive columns `a` of a row:
// at every step of the walk down they read and write neighbouring voxels, coalesced). An
// invocation walks its column's kept metavoxels top to bottom (consecutive slots, as the keys
// sort), records the light entering each (`light_top`), and lights and attenuates the voxels
// of the metavoxel's occupied box exactly as the CPU reference does: τ = σ · voxel size, the
// voxel lit with the light at its top (the exact model: its mean over the voxel's depth),
// `rgb = albedo · (E/π · light · visible + ambient) + emission`, then light *= T(τ).

struct Params {
    // x: M, y: columns (of metavoxels), z: attenuation (0 chapter, 1 Beer-Lambert, 2 exact),
    // w: 1 if the emission buffer is live.
    dims: vec4<u32>,
    // E/π (xyz), w: voxel size.
    direct: vec4<f32>,
    // Ambient irradiance (xyz).
    ambient: vec4<f32>,
}

// A column of metavoxels: x first slot, y slots.
struct Column {
    range: vec4<u32>,
}

@group(0) @binding(0) var<storage, read> params: Params;
@group(0) @binding(1) var<storage, read> columns: array<Column>;
@group(0) @binding(2) var<storage, read> slots: array<vec4<u32>>;
@group(0) @binding(3) var<storage, read> boxes: array<u32>;
@group(0) @binding(4) var<storage, read> emission: array<vec4<f32>>;
// Per voxel column, the depth in voxels from the volume's top of the first mesh hit (±inf).
@group(0) @binding(5) var<storage, read> shadow: array<f32>;
@group(0) @binding(6) var<storage, read_write> voxels: array<vec4<f32>>;
@group(0) @binding(7) var<storage, read_write> light_top: array<f32>;

fn transmittance(tau: f32) -> f32 {
    if params.dims.z == 0u {
        return 1.0 / (1.0 + tau);
    }
    return exp(-tau);
}

fn mean_decay(tau: f32) -> f32 {
    if tau < 1e-4 {
        return 1.0 - 0.5 * tau;
    }
    return (1.0 - exp(-tau)) / tau;
}

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let m = params.dims.x;
    let m2 = m * m;
    let item = gid.x + gid.y * nwg.x * 64u;
    if item >= m2 * params.dims.y {
        return;
    }
    let column = columns[item / m2];
    let col = item % m2;
    let a = col % m;
    let b = col / m;
    let hit = shadow[item];
    let vs = params.direct.w;
    var light = 1.0;
    for (var k = 0u; k < column.range.y; k++) {
        let slot = column.range.x + k;
        light_top[slot * m2 + col] = light;
        let bx = slot * 6u;
        if a < boxes[bx] || a >= boxes[bx + 3u] || b < boxes[bx + 1u] || b >= boxes[bx + 4u] {
            continue;
        }
        let z0 = slots[slot].z * m;
        for (var c = boxes[bx + 2u]; c < boxes[bx + 5u]; c++) {
            let index = slot * m * m2 + c * m2 + col;
            let v = voxels[index];
            var e = vec3<f32>(0.0);
            if params.dims.w != 0u {
                e = emission[index].xyz;
            }
            if all(v == vec4<f32>(0.0)) && all(e == vec3<f32>(0.0)) {
                continue;
            }
            let tau = v.w * vs;
            let t = transmittance(tau);
            var reach = light;
            if params.dims.z == 2u {
                reach = light * mean_decay(tau);
            }
            let visible = select(0.0, 1.0, (f32(z0 + c) + 0.5) < hit);
            var rgb = v.xyz * (params.direct.xyz * (reach * visible) + params.ambient.xyz);
            if params.dims.w != 0u {
                rgb = rgb + e;
            }
            voxels[index] = vec4<f32>(rgb, v.w);
            light = light * t;
        }
    }
}
