// Binning (McNabb 2015, Listing 5.1): one invocation per (particle, candidate metavoxel). The host
// lists each particle's candidate metavoxels (the CPU reference's per-axis metavoxel ranges,
// computed by the same Rust code) and their prefix sum; an invocation finds its particle by
// binary search over the prefix sum (neighbours read the same entries: coherent), decodes its
// metavoxel (x fastest, then y, then z: the CPU's enumeration order) and evaluates the
// reference's predicate, squared distance from the centre to the metavoxel's box against the
// squared outer radius. Result per candidate: 0 miss, 1 hit, 2 too close to call (|d² − r²|
// within a relative 2^-16: a fused multiply-add or a reassociation could flip it), which the
// host decides with the reference predicate itself. No atomics: the output is in candidate
// order, so the result is deterministic.

struct Params {
    // x: candidates, y: particles, z: M (voxels per metavoxel edge), w: unused.
    counts: vec4<u32>,
}

struct Candidate {
    // Centre in voxel coordinates, w: outer radius in voxels.
    sphere: vec4<f32>,
    // First metavoxel of the range (xyz), w: first candidate index.
    lo: vec4<u32>,
    // Last metavoxel of the range (xyz, inclusive), w: unused.
    hi: vec4<u32>,
}

@group(0) @binding(0) var<storage, read> params: Params;
@group(0) @binding(1) var<storage, read> particles: array<Candidate>;
@group(0) @binding(2) var<storage, read_write> result: array<u32>;

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let item = gid.x + gid.y * nwg.x * 64u;
    if item >= params.counts.x {
        return;
    }
    // Last particle whose first candidate is ≤ item (particles without candidates share the
    // next one's start and are skipped by taking the last).
    var lo = 0u;
    var hi = params.counts.y;
    while hi - lo > 1u {
        let mid = (lo + hi) / 2u;
        if particles[mid].lo.w <= item {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    let p = particles[lo];
    let local = item - p.lo.w;
    let n = p.hi.xyz - p.lo.xyz + vec3<u32>(1u);
    let c = p.lo.xyz + vec3<u32>(local % n.x, (local / n.x) % n.y, local / (n.x * n.y));
    let m = f32(params.counts.z);
    let box_lo = vec3<f32>(c) * m;
    let box_hi = box_lo + vec3<f32>(m);
    let centre = p.sphere.xyz;
    let d = centre - clamp(centre, box_lo, box_hi);
    let d2 = d.x * d.x + d.y * d.y + d.z * d.z;
    let r2 = p.sphere.w * p.sphere.w;
    var out = 0u;
    if abs(d2 - r2) <= max(d2, r2) * 1.52587890625e-5 {
        out = 2u;
    } else if d2 <= r2 {
        out = 1u;
    }
    result[item] = out;
}
