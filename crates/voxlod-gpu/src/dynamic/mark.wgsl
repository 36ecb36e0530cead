// Mark: one invocation per (moved voxel, corner) — `extra` = 1 for the static cells instead,
// one per cell — sets the flag of the 2×2×2 brick its world voxel lies in (flags indexed by
// the brick's Morton code; relaxed stores, every writer writes 1).

@group(0) @binding(0) var<storage, read> params: Params;
@group(0) @binding(1) var<storage, read> placed: array<Placed>;
@group(0) @binding(2) var<storage, read> cells: array<u32>;
@group(0) @binding(3) var<storage, read_write> flags: array<atomic<u32>>;

@compute @workgroup_size(64)
fn main(
    @builtin(workgroup_id) wg: vec3<u32>,
    @builtin(num_workgroups) nwg: vec3<u32>,
    @builtin(local_invocation_index) li: u32,
) {
    let i = flat_index(wg, nwg, li);
    if i >= params.n {
        return;
    }
    var c: vec3<i32>;
    if params.extra == 1u {
        c = vec3<i32>(vec3<u32>(cells[3u * i], cells[3u * i + 1u], cells[3u * i + 2u]));
    } else {
        let corners = select(1u, 8u, params.filter_mode == 1u);
        let p = placed[i / corners];
        if p.status != 0u {
            return;
        }
        let k = corner(p, i % corners);
        if k.w == 0 || !inside(k.xyz) {
            return;
        }
        c = k.xyz;
    }
    atomicStore(&flags[morton(vec3<u32>(c) >> vec3<u32>(1u))], 1u);
}
