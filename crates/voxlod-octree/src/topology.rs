//! [`Topology`]: the occupied nodes of every level and their child structure, nothing else — a
//! sparse voxel octree without payloads, without the interpolation closure and without
//! neighbour links (what ESVO-style traversal needs). The full build ([`Octree::from_topology`],
//! and [`Octree::from_morton_sorted`] through it) extends it with payloads, the closure nodes,
//! the 2×2×2 tiles, the dense top levels and the neighbour links.
//!
//! # Layout
//! Level `l` (0 = leaves, `depth` = root) lists its occupied nodes — the input voxels at level 0,
//! every ancestor of one above — as strictly increasing Morton codes at that level's resolution.
//! Above level 0 each node also stores `mask` (bit `k`: child in octant `x + 2y + 4z` is
//! occupied) and `first` (index of its first occupied child in the level below). Children are
//! stored compactly (only occupied ones, in octant order, siblings contiguous), so child `k` of
//! node `i` is at `first[i] + popcount(mask[i] & ((1 << k) − 1))`, as in ESVO's child
//! descriptors. 13 bytes per node (8 code, 4 first, 1 mask), 8 at level 0.
//!
//! # Cost
//! One sequential pass per level over the codes of the level below (count the distinct
//! parents, then write codes, masks and first-child indices into exact-size arrays): linear, no
//! sort (the input is sorted), no per-node allocation. The input check (inside the grid,
//! strictly increasing) is one parallel pass.

use glam::UVec3;
use rayon::prelude::*;
use voxlod_format::{GridSpec, morton};

#[cfg(doc)]
use crate::Octree;
use crate::input::{all_codes_ok, code_problem, plan};
use crate::octree::{BuildOptions, NONE};
use crate::{Error, Result};

/// One level of a [`Topology`].
#[derive(Clone, Debug, PartialEq, Eq)]
pub(crate) struct TopologyLevel {
    /// Occupied nodes' Morton codes, strictly increasing.
    pub codes: Vec<u64>,
    /// Per node (above level 0): bit `k` set if child `k` is occupied.
    pub mask: Vec<u8>,
    /// Per node (above level 0): index of its first occupied child in the level below.
    pub first: Vec<u32>,
}

/// The occupied levels of an octree and their child structure (module docs).
#[derive(Clone, Debug, PartialEq)]
pub struct Topology {
    pub(crate) grid: GridSpec,
    pub(crate) depth: u32,
    pub(crate) first_dense: u32,
    /// Indexed by level, 0 = leaves.
    pub(crate) levels: Vec<TopologyLevel>,
}

impl Topology {
    /// The topology of voxels in any order (sorted here). A voxel outside `grid.dims` or given
    /// twice is an error naming it. `options.depth` sets the depth as for [`Octree::build`];
    /// `options.dense_log2` is checked and kept for the octree [`Octree::from_topology`] builds.
    ///
    /// ```
    /// use glam::{DVec3, UVec3};
    /// use voxlod_format::GridSpec;
    /// use voxlod_octree::{BuildOptions, Topology};
    /// let grid = GridSpec::new(DVec3::ZERO, 1.0, UVec3::splat(8))?;
    /// let voxels = [UVec3::new(7, 7, 7), UVec3::new(6, 7, 7), UVec3::ZERO];
    /// let t = Topology::build(grid, voxels, &BuildOptions::default())?;
    /// assert_eq!((t.depth(), t.voxel_count()), (3, 3));
    /// assert_eq!(t.codes(1).len(), 2); // (0,0,0) and (3,3,3)
    /// assert_eq!(t.masks(1)[1], 0b1100_0000); // octants 6 and 7 of node (3,3,3)
    /// assert_eq!(t.find(0, UVec3::new(6, 7, 7)), Some(1));
    /// assert_eq!(t.find(0, UVec3::new(6, 6, 7)), None);
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    pub fn build(
        grid: GridSpec,
        voxels: impl IntoIterator<Item = UVec3>,
        options: &BuildOptions,
    ) -> Result<Self> {
        let dims = grid.dims;
        let mut codes = Vec::new();
        for c in voxels {
            if !c.cmplt(dims).all() {
                return Err(Error::OutOfBounds { coord: c, dims });
            }
            codes.push(morton::encode(c));
        }
        codes.par_sort_unstable();
        Self::from_morton_sorted(grid, codes, options)
    }

    /// The topology of voxels given as strictly increasing Morton codes. Out-of-order or
    /// repeated codes and voxels outside the grid are errors naming the first one.
    pub fn from_morton_sorted(
        grid: GridSpec,
        codes: Vec<u64>,
        options: &BuildOptions,
    ) -> Result<Self> {
        grid.validate()?;
        let (depth, first_dense) = plan(grid.dims, options)?;
        let dims = grid.dims;
        if !all_codes_ok(dims, codes.len(), |i| codes[i], |_| true) {
            let problem =
                |i: usize| code_problem(dims, codes[i], i.checked_sub(1).map(|j| codes[j]));
            if let Some(e) = (0..codes.len()).find_map(problem) {
                return Err(e);
            }
        }
        Self::from_checked(grid, depth, first_dense, codes)
    }

    /// [`Topology::from_morton_sorted`] for codes already checked and a depth already planned.
    pub(crate) fn from_checked(
        grid: GridSpec,
        depth: u32,
        first_dense: u32,
        codes: Vec<u64>,
    ) -> Result<Self> {
        if codes.len() as u64 >= NONE as u64 {
            return Err(Error::TooManyNodes { level: 0, nodes: codes.len() as u64 });
        }
        let mut levels = Vec::with_capacity(depth as usize + 1);
        levels.push(TopologyLevel { codes, mask: Vec::new(), first: Vec::new() });
        for _ in 0..depth {
            let next = coarsen(&levels[levels.len() - 1].codes);
            levels.push(next);
        }
        Ok(Self { grid, depth, first_dense, levels })
    }

    /// The grid the voxels lie in.
    pub fn grid(&self) -> &GridSpec {
        &self.grid
    }
    /// Levels below the root.
    pub fn depth(&self) -> u32 {
        self.depth
    }
    /// The finest dense level of the octree built from this topology (from
    /// `BuildOptions::dense_log2`).
    pub fn first_dense(&self) -> u32 {
        self.first_dense
    }
    /// Number of input (occupied) voxels.
    pub fn voxel_count(&self) -> u64 {
        self.levels[0].codes.len() as u64
    }
    /// Morton codes of the occupied nodes of `level`, strictly increasing (empty above the
    /// depth).
    pub fn codes(&self, level: u32) -> &[u64] {
        self.levels.get(level as usize).map_or(&[], |l| &l.codes)
    }
    /// Occupied-children masks of `level`'s nodes, alongside [`Topology::codes`] (empty at level
    /// 0 and above the depth).
    pub fn masks(&self, level: u32) -> &[u8] {
        self.levels.get(level as usize).map_or(&[], |l| &l.mask)
    }
    /// Index in level `level − 1` of each node's first occupied child, alongside
    /// [`Topology::codes`] (empty at level 0 and above the depth).
    pub fn first_child(&self, level: u32) -> &[u32] {
        self.levels.get(level as usize).map_or(&[], |l| &l.first)
    }
    /// Index in level `level − 1` of child `octant` (`x + 2y + 4z`) of node `node` of `level`,
    /// or `None` if that child is not occupied or the arguments name no node.
    pub fn child(&self, level: u32, node: u32, octant: u32) -> Option<u32> {
        let l = self.levels.get(level as usize)?;
        let (&m, &f) = (l.mask.get(node as usize)?, l.first.get(node as usize)?);
        if octant > 7 || m >> octant & 1 == 0 {
            return None;
        }
        Some(f + (m as u32 & ((1 << octant) - 1)).count_ones())
    }
    /// Index of occupied node `c` of `level`, descending from the root by masks and first-child
    /// indices; `None` if it is not occupied or lies outside the cube.
    pub fn find(&self, level: u32, c: UVec3) -> Option<u32> {
        if level > self.depth || self.voxel_count() == 0 {
            return None;
        }
        let shift = self.depth - level;
        if shift < 32 && c.max_element() >> shift != 0 {
            return None;
        }
        let mut idx = 0u32;
        for l in (level + 1..=self.depth).rev() {
            let o = (c >> (l - 1 - level)) & UVec3::ONE;
            idx = self.child(l, idx, o.x + 2 * o.y + 4 * o.z)?;
        }
        Some(idx)
    }
    /// Bytes of the arrays (codes, masks, first-child indices): the heap this topology holds,
    /// up to allocator overhead.
    pub fn memory_bytes(&self) -> u64 {
        self.levels
            .iter()
            .map(|l| (l.codes.len() * 8 + l.mask.len() + l.first.len() * 4) as u64)
            .sum()
    }
}

/// Codes per rayon task of [`coarsen`]; smaller levels are coarsened on one thread.
const COARSEN_CHUNK: usize = 1 << 15;

/// The occupied level above sorted `codes`: distinct parents, their children's masks and first
/// indices. Two passes over chunks that do not split a sibling group, in parallel: count each
/// chunk's parents, then write them at their offsets into arrays allocated once at their final
/// size (zeroed by the allocator, so nothing is written twice).
fn coarsen(codes: &[u64]) -> TopologyLevel {
    let n = codes.len();
    // Chunk starts, moved forward to the next sibling group (at most 7 steps).
    let mut bounds: Vec<usize> = (0..n.div_ceil(COARSEN_CHUNK))
        .map(|k| {
            let mut s = k * COARSEN_CHUNK;
            while s > 0 && s < n && codes[s] >> 3 == codes[s - 1] >> 3 {
                s += 1;
            }
            s
        })
        .collect();
    bounds.push(n);
    bounds.dedup();
    let count = |r: &[usize]| {
        let c = &codes[r[0]..r[1]];
        c.len().min(1) + c.windows(2).filter(|w| w[0] >> 3 != w[1] >> 3).count()
    };
    // One chunk: no rayon call (each one from outside the pool wakes a worker).
    let counts: Vec<usize> = if bounds.len() <= 2 {
        bounds.windows(2).map(count).collect()
    } else {
        bounds.par_windows(2).map(count).collect()
    };
    let total: usize = counts.iter().sum();
    let mut out =
        TopologyLevel { codes: vec![0; total], mask: vec![0; total], first: vec![0; total] };
    // Disjoint output slices per chunk.
    let mut jobs = Vec::with_capacity(counts.len());
    let (mut oc, mut om, mut of) = (&mut out.codes[..], &mut out.mask[..], &mut out.first[..]);
    for (r, &k) in bounds.windows(2).zip(&counts) {
        let (c, rest_c) = std::mem::take(&mut oc).split_at_mut(k);
        let (m, rest_m) = std::mem::take(&mut om).split_at_mut(k);
        let (f, rest_f) = std::mem::take(&mut of).split_at_mut(k);
        (oc, om, of) = (rest_c, rest_m, rest_f);
        jobs.push((r[0], r[1], c, m, f));
    }
    // Branch-free (sibling groups of 1–8 codes make a per-group branch unpredictable): every
    // code rewrites its group's slot, the last write leaves the group's full mask.
    let fill = |(lo, hi, c, m, f): (usize, usize, &mut [u64], &mut [u8], &mut [u32])| {
        let (mut j, mut last, mut start, mut acc) = (0usize, codes[lo] >> 3, lo as u32, 0u8);
        for (i, &code) in codes[lo..hi].iter().enumerate() {
            let p = code >> 3;
            let new = p != last;
            j += new as usize;
            start = if new { (lo + i) as u32 } else { start };
            acc = if new { 0 } else { acc } | 1 << (code & 7);
            last = p;
            c[j] = p;
            m[j] = acc;
            f[j] = start;
        }
    };
    if jobs.len() <= 1 {
        jobs.into_iter().for_each(fill);
    } else {
        jobs.into_par_iter().for_each(fill);
    }
    out
}

#[cfg(test)]
mod tests {
    use glam::{DVec3, UVec3};
    use voxlod_format::{GridSpec, morton};

    use super::Topology;
    use crate::octree::NONE;
    use crate::tests::payload_of;
    use crate::{BuildOptions, Error, Octree};

    fn grid(dims: UVec3) -> GridSpec {
        GridSpec::new(DVec3::ZERO, 1.0, dims).expect("valid grid")
    }

    /// The topology's nodes and masks are exactly the occupied nodes of the full build (those
    /// whose parent's mask bit is set, on the sparse levels; the non-empty ones on the dense
    /// levels), and `find` reaches every input voxel.
    #[test]
    fn topology_equals_the_occupied_nodes_of_the_full_build() {
        for (dims, dense, n) in [
            (UVec3::splat(32), 2, 400u32),
            (UVec3::new(9, 17, 5), 0, 90),
            (UVec3::splat(16), 4, 200),
            (UVec3::splat(64), 1, 50),
        ] {
            let coords: Vec<UVec3> = (0..n)
                .map(|i| [i * 7 % dims.x, (i * i + 1) % dims.y, (i * 5 + i / 7) % dims.z])
                .collect::<std::collections::BTreeSet<_>>()
                .into_iter()
                .map(UVec3::from)
                .collect();
            let opts = BuildOptions { depth: None, dense_log2: dense };
            let topo = Topology::build(grid(dims), coords.iter().copied(), &opts).unwrap();
            let tree = Octree::build(grid(dims), coords.iter().map(|&c| (c, payload_of(c))), &opts)
                .unwrap();
            assert_eq!((topo.depth(), topo.first_dense()), (tree.depth(), tree.first_dense()));
            assert_eq!(topo.voxel_count(), tree.voxel_count());
            for l in 0..=tree.depth() {
                let lv = tree.level(l);
                let codes = tree.node_codes(l);
                // Occupancy of each stored node of a sparse level from the level above's masks.
                let occupied: Vec<u64> = if l < tree.first_dense() {
                    let up = tree.level(l + 1);
                    let mut occ = vec![false; codes.len()];
                    for (p, &c) in up.child.iter().enumerate() {
                        if c != NONE {
                            for k in 0..8 {
                                occ[c as usize + k] = up.mask[p] >> k & 1 == 1;
                            }
                        }
                    }
                    codes.iter().zip(&occ).filter(|e| *e.1).map(|e| *e.0).collect()
                } else {
                    // Dense: payload opacity > 0 (every input opacity is positive).
                    codes
                        .iter()
                        .zip(lv.payload)
                        .filter(|(_, p)| p.opacity > 0.0)
                        .map(|(c, _)| *c)
                        .collect()
                };
                assert_eq!(topo.codes(l), &occupied[..], "level {l} of {dims}");
                if l >= 1 && !lv.mask.is_empty() {
                    let want: Vec<u8> = occupied
                        .iter()
                        .map(|&c| lv.mask[codes.binary_search(&c).unwrap()])
                        .collect();
                    assert_eq!(topo.masks(l), &want[..], "masks, level {l} of {dims}");
                }
                // Children through first + mask are the occupied codes of the level below.
                for (i, &c) in topo.codes(l).iter().enumerate().filter(|_| l > 0) {
                    for k in 0..8u32 {
                        let want = topo.codes(l - 1).binary_search(&(c << 3 | k as u64)).ok();
                        let got = topo.child(l, i as u32, k);
                        assert_eq!(got, want.map(|x| x as u32), "child {k} of {c}, level {l}");
                    }
                }
            }
            for &c in &coords {
                let want = topo.codes(0).binary_search(&morton::encode(c)).unwrap() as u32;
                assert_eq!(topo.find(0, c), Some(want), "{c}");
                if topo.depth() > 0 {
                    let up = topo.codes(1).binary_search(&morton::encode(c >> 1)).unwrap();
                    assert_eq!(topo.find(1, c >> 1), Some(up as u32), "{c}");
                }
            }
            let empty = (0..dims.x).map(|x| UVec3::new(x, 0, 0)).find(|c| !coords.contains(c));
            if let Some(c) = empty {
                assert_eq!(topo.find(0, c), None);
            }
            assert_eq!(topo.find(0, UVec3::splat(1 << 20)), None);
            let bytes: u64 = (0..=topo.depth())
                .map(|l| {
                    (topo.codes(l).len() * 8 + topo.masks(l).len() + 4 * topo.first_child(l).len())
                        as u64
                })
                .sum();
            assert_eq!(topo.memory_bytes(), bytes);
        }
    }

    /// `from_topology` builds what `from_morton_sorted` builds, and refuses a payload list that
    /// does not fit or holds a rejected payload.
    #[test]
    fn the_full_build_extends_the_topology() {
        use crate::AveragePayload;
        use glam::Vec3;
        let dims = UVec3::new(20, 12, 9);
        let coords: Vec<UVec3> = (0..150u32)
            .map(|i| [i * 7 % dims.x, (i * i + 1) % dims.y, (i * 5 + i / 7) % dims.z])
            .collect::<std::collections::BTreeSet<_>>()
            .into_iter()
            .map(UVec3::from)
            .collect();
        let mut voxels: Vec<(u64, AveragePayload)> =
            coords.iter().map(|&c| (morton::encode(c), payload_of(c))).collect();
        voxels.sort_unstable_by_key(|v| v.0);
        let opts = BuildOptions { depth: Some(6), dense_log2: 2 };
        let direct = Octree::from_morton_sorted(grid(dims), voxels.clone(), &opts).unwrap();
        let codes: Vec<u64> = voxels.iter().map(|v| v.0).collect();
        let payload: Vec<AveragePayload> = voxels.iter().map(|v| v.1).collect();
        let topo = Topology::from_morton_sorted(grid(dims), codes, &opts).unwrap();
        let extended = Octree::from_topology(topo.clone(), payload.clone()).unwrap();
        assert_eq!((extended.depth(), extended.first_dense()), (6, 4));
        for l in 0..=6 {
            let (a, b) = (direct.level(l), extended.level(l));
            assert!(a.payload == b.payload, "level {l}");
            assert_eq!((a.child, a.mask, a.tile_links), (b.child, b.mask, b.tile_links));
        }
        let e = Octree::from_topology(topo.clone(), payload[1..].to_vec()).unwrap_err();
        assert!(
            matches!(e, Error::PayloadCount { voxels, payloads } if voxels == payload.len() as u64 && payloads + 1 == voxels),
            "{e}"
        );
        let mut bad = payload;
        bad[3] = AveragePayload::new(Vec3::ONE, Vec3::Z, 1.5);
        let e = Octree::from_topology(topo.clone(), bad).unwrap_err();
        let want = morton::decode(topo.codes(0)[3]);
        assert!(matches!(e, Error::InvalidPayload { coord, .. } if coord == want), "{e}");
    }

    #[test]
    fn bad_input_is_an_error_naming_the_voxel() {
        let g = grid(UVec3::new(4, 4, 2));
        let opts = BuildOptions::default();
        let e = Topology::build(g, [UVec3::ONE, UVec3::new(0, 0, 2)], &opts).unwrap_err();
        assert!(matches!(e, Error::OutOfBounds { coord, .. } if coord == UVec3::new(0, 0, 2)));
        let e = Topology::build(g, [UVec3::ONE, UVec3::ZERO, UVec3::ONE], &opts).unwrap_err();
        assert!(matches!(e, Error::DuplicateVoxel { coord } if coord == UVec3::ONE), "{e}");
        let codes = vec![morton::encode(UVec3::ONE), morton::encode(UVec3::ZERO)];
        let e = Topology::from_morton_sorted(g, codes, &opts).unwrap_err();
        assert!(matches!(e, Error::OutOfOrder { coord, .. } if coord == UVec3::ZERO), "{e}");
        // (3, 3, 3) is inside the 4³ cube but outside the grid's z = 2.
        let codes = vec![morton::encode(UVec3::new(3, 3, 3))];
        let e = Topology::from_morton_sorted(g, codes, &opts).unwrap_err();
        assert!(matches!(e, Error::OutOfBounds { .. }), "{e}");
        let deep = BuildOptions { depth: Some(1), dense_log2: 0 };
        assert!(matches!(Topology::build(g, [], &deep), Err(Error::GridDoesNotFit { .. })));
        let empty = Topology::build(g, [], &opts).unwrap();
        assert_eq!((empty.voxel_count(), empty.find(0, UVec3::ZERO)), (0, None));
        assert_eq!(empty.codes(empty.depth()), &[] as &[u64]);
    }
}
