//! Shadow rays toward a directional light, walked from one precomputed step pattern.
//!
//! Every shadow ray of a directional light has the same direction `d` and starts at a voxel
//! centre, `o = c + ½` exactly in grid coordinates. The DDA crosses plane `k` of an axis at
//! `(k − o)·(1/d)`, and in `f32` `k − (c + ½) = (k − c) − ½` exactly (coordinates are below
//! 2²¹), so the crossing times — and with them the order of the cells, the tie rules at
//! edges and corners, and every `t_enter`/`t_exit` — depend only on the offset `k − c`: every
//! shadow ray walks the same sequence of cell offsets with bit-identical times. The
//! [`ShadowPattern`] is that sequence, walked once per light (the [`Dda`]'s own stepping), and
//! for each of the 512 start positions inside an 8³ brick, the runs of consecutive steps that
//! fall in one brick. A shadow ray then goes run by run: one brick look-up per brick it
//! crosses (unallocated: on to the next run, with no plane arithmetic at all) and, inside an
//! allocated brick, one mask bit per step. It meets the voxels a [`Dda`] walk from `c + ½`
//! meets, with the same chords, in the same order (tested bit for bit), so the transmittance is
//! the same `f32`.
//!
//! A ray leaves the grid on the far side of a brick that lies outside the grid's bricks (the
//! walk stops there: the grid is convex) or through the unoccupied tail of a partial brick
//! (those voxels have no record, so they change nothing).

use glam::{IVec3, UVec3, Vec3};
use rayon::prelude::*;
use voxlod_format::BRICK_EDGE;

use super::super::dda::Dda;

/// One cell of the pattern: its offset from the start cell and the ray's `t` on entering
/// and leaving it.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Step {
    offset: IVec3,
    /// Whether the shadow rule ignores this cell (centre closer than 1.5 voxel sizes).
    skip: bool,
    t_enter: f32,
    t_exit: f32,
}

/// Consecutive steps `first..end` of the pattern that lie in one brick, at `brick` (in
/// bricks) from the start cell's brick.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct Run {
    brick: IVec3,
    first: u32,
    end: u32,
}

/// The cell offsets every shadow ray toward one directional light crosses, and their brick
/// runs per start position (see the [module docs](self)).
#[derive(Clone, Debug)]
pub(super) struct ShadowPattern {
    steps: Vec<Step>,
    runs: Vec<Run>,
    /// Runs of start position `p` (`x + 8y + 64z` within its brick): `runs[starts[p]..starts[p + 1]]`.
    starts: Vec<u32>,
}

/// Positions within a brick.
const POSITIONS: usize = (BRICK_EDGE * BRICK_EDGE * BRICK_EDGE) as usize;

impl ShadowPattern {
    /// The pattern of rays with grid-space direction `d` (world direction toward the light
    /// divided by the voxel size) in a grid of `dims` voxels: every step a ray from any voxel
    /// centre can take before it leaves the grid. `skip_sq`: offsets with `|offset|²` up to it
    /// are marked skipped. A zero or non-finite direction gives the empty pattern.
    pub fn new(dims: UVec3, d: Vec3, skip_sq: i32) -> Self {
        // A walk from the centre of cell `dims` (so that no grid bound cuts it short) through a
        // grid twice as large: the offsets reach ±dims on every axis, past which every ray has
        // left the grid.
        let big = dims * 2 + 1;
        let mut steps = Vec::new();
        for v in Dda::in_grid_space(big, dims.as_vec3() + 0.5, d, 0.0, f32::INFINITY) {
            let offset = v.voxel.as_ivec3() - dims.as_ivec3();
            if offset.abs().cmpge(dims.as_ivec3()).any() {
                break;
            }
            steps.push(Step {
                offset,
                skip: offset.length_squared() <= skip_sq,
                t_enter: v.t_enter,
                t_exit: v.t_exit,
            });
        }
        let per_position: Vec<Vec<Run>> = (0..POSITIONS as u32)
            .into_par_iter()
            .map(|p| {
                let start = position(p);
                let mut runs: Vec<Run> = Vec::new();
                for (i, s) in steps.iter().enumerate() {
                    // Arithmetic shifts: the floor of a division by 8, negatives included.
                    let brick = (start + s.offset) >> 3;
                    match runs.last_mut() {
                        Some(r) if r.brick == brick => r.end = i as u32 + 1,
                        _ => runs.push(Run { brick, first: i as u32, end: i as u32 + 1 }),
                    }
                }
                runs
            })
            .collect();
        let mut starts = Vec::with_capacity(POSITIONS + 1);
        let mut runs = Vec::new();
        for r in per_position {
            starts.push(runs.len() as u32);
            runs.extend(r);
        }
        starts.push(runs.len() as u32);
        Self { steps, runs, starts }
    }

    /// Heap bytes held.
    pub fn memory_bytes(&self) -> usize {
        self.steps.capacity() * size_of::<Step>()
            + self.runs.capacity() * size_of::<Run>()
            + self.starts.capacity() * size_of::<u32>()
    }

    /// Walks the shadow ray from the centre of `voxel` up to `t_max`: for each voxel it meets
    /// that is not skipped and that `brick_of` (a brick coordinate inside the grid's
    /// `brick_dims` → brick number) and `occupied` (brick number, linear index
    /// `x + 8y + 64z` in it → whether to visit) accept, calls `visit(brick number, linear
    /// index, voxel, chord in t)` and stops when it returns `false`.
    #[inline]
    pub fn walk(
        &self,
        voxel: UVec3,
        brick_dims: UVec3,
        t_max: f32,
        brick_of: impl Fn(UVec3) -> Option<u32>,
        occupied: impl Fn(u32, u32) -> bool,
        mut visit: impl FnMut(u32, u32, UVec3, f32) -> bool,
    ) {
        let local = voxel % BRICK_EDGE;
        let p = (local.x | local.y << 3 | local.z << 6) as usize;
        let start = local.as_ivec3();
        let home = (voxel / BRICK_EDGE).as_ivec3();
        let bricks = brick_dims.as_ivec3();
        let runs = &self.runs[self.starts[p] as usize..self.starts[p + 1] as usize];
        // A NaN bound meets nothing, as in the DDA.
        if t_max.is_nan() {
            return;
        }
        for run in runs {
            let steps = &self.steps[run.first as usize..run.end as usize];
            if steps[0].t_enter >= t_max {
                return;
            }
            let b = home + run.brick;
            if (b.cmplt(IVec3::ZERO) | b.cmpge(bricks)).any() {
                return;
            }
            let Some(brick) = brick_of(b.as_uvec3()) else { continue };
            for s in steps {
                if s.t_enter >= t_max {
                    return;
                }
                let l = (start + s.offset) & 7;
                let linear = (l.x | l.y << 3 | l.z << 6) as u32;
                if s.skip || !occupied(brick, linear) {
                    continue;
                }
                let at = (voxel.as_ivec3() + s.offset).as_uvec3();
                if !visit(brick, linear, at, s.t_exit.min(t_max) - s.t_enter) {
                    return;
                }
            }
        }
    }
}

/// The local coordinate of start position `p = x + 8y + 64z`.
fn position(p: u32) -> IVec3 {
    IVec3::new((p & 7) as i32, (p >> 3 & 7) as i32, (p >> 6) as i32)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::random::{rand_f32, rand_u32};
    use crate::render::bricks::{BrickLookup, BrickMasks, Occupancy, brick_masks};
    use voxlod_format::BrickMap;

    /// Every visit of the pattern walk, in order.
    fn pattern_visits(
        pattern: &ShadowPattern,
        map: &BrickMap<()>,
        masks: &[BrickMasks],
        voxel: UVec3,
        t_max: f32,
    ) -> Vec<(UVec3, u32, f32)> {
        let mut out = Vec::new();
        pattern.walk(
            voxel,
            map.brick_dims(),
            t_max,
            |b| BrickLookup::brick_index(map, b),
            |b, i| masks[b as usize].has_voxel_linear(i),
            |b, _, v, chord| {
                out.push((v, b, chord));
                true
            },
        );
        out
    }

    /// Every voxel a DDA walk from the exact centre meets, with the shadow rule's skip.
    fn dda_visits(
        map: &BrickMap<()>,
        masks: &[BrickMasks],
        voxel: UVec3,
        d: Vec3,
        t_max: f32,
    ) -> Vec<(UVec3, u32, f32)> {
        let occ = Occupancy { bricks: map, masks };
        let mut dda = Dda::in_grid_space(map.dims(), voxel.as_vec3() + 0.5, d, 0.0, t_max);
        let mut out = Vec::new();
        while let Some(v) = dda.next_occupied_voxel(&occ) {
            if (v.voxel.as_ivec3() - voxel.as_ivec3()).length_squared() <= 2 {
                continue;
            }
            out.push((v.voxel, v.brick, v.t_exit - v.t_enter));
        }
        out
    }

    /// A random grid with about `fill` of its voxels occupied, in clumps.
    fn random_map(seed: u32, dims: UVec3, fill: f32) -> BrickMap<()> {
        let mut voxels = std::collections::BTreeSet::new();
        let n = (dims.as_vec3().element_product() * fill) as u32;
        for i in 0..n {
            let r = |k| rand_u32(seed, i, k);
            // Half the voxels in a slab, so that some bricks are dense and some empty.
            let mut c = UVec3::new(r(0) % dims.x, r(1) % dims.y, r(2) % dims.z);
            if i % 2 == 0 {
                c.y = (dims.y / 3 + r(3) % 3).min(dims.y - 1);
            }
            voxels.insert((c.z, c.y, c.x));
        }
        BrickMap::from_voxels(dims, voxels.into_iter().map(|(z, y, x)| (UVec3::new(x, y, z), ())))
            .unwrap()
    }

    #[test]
    fn pattern_walks_meet_what_the_dda_meets_bit_for_bit() {
        let mut checked = 0;
        for case in 0..40u32 {
            let r = |k| rand_u32(case, 1, k);
            let f = |k| rand_f32(case, 2, k);
            let dims = UVec3::new(1 + r(0) % 40, 1 + r(1) % 40, 1 + r(2) % 40);
            let map = random_map(case, dims, 0.1 + 0.4 * f(3));
            let masks = brick_masks(&map);
            // Directions: random, axis-aligned, diagonal (corner ties), in a coordinate plane.
            let mut d = Vec3::new(f(4) - 0.5, f(5) - 0.5, f(6) - 0.5);
            match case % 5 {
                1 => d = Vec3::new(0.0, 1.0, 0.0),
                2 => d = Vec3::new(-1.0, 1.0, 1.0),
                3 => d.z = 0.0,
                _ => {}
            }
            let size = 0.25 + 2.0 * f(7);
            let d = d.normalize() / size;
            let pattern = ShadowPattern::new(dims, d, 2);
            for v in 0..60u32 {
                let c = UVec3::new(r(10 + v) % dims.x, r(100 + v) % dims.y, r(200 + v) % dims.z);
                let t_max = match v % 4 {
                    0 => f32::INFINITY,
                    1 => 3.0 * f(300 + v) * size,
                    2 => -1.0,
                    _ => f32::NAN,
                };
                let got = pattern_visits(&pattern, &map, &masks, c, t_max);
                let want = dda_visits(&map, &masks, c, d, t_max);
                // Bit for bit: chords compared as bits.
                let bits = |v: &[(UVec3, u32, f32)]| {
                    v.iter().map(|&(c, b, t)| (c, b, t.to_bits())).collect::<Vec<_>>()
                };
                assert_eq!(bits(&got), bits(&want), "case {case}, voxel {c}, t_max {t_max}");
                checked += want.len();
            }
        }
        assert!(checked > 1000, "too few voxels met to mean anything: {checked}");
    }

    #[test]
    fn degenerate_directions_give_an_empty_pattern() {
        for d in [Vec3::ZERO, Vec3::NAN, Vec3::new(f32::INFINITY, 0.0, 0.0)] {
            let p = ShadowPattern::new(UVec3::splat(9), d, 2);
            assert!(p.steps.is_empty(), "{d}");
            let mut met = 0;
            p.walk(
                UVec3::ONE,
                UVec3::splat(2),
                f32::INFINITY,
                |_| Some(0),
                |_, _| true,
                |_, _, _, _| {
                    met += 1;
                    true
                },
            );
            assert_eq!(met, 0);
        }
    }

    #[test]
    fn runs_partition_the_steps_by_brick() {
        let dims = UVec3::new(30, 17, 23);
        let pattern = ShadowPattern::new(dims, Vec3::new(0.3, -0.8, 0.52), 2);
        assert!(pattern.steps.len() > 30);
        for p in 0..POSITIONS {
            let runs = &pattern.runs[pattern.starts[p] as usize..pattern.starts[p + 1] as usize];
            assert_eq!(runs.first().unwrap().first, 0);
            assert_eq!(runs.last().unwrap().end as usize, pattern.steps.len());
            for w in runs.windows(2) {
                assert_eq!(w[0].end, w[1].first);
                assert_ne!(w[0].brick, w[1].brick);
            }
            for r in runs {
                for s in &pattern.steps[r.first as usize..r.end as usize] {
                    assert_eq!(
                        (position(p as u32) + s.offset).div_euclid(IVec3::splat(8)),
                        r.brick
                    );
                }
            }
        }
    }
}
