//! 63-bit 3D Morton codes: 21 bits per axis, x in the lowest bit of each triple
//! (`code = … z1 y1 x1 z0 y0 x0`). Sorting voxels by Morton code groups them by brick and by
//! octree node at every level, which is the order [`crate::BrickMap`] iterates in.

use glam::UVec3;

/// Bits per axis in a 63-bit Morton code.
pub const BITS_PER_AXIS: u32 = 21;
/// Largest coordinate (exclusive) a Morton code can hold on each axis: 2²¹.
pub const MAX_COORD: u32 = 1 << BITS_PER_AXIS;

/// Spreads the low 21 bits of `v` so that bit `i` moves to bit `3i`.
#[inline]
pub const fn part1by2(v: u32) -> u64 {
    let mut x = (v & 0x1f_ffff) as u64;
    x = (x | (x << 32)) & 0x001f_0000_0000_ffff;
    x = (x | (x << 16)) & 0x001f_0000_ff00_00ff;
    x = (x | (x << 8)) & 0x100f_00f0_0f00_f00f;
    x = (x | (x << 4)) & 0x10c3_0c30_c30c_30c3;
    x = (x | (x << 2)) & 0x1249_2492_4924_9249;
    x
}

/// Inverse of [`part1by2`]: gathers every third bit, starting at bit 0.
#[inline]
pub const fn compact1by2(v: u64) -> u32 {
    let mut x = v & 0x1249_2492_4924_9249;
    x = (x | (x >> 2)) & 0x10c3_0c30_c30c_30c3;
    x = (x | (x >> 4)) & 0x100f_00f0_0f00_f00f;
    x = (x | (x >> 8)) & 0x001f_0000_ff00_00ff;
    x = (x | (x >> 16)) & 0x001f_0000_0000_ffff;
    x = (x | (x >> 32)) & 0x1f_ffff;
    x as u32
}

/// Morton code of `c`. Coordinates must be below [`MAX_COORD`]; higher bits are discarded
/// (checked in debug builds).
///
/// ```
/// use glam::UVec3;
/// use voxlod_format::morton;
/// assert_eq!(morton::encode(UVec3::new(1, 0, 0)), 0b001);
/// assert_eq!(morton::encode(UVec3::new(0, 1, 0)), 0b010);
/// assert_eq!(morton::encode(UVec3::new(0, 0, 1)), 0b100);
/// assert_eq!(morton::decode(morton::encode(UVec3::new(5, 9, 1234))), UVec3::new(5, 9, 1234));
/// ```
#[inline]
pub const fn encode(c: UVec3) -> u64 {
    debug_assert!(c.x < MAX_COORD && c.y < MAX_COORD && c.z < MAX_COORD);
    part1by2(c.x) | (part1by2(c.y) << 1) | (part1by2(c.z) << 2)
}

/// Coordinates of a Morton code.
#[inline]
pub const fn decode(code: u64) -> UVec3 {
    UVec3::new(compact1by2(code), compact1by2(code >> 1), compact1by2(code >> 2))
}

/// The Morton-code bits of each axis (x: bits 0, 3, 6, …; y: 1, 4, 7, …; z: 2, 5, 8, …).
pub const AXIS_BITS: [u64; 3] =
    [0x1249_2492_4924_9249, 0x1249_2492_4924_9249 << 1, 0x1249_2492_4924_9249 << 2];

/// The code one step down axis `axis` (0, 1, 2), or `None` at coordinate 0, without decoding.
///
/// ```
/// use glam::UVec3;
/// use voxlod_format::morton::{encode, step_down};
/// assert_eq!(step_down(encode(UVec3::new(4, 7, 1)), 1), Some(encode(UVec3::new(4, 6, 1))));
/// assert_eq!(step_down(encode(UVec3::new(4, 0, 1)), 1), None);
/// ```
#[inline]
pub fn step_down(code: u64, axis: usize) -> Option<u64> {
    let m = AXIS_BITS[axis];
    let field = code & m;
    (field != 0).then_some((field.wrapping_sub(1) & m) | (code & !m))
}

/// The code one step up axis `axis` (0, 1, 2) in a grid of `2^res_log2` cells per axis
/// (`res_log2` ≤ 21), or `None` past the grid's edge, without decoding.
///
/// ```
/// use glam::UVec3;
/// use voxlod_format::morton::{encode, step_up};
/// assert_eq!(step_up(encode(UVec3::new(3, 0, 0)), 0, 3), Some(encode(UVec3::new(4, 0, 0))));
/// assert_eq!(step_up(encode(UVec3::new(7, 0, 0)), 0, 3), None);
/// ```
#[inline]
pub fn step_up(code: u64, axis: usize, res_log2: u32) -> Option<u64> {
    let m = AXIS_BITS[axis];
    // The field of coordinate `2^res_log2 − 1`: every axis bit below bit 3·res_log2.
    if code & m == m & ((1u64 << (3 * res_log2)) - 1) {
        return None;
    }
    Some(((code | !m).wrapping_add(1)) & m | (code & !m))
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn encode_naive(c: UVec3) -> u64 {
        (0..BITS_PER_AXIS).fold(0, |acc, i| {
            acc | ((((c.x >> i) & 1) as u64) << (3 * i))
                | ((((c.y >> i) & 1) as u64) << (3 * i + 1))
                | ((((c.z >> i) & 1) as u64) << (3 * i + 2))
        })
    }

    #[test]
    fn extreme_coordinates_fill_63_bits() {
        let max = UVec3::splat(MAX_COORD - 1);
        assert_eq!(encode(max), (1u64 << 63) - 1);
        assert_eq!(decode((1u64 << 63) - 1), max);
        assert_eq!(encode(UVec3::ZERO), 0);
    }

    proptest! {
        #[test]
        fn round_trip(x in 0..MAX_COORD, y in 0..MAX_COORD, z in 0..MAX_COORD) {
            let c = UVec3::new(x, y, z);
            prop_assert_eq!(decode(encode(c)), c);
            prop_assert_eq!(encode(c), encode_naive(c));
        }

        #[test]
        fn order_groups_octree_cells(x in 0..MAX_COORD, y in 0..MAX_COORD, z in 0..MAX_COORD, level in 0..BITS_PER_AXIS) {
            // Dropping 3·level low bits of the code is the code of the parent cell at that level.
            let c = UVec3::new(x, y, z);
            prop_assert_eq!(encode(c) >> (3 * level), encode(c >> level));
        }
    }

    proptest! {
        /// The Morton-code steps (no decode) against decode, step, encode.
        #[test]
        fn morton_steps_equal_decode_step_encode(x in 0u32..1 << 21, y in 0u32..1 << 21, z in 0u32..1 << 21, res_log2 in 0u32..=21) {
            let c = UVec3::new(x, y, z) & UVec3::splat((1u32 << res_log2) - 1);
            let code = encode(c);
            for a in 0..3 {
                let mut up = c;
                up[a] += 1;
                let want_up = (up[a] < 1 << res_log2).then(|| encode(up));
                prop_assert_eq!(step_up(code, a, res_log2), want_up);
                let want_down = (c[a] > 0).then(|| { let mut d = c; d[a] -= 1; encode(d) });
                prop_assert_eq!(step_down(code, a), want_down);
            }
        }
    }

    #[test]
    fn morton_steps_stop_at_the_edges() {
        for res_log2 in [0, 1, 5, 21] {
            let max = UVec3::splat((1u32 << res_log2) - 1);
            for a in 0..3 {
                assert_eq!(step_up(encode(max), a, res_log2), None, "{res_log2} {a}");
                assert_eq!(step_down(0, a), None);
            }
        }
    }
}
