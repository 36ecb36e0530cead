//! Quadrilinear sampling: trilinear within a level, linear between two levels.
//!
//! # Conventions
//! - Positions are **grid coordinates** in level-0 voxels (voxel `i` spans `[i, i+1)`, as
//!   [`voxlod_format::GridSpec::to_grid`]); [`Octree::sample_world`] converts world positions.
//! - A node `c` of level `l` spans `[c·2^l, (c+1)·2^l)`; its payload is the value **at its
//!   centre** (the paper's sampling positions). Between centres the value is trilinear; nodes
//!   that do not exist (outside the grid or empty space) contribute [`Payload::empty`], so the
//!   octree samples exactly like a dense grid of its level with zeros around occupied content.
//! - A footprint of diameter `d` voxels samples the fractional level `log2(max(d, 1))`, clamped
//!   to `depth`: a node of level `l` is `2^l` voxels wide. A diameter below one voxel (a cone's
//!   apex, a ray), zero or NaN samples level 0; an infinite one the root.
//! - A non-finite position samples empty space.
//!
//! Cost: per level, one descent from the finest dense level (`first_dense − l` child reads) and
//! at most 7 neighbour steps (a tile-link read only when the step leaves the
//! node's tile); no allocation. Dense levels are read by index.

use glam::{DVec3, IVec3, UVec3, Vec3};
use voxlod_format::morton;

use crate::octree::{NONE, Octree, sparse_neighbour};
use crate::payload::Payload;

impl<P: Payload> Octree<P> {
    /// The fractional level a footprint of `diameter` voxels samples (module docs).
    #[inline]
    pub fn level_for_diameter(&self, diameter: f32) -> f32 {
        // `f32::max` ignores NaN: NaN and anything below one voxel give level 0.
        diameter.max(1.0).log2().min(self.depth as f32)
    }

    /// Quadrilinear sample at grid position `pos` with a footprint of `diameter` voxels:
    /// trilinear on the two levels around [`Octree::level_for_diameter`], blended linearly.
    #[inline]
    pub fn sample(&self, pos: Vec3, diameter: f32) -> P {
        self.sample_at_level(pos, self.level_for_diameter(diameter))
    }

    /// Quadrilinear sample at a fractional `level` in `[0, depth]` (clamped).
    pub fn sample_at_level(&self, pos: Vec3, level: f32) -> P {
        let level = if level.is_nan() { 0.0 } else { level.clamp(0.0, self.depth as f32) };
        let l0 = level.floor() as u32;
        let t = level - l0 as f32;
        let mut out = self.sample_level(pos, l0);
        if t > 0.0 && l0 < self.depth {
            let upper = self.sample_level(pos, l0 + 1);
            let mut mixed = P::empty();
            mixed.add_scaled(&out, 1.0 - t);
            mixed.add_scaled(&upper, t);
            out = mixed;
        }
        out
    }

    /// [`Octree::sample`] at a world position with a world-space footprint diameter, through
    /// the octree's grid.
    pub fn sample_world(&self, pos: DVec3, diameter: f64) -> P {
        let g = self.grid.to_grid(pos).as_vec3();
        self.sample(g, (diameter / self.grid.voxel_size) as f32)
    }

    /// Trilinear sample of one `level` (clamped to `depth`) at grid position `pos`.
    pub fn sample_level(&self, pos: Vec3, level: u32) -> P {
        let level = level.min(self.depth);
        let mut out = P::empty();
        if !pos.is_finite() {
            return out;
        }
        let res = 1i32 << (self.depth - level);
        let u = pos * (1.0 / (1u32 << level) as f32) - 0.5;
        let lower = u.floor();
        if lower.cmplt(Vec3::splat(-1.0)).any() || lower.cmpge(Vec3::splat(res as f32)).any() {
            return out;
        }
        let base = lower.as_ivec3();
        let f = u - lower;
        // The corner nodes, indexed by their offset (x + 2y + 4z) from `start`.
        let start = base.max(IVec3::ZERO);
        let nodes = self.corners(level, start.as_uvec3());
        let lv = &self.levels[level as usize];
        for e in 0..8u32 {
            let off = IVec3::new((e & 1) as i32, (e >> 1 & 1) as i32, (e >> 2 & 1) as i32);
            let c = base + off;
            if c.cmplt(IVec3::ZERO).any() || c.cmpge(IVec3::splat(res)).any() {
                continue;
            }
            let d = c - start;
            let n = nodes[(d.x + 2 * d.y + 4 * d.z) as usize];
            if n == NONE {
                continue;
            }
            let w = Vec3::select(off.cmpeq(IVec3::ZERO), 1.0 - f, f).element_product();
            out.add_scaled(&lv.payload[n as usize], w);
        }
        out
    }

    /// Node indices of `start + e`, `e ∈ {0,1}³` (index `x + 2y + 4z`), at `level`; [`NONE`]
    /// where absent.
    #[inline]
    fn corners(&self, level: u32, start: UVec3) -> [u32; 8] {
        let lv = &self.levels[level as usize];
        if lv.dense {
            let res = 1u32 << lv.res_log2;
            return std::array::from_fn(|e| {
                let c = start + UVec3::new(e as u32 & 1, e as u32 >> 1 & 1, e as u32 >> 2 & 1);
                if c.cmplt(UVec3::splat(res)).all() { morton::encode(c) as u32 } else { NONE }
            });
        }
        let mut n = [NONE; 8];
        n[0] = self.find(level, start);
        let links = &lv.tile_links;
        let hop =
            |i: u32, axis: usize| if i == NONE { NONE } else { sparse_neighbour(links, i, axis) };
        n[1] = hop(n[0], 0);
        n[2] = hop(n[0], 1);
        n[4] = hop(n[0], 2);
        n[3] = hop(n[1], 1);
        n[5] = hop(n[1], 2);
        n[6] = hop(n[2], 2);
        n[7] = hop(n[3], 2);
        n
    }

    /// Index of node `c` of sparse `level`, descending from the finest dense level; [`NONE`] if
    /// it does not exist.
    #[inline]
    pub(crate) fn find(&self, level: u32, c: UVec3) -> u32 {
        let top = self.first_dense;
        let mut idx = morton::encode(c >> (top - level)) as usize;
        for lv in (level + 1..=top).rev() {
            let child = self.levels[lv as usize].child[idx];
            if child == NONE {
                return NONE;
            }
            let o = (c >> (lv - 1 - level)) & UVec3::ONE;
            idx = child as usize + (o.x + 2 * o.y + 4 * o.z) as usize;
        }
        idx as u32
    }
}
