// Shared by every octree-build kernel: the mirrors of voxlod_octree's flat layout (checked
// for size and offsets by a test), the dispatch parameters, Morton codes.

// voxlod_octree::GpuNode: child tile (global index of its first node, or NONE) and the
// occupied-children mask (low 8 bits). 8 bytes.
struct GpuNode {
    child: u32,
    mask: u32,
}

// voxlod_octree::GpuTile: global index of the first node of the +x, +y, +z neighbour tile.
// 12 bytes.
struct GpuTile {
    links: array<u32, 3>,
}

// voxlod_octree::GpuLevel: where a level's nodes and tiles are. 20 bytes.
struct GpuLevel {
    first: u32,
    count: u32,
    res_log2: u32,
    dense: u32,
    first_tile: u32,
}

// voxlod_octree::AveragePayload: colour × opacity, normal × opacity, opacity. 28 bytes.
struct Average {
    color_alpha: array<f32, 3>,
    normal_alpha: array<f32, 3>,
    opacity: f32,
}

// GpuOctreeParams: `n` threads (or items), the level being built or filtered, the finest
// dense level, and one kernel-specific word.
struct Params {
    n: u32,
    level: u32,
    first_dense: u32,
    extra: u32,
}

const NONE: u32 = 0xffffffffu;
const WG: u32 = 64u;

// The flat invocation index of a 2D dispatch of WG-wide workgroups.
fn flat_index(wg: vec3<u32>, nwg: vec3<u32>, li: u32) -> u32 {
    return (wg.y * nwg.x + wg.x) * WG + li;
}
