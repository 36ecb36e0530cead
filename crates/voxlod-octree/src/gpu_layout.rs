//! A GPU-friendly flat layout ([`FlatOctree`]: one node array, one payload array, a level
//! table) and a CPU emulation of the lock-free level-by-level build that voxlod-gpu's `octree`
//! kernel runs ([`FlatOctree::build_level_by_level`]), checked against the reference build.
//!
//! # Layout
//! All levels are concatenated, root first (level `depth` … level 0), so that a storage buffer
//! holds the whole tree. Node `i` of level `l` is global node `levels[l].first + i`; every index
//! stored in a [`GpuNode`] or [`GpuTile`] is global, [`NONE`] meaning none. Dense levels keep
//! their Morton indexing (`first + morton(c)`); they have no tiles (a neighbour is an index
//! computation) and only the finest dense level has child pointers. The sparse levels' 2×2×2
//! tiles are concatenated the same way in `tiles`: tile `t` of level `l` (its nodes `8t..8t + 8`
//! local) is `tiles[levels[l].first_tile + t]`, and holds the global index of the first node of
//! its +x, +y, +z neighbour tile. A node's neighbour follows as on the CPU
//! ([`crate::LevelView::neighbour`], [`FlatOctree::neighbour`]): local index `i`, axis bit `b`:
//! `first + (i | b)` if `i & b == 0`, else `links[a] + (i & 7 & !b)` of its tile. The WGSL
//! mirror is `struct GpuNode { child: u32, mask: u32 }` (8 bytes),
//! `struct GpuTile { links: array<u32, 3> }` (12 bytes) and
//! `struct GpuLevel { first: u32, count: u32, res_log2: u32, dense: u32, first_tile: u32 }`
//! (20 bytes).
//!
//! # The lock-free build (Yalçıner and Sahillioğlu's (2020) Algorithm 1 without its spin lock)
//! WGSL has relaxed atomics only and no forward-progress guarantee, so the paper's top-down
//! allocation (compare-and-swap, spin while another thread allocates, volatile write) cannot be
//! ported. Instead, from the dense levels down, for each sparse level `l`:
//! 1. **mark**: one thread per input voxel and backward shift `d ∈ {0,1}³`: the node
//!    `(v >> l) − d` needs a tile under its parent; descend from the finest dense level to that
//!    parent (it exists: the levels above are built) and set its flag (`atomicStore`/`atomicOr`,
//!    relaxed: every writer writes the same value). The voxel's own parent also gets its
//!    occupancy bit (`atomicOr` on the mask).
//! 2. **allocate**: an exclusive prefix sum over the parent level's flags gives each flagged
//!    parent its tile `8·rank`: tiles in parent order, hence in Morton order, with no atomics on a
//!    shared allocator and a deterministic result.
//! 3. **link**: one thread per tile of level `l`: its +a neighbour tile is the child tile of its
//!    parent's +a neighbour (the reference rule, `build` module docs).
//!
//! Payloads then go bottom-up: leaves scattered by descent, one thread per parent prefiltering
//! its tile. The emulation runs each step as a rayon pass with `AtomicU32` relaxed operations,
//! and its topology equals the reference exactly (tested), payloads within float tolerance.

use std::sync::atomic::{AtomicU32, Ordering::Relaxed};

use glam::UVec3;
use rayon::prelude::*;
use voxlod_format::morton;

use crate::octree::{NONE, Octree};
use crate::payload::Payload;
use crate::{BuildOptions, Error, Result};

/// One node's topology: child tile (global index or [`NONE`]) and the occupied-children mask
/// (low 8 bits). `#[repr(C)]`, 8 bytes, no padding.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
pub struct GpuNode {
    /// Global index of the first node of the child tile, or [`NONE`].
    pub child: u32,
    /// Bit `k`: child `k`'s subtree holds an input voxel.
    pub mask: u32,
}

/// One 2×2×2 tile of a sparse level: the global index of the first node of its +x, +y, +z
/// neighbour tile at the same level, or [`NONE`]. `#[repr(C)]`, 12 bytes.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
pub struct GpuTile {
    /// +x, +y, +z neighbour tiles.
    pub links: [u32; 3],
}

/// Where a level's nodes and tiles are in the flat arrays. `#[repr(C)]`, 20 bytes.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
pub struct GpuLevel {
    /// Global index of the level's first node.
    pub first: u32,
    /// Nodes in the level.
    pub count: u32,
    /// `log2` of the resolution per axis.
    pub res_log2: u32,
    /// 1 if stored densely (Morton-indexed), 0 if in sparse tiles.
    pub dense: u32,
    /// Index in [`FlatOctree::tiles`] of the level's first tile (sparse levels; for dense
    /// levels, which have none, where the next sparse level's tiles start).
    pub first_tile: u32,
}

/// The flat layout (module docs): `levels[l]` for level `l` (0 = leaves), nodes of all levels
/// root first, one payload per node, tiles of the sparse levels.
#[derive(Clone, Debug, PartialEq)]
pub struct FlatOctree<P> {
    /// Levels below the root.
    pub depth: u32,
    /// Indexed by level, 0 = leaves.
    pub levels: Vec<GpuLevel>,
    /// Topology of every node.
    pub nodes: Vec<GpuNode>,
    /// Payload of every node, same indices.
    pub payload: Vec<P>,
    /// Neighbour links of every tile of the sparse levels, level `depth − 1` … 0.
    pub tiles: Vec<GpuTile>,
}

fn global(first: u32, local: u32) -> u32 {
    if local == NONE { NONE } else { first + local }
}

/// The level table, node count and tile count for a tree whose level `l` holds `counts[l]`
/// nodes.
fn level_table(counts: &[usize], first_dense: u32) -> Result<(Vec<GpuLevel>, usize, usize)> {
    let depth = counts.len() as u32 - 1;
    let mut levels = vec![GpuLevel::default(); counts.len()];
    let (mut next, mut tiles) = (0u64, 0u64);
    for l in (0..=depth).rev() {
        let count = counts[l as usize] as u64;
        if next + count >= NONE as u64 {
            return Err(Error::TooManyNodes { level: l, nodes: next + count });
        }
        let dense = l >= first_dense;
        levels[l as usize] = GpuLevel {
            first: next as u32,
            count: count as u32,
            res_log2: depth - l,
            dense: dense as u32,
            first_tile: tiles as u32,
        };
        next += count;
        if !dense {
            tiles += count / 8;
        }
    }
    Ok((levels, next as usize, tiles as usize))
}

impl<P: Payload> FlatOctree<P> {
    /// The flat layout of a reference-built octree.
    pub fn from_octree(tree: &Octree<P>) -> Result<Self> {
        let counts: Vec<usize> = tree.levels.iter().map(|l| l.payload.len()).collect();
        let (levels, total, tile_count) = level_table(&counts, tree.first_dense)?;
        let mut nodes = vec![GpuNode { child: NONE, mask: 0 }; total];
        let mut payload = vec![P::empty(); total];
        let mut tiles = vec![GpuTile { links: [NONE; 3] }; tile_count];
        for (l, lv) in tree.levels.iter().enumerate() {
            let first = levels[l].first as usize;
            payload[first..first + lv.payload.len()].copy_from_slice(&lv.payload);
            let below = if l > 0 { levels[l - 1].first } else { 0 };
            for (i, (&c, &m)) in lv.child.iter().zip(&lv.mask).enumerate() {
                nodes[first + i] = GpuNode { child: global(below, c), mask: m as u32 };
            }
            let ft = levels[l].first_tile as usize;
            for (t, links) in lv.tile_links.iter().enumerate() {
                tiles[ft + t].links = links.map(|x| global(first as u32, x));
            }
        }
        Ok(Self { depth: tree.depth, levels, nodes, payload, tiles })
    }

    /// Global index of the node one step along `axis` (0: +x, 1: +y, 2: +z) from global node
    /// `node` of `level` (module docs for the rule), or `None` if that node does not exist,
    /// `node` is not a node of `level`, or `axis > 2`. What a kernel computes.
    pub fn neighbour(&self, level: u32, node: u32, axis: usize) -> Option<u32> {
        let lv = self.levels.get(level as usize)?;
        let local = node.checked_sub(lv.first).filter(|&i| i < lv.count)?;
        if axis > 2 {
            return None;
        }
        if lv.dense == 1 {
            let next = voxlod_format::morton::step_up(local as u64, axis, lv.res_log2)?;
            return Some(lv.first + next as u32);
        }
        let bit = 1u32 << axis;
        if local & bit == 0 {
            return Some(lv.first + (local | bit));
        }
        let t = self.tiles.get((lv.first_tile + local / 8) as usize)?.links[axis];
        (t != NONE).then(|| t + (local & 7 & !bit))
    }

    /// The lock-free level-by-level build (module docs), emulated on the CPU, from voxels in any
    /// order. Input errors as [`Octree::build`]'s.
    pub fn build_level_by_level(
        grid: voxlod_format::GridSpec,
        voxels: &[(UVec3, P)],
        options: &BuildOptions,
    ) -> Result<Self> {
        // Input checks and the level plan are host work, shared with the reference.
        grid.validate()?;
        let (depth, first_dense) = crate::input::plan(grid.dims, options)?;
        let mut seen: Vec<(u64, usize)> =
            voxels.iter().enumerate().map(|(i, (c, _))| (morton::encode(*c), i)).collect();
        for (c, p) in voxels {
            if !c.cmplt(grid.dims).all() {
                return Err(Error::OutOfBounds { coord: *c, dims: grid.dims });
            }
            if let Some(reason) = p.check() {
                return Err(Error::InvalidPayload { coord: *c, reason });
            }
        }
        seen.par_sort_unstable();
        if let Some(w) = seen.windows(2).find(|w| w[0].0 == w[1].0) {
            return Err(Error::DuplicateVoxel { coord: morton::decode(w[0].0) });
        }
        let coords: Vec<UVec3> = voxels.iter().map(|v| v.0).collect();

        // Per level: child pointers and masks (levels 1..=first_dense), tile links (sparse
        // levels, local indices).
        let mut child: Vec<Vec<u32>> = vec![Vec::new(); depth as usize + 1];
        let mut mask: Vec<Vec<u32>> = vec![Vec::new(); depth as usize + 1];
        let mut links: Vec<Vec<[u32; 3]>> = vec![Vec::new(); depth as usize + 1];
        let mut counts: Vec<usize> = (0..=depth)
            .map(|l| if l >= first_dense { 1usize << (3 * (depth - l)) } else { 0 })
            .collect();
        let fd = first_dense as usize;
        for l in (0..fd).rev() {
            let parents = counts[l + 1];
            let flags: Vec<AtomicU32> = (0..parents).map(|_| AtomicU32::new(0)).collect();
            let masks: Vec<AtomicU32> = (0..parents).map(|_| AtomicU32::new(0)).collect();
            let find = |c: UVec3| descend(&child, fd, l + 1, c);
            // Mark.
            coords.par_iter().for_each(|&v| {
                let o = v >> l as u32;
                let parent = find(o >> 1);
                masks[parent].fetch_or(1 << octant(o), Relaxed);
                for d in 0..8u32 {
                    let e = UVec3::new(d & 1, d >> 1 & 1, d >> 2 & 1);
                    if o.cmpge(e).all() {
                        flags[find((o - e) >> 1)].store(1, Relaxed);
                    }
                }
            });
            // Allocate: exclusive prefix sum over the flags, in parent order.
            let mut next = 0u32;
            child[l + 1] = flags
                .iter()
                .map(|f| {
                    if f.load(Relaxed) == 1 {
                        next += 8;
                        next - 8
                    } else {
                        NONE
                    }
                })
                .collect();
            mask[l + 1] = masks.into_iter().map(AtomicU32::into_inner).collect();
            counts[l] = next as usize;
            // Link.
            let parent_links = &links[l + 1];
            let parent_child = &child[l + 1];
            let mut tile_parent = vec![NONE; counts[l] / 8];
            for (p, &c) in parent_child.iter().enumerate() {
                if c != NONE {
                    tile_parent[c as usize / 8] = p as u32;
                }
            }
            let parent_res = 1u32 << (depth - l as u32 - 1);
            let parent_dense = l + 1 >= fd;
            // One thread per tile: the child tile of the parent's +a neighbour (a node of the
            // parent level: by coordinates on a dense level, from the parent's tile links on a
            // sparse one).
            links[l] = tile_parent
                .par_iter()
                .map(|&p| {
                    std::array::from_fn(|a| {
                        let q = if parent_dense {
                            let mut c = morton::decode(p as u64);
                            c[a] += 1;
                            if c[a] < parent_res { morton::encode(c) as u32 } else { NONE }
                        } else {
                            let bit = 1u32 << a;
                            if p & bit == 0 {
                                p | bit
                            } else {
                                let t = parent_links[p as usize / 8][a];
                                if t == NONE { NONE } else { t + (p & 7 & !bit) }
                            }
                        };
                        match parent_child.get(q as usize) {
                            Some(&ch) if ch != NONE => ch,
                            _ => NONE,
                        }
                    })
                })
                .collect();
        }

        // Payloads, bottom-up: scatter the leaves by descent, then prefilter per parent.
        let mut pay: Vec<Vec<P>> = counts.iter().map(|&n| vec![P::empty(); n]).collect();
        for (c, p) in voxels {
            pay[0][descend(&child, fd, 0, *c)] = *p;
        }
        for l in 1..=depth as usize {
            let (lower, upper) = pay.split_at_mut(l);
            let below = &lower[l - 1];
            let ch = &child[l];
            upper[0].par_iter_mut().enumerate().for_each(|(i, out)| {
                let first = if l > fd {
                    Some(8 * i as u32)
                } else {
                    ch.get(i).copied().filter(|&c| c != NONE)
                };
                if let Some(f) = first {
                    let kids: [P; 8] = std::array::from_fn(|k| below[f as usize + k]);
                    *out = P::prefilter(&kids);
                }
            });
        }

        let (levels, total, tile_count) = level_table(&counts, first_dense)?;
        let mut nodes = vec![GpuNode { child: NONE, mask: 0 }; total];
        let mut payload = vec![P::empty(); total];
        let mut tiles = vec![GpuTile { links: [NONE; 3] }; tile_count];
        for l in 0..=depth as usize {
            let first = levels[l].first as usize;
            let below = if l > 0 { levels[l - 1].first } else { 0 };
            payload[first..first + counts[l]].copy_from_slice(&pay[l]);
            for (i, &c) in child[l].iter().enumerate() {
                nodes[first + i] = GpuNode { child: global(below, c), mask: mask[l][i] };
            }
            let ft = levels[l].first_tile as usize;
            for (t, x) in links[l].iter().enumerate() {
                tiles[ft + t].links = x.map(|x| global(first as u32, x));
            }
        }
        Ok(Self { depth, levels, nodes, payload, tiles })
    }
}

fn octant(c: UVec3) -> u32 {
    (c.x & 1) + 2 * (c.y & 1) + 4 * (c.z & 1)
}

/// Local index of node `c` of `level` (which must exist), descending from the finest dense
/// level `fd` through the `child` arrays built so far.
fn descend(child: &[Vec<u32>], fd: usize, level: usize, c: UVec3) -> usize {
    if level >= fd {
        return morton::encode(c) as usize;
    }
    let mut idx = morton::encode(c >> (fd - level) as u32) as usize;
    for lv in (level + 1..=fd).rev() {
        let o = c >> (lv - 1 - level) as u32;
        idx = child[lv][idx] as usize + octant(o) as usize;
    }
    idx
}

#[cfg(test)]
mod tests {
    use glam::{DVec3, Vec3};
    use voxlod_format::GridSpec;

    use super::*;
    use crate::AveragePayload;

    #[test]
    fn gpu_structs_have_the_documented_layout() {
        assert_eq!(size_of::<GpuNode>(), 8);
        assert_eq!(std::mem::offset_of!(GpuNode, mask), 4);
        assert_eq!(size_of::<GpuTile>(), 12);
        assert_eq!(size_of::<GpuLevel>(), 20);
        assert_eq!(std::mem::offset_of!(GpuLevel, first_tile), 16);
        assert_eq!(size_of::<AveragePayload>(), 28);
    }

    #[test]
    fn level_by_level_build_rejects_bad_input() {
        let grid = GridSpec::new(DVec3::ZERO, 1.0, UVec3::splat(4)).unwrap();
        let ok = AveragePayload::new(Vec3::ONE, Vec3::Z, 0.5);
        let opts = BuildOptions::default();
        let dup = [(UVec3::ONE, ok), (UVec3::ZERO, ok), (UVec3::ONE, ok)];
        let e = FlatOctree::build_level_by_level(grid, &dup, &opts).unwrap_err();
        assert!(matches!(e, Error::DuplicateVoxel { coord } if coord == UVec3::ONE), "{e}");
        let e = FlatOctree::build_level_by_level(grid, &[(UVec3::new(0, 4, 0), ok)], &opts);
        assert!(matches!(e, Err(Error::OutOfBounds { .. })));
        let nan = AveragePayload::new(Vec3::ONE, Vec3::Z, f32::NAN);
        let e = FlatOctree::build_level_by_level(grid, &[(UVec3::new(1, 2, 3), nan)], &opts);
        assert!(
            matches!(e, Err(Error::InvalidPayload { coord, .. }) if coord == UVec3::new(1, 2, 3))
        );
    }

    /// The emulated lock-free build gives the reference topology exactly (same Morton order,
    /// no sort needed) and its payloads within float tolerance.
    #[test]
    fn level_by_level_build_equals_the_reference() {
        for (dims, dense, n) in
            [(UVec3::splat(32), 2, 300u32), (UVec3::new(9, 17, 5), 0, 80), (UVec3::splat(8), 3, 40)]
        {
            let voxels: Vec<(UVec3, AveragePayload)> = (0..n)
                .map(|i| [i * 7 % dims.x, i * i % dims.y, (i * 5 + i / 7) % dims.z])
                .collect::<std::collections::BTreeSet<_>>()
                .into_iter()
                .map(|c| {
                    let c = UVec3::from(c);
                    (c, AveragePayload::new(c.as_vec3() / 32.0, Vec3::Y, 0.5))
                })
                .collect();
            let grid = GridSpec::new(DVec3::ZERO, 1.0, dims).unwrap();
            let opts = BuildOptions { depth: None, dense_log2: dense };
            let reference =
                FlatOctree::from_octree(&Octree::build(grid, voxels.clone(), &opts).unwrap())
                    .unwrap();
            // Reverse input order: the GPU build does not care.
            let mut rev = voxels.clone();
            rev.reverse();
            let emulated = FlatOctree::build_level_by_level(grid, &rev, &opts).unwrap();
            assert_eq!(emulated.levels, reference.levels, "{dims}");
            assert_eq!(emulated.nodes, reference.nodes, "{dims}");
            assert_eq!(emulated.tiles, reference.tiles, "{dims}");
            // The flat neighbour rule answers what the octree's does, for every node.
            let tree = Octree::build(grid, voxels.clone(), &opts).unwrap();
            for (l, lv) in emulated.levels.iter().enumerate() {
                let view = tree.level(l as u32);
                for i in 0..lv.count {
                    for a in 0..3 {
                        let want = view.neighbour(i, a).map(|n| lv.first + n);
                        assert_eq!(emulated.neighbour(l as u32, lv.first + i, a), want);
                    }
                }
                assert_eq!(emulated.neighbour(l as u32, lv.first + lv.count, 0), None);
            }
            for (i, (a, b)) in emulated.payload.iter().zip(&reference.payload).enumerate() {
                assert!(a.max_abs_diff(b) <= 1e-6, "node {i}: {a:?} vs {b:?}");
            }
        }
    }
}
