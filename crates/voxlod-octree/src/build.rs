//! The CPU reference build, bottom-up from Morton-sorted voxels, then top-down level by level.
//! Every step is linear in the nodes it touches: no sort, no hash map, no search (rayon over the
//! nodes of each step):
//! 1. **Input check**: coordinates inside the grid, strictly increasing Morton codes (no
//!    duplicate), every payload accepted by [`Payload::check`].
//! 2. **Occupied levels, bottom-up**: the [`Topology`] (the occupied nodes of level `l+1` are the
//!    distinct codes `c >> 3` of level `l`, each with its children's mask and the index of its
//!    first occupied child; sorted input stays sorted at every level), then per level each
//!    occupied node's payload, [`Payload::prefilter`] of its (up to) eight occupied children,
//!    the others counting as empty.
//! 3. **Sparse levels, top-down**, each from the finished level above it (`octree` module docs
//!    for the node set):
//!    - *tiles*: a node `q` of level `l+1` gets a 2×2×2 tile of children iff it is the parent of
//!      a backward neighbour of an occupied child of some occupied `q + d`, `d ∈ {0,1}³`; that
//!      is the case iff `d` is a subset of the axes along which one of `q + d`'s occupied children
//!      lies in the lower half (`SHIFTS`). On the dense level the occupied nodes mark their
//!      `q − d` directly (Morton decrement); on a sparse level each tile of the level reads the
//!      masks of the 3×3×3 block of nodes at its first node (its own tile and 7 neighbour tiles,
//!      found by x-, y-, then z-links, as the sampler hops) and marks its nodes from them. Marked
//!      nodes, in storage order, are the tiles in Morton order (one branch-free pass gives the
//!      tile list and the child pointers): tile `t` starts at node `8t`;
//!    - *payloads*: tile `t`'s occupied children are a run of the occupied list, found through the
//!      parent's first-child index and mask (no search);
//!    - *links*: per tile, the +a neighbour tile is the child tile of the parent's +a neighbour
//!      (through the parent level's links, or a Morton increment on the dense level), computed
//!      per parent tile from four runs of child pointers; the nodes' neighbours follow from the
//!      tile links (`octree` module docs). It finds every existing neighbour because a tile
//!      exists exactly when its parent is a node of the closure.
//!
//! The first build (sorted closure parents, per-node link search of the parents) is kept in
//! `reference` (test builds), and a test asserts both build identical octrees.
//!
//! Debug builds then run [`Octree::validate`] and return its error.

use glam::UVec3;
use rayon::prelude::*;
use voxlod_format::{BrickMap, GridSpec, morton};

use crate::input::{all_codes_ok, code_problem, plan};
use crate::octree::{BuildOptions, Level, NONE, Octree};
use crate::payload::Payload;
use crate::topology::{Topology, TopologyLevel};
use crate::{Error, Result};

#[cfg(test)]
pub(crate) mod reference;

/// Items per rayon task below which splitting does not pay.
pub(crate) const MIN_LEN: usize = 2048;

/// Occupied nodes of one level: a [`TopologyLevel`]'s arrays and the nodes' payloads.
struct Occupied<'a, P> {
    /// Sorted Morton codes.
    codes: &'a [u64],
    /// Per node (above level 0): bit `k` set if child `k` is occupied.
    mask: &'a [u8],
    /// Per node (above level 0): index of its first occupied child in the level below.
    first: &'a [u32],
    payload: &'a [P],
}

impl<P: Payload> Octree<P> {
    /// Builds an octree over `grid` from `(voxel, payload)` pairs in any order (sorted here).
    /// A voxel outside `grid.dims`, given twice, or with a payload [`Payload::check`] rejects is
    /// an error naming it.
    ///
    /// ```
    /// use glam::{DVec3, UVec3, Vec3};
    /// use voxlod_format::GridSpec;
    /// use voxlod_octree::{AveragePayload, BuildOptions, Octree};
    /// let grid = GridSpec::new(DVec3::ZERO, 1.0, UVec3::splat(8)).unwrap();
    /// let red = AveragePayload::new(Vec3::X, Vec3::Y, 1.0);
    /// let tree = Octree::build(grid, [(UVec3::new(7, 7, 7), red)], &BuildOptions::default())
    ///     .unwrap();
    /// assert_eq!(tree.depth(), 3);
    /// let bad = AveragePayload::new(Vec3::X, Vec3::Y, f32::NAN);
    /// let err = Octree::build(grid, [(UVec3::new(1, 2, 3), bad)], &BuildOptions::default());
    /// assert!(err.unwrap_err().to_string().contains("[1, 2, 3]"));
    /// ```
    pub fn build(
        grid: GridSpec,
        voxels: impl IntoIterator<Item = (UVec3, P)>,
        options: &BuildOptions,
    ) -> Result<Self> {
        let dims = grid.dims;
        let mut keyed = Vec::new();
        for (c, p) in voxels {
            if !c.cmplt(dims).all() {
                return Err(Error::OutOfBounds { coord: c, dims });
            }
            keyed.push((morton::encode(c), p));
        }
        keyed.par_sort_unstable_by_key(|k| k.0);
        Self::from_morton_sorted(grid, keyed, options)
    }

    /// Builds an octree from the records of a brick map (iterated in Morton order, so nothing
    /// is sorted), converting each record with `to_payload` (e.g.
    /// [`crate::AveragePayload::from_record`]). The map must fit in `grid`.
    pub fn from_brick_map<R>(
        grid: GridSpec,
        map: &BrickMap<R>,
        to_payload: impl Fn(&R) -> P,
        options: &BuildOptions,
    ) -> Result<Self> {
        let voxels = map.iter().map(|(c, r)| (morton::encode(c), to_payload(r))).collect();
        Self::from_morton_sorted(grid, voxels, options)
    }

    /// Builds an octree from `(Morton code, payload)` pairs in strictly increasing code order.
    /// Out-of-order or repeated codes, voxels outside the grid and rejected payloads are errors.
    /// The same as [`Topology::from_morton_sorted`] followed by [`Octree::from_topology`].
    pub fn from_morton_sorted(
        grid: GridSpec,
        voxels: Vec<(u64, P)>,
        options: &BuildOptions,
    ) -> Result<Self> {
        grid.validate()?;
        let (depth, first_dense) = plan(grid.dims, options)?;
        check_input(grid.dims, &voxels)?;
        let (codes, payload): (Vec<u64>, Vec<P>) = voxels.into_iter().unzip();
        let topology = Topology::from_checked(grid, depth, first_dense, codes)?;
        Self::extend(topology, payload)
    }

    /// Extends a [`Topology`] into an octree: `payload[i]` is the payload of voxel `i` of the
    /// topology (its level-0 node, in Morton order). Pre-filters the payloads up the occupied
    /// levels, adds the closure nodes and tiles, the dense top levels (down to the topology's
    /// [`Topology::first_dense`]) and the neighbour links. A payload count other than the
    /// topology's voxel count, or a payload [`Payload::check`] rejects, is an error (naming the
    /// voxel).
    pub fn from_topology(topology: Topology, payload: Vec<P>) -> Result<Self> {
        let voxels = topology.voxel_count();
        if payload.len() as u64 != voxels {
            return Err(Error::PayloadCount { voxels, payloads: payload.len() as u64 });
        }
        let bad = payload.par_iter().with_min_len(MIN_LEN).position_first(|p| p.check().is_some());
        if let Some(i) = bad {
            let coord = morton::decode(topology.levels[0].codes[i]);
            let reason = payload[i].check().unwrap_or("rejected");
            return Err(Error::InvalidPayload { coord, reason });
        }
        Self::extend(topology, payload)
    }

    /// The build after the input checks (module docs, steps 2–3).
    fn extend(topology: Topology, payload: Vec<P>) -> Result<Self> {
        let Topology { grid, depth, first_dense, levels: topo } = topology;
        let voxel_count = topo[0].codes.len() as u64;
        let mut payloads = Vec::with_capacity(topo.len());
        payloads.push(payload);
        for l in 1..topo.len() {
            let next = prefilter_level(&topo[l], &payloads[l - 1]);
            payloads.push(next);
        }
        let occupied: Vec<Occupied<'_, P>> = topo
            .iter()
            .zip(&payloads)
            .map(|(t, p)| Occupied { codes: &t.codes, mask: &t.mask, first: &t.first, payload: p })
            .collect();
        let fd = first_dense as usize;
        let mut levels: Vec<Level<P>> = (0..=depth as usize)
            .into_par_iter()
            .map(|l| {
                let res_log2 = depth - l as u32;
                if l >= fd {
                    dense_level(res_log2, &occupied[l])
                } else {
                    Level {
                        res_log2,
                        dense: false,
                        payload: Vec::new(),
                        child: Vec::new(),
                        mask: Vec::new(),
                        tile_links: Vec::new(),
                    }
                }
            })
            .collect();
        // Occupied index per node of the level above the one being built (NONE: unoccupied).
        let mut occ_above =
            if fd >= 1 { dense_occupancy(&levels[fd], &occupied[fd]) } else { vec![] };
        for l in (0..fd).rev() {
            let (lower, upper) = levels.split_at_mut(l + 1);
            let (level, parent) = (&mut lower[l], &mut upper[0]);
            let (occ, occ_parent) = (&occupied[l], &occupied[l + 1]);
            // Masks first: on a sparse parent level the tiles are read from them.
            parent.mask = occ_above
                .par_iter()
                .with_min_len(MIN_LEN)
                .map(|&g| if g == NONE { 0 } else { occ_parent.mask[g as usize] })
                .collect();
            let marked = if parent.dense {
                dense_tile_marks(parent, occ_parent)
            } else {
                sparse_tile_marks(parent)
            };
            let (tiles, child) = allocate_tiles(&marked);
            drop(marked);
            let nodes = 8 * tiles.len() as u64;
            if nodes >= NONE as u64 {
                return Err(Error::TooManyNodes { level: l as u32, nodes });
            }
            parent.child = child;
            let (payload, occ_here) = fill_tiles(&tiles, &occ_above, occ_parent, occ, l > 0);
            level.payload = payload;
            level.tile_links = links(&tiles, parent);
            occ_above = occ_here;
        }
        let tree = Octree { grid, depth, first_dense, voxels: voxel_count, levels };
        if cfg!(debug_assertions) {
            tree.validate()?;
        }
        Ok(tree)
    }
}

/// Checks the input, so the error names the first bad voxel.
fn check_input<P: Payload>(dims: UVec3, voxels: &[(u64, P)]) -> Result<()> {
    let ok = all_codes_ok(dims, voxels.len(), |i| voxels[i].0, |i| voxels[i].1.check().is_none());
    if ok {
        return Ok(());
    }
    let problem = |i: usize| -> Option<Error> {
        let (code, ref p) = voxels[i];
        if let Some(e) = code_problem(dims, code, i.checked_sub(1).map(|j| voxels[j].0)) {
            return Some(e);
        }
        let coord = morton::decode(code);
        p.check().map(|reason| Error::InvalidPayload { coord, reason })
    };
    match (0..voxels.len()).find_map(problem) {
        Some(e) => Err(e),
        None => Ok(()),
    }
}

/// Payloads of an occupied level from the level below's: each node's is [`Payload::prefilter`]
/// of its occupied children (found by first index and mask), the others counting as empty.
fn prefilter_level<P: Payload>(level: &TopologyLevel, below: &[P]) -> Vec<P> {
    (0..level.first.len())
        .into_par_iter()
        .with_min_len(MIN_LEN)
        .map(|g| {
            let mut children = [P::empty(); 8];
            let (mut m, mut j) = (level.mask[g], level.first[g] as usize);
            while m != 0 {
                children[m.trailing_zeros() as usize] = below[j];
                j += 1;
                m &= m - 1;
            }
            P::prefilter(&children)
        })
        .collect()
}

/// `SUBSETS[m]`: bit `d` set for every `d ⊆ m` (3-bit sets).
const SUBSETS: [u8; 8] = {
    let mut t = [0u8; 8];
    let mut m = 0;
    while m < 8 {
        let mut d = 0;
        while d < 8 {
            if d & !m == 0 {
                t[m] |= 1 << d;
            }
            d += 1;
        }
        m += 1;
    }
    t
};

/// `SHIFTS[mask]`: for an occupied node `q` whose occupied children are `mask`, bit `d` set if
/// `q − d` is the parent of a backward neighbour of one of them. Child `o = 2q + b` has backward
/// neighbours `o − e` whose parents are `q − d` with `d_a = e_a` where `b_a = 0` and `d_a = 0`
/// where `b_a = 1`: `d` ranges over the subsets of the axes along which `b` is 0.
const SHIFTS: [u8; 256] = {
    let mut t = [0u8; 256];
    let mut m = 0;
    while m < 256 {
        let mut b = 0;
        while b < 8 {
            if m >> b & 1 == 1 {
                t[m] |= SUBSETS[!b & 7];
            }
            b += 1;
        }
        m += 1;
    }
    t
};

/// A dense level: every payload, indexed by Morton code (child pointers and masks of the
/// finest dense level are set when the level below is built).
fn dense_level<P: Payload>(res_log2: u32, occupied: &Occupied<'_, P>) -> Level<P> {
    let n = 1usize << (3 * res_log2);
    let mut payload = vec![P::empty(); n];
    for (&c, p) in occupied.codes.iter().zip(occupied.payload) {
        payload[c as usize] = *p;
    }
    Level {
        res_log2,
        dense: true,
        payload,
        child: Vec::new(),
        mask: Vec::new(),
        tile_links: Vec::new(),
    }
}

/// Occupied index per node of a dense level.
fn dense_occupancy<P>(level: &Level<P>, occupied: &Occupied<'_, P>) -> Vec<u32> {
    let mut occ = vec![NONE; level.payload.len()];
    for (g, &c) in occupied.codes.iter().enumerate() {
        occ[c as usize] = g as u32;
    }
    occ
}

/// Per node of a dense level: whether it gets a child tile. Each occupied node `q` marks
/// `q − d` for `d ∈ SHIFTS[mask]`.
fn dense_tile_marks<P>(level: &Level<P>, occupied: &Occupied<'_, P>) -> Vec<bool> {
    let mut marked = vec![false; level.payload.len()];
    for (&q, &m) in occupied.codes.iter().zip(occupied.mask) {
        let s = SHIFTS[m as usize];
        for d in 0..8usize {
            if s >> d & 1 == 0 {
                continue;
            }
            let c =
                (0..3).try_fold(
                    q,
                    |c, a| if d >> a & 1 == 1 { morton::step_down(c, a) } else { Some(c) },
                );
            if let Some(c) = c {
                marked[c as usize] = true;
            }
        }
    }
    marked
}

/// `BLOCK[x + 3y + 9z]` for a position in the 3×3×3 block of nodes starting at a tile's first
/// node: which of the eight tiles (own, +x, +y, +xy, +z, +xz, +yz, +xyz: bit `a` for a step
/// along axis `a`) holds it, and its index in that tile.
const BLOCK: [(u8, u8); 27] = {
    let mut t = [(0u8, 0u8); 27];
    let mut p = 0;
    while p < 27 {
        let (x, y, z) = (p % 3, p / 3 % 3, p / 9);
        t[p] = (
            ((x >> 1) | (y >> 1) << 1 | (z >> 1) << 2) as u8,
            ((x & 1) | (y & 1) << 1 | (z & 1) << 2) as u8,
        );
        p += 1;
    }
    t
};

/// `CORNER[k][d]`: the block position (`BLOCK`) of node `k + d` of a tile, `k, d ∈ {0,1}³`.
const CORNER: [[u8; 8]; 8] = {
    let mut t = [[0u8; 8]; 8];
    let mut k = 0;
    while k < 8 {
        let mut d = 0;
        while d < 8 {
            let x = (k & 1) + (d & 1);
            let y = (k >> 1 & 1) + (d >> 1 & 1);
            let z = (k >> 2 & 1) + (d >> 2 & 1);
            t[k][d] = (x + 3 * y + 9 * z) as u8;
            d += 1;
        }
        k += 1;
    }
    t
};

/// Per node of a sparse level whose masks and tile links are set: whether it gets a child tile,
/// i.e. whether a corner `n + d` is occupied with `d ∈ SHIFTS[its mask]`. Per tile: the eight
/// tiles of the 3×3×3 block of nodes at its first node are found by x-, then y-, then z-links
/// (the tiles on a monotone path to an occupied corner exist: closure), their masks mapped
/// through `SHIFTS`, and the 64 (node, corner) pairs read from that block.
fn sparse_tile_marks<P>(level: &Level<P>) -> Vec<bool> {
    let (mask, links) = (&level.mask, &level.tile_links);
    let step =
        |first: u32, a: usize| if first == NONE { NONE } else { links[first as usize / 8][a] };
    let marks: Vec<[bool; 8]> = (0..links.len())
        .into_par_iter()
        .with_min_len(MIN_LEN / 8)
        .map(|t| {
            let [x, y, z] = links[t];
            let (xy, xz, yz) = (step(x, 1), step(x, 2), step(y, 2));
            let tiles = [8 * t as u32, x, y, xy, z, xz, yz, step(xy, 2)];
            let block: [u8; 27] = std::array::from_fn(|p| {
                let (tile, j) = BLOCK[p];
                let first = tiles[tile as usize];
                if first == NONE { 0 } else { SHIFTS[mask[(first + j as u32) as usize] as usize] }
            });
            std::array::from_fn(|k| {
                (0..8).fold(0u8, |any, d| any | block[CORNER[k][d] as usize] >> d) & 1 == 1
            })
        })
        .collect();
    marks.into_flattened()
}

/// The tile parents (node indices, ascending: tile `t` under `tiles[t]`) and child pointers
/// (`8t` or [`NONE`]) of a level whose nodes `marked` get tiles. One branch-free pass.
fn allocate_tiles(marked: &[bool]) -> (Vec<u32>, Vec<u32>) {
    let count = marked.iter().filter(|&&m| m).count();
    // One spare slot takes the unmarked nodes' writes.
    let mut tiles = vec![0u32; count + 1];
    let mut child = Vec::with_capacity(marked.len());
    let mut rank = 0usize;
    for (i, &m) in marked.iter().enumerate() {
        child.push(if m { 8 * rank as u32 } else { NONE });
        tiles[rank] = i as u32;
        rank += m as usize;
    }
    tiles.truncate(count);
    (tiles, child)
}

/// Payloads of the tiles under `tiles` (node indices of the level above, whose occupied index
/// per node is `occ_above`), and, if `with_occupancy`, the occupied index per node of this level.
/// Per tile: its occupied children are a run of `here` starting at the parent's first child, in
/// the order of the parent's mask bits. Each array is written once, in parallel.
fn fill_tiles<P: Payload>(
    tiles: &[u32],
    occ_above: &[u32],
    above: &Occupied<'_, P>,
    here: &Occupied<'_, P>,
    with_occupancy: bool,
) -> (Vec<P>, Vec<u32>) {
    let tile = |t: usize| -> ([P; 8], [u32; 8]) {
        let (mut payload, mut occ) = ([P::empty(); 8], [NONE; 8]);
        let g = occ_above[tiles[t] as usize];
        if g != NONE {
            let (mut m, mut j) = (above.mask[g as usize], above.first[g as usize]);
            while m != 0 {
                let k = m.trailing_zeros() as usize;
                payload[k] = here.payload[j as usize];
                occ[k] = j;
                j += 1;
                m &= m - 1;
            }
        }
        (payload, occ)
    };
    let par = (0..tiles.len()).into_par_iter().with_min_len(MIN_LEN / 8);
    if with_occupancy {
        let (mut payload, mut occ) = (Vec::new(), Vec::new());
        par.map(tile).unzip_into_vecs(&mut payload, &mut occ);
        (payload.into_flattened(), occ.into_flattened())
    } else {
        let payload: Vec<[P; 8]> = par.map(|t| tile(t).0).collect();
        (payload.into_flattened(), Vec::new())
    }
}

/// Parent tiles per rayon task of [`links`].
const LINK_RANGE: usize = 1024;

/// Tile links of the sparse level under `tiles` (node indices of `parent`, ascending, whose
/// child pointers are set and, if sparse, tile links built): the +a neighbour of the tile under
/// parent node `p` is the child tile of `p`'s +a neighbour. Per parent tile (8 nodes, whose
/// child tiles are consecutive): its own 8 child pointers and those of its 3 neighbour tiles,
/// read as 4 runs, give the links of all its child tiles. Ranges of parent tiles in parallel,
/// each writing its own part of the output (found from `tiles`).
fn links<P: Payload>(tiles: &[u32], parent: &Level<P>) -> Vec<[u32; 3]> {
    let child = &parent.child;
    let n = child.len();
    // First node of parent tile `t`'s +a neighbour tile, or NONE. A dense level of fewer than
    // 8 nodes is the 1-node root: no neighbours.
    let neighbour_tile = |t: usize, a: usize| -> u32 {
        if !parent.dense {
            parent.tile_links[t][a]
        } else if n < 8 {
            NONE
        } else {
            // Node `8t + bit` has its a-bit set: its +a neighbour is node 0 of that tile.
            morton::step_up((8 * t + (1 << a)) as u64, a, parent.res_log2)
                .map_or(NONE, |q| q as u32)
        }
    };
    let mut out = vec![[0u32; 3]; tiles.len()];
    let mut jobs = Vec::new();
    let mut rest = &mut out[..];
    let mut done = 0;
    for t0 in (0..n.div_ceil(8)).step_by(LINK_RANGE) {
        let t1 = (t0 + LINK_RANGE).min(n.div_ceil(8));
        let end = tiles.partition_point(|&p| (p as usize) < 8 * t1);
        let (part, tail) = std::mem::take(&mut rest).split_at_mut(end - done);
        (rest, done) = (tail, end);
        jobs.push((t0, t1, part));
    }
    jobs.into_par_iter().for_each(|(t0, t1, part)| {
        let mut w = 0;
        for t in t0..t1 {
            let own: [u32; 8] =
                std::array::from_fn(|k| child.get(8 * t + k).copied().unwrap_or(NONE));
            if own == [NONE; 8] {
                continue;
            }
            let near: [[u32; 8]; 3] = std::array::from_fn(|a| {
                let f = neighbour_tile(t, a);
                if f == NONE { [NONE; 8] } else { std::array::from_fn(|k| child[f as usize + k]) }
            });
            for (k, &c) in own.iter().enumerate() {
                if c == NONE {
                    continue;
                }
                part[w] = std::array::from_fn(|a| {
                    let bit = 1 << a;
                    if k & bit == 0 { own[k | bit] } else { near[a][k & !bit] }
                });
                w += 1;
            }
        }
        debug_assert_eq!(w, part.len());
    });
    out
}
