//! A straightforward CPU build (sort-based closure, per-node links from a scan of the parents'
//! child pointers): the reference the linear build in [`super`] is tested against
//! (the `tests::fast_build` module). Test builds only.

use glam::UVec3;
use rayon::prelude::*;
use voxlod_format::{GridSpec, morton};

use super::{check_input, plan};
use crate::Error;
use crate::Result;
use crate::octree::{BuildOptions, Level, NONE, Octree};
use crate::payload::Payload;

/// Occupied nodes of one level: sorted Morton codes and their payloads.
struct Occupied<P> {
    codes: Vec<u64>,
    payload: Vec<P>,
    /// Per node (above level 0): bit `d` set if the node minus `d` is the parent of a backward
    /// neighbour of one of its occupied children ([`tile_parents`]).
    shifts: Vec<u8>,
}

/// Per level, the +x, +y, +z neighbour of every node (empty for dense levels).
pub(crate) type NodeLinks = Vec<Vec<[u32; 3]>>;

/// The reference build of [`Octree::from_morton_sorted`] (same checks, same output), and the
/// per-node links (+x, +y, +z neighbour of every node of each sparse level) it derives the tile
/// links from.
pub(crate) fn from_morton_sorted<P: Payload>(
    grid: GridSpec,
    voxels: Vec<(u64, P)>,
    options: &BuildOptions,
) -> Result<(Octree<P>, NodeLinks)> {
    grid.validate()?;
    let (depth, first_dense) = plan(grid.dims, options)?;
    check_input(grid.dims, &voxels)?;
    let voxel_count = voxels.len() as u64;
    let (codes, payload) = voxels.into_iter().unzip();
    let mut occupied = vec![Occupied { codes, payload, shifts: Vec::new() }];
    for l in 1..=depth as usize {
        let next = coarsen(&occupied[l - 1]);
        occupied.push(next);
    }
    // Tiles of each sparse level: parents of the backward closure.
    let tiles: Vec<Vec<u64>> =
        occupied[1..=first_dense as usize].par_iter().map(tile_parents).collect();
    for (l, t) in tiles.iter().enumerate() {
        let nodes = 8 * t.len() as u64;
        if nodes >= NONE as u64 {
            return Err(Error::TooManyNodes { level: l as u32, nodes });
        }
    }
    let mut levels: Vec<Level<P>> = (0..=depth)
        .into_par_iter()
        .map(|l| {
            let res_log2 = depth - l;
            // The level below and its tiles' parents, where this level has child pointers.
            let below = l
                .checked_sub(1)
                .and_then(|b| tiles.get(b as usize).map(|t| (&occupied[b as usize], t.as_slice())));
            if l >= first_dense {
                dense_level(res_log2, &occupied[l as usize], below)
            } else {
                sparse_level(res_log2, &occupied[l as usize], &tiles[l as usize], below)
            }
        })
        .collect();
    let mut node_links = vec![Vec::new(); levels.len()];
    for l in (0..first_dense as usize).rev() {
        let (lower, upper) = levels.split_at_mut(l + 1);
        node_links[l] = links(&lower[l], &upper[0], &node_links[l + 1]);
        // Tile t's +a neighbour tile starts at the +a link of its node with only the a-bit set.
        lower[l].tile_links = (0..node_links[l].len() / 8)
            .map(|t| std::array::from_fn(|a| node_links[l][8 * t + (1 << a)][a]))
            .collect();
    }
    for level in &mut levels {
        level.payload.shrink_to_fit();
        level.child.shrink_to_fit();
        level.mask.shrink_to_fit();
    }
    let tree = Octree { grid, depth, first_dense, voxels: voxel_count, levels };
    if cfg!(debug_assertions) {
        tree.validate()?;
    }
    Ok((tree, node_links))
}

/// The occupied nodes one level up: distinct parents, each the prefilter of its children.
fn coarsen<P: Payload>(level: &Occupied<P>) -> Occupied<P> {
    let c = &level.codes;
    let starts: Vec<usize> =
        (0..c.len()).filter(|&i| i == 0 || c[i] >> 3 != c[i - 1] >> 3).collect();
    let (codes, (payload, shifts)) = (0..starts.len())
        .into_par_iter()
        .map(|g| {
            let end = starts.get(g + 1).copied().unwrap_or(c.len());
            let mut children = [P::empty(); 8];
            let mut shifts = 0u8;
            for i in starts[g]..end {
                children[(c[i] & 7) as usize] = level.payload[i];
                shifts |= SUBSETS[(!c[i] & 7) as usize];
            }
            (c[starts[g]] >> 3, (P::prefilter(&children), shifts))
        })
        .unzip();
    Occupied { codes, payload, shifts }
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

/// Codes of the parents of the backward closure of a level, sorted and distinct, from the
/// occupied nodes one level up (`parents`). Child `o = 2q + b` of `q` has backward neighbours
/// `o − d` whose parents are `q − d'` with `d'_a = d_a` where `b_a = 0` and `d'_a = 0` where
/// `b_a = 1`: `d'` ranges over the subsets of the axes along which `o` is in the lower half.
/// `Occupied::shifts` holds the union of those over the occupied children, so this enumerates
/// the exact set from about a quarter as many nodes (on surfaces) as the children's closure.
fn tile_parents<P>(parents: &Occupied<P>) -> Vec<u64> {
    let mut out: Vec<u64> = parents
        .codes
        .par_iter()
        .zip(&parents.shifts)
        .flat_map_iter(|(&code, &shifts)| {
            let q = morton::decode(code);
            (0..8u32).filter_map(move |d| {
                let e = UVec3::new(d & 1, d >> 1 & 1, d >> 2 & 1);
                (shifts >> d & 1 == 1 && q.cmpge(e).all()).then(|| morton::encode(q - e))
            })
        })
        .collect();
    out.par_sort_unstable();
    out.dedup();
    out
}

/// Node indices, in a tiled level whose tiles' parents are `tiles`, of sorted `codes` that all
/// lie in those tiles.
fn locate(tiles: &[u64], codes: impl Iterator<Item = u64>) -> impl Iterator<Item = usize> {
    let mut t = 0;
    codes.map(move |code| {
        while tiles[t] < code >> 3 {
            t += 1;
        }
        debug_assert_eq!(tiles[t], code >> 3, "code {code} lies in no tile");
        8 * t + (code & 7) as usize
    })
}

/// A dense level; `below` (finest dense level only, above level 0) gives the occupied nodes and
/// tile parents of the level under it, for child pointers and masks.
fn dense_level<P: Payload>(
    res_log2: u32,
    occupied: &Occupied<P>,
    below: Option<(&Occupied<P>, &[u64])>,
) -> Level<P> {
    let n = 1usize << (3 * res_log2);
    let mut payload = vec![P::empty(); n];
    for (&c, p) in occupied.codes.iter().zip(&occupied.payload) {
        payload[c as usize] = *p;
    }
    let (mut child, mut mask) = (Vec::new(), Vec::new());
    if let Some((occ_below, tiles_below)) = below {
        child = vec![NONE; n];
        mask = vec![0u8; n];
        for (rank, &q) in tiles_below.iter().enumerate() {
            child[q as usize] = 8 * rank as u32;
        }
        for &c in &occ_below.codes {
            mask[(c >> 3) as usize] |= 1 << (c & 7);
        }
    }
    Level { res_log2, dense: true, payload, child, mask, tile_links: Vec::new() }
}

/// A sparse level made of the tiles of `tiles` (parents' codes); `below` as for
/// [`dense_level`].
fn sparse_level<P: Payload>(
    res_log2: u32,
    occupied: &Occupied<P>,
    tiles: &[u64],
    below: Option<(&Occupied<P>, &[u64])>,
) -> Level<P> {
    let n = 8 * tiles.len();
    let mut payload = vec![P::empty(); n];
    for (i, p) in locate(tiles, occupied.codes.iter().copied()).zip(&occupied.payload) {
        payload[i] = *p;
    }
    let (mut child, mut mask) = (Vec::new(), Vec::new());
    if let Some((occ_below, tiles_below)) = below {
        child = vec![NONE; n];
        mask = vec![0u8; n];
        for (rank, i) in locate(tiles, tiles_below.iter().copied()).enumerate() {
            child[i] = 8 * rank as u32;
        }
        let parents = occ_below.codes.iter().map(|c| c >> 3);
        for (i, &c) in locate(tiles, parents).zip(&occ_below.codes) {
            mask[i] |= 1 << (c & 7);
        }
    }
    Level { res_log2, dense: false, payload, child, mask, tile_links: Vec::new() }
}

/// Forward links of a sparse level from its parent level (`parent_links`, the parent's per-node
/// links, already built if sparse).
fn links<P: Payload>(
    level: &Level<P>,
    parent: &Level<P>,
    parent_links: &[[u32; 3]],
) -> Vec<[u32; 3]> {
    let mut tile_parent = vec![NONE; level.payload.len() / 8];
    for (p, &c) in parent.child.iter().enumerate() {
        if c != NONE {
            tile_parent[c as usize / 8] = p as u32;
        }
    }
    let parent_res = 1u32 << parent.res_log2;
    (0..level.payload.len())
        .into_par_iter()
        .map(|i| {
            let (t, k) = (i / 8, (i % 8) as u32);
            let p = tile_parent[t];
            std::array::from_fn(|a| {
                let bit = 1 << a;
                if k & bit == 0 {
                    return (8 * t) as u32 + (k | bit);
                }
                let q = if parent.dense {
                    let mut c = morton::decode(p as u64);
                    c[a] += 1;
                    if c[a] < parent_res { morton::encode(c) as u32 } else { NONE }
                } else {
                    parent_links[p as usize][a]
                };
                match parent.child.get(q as usize) {
                    Some(&ch) if ch != NONE => ch + (k & !bit),
                    _ => NONE,
                }
            })
        })
        .collect()
}
