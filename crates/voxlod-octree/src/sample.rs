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
//! - Each corner is added through [`Payload::add_scaled_at`] with the offset from its centre to
//!   the sample point and its size, so that a payload stored relative to its node (a distance
//!   from the node's centre, [`crate::MicrosurfacePayload`]) is read at the sample point, in
//!   voxel units, on every level; for every other payload this is [`Payload::add_scaled`].
//!
//! Cost: per level, one descent from the finest dense level (`first_dense − l` child reads) and
//! at most 7 neighbour steps (a tile-link read only when the step leaves the
//! node's tile); no allocation. Dense levels are read by index.

use glam::{DVec3, IVec3, UVec3, Vec3};
use voxlod_format::morton;

use crate::octree::{NONE, Octree, sparse_neighbour};
use crate::payload::Payload;

/// `SPREAD_8[c]`: the 8 bits of `c` moved to bits `0, 3, 6, …, 21` (a Morton code's x bits),
/// so that a dense-level node's code is `SPREAD_8[x] | SPREAD_8[y] << 1 | SPREAD_8[z] << 2`.
static SPREAD_8: [u32; 256] = {
    let mut t = [0u32; 256];
    let mut c = 0;
    while c < 256 {
        t[c] = morton::part1by2(c as u32) as u32;
        c += 1;
    }
    t
};

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
        // `level` is in [0, depth] here, so truncation is its floor (no libm `floorf` call).
        let l0 = level as u32;
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
    ///
    /// The arithmetic is, operation for operation, that of the plain formulation (kept as the
    /// oracle of `tests/fast_sample.rs`, which checks bit-identical results): `u = pos·2^−l −
    /// 0.5`, `b = ⌊u⌋`, `f = u − b`, corners `b + e` outside `[0, res)³` or absent skipped, and
    /// `payload(b + e) · ((w_x·w_y)·w_z)` added for `e = 0..8` in order (index `x + 2y + 4z`),
    /// `w = 1 − f` on the lower and `f` on the upper side. What is cheaper, and why it is exact:
    /// - the test "outside the cube" is done on `u` instead of `⌊u⌋`: `⌊u⌋ < −1 ⇔ u < −1` and
    ///   `⌊u⌋ ≥ res ⇔ u ≥ res` because `−1` and `res` are integers;
    /// - inside, `−1 ≤ u < res ≤ 2²¹`, so `⌊u⌋` is the truncation `u as i32`, minus one where
    ///   that lies above `u` (negative non-integers), with no libm `floorf` call (the build
    ///   targets x86-64 without SSE4.1's `roundps`). The two differ only in the sign of a zero
    ///   (`⌊−0⌋ = −0`), and `u` is never `−0`: `x − 0.5` is `+0` when `x = 0.5`;
    /// - `2^−l` is built from its exponent bits rather than divided (`l ≤ 21`: a normal float,
    ///   the same value as `1 / 2^l`);
    /// - the corner weights share their products: `w_x·w_y` is computed once per `(x, y)`
    ///   pair and reused for both `z`, the same two multiplications in the same order;
    /// - on dense levels (the common case: every level of a ≤ 64³ scene by default) the eight
    ///   Morton codes come from six 8-bit table lookups (`x`, `x + 1`, `y`, `y + 1`, `z`,
    ///   `z + 1`, spread to every third bit) OR-ed together, instead of eight full encodes:
    ///   dense levels are at most `2^MAX_DENSE_LOG2 = 256` nodes wide.
    #[inline]
    pub fn sample_level(&self, pos: Vec3, level: u32) -> P {
        let level = level.min(self.depth);
        let mut out = P::empty();
        if !pos.is_finite() {
            return out;
        }
        let lv = &self.levels[level as usize];
        let res = 1i32 << (self.depth - level);
        let inv_node = f32::from_bits((127 - level) << 23); // 2^−level, exactly 1 / 2^level
        let u = pos * inv_node - 0.5;
        let resf = res as f32;
        if u.x < -1.0 || u.y < -1.0 || u.z < -1.0 || u.x >= resf || u.y >= resf || u.z >= resf {
            return out;
        }
        let floor = |x: f32| {
            let i = x as i32;
            if i as f32 > x { i - 1 } else { i }
        };
        let base = IVec3::new(floor(u.x), floor(u.y), floor(u.z));
        let f = u - base.as_vec3();
        // Per axis: is the lower / upper corner inside [0, res)? (`base` is in [−1, res − 1].)
        let inside = |b: i32| [b >= 0, b + 1 < res];
        let (ix, iy, iz) = (inside(base.x), inside(base.y), inside(base.z));
        let nodes: [u32; 8] = if lv.dense {
            debug_assert!(lv.res_log2 <= crate::octree::MAX_DENSE_LOG2);
            // Spread coordinates (clamped only to keep the lookup in the table; a clamped
            // corner is outside and dropped below).
            let spread = |b: i32, axis: u32| {
                let s = |c: i32| SPREAD_8[c.clamp(0, 255) as usize] << axis;
                [s(b), s(b + 1)]
            };
            let (sx, sy, sz) = (spread(base.x, 0), spread(base.y, 1), spread(base.z, 2));
            std::array::from_fn(|e| {
                let (x, y, z) = (e & 1, e >> 1 & 1, e >> 2 & 1);
                if ix[x] && iy[y] && iz[z] { sx[x] | sy[y] | sz[z] } else { NONE }
            })
        } else {
            // `corners` starts at `max(base, 0)`: a corner `e` is `start + (e − shift)`.
            let start = base.max(IVec3::ZERO);
            let shift = (start - base).as_uvec3();
            let found = self.corners(level, start.as_uvec3());
            std::array::from_fn(|e| {
                let (x, y, z) = (e as u32 & 1, e as u32 >> 1 & 1, e as u32 >> 2 & 1);
                if ix[x as usize] && iy[y as usize] && iz[z as usize] {
                    found[(x - shift.x + 2 * (y - shift.y) + 4 * (z - shift.z)) as usize]
                } else {
                    NONE
                }
            })
        };
        let wx = [1.0 - f.x, f.x];
        let wy = [1.0 - f.y, f.y];
        let wz = [1.0 - f.z, f.z];
        let wxy = [wx[0] * wy[0], wx[1] * wy[0], wx[0] * wy[1], wx[1] * wy[1]];
        let node = (1u32 << level) as f32;
        for (e, &n) in nodes.iter().enumerate() {
            if n != NONE {
                // Sample point − corner centre, voxels (read only by payloads stored relative
                // to their node; the others ignore it and the compiler drops it).
                let corner = Vec3::new((e & 1) as f32, (e >> 1 & 1) as f32, (e >> 2) as f32);
                let offset = (f - corner) * node;
                out.add_scaled_at(&lv.payload[n as usize], wxy[e & 3] * wz[e >> 2], offset, node);
            }
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
