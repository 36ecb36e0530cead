// Link: one invocation per tile of `level`: its +a neighbour tile is the child tile of its
// parent's +a neighbour (a Morton increment on a dense parent level, the parent tile's own
// node or its tile link on a sparse one).

@group(0) @binding(0) var<storage, read> params: Params;
@group(0) @binding(1) var<storage, read> levels: array<GpuLevel>;
@group(0) @binding(2) var<storage, read> nodes: array<GpuNode>;
@group(0) @binding(3) var<storage, read> tile_parent: array<u32>;
@group(0) @binding(4) var<storage, read_write> tiles: array<GpuTile>;

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
    let lv = levels[params.level];
    let pl = levels[params.level + 1u];
    let p = tile_parent[t];
    var out = GpuTile(array<u32, 3>(NONE, NONE, NONE));
    for (var a = 0u; a < 3u; a = a + 1u) {
        var q = NONE;
        if pl.dense == 1u {
            var c = demorton(p);
            c[a] = c[a] + 1u;
            if c[a] < (1u << pl.res_log2) {
                q = morton(c);
            }
        } else {
            let bit = 1u << a;
            if (p & bit) == 0u {
                q = p | bit;
            } else {
                let next = tiles[pl.first_tile + p / 8u].links[a];
                if next != NONE {
                    q = next - pl.first + (p & 7u & ~bit);
                }
            }
        }
        if q != NONE {
            out.links[a] = nodes[pl.first + q].child;
        }
    }
    tiles[lv.first_tile + t] = out;
}
