// The descent from the finest dense level through the child pointers built so far.

@group(0) @binding(1) var<storage, read> levels: array<GpuLevel>;
@group(0) @binding(2) var<storage, read> nodes: array<GpuNode>;

// Global index of node `c` of `level` (which must exist), with `fd` the finest dense level;
// NONE if a child pointer on the way is missing (a broken tree, never for the nodes asked).
fn descend(c: vec3<u32>, level: u32, fd: u32) -> u32 {
    if level >= fd {
        return levels[level].first + morton(c);
    }
    var idx = levels[fd].first + morton(c >> vec3<u32>(fd - level));
    for (var lv = fd; lv > level; lv -= 1u) {
        let child = nodes[idx].child;
        if child == NONE {
            return NONE;
        }
        idx = child + octant(c >> vec3<u32>(lv - 1u - level));
    }
    return idx;
}

fn voxel(i: u32) -> vec3<u32> {
    return vec3<u32>(coords[3u * i], coords[3u * i + 1u], coords[3u * i + 2u]);
}
