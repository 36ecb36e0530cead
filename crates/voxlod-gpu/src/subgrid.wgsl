// The 3×3×3 opacity subgrid's line crossing (voxlod-cpu appearance/subgrid.rs), shared by
// the virtual-mesh renderer (the Lines rule of directional opacity, filtered/vmesh.wgsl) and
// the appearance precompute (each line books the sub-cells it crosses, precompute.wgsl).

const TOUCH: f32 = 1e-6f;
// f32 constants as the CPU rounds them: f32 literals of 9 significant digits, each the
// decimal of one f32 (WGSL would fold `1.0 / 3.0` as an abstract float).
const THIRD: f32 = 3.333333433e-01f;         // 1.0f32 / 3.0 (0x3eaaaaab)
const TWO_THIRDS: f32 = 6.666666865e-01f;    // 2.0f32 / 3.0 (0x3f2aaaab)
// Stands for ±∞ in the slab intervals (every crossing compared with it is at most the chord
// or at least 0, so the comparisons are those of the CPU's infinities).
const SUBGRID_BIG: f32 = 1e30f;

// subgrid::crossed_subcells: bit x + 3y + 9z for each sub-cell the segment e + t·d,
// t ∈ [0, chord], overlaps over more than TOUCH (branch-free, as the CPU's: per axis the
// three slab intervals, then 27 overlaps; the x-slab terms are compared with y/z terms
// already clipped to [0, chord]).
fn crossed_subcells(e: vec3<f32>, d: vec3<f32>, chord: f32) -> u32 {
    if !(chord > TOUCH) {
        return 0u;
    }
    var lo: array<vec3<f32>, 3>;
    var hi: array<vec3<f32>, 3>;
    for (var j = 0u; j < 3u; j++) {
        if d[j] == 0.0 {
            let home = u32(clamp(i32(3.0 * e[j]), 0, 2));
            let is_home = vec3<u32>(0u, 1u, 2u) == vec3<u32>(home);
            let l = select(vec3<f32>(SUBGRID_BIG), vec3<f32>(-SUBGRID_BIG), is_home);
            lo[j] = l;
            hi[j] = -l;
        } else {
            let inv = 1.0 / d[j];
            let t0 = (0.0 - e[j]) * inv;
            let t1 = (THIRD - e[j]) * inv;
            let t2 = (TWO_THIRDS - e[j]) * inv;
            let t3 = (1.0 - e[j]) * inv;
            let a = vec3<f32>(t0, t1, t2);
            let b = vec3<f32>(t1, t2, t3);
            lo[j] = min(a, b);
            hi[j] = max(a, b);
        }
    }
    let lo_y = max(lo[1], vec3<f32>(0.0));
    let hi_y = min(hi[1], vec3<f32>(chord));
    var mask = 0u;
    for (var z = 0u; z < 3u; z++) {
        let l_yz = max(lo_y, vec3<f32>(lo[2][z]));
        let h_yz = min(hi_y, vec3<f32>(hi[2][z]));
        for (var y = 0u; y < 3u; y++) {
            let len = min(hi[0], vec3<f32>(h_yz[y])) - max(lo[0], vec3<f32>(l_yz[y]));
            let bits = select(0u, 1u, len.x > TOUCH) | select(0u, 2u, len.y > TOUCH)
                | select(0u, 4u, len.z > TOUCH);
            mask |= bits << (3u * y + 9u * z);
        }
    }
    return mask;
}

// sampler/lines.rs chord: the length of the line e + t·d, t ≥ 0, inside the unit voxel; an axis
// with d = 0 never ends the chord. Uses the includer's F32_MAX (f32::MAX).
fn chord_of(e: vec3<f32>, d: vec3<f32>) -> f32 {
    var t = F32_MAX;
    var ends = false;
    for (var j = 0u; j < 3u; j++) {
        if d[j] == 0.0 {
            continue;
        }
        let inv = 1.0 / d[j];
        t = min(t, max(-e[j] * inv, (1.0 - e[j]) * inv));
        ends = true;
    }
    if !ends || !(abs(t) <= F32_MAX) {
        return 0.0;
    }
    return max(t, 0.0);
}
