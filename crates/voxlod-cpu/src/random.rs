//! Counter-based random numbers, the CPU↔GPU contract: a number is a pure function of
//! `(id, sample, dimension)` (id = pixel or voxel index, sample = sample index, dimension =
//! which coordinate of the sample), computed with wrapping `u32` arithmetic that WGSL reproduces
//! bit for bit. No state, so any thread or GPU invocation can draw any number in any order.
//!
//! The hash is PCG3D (Jarzynski & Olano, "Hash Functions for GPU Rendering", JCGT 2020),
//! returning its first component.

/// PCG3D hash of three words.
#[inline]
pub const fn pcg3d(x: u32, y: u32, z: u32) -> [u32; 3] {
    let mut v = [
        x.wrapping_mul(1_664_525).wrapping_add(1_013_904_223),
        y.wrapping_mul(1_664_525).wrapping_add(1_013_904_223),
        z.wrapping_mul(1_664_525).wrapping_add(1_013_904_223),
    ];
    v[0] = v[0].wrapping_add(v[1].wrapping_mul(v[2]));
    v[1] = v[1].wrapping_add(v[2].wrapping_mul(v[0]));
    v[2] = v[2].wrapping_add(v[0].wrapping_mul(v[1]));
    v[0] ^= v[0] >> 16;
    v[1] ^= v[1] >> 16;
    v[2] ^= v[2] >> 16;
    v[0] = v[0].wrapping_add(v[1].wrapping_mul(v[2]));
    v[1] = v[1].wrapping_add(v[2].wrapping_mul(v[0]));
    v[2] = v[2].wrapping_add(v[0].wrapping_mul(v[1]));
    v
}

/// A random `u32` for `(id, sample, dimension)`.
#[inline]
pub const fn rand_u32(id: u32, sample: u32, dim: u32) -> u32 {
    pcg3d(id, sample, dim)[0]
}

/// A random `f32` in [0, 1) for `(id, sample, dimension)`, from the top 24 bits (exactly
/// representable, so both backends produce the same float).
#[inline]
pub fn rand_f32(id: u32, sample: u32, dim: u32) -> f32 {
    (rand_u32(id, sample, dim) >> 8) as f32 * (1.0 / 16_777_216.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn known_values_pin_the_contract() {
        // These values are what the WGSL mirror must produce too.
        assert_eq!(rand_u32(0, 0, 0), pcg3d(0, 0, 0)[0]);
        let a = rand_u32(1, 2, 3);
        assert_eq!(a, rand_u32(1, 2, 3));
        assert_ne!(a, rand_u32(1, 3, 2));
        assert_ne!(a, rand_u32(2, 1, 3));
    }

    #[test]
    fn uniform_enough_for_sampling() {
        // Mean and a 16-bin histogram over 2^16 draws along each argument.
        for axis in 0..3 {
            let mut bins = [0u32; 16];
            let mut sum = 0.0f64;
            let n = 1u32 << 16;
            for i in 0..n {
                let (id, s, d) = match axis {
                    0 => (i, 7, 1),
                    1 => (7, i, 1),
                    _ => (7, 1, i),
                };
                let x = rand_f32(id, s, d);
                assert!((0.0..1.0).contains(&x));
                sum += x as f64;
                bins[(x * 16.0) as usize] += 1;
            }
            let mean = sum / n as f64;
            assert!((mean - 0.5).abs() < 0.01, "axis {axis}: mean {mean}");
            let expected = n / 16;
            for b in bins {
                assert!(b.abs_diff(expected) < expected / 10, "axis {axis}: bins {bins:?}");
            }
        }
    }
}
