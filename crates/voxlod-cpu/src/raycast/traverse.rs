//! Stack-based traversal of obvhs's compressed wide BVH (CWBVH, Ylitie et al. 2017): an
//! explicit loop with a fixed-size stack, no recursion, the shape a WGSL kernel takes.
//!
//! The loop and the child ordering follow obvhs's `traverse!` macro. The child boxes are not
//! read from the 8-bit quantized nodes but from [`WideNode`]s decompressed once at build time
//! into `f32` planes rounded outward (a conservative superset of obvhs's boxes), which spares
//! 48 byte-to-float conversions per node visit. The box test clamps the entry distance to the
//! ray's own `t_min` (obvhs clamps to an absolute `1e-4`, which culls geometry near the origin
//! of small scenes), builds the inverse direction so that `±0` and denormal components never
//! give NaN or a wrong slab, and widens each exit distance by 2⁻²⁰ relative, more than the
//! rounding of the slab arithmetic, so a ray grazing a box boundary is never culled.

use glam::{UVec2, Vec3, Vec4};
use obvhs::cwbvh::CwBvh;
use obvhs::cwbvh::node::extract_byte64;

/// Traversal stack entries: one per BVH level. Trees deeper than this are refused at build
/// time ([`super::Bvh::new`]); obvhs's own traversal uses 32 as well.
pub(crate) const STACK_SIZE: usize = 32;

/// Relative widening of a box's exit distance.
pub(crate) const EXIT_SLACK: f32 = 1.0 + 1.0 / 1_048_576.0;

/// A CWBVH node with its children's boxes as `f32` planes: `planes[2·axis + (0 = min, 1 =
/// max)][half]` holds children `4·half .. 4·half + 4`.
#[derive(Clone, Copy, Debug)]
#[repr(C, align(16))]
pub(crate) struct WideNode {
    pub planes: [[Vec4; 2]; 6],
    /// obvhs's `child_meta` bytes as one word.
    pub meta: u64,
    /// Which children are inner nodes.
    pub imask: u32,
    /// Index of the first child node.
    pub child_base: u32,
    /// Index of the first primitive of the leaf children.
    pub primitive_base: u32,
}

impl WideNode {
    /// Decompresses every node of `bvh`.
    pub(crate) fn decompress(bvh: &CwBvh) -> Vec<WideNode> {
        bvh.nodes
            .iter()
            .map(|n| {
                let q = [
                    &n.child_min_x,
                    &n.child_max_x,
                    &n.child_min_y,
                    &n.child_max_y,
                    &n.child_min_z,
                    &n.child_max_z,
                ];
                let mut planes = [[Vec4::ZERO; 2]; 6];
                for (k, plane) in planes.iter_mut().enumerate() {
                    let axis = k / 2;
                    let scale = f32::from_bits((n.e[axis] as u32) << 23) as f64;
                    let mut v = [0f32; 8];
                    for (child, value) in v.iter_mut().enumerate() {
                        *value = if n.child_meta[child] == 0 {
                            // Empty slot: an inverted box that no ray enters.
                            if k % 2 == 0 { f32::INFINITY } else { f32::NEG_INFINITY }
                        } else {
                            let exact = n.p[axis] as f64 + q[k][child] as f64 * scale;
                            round_outward(exact, k % 2 == 1)
                        };
                    }
                    *plane = [Vec4::from_slice(&v[..4]), Vec4::from_slice(&v[4..])];
                }
                WideNode {
                    planes,
                    meta: u64::from_le_bytes(n.child_meta),
                    imask: n.imask as u32,
                    child_base: n.child_base_idx,
                    primitive_base: n.primitive_base_idx,
                }
            })
            .collect()
    }

    /// obvhs's `get_child_and_index_bits`: per child, the bits it sets in the hit mask and where.
    #[inline(always)]
    pub(crate) fn child_and_index_bits(&self, oct_inv4: u32) -> (u64, u64) {
        let oct_inv8 = oct_inv4 as u64 | (oct_inv4 as u64) << 32;
        let meta8 = self.meta;
        let is_inner8 = (meta8 & (meta8 << 1)) & 0x1010_1010_1010_1010;
        let inner_mask8 = (is_inner8 >> 4) * 0xff;
        let bit_index8 = (meta8 ^ (oct_inv8 & inner_mask8)) & 0x1f1f_1f1f_1f1f_1f1f;
        let child_bits8 = (meta8 >> 5) & 0x0707_0707_0707_0707;
        (child_bits8, bit_index8)
    }
}

/// `x` rounded to an `f32` no greater (`up = false`) or no less (`up = true`) than it.
fn round_outward(x: f64, up: bool) -> f32 {
    let f = x as f32;
    match (up, (f as f64).partial_cmp(&x)) {
        (false, Some(std::cmp::Ordering::Greater)) => f.next_down(),
        (true, Some(std::cmp::Ordering::Less)) => f.next_up(),
        _ => f,
    }
}

/// What a primitive callback tells the traversal.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Visit {
    /// Keep going.
    Continue,
    /// Stop: the answer is known (any-hit queries).
    Stop,
}

/// The ray as the box test needs it.
#[derive(Clone, Copy, Debug)]
pub(crate) struct BoxRay {
    origin: Vec3,
    inv_dir: Vec3,
    /// Per axis, the plane index (0 = min, 1 = max) the ray enters a slab through.
    near: [usize; 3],
    /// CWBVH child-order octant, as obvhs encodes it.
    oct_inv4: u32,
}

impl BoxRay {
    /// `dir` must be finite and non-zero. Negative zero is treated as positive; components below
    /// `1e-20` in magnitude get an inverse of `±1e20` (finite, so `0·inv` stays 0).
    #[inline]
    pub(crate) fn new(origin: Vec3, dir: Vec3) -> Self {
        let dir = dir + Vec3::ZERO; // −0 → +0
        let negative = dir.cmplt(Vec3::ZERO);
        let clamped = dir.abs().max(Vec3::splat(1e-20));
        let inv_dir = Vec3::select(negative, -clamped.recip(), clamped.recip());
        let near =
            [negative.test(0) as usize, negative.test(1) as usize, negative.test(2) as usize];
        let oct_inv4 = (if near[0] == 1 { 0 } else { 0x0404_0404 })
            | (if near[1] == 1 { 0 } else { 0x0202_0202 })
            | (if near[2] == 1 { 0 } else { 0x0101_0101 });
        Self { origin, inv_dir, near, oct_inv4 }
    }

    /// Whether the segment `[t_min, t_max]` overlaps the box `(lo, hi)` (boundary included,
    /// exit widened as in the node test).
    #[inline(always)]
    pub(crate) fn overlaps(&self, (lo, hi): (Vec3, Vec3), t_min: f32, t_max: f32) -> bool {
        let a = (lo - self.origin) * self.inv_dir;
        let b = (hi - self.origin) * self.inv_dir;
        let near = a.min(b).max_element().max(t_min);
        let far = (a.max(b) * EXIT_SLACK).min_element().min(t_max);
        near <= far
    }

    /// Which children of `node` the segment `[t_min, t_max]` overlaps, as the CWBVH hit mask
    /// (bits 24..32: inner children in traversal order, bits 0..24: leaf primitives).
    #[inline(always)]
    fn intersect_node(&self, node: &WideNode, t_min: f32, t_max: f32) -> u32 {
        let (child_bits8, bit_index8) = node.child_and_index_bits(self.oct_inv4);
        let o =
            [Vec4::splat(self.origin.x), Vec4::splat(self.origin.y), Vec4::splat(self.origin.z)];
        let inv =
            [Vec4::splat(self.inv_dir.x), Vec4::splat(self.inv_dir.y), Vec4::splat(self.inv_dir.z)];
        let mut hit_mask = 0u32;
        for half in 0..2 {
            let t = |k: usize, a: usize| (node.planes[k][half] - o[a]) * inv[a];
            let (n, f) = (&self.near, |a: usize| 2 * a + 1 - self.near[a]);
            let near = t(n[0], 0).max(t(2 + n[1], 1)).max(t(4 + n[2], 2)).max(Vec4::splat(t_min));
            // A negative exit shrinks under the slack, but is then behind t_min ≥ 0 anyway.
            let far =
                (t(f(0), 0).min(t(f(1), 1)).min(t(f(2), 2)) * EXIT_SLACK).min(Vec4::splat(t_max));
            let mut mask = near.cmple(far).bitmask();
            while mask != 0 {
                let child = half * 4 + mask.trailing_zeros() as usize;
                mask &= mask - 1;
                hit_mask |= extract_byte64(child_bits8, child) << extract_byte64(bit_index8, child);
            }
        }
        hit_mask
    }
}

#[inline(always)]
pub(crate) fn first_bit_high(v: u32) -> u32 {
    31 - v.leading_zeros()
}

/// Visits, nearest child first, every primitive slot (an index into the BVH's primitive order)
/// whose leaf box the segment `[t_min, *t_max]` overlaps. `visit` may shrink `*t_max` (closest
/// hit) or stop the traversal (any hit).
#[inline(always)]
pub(crate) fn traverse(
    nodes: &[WideNode],
    ray: &BoxRay,
    t_min: f32,
    t_max: &mut f32,
    mut visit: impl FnMut(u32, &mut f32) -> Visit,
) {
    if nodes.is_empty() {
        return;
    }
    let mut stack = [UVec2::ZERO; STACK_SIZE];
    let mut sp = 0usize;
    // A virtual parent whose only inner child (slot 7) is the root, node 0.
    let mut current = UVec2::new(0, 0x8000_0000);
    let mut prims = UVec2::ZERO;
    loop {
        while prims.y != 0 {
            let local = first_bit_high(prims.y);
            prims.y &= !(1 << local);
            if visit(prims.x + local, t_max) == Visit::Stop {
                return;
            }
        }
        if current.y & 0xff00_0000 != 0 {
            let hits = current.y;
            let offset = first_bit_high(hits);
            current.y &= !(1 << offset);
            if current.y & 0xff00_0000 != 0 {
                stack[sp] = current;
                sp = (sp + 1).min(STACK_SIZE - 1);
            }
            let slot = (offset - 24) ^ (ray.oct_inv4 & 0xff);
            let relative = (hits & !(u32::MAX << slot)).count_ones();
            let node = &nodes[(current.x + relative) as usize];
            let hit_mask = ray.intersect_node(node, t_min, *t_max);
            current = UVec2::new(node.child_base, (hit_mask & 0xff00_0000) | node.imask);
            prims = UVec2::new(node.primitive_base, hit_mask & 0x00ff_ffff);
        } else {
            current = UVec2::ZERO;
        }
        if prims.y == 0 && current.y & 0xff00_0000 == 0 {
            if sp == 0 {
                return;
            }
            sp -= 1;
            current = stack[sp];
        }
    }
}
