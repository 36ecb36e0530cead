//! The sampler of `sample.rs` against the plain formulation (`oracle` below: the same arithmetic
//! without the floor, bounds, weight and Morton shortcuts), **bit for bit**: the
//! GPU cone kernel's equivalence suite and the published cone figures rely on sampling never
//! changing. Random octrees (dense and sparse levels, non-power-of-two grids, virtual depth
//! above the grid, isotropic and `Directional` payloads) and random positions and levels,
//! including exact integers and half-integers (node centres and faces), positions outside the
//! cube, ±0, subnormals, huge values, NaN and ±∞.

use glam::{IVec3, UVec3, Vec3};
use proptest::prelude::*;

use super::{grid, payload_of};
use crate::octree::{NONE, sparse_neighbour};
use crate::{AveragePayload, BuildOptions, Directional, Octree, Payload};
use voxlod_format::morton;

/// `sample.rs` as it was (commit a0dd72f), written as free functions.
mod oracle {
    use super::*;

    pub fn sample_at_level<P: Payload>(t: &Octree<P>, pos: Vec3, level: f32) -> P {
        let level = if level.is_nan() { 0.0 } else { level.clamp(0.0, t.depth as f32) };
        let l0 = level.floor() as u32;
        let tt = level - l0 as f32;
        let mut out = sample_level(t, pos, l0);
        if tt > 0.0 && l0 < t.depth {
            let upper = sample_level(t, pos, l0 + 1);
            let mut mixed = P::empty();
            mixed.add_scaled(&out, 1.0 - tt);
            mixed.add_scaled(&upper, tt);
            out = mixed;
        }
        out
    }

    pub fn sample_level<P: Payload>(t: &Octree<P>, pos: Vec3, level: u32) -> P {
        let level = level.min(t.depth);
        let mut out = P::empty();
        if !pos.is_finite() {
            return out;
        }
        let res = 1i32 << (t.depth - level);
        let u = pos * (1.0 / (1u32 << level) as f32) - 0.5;
        let lower = u.floor();
        if lower.cmplt(Vec3::splat(-1.0)).any() || lower.cmpge(Vec3::splat(res as f32)).any() {
            return out;
        }
        let base = lower.as_ivec3();
        let f = u - lower;
        let start = base.max(IVec3::ZERO);
        let nodes = corners(t, level, start.as_uvec3());
        let lv = &t.levels[level as usize];
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

    fn corners<P: Payload>(t: &Octree<P>, level: u32, start: UVec3) -> [u32; 8] {
        let lv = &t.levels[level as usize];
        if lv.dense {
            let res = 1u32 << lv.res_log2;
            return std::array::from_fn(|e| {
                let c = start + UVec3::new(e as u32 & 1, e as u32 >> 1 & 1, e as u32 >> 2 & 1);
                if c.cmplt(UVec3::splat(res)).all() { morton::encode(c) as u32 } else { NONE }
            });
        }
        let mut n = [NONE; 8];
        n[0] = find(t, level, start);
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

    fn find<P: Payload>(t: &Octree<P>, level: u32, c: UVec3) -> u32 {
        let top = t.first_dense;
        let mut idx = morton::encode(c >> (top - level)) as usize;
        for lv in (level + 1..=top).rev() {
            let child = t.levels[lv as usize].child[idx];
            if child == NONE {
                return NONE;
            }
            let o = (c >> (lv - 1 - level)) & UVec3::ONE;
            idx = child as usize + (o.x + 2 * o.y + 4 * o.z) as usize;
        }
        idx as u32
    }
}

/// The exact bits of a payload's floats.
trait Bits {
    fn bits(&self) -> Vec<u32>;
}
impl Bits for AveragePayload {
    fn bits(&self) -> Vec<u32> {
        bytemuck::cast::<_, [u32; 7]>(*self).to_vec()
    }
}
impl Bits for Directional<AveragePayload> {
    fn bits(&self) -> Vec<u32> {
        let mut b = self.inner.bits();
        b.extend(self.opacity.map(f32::to_bits));
        b
    }
}

/// Every level and a few fractional levels (and odd ones) at `p`, both samplers, bit for bit.
fn check<P: Payload + Bits>(
    tree: &Octree<P>,
    p: Vec3,
    levels: &[f32],
) -> Result<(), TestCaseError> {
    for level in 0..=tree.depth() + 1 {
        let (got, want) = (tree.sample_level(p, level), oracle::sample_level(tree, p, level));
        prop_assert_eq!(got.bits(), want.bits(), "sample_level({:?}, {})", p, level);
    }
    for &level in levels {
        let got = tree.sample_at_level(p, level);
        let want = oracle::sample_at_level(tree, p, level);
        prop_assert_eq!(got.bits(), want.bits(), "sample_at_level({:?}, {:?})", p, level);
    }
    Ok(())
}

/// A coordinate: anywhere around a grid of up to `hi` voxels, integers, half-integers, or an
/// extreme value.
fn coord(hi: i32) -> impl Strategy<Value = f32> {
    prop_oneof![
        6 => -3.0f32..(hi + 3) as f32,
        2 => (-3..hi + 3).prop_map(|i| i as f32),
        2 => (-6..2 * hi + 6).prop_map(|i| i as f32 * 0.5),
        1 => prop::sample::select(vec![
            -0.0f32, 0.0, 1e-40, -1e-40, -0.5, -1.0, -1.5, f32::EPSILON, -f32::EPSILON,
            1e30, -1e30, f32::MAX, f32::MIN, f32::NAN, f32::INFINITY, f32::NEG_INFINITY,
        ]),
    ]
}

fn level() -> impl Strategy<Value = f32> {
    prop_oneof![
        4 => -1.0f32..8.0,
        2 => (0..8).prop_map(|i| i as f32),
        1 => prop::sample::select(vec![
            -0.0f32, 0.0, 1e-40, f32::EPSILON, 1.0 - f32::EPSILON / 2.0, 2.0 + 1e-6, f32::NAN,
            f32::INFINITY, f32::NEG_INFINITY, f32::MAX,
        ]),
    ]
}

/// Grid dims, occupied voxels, `dense_log2` and extra virtual depth.
fn scene() -> impl Strategy<Value = (UVec3, Vec<UVec3>, u32, u32)> {
    (1u32..=40, 1u32..=40, 1u32..=40, 0u32..=4, 0u32..=1).prop_flat_map(
        |(x, y, z, dense, extra)| {
            let coord = (0..x, 0..y, 0..z).prop_map(|(a, b, c)| [a, b, c]);
            (
                Just(UVec3::new(x, y, z)),
                proptest::collection::btree_set(coord, 0..200),
                Just(dense),
                Just(extra),
            )
                .prop_map(|(d, set, dense, extra)| {
                    (d, set.into_iter().map(UVec3::from).collect(), dense, extra)
                })
        },
    )
}

fn options(dims: UVec3, dense_log2: u32, extra: u32) -> BuildOptions {
    let depth = (dims.max_element().max(1) - 1).checked_ilog2().map_or(0, |l| l + 1);
    BuildOptions { depth: Some(depth + extra), dense_log2 }
}

fn positions() -> impl Strategy<Value = Vec<(Vec3, Vec<f32>)>> {
    let p = (coord(40), coord(40), coord(40)).prop_map(|(x, y, z)| Vec3::new(x, y, z));
    proptest::collection::vec((p, proptest::collection::vec(level(), 3)), 1..32)
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]

    /// Averages payloads: the sampler equals the plain formulation bit for bit.
    #[test]
    fn sampling_is_bit_identical_to_the_plain_formulation(
        (dims, coords, dense, extra) in scene(),
        samples in positions(),
    ) {
        let voxels = coords.iter().map(|&c| (c, payload_of(c)));
        let tree = Octree::build(grid(dims), voxels, &options(dims, dense, extra)).unwrap();
        for (p, levels) in &samples {
            check(&tree, *p, levels)?;
        }
    }

    /// `Directional` payloads (six more floats, anisotropic opacities), the same.
    #[test]
    fn directional_sampling_is_bit_identical_to_the_plain_formulation(
        (dims, coords, dense, extra) in scene(),
        samples in positions(),
    ) {
        let voxels = coords.iter().map(|&c| {
            let mut d = Directional::isotropic(payload_of(c));
            for (k, a) in d.opacity.iter_mut().enumerate() {
                *a = payload_of(c + UVec3::splat(k as u32 + 1)).opacity;
            }
            (c, d)
        });
        let tree = Octree::build(grid(dims), voxels, &options(dims, dense, extra)).unwrap();
        for (p, levels) in &samples {
            check(&tree, *p, levels)?;
        }
    }
}

/// Every node centre, face and corner (exact integers and half-integers) of a small sparse
/// octree, and the quarter points between, at every level: deterministic coverage of the
/// positions where `⌊u⌋` and the weights are most delicate.
#[test]
fn lattice_positions_are_bit_identical() {
    let dims = UVec3::new(7, 5, 6);
    let coords: Vec<UVec3> =
        (0..60u32).map(|i| UVec3::new(i * 5 % 7, i * 3 % 5, i * 7 % 6)).collect();
    for dense in [0, 1, 3] {
        let voxels = coords.iter().map(|&c| (c, payload_of(c)));
        let tree = Octree::build(grid(dims), voxels, &options(dims, dense, 0)).unwrap();
        for x in -6..=36 {
            for y in -6..=28 {
                for z in -6..=32 {
                    let p = Vec3::new(x as f32, y as f32, z as f32) * 0.25;
                    check(&tree, p, &[0.0, 0.5, 1.0, 1.25, 2.0, 2.75, 3.0]).unwrap();
                }
            }
        }
    }
}
