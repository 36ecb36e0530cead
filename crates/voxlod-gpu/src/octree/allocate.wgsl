// Allocate: one invocation per node `p` of the parent level `level + 1`. The exclusive scan
// of the flags is each flagged parent's rank `r`: its tile is nodes `8r .. 8r + 8` of
// `level` (parent order, hence Morton order), and tile `r` records its parent. No atomics.
// `extra` = the number of flagged parents (the scan's total).

@group(0) @binding(0) var<storage, read> params: Params;
@group(0) @binding(1) var<storage, read> levels: array<GpuLevel>;
@group(0) @binding(2) var<storage, read_write> nodes: array<GpuNode>;
@group(0) @binding(3) var<storage, read> ranks: array<u32>;
@group(0) @binding(4) var<storage, read> masks: array<u32>;
@group(0) @binding(5) var<storage, read_write> tile_parent: array<u32>;

@compute @workgroup_size(64)
fn main(
    @builtin(workgroup_id) wg: vec3<u32>,
    @builtin(num_workgroups) nwg: vec3<u32>,
    @builtin(local_invocation_index) li: u32,
) {
    let p = flat_index(wg, nwg, li);
    if p >= params.n {
        return;
    }
    let r = ranks[p];
    var next = params.extra;
    if p + 1u < params.n {
        next = ranks[p + 1u];
    }
    var child = NONE;
    if next != r {
        child = levels[params.level].first + 8u * r;
        tile_parent[r] = p;
    }
    nodes[levels[params.level + 1u].first + p] = GpuNode(child, masks[p]);
}
