//! Packets of 4 camera rays from one origin ([`Bvh::intersect_packet`]): one traversal for
//! the four, sharing the stack, the node fetches and the plane offsets `plane − origin`, with a
//! per-ray box test and per-ray triangle tests. Coherent rays (the samples of one pixel, a 2×2
//! block of pixels) visit nearly the same nodes, so the shared work is most of the work.
//!
//! The answers are those of [`Bvh::intersect_filtered`] ray by ray, bit for bit: the same
//! triangle test on the same triangles, the same tie rule; a box test can only add candidates,
//! never lose one. Packets whose rays differ in direction octant or dominant axis, or hold an
//! invalid direction, are traced ray by ray.

use glam::{UVec2, Vec3, Vec4};
use obvhs::cwbvh::node::extract_byte64;

use super::traverse::{EXIT_SLACK, STACK_SIZE, WideNode, first_bit_high};
use super::triangle::ShearedRay;
use super::{Bvh, Hit, valid_ray};

/// Four rays from one origin, sharing a direction octant.
struct Packet {
    origin: Vec3,
    /// Per axis, the four rays' inverse direction components (see `BoxRay::new`).
    inv: [Vec4; 3],
    /// Per axis, the plane index (0 = min, 1 = max) the rays enter a slab through.
    near: [usize; 3],
    oct_inv4: u32,
}

impl Bvh {
    /// The closest hits of four rays from `origin` with `t_min ≤ t ≤ t_max` (`t_min` below 0
    /// counts as 0): the results of four [`Bvh::intersect`] calls, faster for coherent rays.
    #[inline]
    pub fn intersect_packet(
        &self,
        origin: Vec3,
        dirs: &[Vec3; 4],
        t_min: f32,
        t_max: f32,
    ) -> [Option<Hit>; 4] {
        self.intersect_packet_filtered(origin, dirs, t_min, t_max, |_, _| true)
    }

    /// [`Bvh::intersect_packet`] with a filter: `accept(lane, hit)` may discard a candidate of
    /// ray `lane`, as [`Bvh::intersect_filtered`]'s `accept` does.
    pub fn intersect_packet_filtered(
        &self,
        origin: Vec3,
        dirs: &[Vec3; 4],
        t_min: f32,
        t_max: f32,
        mut accept: impl FnMut(usize, &Hit) -> bool,
    ) -> [Option<Hit>; 4] {
        let single = |accept: &mut dyn FnMut(usize, &Hit) -> bool| {
            std::array::from_fn(|lane| {
                self.intersect_filtered(origin, dirs[lane], t_min, t_max, |h| accept(lane, h))
            })
        };
        if !dirs.iter().all(|&d| valid_ray(origin, d)) || t_min.is_nan() || t_max.is_nan() {
            return single(&mut accept);
        }
        let t_min = t_min.max(0.0);
        if t_min > t_max || self.nodes.is_empty() {
            return [None; 4];
        }
        // Explicit arrays: `map` on arrays is not reliably inlined.
        let sheared = |l: usize| ShearedRay::new(origin, dirs[l]);
        let rays = [sheared(0), sheared(1), sheared(2), sheared(3)];
        let d = [dirs[0], dirs[1], dirs[2], dirs[3]].map(|d| d + Vec3::ZERO); // −0 → +0
        let negative = |a: usize| d[0][a] < 0.0;
        let same = (0..3).all(|a| d.iter().all(|d| (d[a] < 0.0) == negative(a)))
            && rays.iter().all(|r| r.kz == rays[0].kz);
        if !same {
            return single(&mut accept);
        }
        let inv = |a: usize| {
            let lane = |l: usize| {
                let clamped = d[l][a].abs().max(1e-20);
                if d[l][a] < 0.0 { -clamped.recip() } else { clamped.recip() }
            };
            Vec4::new(lane(0), lane(1), lane(2), lane(3))
        };
        let near = [negative(0) as usize, negative(1) as usize, negative(2) as usize];
        let oct_inv4 = (if near[0] == 1 { 0 } else { 0x0404_0404 })
            | (if near[1] == 1 { 0 } else { 0x0202_0202 })
            | (if near[2] == 1 { 0 } else { 0x0101_0101 });
        let packet = Packet { origin, inv: [inv(0), inv(1), inv(2)], near, oct_inv4 };
        // Rays that miss the scene's bounds get an empty range: no box lets them through.
        let limit = Vec4::select(
            packet.overlaps(self.bounds, t_min, t_max),
            Vec4::splat(t_max),
            Vec4::NEG_INFINITY,
        );
        if limit == Vec4::NEG_INFINITY {
            return [None; 4];
        }
        match rays[0].kz {
            0 => self.closest_packet::<0>(&packet, &rays, t_min, limit, accept),
            1 => self.closest_packet::<1>(&packet, &rays, t_min, limit, accept),
            _ => self.closest_packet::<2>(&packet, &rays, t_min, limit, accept),
        }
    }

    fn closest_packet<const KZ: usize>(
        &self,
        packet: &Packet,
        rays: &[ShearedRay; 4],
        t_min: f32,
        mut limit: Vec4,
        mut accept: impl FnMut(usize, &Hit) -> bool,
    ) -> [Option<Hit>; 4] {
        let mut best: [Option<Hit>; 4] = [None; 4];
        let mut stack = [UVec2::ZERO; STACK_SIZE];
        let mut sp = 0usize;
        let mut current = UVec2::new(0, 0x8000_0000);
        // Leaf primitives to test, and per ray which of them its box tests let through.
        let mut prims = UVec2::ZERO;
        let mut lane_prims = [0u32; 4];
        loop {
            while prims.y != 0 {
                let local = first_bit_high(prims.y);
                prims.y &= !(1 << local);
                let slot = (prims.x + local) as usize;
                let tri = &self.triangles[slot];
                for (lane, ray) in rays.iter().enumerate() {
                    if lane_prims[lane] & (1 << local) == 0 {
                        continue;
                    }
                    if let Some(h) = ray.intersect::<KZ>(tri, t_min, limit[lane]) {
                        let triangle = self.ids[slot];
                        let closer = match best[lane] {
                            None => true,
                            Some(b) => h.t < b.t || (h.t == b.t && triangle < b.triangle),
                        };
                        let hit = Hit { t: h.t, triangle, u: h.u, v: h.v };
                        if closer && accept(lane, &hit) {
                            best[lane] = Some(hit);
                            limit[lane] = h.t;
                        }
                    }
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
                let slot = (offset - 24) ^ (packet.oct_inv4 & 0xff);
                let relative = (hits & !(u32::MAX << slot)).count_ones();
                let node = &self.nodes[(current.x + relative) as usize];
                let masks = packet.intersect_node(node, t_min, limit);
                let union = masks[0] | masks[1] | masks[2] | masks[3];
                current = UVec2::new(node.child_base, (union & 0xff00_0000) | node.imask);
                prims = UVec2::new(node.primitive_base, union & 0x00ff_ffff);
                for (lane, m) in lane_prims.iter_mut().zip(masks) {
                    *lane = m & 0x00ff_ffff;
                }
            } else {
                current = UVec2::ZERO;
            }
            if prims.y == 0 && current.y & 0xff00_0000 == 0 {
                if sp == 0 {
                    return best;
                }
                sp -= 1;
                current = stack[sp];
            }
        }
    }
}

impl Packet {
    /// Per ray, whether `[t_min, t_max]` overlaps the box `(lo, hi)` (as `BoxRay::overlaps`).
    #[inline(always)]
    fn overlaps(&self, (lo, hi): (Vec3, Vec3), t_min: f32, t_max: f32) -> glam::BVec4A {
        let mut near = Vec4::splat(t_min);
        let mut far = Vec4::splat(f32::INFINITY);
        for a in 0..3 {
            let t1 = Vec4::splat(lo[a] - self.origin[a]) * self.inv[a];
            let t2 = Vec4::splat(hi[a] - self.origin[a]) * self.inv[a];
            near = near.max(t1.min(t2));
            far = far.min(t1.max(t2));
        }
        near.cmple((far * EXIT_SLACK).min(Vec4::splat(t_max)))
    }

    /// The CWBVH hit mask of each ray for `node` (see `BoxRay::intersect_node`).
    #[inline(always)]
    fn intersect_node(&self, node: &WideNode, t_min: f32, t_max: Vec4) -> [u32; 4] {
        let (child_bits8, bit_index8) = node.child_and_index_bits(self.oct_inv4);
        let mut child_masks = [0u32; 4];
        for half in 0..2 {
            // Plane offsets from the shared origin, for near and far planes of each axis.
            let rel = |a: usize, far: bool| {
                let k = 2 * a + (self.near[a] ^ far as usize);
                node.planes[k][half] - Vec4::splat(self.origin[a])
            };
            let (nx, ny, nz) = (rel(0, false), rel(1, false), rel(2, false));
            let (fx, fy, fz) = (rel(0, true), rel(1, true), rel(2, true));
            for (lane, mask) in child_masks.iter_mut().enumerate() {
                let inv = |a: usize| Vec4::splat(self.inv[a][lane]);
                let near = (nx * inv(0)).max(ny * inv(1)).max(nz * inv(2)).max(Vec4::splat(t_min));
                let far = ((fx * inv(0)).min(fy * inv(1)).min(fz * inv(2)) * EXIT_SLACK)
                    .min(Vec4::splat(t_max[lane]));
                *mask |= near.cmple(far).bitmask() << (4 * half);
            }
        }
        // Array `map` is not reliably inlined here: plain loops.
        let mut hit_masks = [0u32; 4];
        for (hit_mask, mut m) in hit_masks.iter_mut().zip(child_masks) {
            while m != 0 {
                let child = m.trailing_zeros() as usize;
                m &= m - 1;
                *hit_mask |=
                    extract_byte64(child_bits8, child) << extract_byte64(bit_index8, child);
            }
        }
        hit_masks
    }
}
