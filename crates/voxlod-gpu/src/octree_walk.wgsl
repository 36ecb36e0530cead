// Finding octree nodes from WGSL: Morton codes of dense levels, the +axis neighbour on a sparse
// level (FlatOctree::neighbour) and the descent to a node (Octree::find). Shared by the cone and
// differential cone-tracing kernels; the including kernel declares `Level`, `NONE`, `params`
// (with `tree.y` the finest dense level) and the `levels`, `nodes` and `tiles` buffers.

fn part1by2(x: u32) -> u32 {
    var v = x & 0x3ffu;
    v = (v | (v << 16u)) & 0x030000ffu;
    v = (v | (v << 8u)) & 0x0300f00fu;
    v = (v | (v << 4u)) & 0x030c30c3u;
    v = (v | (v << 2u)) & 0x09249249u;
    return v;
}

// Morton code of a node of a dense level (at most 256 per axis: 24 bits).
fn morton(c: vec3<u32>) -> u32 {
    return part1by2(c.x) | (part1by2(c.y) << 1u) | (part1by2(c.z) << 2u);
}

// FlatOctree::neighbour on a sparse level: the +axis neighbour of global node `node`.
fn sparse_neighbour(lv: Level, node: u32, axis: u32) -> u32 {
    if node == NONE {
        return NONE;
    }
    let local = node - lv.first;
    let bit = 1u << axis;
    if (local & bit) == 0u {
        return lv.first + (local | bit);
    }
    let t = tiles[lv.first_tile + local / 8u].links[axis];
    if t == NONE {
        return NONE;
    }
    return t + (local & 7u & ~bit);
}

// Octree::find: global index of node `c` of sparse `level`, descending from the finest dense
// level; NONE if it does not exist.
fn find(level: u32, c: vec3<u32>) -> u32 {
    let top = params.tree.y;
    var idx = levels[top].first + morton(c >> vec3<u32>(top - level));
    for (var lv = top; lv > level; lv -= 1u) {
        let child = nodes[idx].child;
        if child == NONE {
            return NONE;
        }
        let o = (c >> vec3<u32>(lv - 1u - level)) & vec3<u32>(1u);
        idx = child + o.x + 2u * o.y + 4u * o.z;
    }
    return idx;
}
