// Mark: one invocation per (voxel, backward shift d ∈ {0,1}³), 8 per voxel, adjacent
// invocations on the same voxel. The node `(v >> level) − d` needs a tile under its parent
// at `level + 1`: set the parent's flag; d = 0 also sets the voxel's octant in its parent's
// mask. Relaxed atomics: every writer of a flag writes the same 1, masks are OR-ed.

@group(0) @binding(0) var<storage, read> params: Params;
@group(0) @binding(3) var<storage, read> coords: array<u32>;
@group(0) @binding(4) var<storage, read_write> flags: array<atomic<u32>>;
@group(0) @binding(5) var<storage, read_write> masks: array<atomic<u32>>;

@compute @workgroup_size(64)
fn main(
    @builtin(workgroup_id) wg: vec3<u32>,
    @builtin(num_workgroups) nwg: vec3<u32>,
    @builtin(local_invocation_index) li: u32,
) {
    let t = flat_index(wg, nwg, li);
    if t >= params.n {
        return;
    }
    let d = t & 7u;
    let o = voxel(t >> 3u) >> vec3<u32>(params.level);
    let e = vec3<u32>(d & 1u, (d >> 1u) & 1u, (d >> 2u) & 1u);
    if any(o < e) {
        return;
    }
    let parent_level = params.level + 1u;
    let p = descend((o - e) >> vec3<u32>(1u), parent_level, params.first_dense);
    if p == NONE {
        return;
    }
    let local = p - levels[parent_level].first;
    atomicStore(&flags[local], 1u);
    if d == 0u {
        atomicOr(&masks[local], 1u << octant(o));
    }
}
