//! [`Octree::validate`]: every structural invariant of the layout (`octree` module docs),
//! checked against coordinates derived independently of the build.

use std::collections::HashMap;

use glam::UVec3;
use voxlod_format::morton;

use crate::octree::{Level, NONE, Octree, sparse_neighbour};
use crate::payload::Payload;
use crate::{Error, Result};

/// Largest difference tolerated between a parent's payload and the prefilter of its children.
pub const PREFILTER_TOLERANCE: f32 = 1e-5;

fn fail<T>(level: usize, node: usize, reason: String) -> Result<T> {
    Err(Error::Invalid { level: level as u32, node: node as u64, reason })
}

impl<P: Payload> Octree<P> {
    /// Checks every structural invariant, returning the first broken one with its level and
    /// node:
    /// - one level per depth, resolutions `2^(depth − l)`; dense levels `first_dense..=depth`
    ///   complete (`r³` nodes), without links; child pointers and masks exactly where the layout
    ///   says (finest dense level and sparse levels above 0);
    /// - tiles: each level's non-[`NONE`] child pointers, in node order, are `0, 8, 16, …` and
    ///   cover the level below exactly (no orphan, shared or overlapping tile), so node codes
    ///   derived top-down are **strictly increasing** (Morton order);
    /// - masks: a set bit has a child tile; above level 1 bit `k` is set iff child `k` has a
    ///   non-zero mask; the leaves' mask bits count the input voxels; nodes that are not
    ///   occupied hold [`Payload::empty`];
    /// - closure: every backward neighbour (`−{0,1}³`, inside the cube) of an occupied node of a
    ///   sparse level exists;
    /// - links: one per tile, each [`NONE`] or the first node of a tile of the level; every
    ///   node's +x, +y, +z neighbour derived from them ([`crate::LevelView::neighbour`]) is the
    ///   node one step along that axis, and is absent exactly when that node does not exist;
    /// - payloads: finite, and every parent equals [`Payload::prefilter`] of its children within
    ///   [`PREFILTER_TOLERANCE`].
    pub fn validate(&self) -> Result<()> {
        let (depth, fd) = (self.depth as usize, self.first_dense as usize);
        if self.levels.len() != depth + 1 {
            return fail(0, 0, format!("{} levels for depth {depth}", self.levels.len()));
        }
        for (l, lv) in self.levels.iter().enumerate() {
            self.check_shape(l, lv)?;
        }
        // Codes per level, derived top-down from the child pointers.
        let mut codes: Vec<Vec<u64>> = vec![Vec::new(); depth + 1];
        for (l, slot) in codes.iter_mut().enumerate().skip(fd) {
            *slot = (0..self.levels[l].payload.len() as u64).collect();
        }
        for l in (0..fd).rev() {
            let parent = &self.levels[l + 1];
            let mut next = vec![u64::MAX; self.levels[l].payload.len()];
            let mut expected = 0u64;
            for (p, &c) in parent.child.iter().enumerate() {
                if c == NONE {
                    continue;
                }
                if c as u64 != expected {
                    return fail(l + 1, p, format!("child tile at {c}, expected {expected}"));
                }
                for k in 0..8 {
                    next[c as usize + k] = codes[l + 1][p] << 3 | k as u64;
                }
                expected += 8;
            }
            if expected != next.len() as u64 {
                return fail(l, 0, format!("{} nodes but tiles cover {expected}", next.len()));
            }
            if let Some(i) = (1..next.len()).find(|&i| next[i - 1] >= next[i]) {
                return fail(l, i, "nodes out of Morton order".into());
            }
            codes[l] = next;
        }
        for l in 0..=depth {
            self.check_payloads(l, &codes)?;
        }
        for (l, level_codes) in codes.iter().enumerate().take(fd) {
            self.check_sparse(l, level_codes)?;
        }
        Ok(())
    }

    fn check_shape(&self, l: usize, lv: &Level<P>) -> Result<()> {
        let (depth, fd) = (self.depth as usize, self.first_dense as usize);
        if lv.res_log2 as usize != depth - l || lv.dense != (l >= fd) {
            return fail(l, 0, format!("resolution 2^{} dense {}", lv.res_log2, lv.dense));
        }
        let n = lv.payload.len();
        let full = 1usize << (3 * lv.res_log2);
        if lv.dense && n != full {
            return fail(l, 0, format!("dense level holds {n} of {full} nodes"));
        }
        let tiles = lv.tile_links.len();
        if !lv.dense && (!n.is_multiple_of(8) || tiles != n / 8) {
            return fail(l, 0, format!("{n} nodes (tiles of 8), {tiles} tile links"));
        }
        if !lv.dense {
            for (t, links) in lv.tile_links.iter().enumerate() {
                if let Some(&x) =
                    links.iter().find(|&&x| x != NONE && (x % 8 != 0 || x as usize >= n))
                {
                    return fail(l, 8 * t, format!("tile link {x} is not the start of a tile"));
                }
            }
        }
        if lv.dense && !lv.tile_links.is_empty() {
            return fail(l, 0, "a dense level stores links".into());
        }
        let has_children = l > 0 && l <= fd;
        let expect = if has_children { n } else { 0 };
        if lv.child.len() != expect || lv.mask.len() != expect {
            return fail(l, 0, format!("{} children, {} masks", lv.child.len(), lv.mask.len()));
        }
        if let Some(i) = lv.payload.iter().position(|p| p.check().is_some()) {
            return fail(l, i, format!("payload {:?}", lv.payload[i]));
        }
        Ok(())
    }

    /// Children of node `i` of level `l` (≥ 1), as node indices in level `l − 1` (or [`NONE`]).
    fn children(&self, l: usize, i: usize, codes: &[Vec<u64>]) -> [u32; 8] {
        let lv = &self.levels[l];
        if lv.child.is_empty() {
            // Dense above the finest dense level: children by code.
            std::array::from_fn(|k| (codes[l][i] << 3 | k as u64) as u32)
        } else if lv.child[i] == NONE {
            [NONE; 8]
        } else {
            std::array::from_fn(|k| lv.child[i] + k as u32)
        }
    }

    fn check_payloads(&self, l: usize, codes: &[Vec<u64>]) -> Result<()> {
        let lv = &self.levels[l];
        let mut leaves = 0u64;
        for i in 0..lv.payload.len() {
            if l == 0 {
                continue;
            }
            let kids = self.children(l, i, codes);
            let below = &self.levels[l - 1];
            let get = |k: u32| if k == NONE { P::empty() } else { below.payload[k as usize] };
            let expected = P::prefilter(&kids.map(get));
            let diff = expected.max_abs_diff(&lv.payload[i]);
            if diff.is_nan() || diff > PREFILTER_TOLERANCE {
                return fail(l, i, format!("payload differs from the prefilter by {diff}"));
            }
            if lv.mask.is_empty() {
                continue;
            }
            let mask = lv.mask[i];
            if mask != 0 && lv.child[i] == NONE {
                return fail(l, i, format!("mask {mask:#010b} without a child tile"));
            }
            if l == 1 {
                leaves += mask.count_ones() as u64;
                for (k, &n) in kids.iter().enumerate() {
                    let empty =
                        n == NONE || below.payload[n as usize].max_abs_diff(&P::empty()) == 0.0;
                    if mask >> k & 1 == 0 && !empty {
                        return fail(0, n as usize, "unoccupied leaf with a payload".into());
                    }
                }
            } else {
                for (k, &n) in kids.iter().enumerate() {
                    let occupied = n != NONE && below.mask[n as usize] != 0;
                    if (mask >> k & 1 == 1) != occupied {
                        return fail(l, i, format!("mask bit {k} disagrees with child {n}"));
                    }
                    if !occupied && n != NONE {
                        let p = below.payload[n as usize];
                        if p.max_abs_diff(&P::empty()) != 0.0 {
                            return fail(
                                l - 1,
                                n as usize,
                                "unoccupied node with a payload".into(),
                            );
                        }
                    }
                }
            }
        }
        if l == 1 && !lv.mask.is_empty() && leaves != self.voxels {
            return fail(1, 0, format!("masks mark {leaves} leaves, {} voxels given", self.voxels));
        }
        Ok(())
    }

    /// Links and closure of sparse level `l` whose node codes are `codes`.
    fn check_sparse(&self, l: usize, codes: &[u64]) -> Result<()> {
        let lv = &self.levels[l];
        let res = 1u32 << lv.res_log2;
        let index: HashMap<u64, u32> =
            codes.iter().enumerate().map(|(i, &c)| (c, i as u32)).collect();
        let at = |c: UVec3| -> u32 {
            if c.cmplt(UVec3::splat(res)).all() {
                index.get(&morton::encode(c)).copied().unwrap_or(NONE)
            } else {
                NONE
            }
        };
        // Occupancy of this level's nodes, from the parents' masks.
        let parent = &self.levels[l + 1];
        let mut occupied = vec![false; codes.len()];
        for (p, &c) in parent.child.iter().enumerate() {
            if c != NONE {
                for k in 0..8 {
                    occupied[c as usize + k] = parent.mask[p] >> k & 1 == 1;
                }
            }
        }
        for (i, &code) in codes.iter().enumerate() {
            let c = morton::decode(code);
            for a in 0..3 {
                let mut n = c;
                n[a] += 1;
                let expected = at(n);
                let got = sparse_neighbour(&lv.tile_links, i as u32, a);
                if got != expected {
                    return fail(l, i, format!("link {a} is {got}, the node at {n} is {expected}"));
                }
            }
            if occupied[i] {
                for d in 1..8u32 {
                    let e = UVec3::new(d & 1, d >> 1 & 1, d >> 2 & 1);
                    if c.cmpge(e).all() && at(c - e) == NONE {
                        let b = c - e;
                        return fail(
                            l,
                            i,
                            format!("occupied node {c} lacks backward neighbour {b}"),
                        );
                    }
                }
            }
        }
        Ok(())
    }
}
