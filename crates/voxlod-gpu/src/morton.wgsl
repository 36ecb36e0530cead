// Morton codes in WGSL, as voxlod_format::morton: 10 bits per axis, x in bit 0. Shared by the
// octree-build, dynamic, cone, differential and light-injection kernels (prepended to their
// sources).

// 10 bits spread to every third bit.
fn part1by2(x: u32) -> u32 {
    var v = x & 0x3ffu;
    v = (v | (v << 16u)) & 0x030000ffu;
    v = (v | (v << 8u)) & 0x0300f00fu;
    v = (v | (v << 4u)) & 0x030c30c3u;
    v = (v | (v << 2u)) & 0x09249249u;
    return v;
}

// Every third bit gathered into 10 bits (the inverse of part1by2).
fn compact1by2(x: u32) -> u32 {
    var v = x & 0x09249249u;
    v = (v | (v >> 2u)) & 0x030c30c3u;
    v = (v | (v >> 4u)) & 0x0300f00fu;
    v = (v | (v >> 8u)) & 0xff0000ffu;
    v = (v | (v >> 16u)) & 0x000003ffu;
    return v;
}

// Morton code of a coordinate below 2^10 per axis.
fn morton(c: vec3<u32>) -> u32 {
    return part1by2(c.x) | (part1by2(c.y) << 1u) | (part1by2(c.z) << 2u);
}

fn demorton(m: u32) -> vec3<u32> {
    return vec3<u32>(compact1by2(m), compact1by2(m >> 1u), compact1by2(m >> 2u));
}

// A child's index in its parent (x + 2y + 4z of the coordinate's low bits).
fn octant(c: vec3<u32>) -> u32 {
    return (c.x & 1u) | ((c.y & 1u) << 1u) | ((c.z & 1u) << 2u);
}
