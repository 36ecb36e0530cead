// Finding octree nodes from WGSL (after morton.wgsl): the +axis neighbour on a sparse level
// (FlatOctree::neighbour), the descent to a node (Octree::find) and the eight nodes around a
// sample (Octree::corners). Shared by the cone, differential and light-injection kernels; the including kernel declares `Level`, `NONE`, `params`
// (with `tree.y` the finest dense level) and the `levels`, `nodes` and `tiles` buffers.

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

// Octree::corners: the nodes of `level` (`res` nodes per axis) at `s + (x, y, z)` for x, y, z in
// {0, 1}, indexed by x + 2y + 4z; NONE where there is none.
fn corners(level: u32, s: vec3<u32>, res: u32) -> array<u32, 8> {
    let lv = levels[level];
    var n: array<u32, 8>;
    if lv.dense == 1u {
        for (var e = 0u; e < 8u; e += 1u) {
            let c = s + vec3<u32>(e & 1u, (e >> 1u) & 1u, (e >> 2u) & 1u);
            if all(c < vec3<u32>(res)) {
                n[e] = lv.first + morton(c);
            } else {
                n[e] = NONE;
            }
        }
    } else {
        n[0] = find(level, s);
        n[1] = sparse_neighbour(lv, n[0], 0u);
        n[2] = sparse_neighbour(lv, n[0], 1u);
        n[4] = sparse_neighbour(lv, n[0], 2u);
        n[3] = sparse_neighbour(lv, n[1], 1u);
        n[5] = sparse_neighbour(lv, n[1], 2u);
        n[6] = sparse_neighbour(lv, n[2], 2u);
        n[7] = sparse_neighbour(lv, n[3], 2u);
    }
    return n;
}
