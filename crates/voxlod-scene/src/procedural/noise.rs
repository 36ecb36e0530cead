//! Value noise in 2D and 3D from a lattice hash, and its fractal sum: the terrain of `island` and
//! the lumpy surface of its rocks. Only `+`, `−`, `×` and `floor` are used, so the noise is the
//! same bit for bit on every platform (see [`super::rng`]).

use glam::{Vec2, Vec3};

use super::rng::mix64;

/// A lattice value in [−1, 1) for integer point `(x, y, z)` under `seed`.
#[inline]
fn lattice(seed: u64, x: i32, y: i32, z: i32) -> f32 {
    let h = mix64(
        seed ^ (x as u32 as u64).wrapping_mul(0x8CB9_2BA7_2F3D_8DD7)
            ^ (y as u32 as u64).wrapping_mul(0xE9F8_CC1D_3F3A_6E0B).rotate_left(21)
            ^ (z as u32 as u64).wrapping_mul(0xB3E4_C9B2_0E4F_58A1).rotate_left(42),
    );
    (h >> 40) as f32 * (2.0 / (1u32 << 24) as f32) - 1.0
}

/// The quintic fade 6t⁵ − 15t⁴ + 10t³ (C² continuous, so normals of the terrain are smooth).
#[inline]
fn fade(t: f32) -> f32 {
    t * t * t * (t * (t * 6.0 - 15.0) + 10.0)
}

/// Cell index and fractional position of a coordinate. Coordinates beyond ±2³¹ saturate.
#[inline]
fn split(x: f32) -> (i32, f32) {
    let f = x.floor();
    (f as i32, x - f)
}

/// 2D value noise in [−1, 1], interpolating lattice values at integer points.
pub fn value2(seed: u64, p: Vec2) -> f32 {
    let (ix, fx) = split(p.x);
    let (iy, fy) = split(p.y);
    let (u, v) = (fade(fx), fade(fy));
    let l = |dx, dy| lattice(seed, ix.wrapping_add(dx), iy.wrapping_add(dy), 0);
    let a = l(0, 0) + (l(1, 0) - l(0, 0)) * u;
    let b = l(0, 1) + (l(1, 1) - l(0, 1)) * u;
    a + (b - a) * v
}

/// 3D value noise in [−1, 1].
pub fn value3(seed: u64, p: Vec3) -> f32 {
    let (ix, fx) = split(p.x);
    let (iy, fy) = split(p.y);
    let (iz, fz) = split(p.z);
    let (u, v, w) = (fade(fx), fade(fy), fade(fz));
    let l =
        |dx, dy, dz| lattice(seed, ix.wrapping_add(dx), iy.wrapping_add(dy), iz.wrapping_add(dz));
    let lerp = |a: f32, b: f32, t: f32| a + (b - a) * t;
    let face = |dz| lerp(lerp(l(0, 0, dz), l(1, 0, dz), u), lerp(l(0, 1, dz), l(1, 1, dz), u), v);
    lerp(face(0), face(1), w)
}

/// Fractal sum of `octaves` layers of [`value2`], each at twice the frequency and half the
/// amplitude of the previous, normalized to [−1, 1].
pub fn fbm2(seed: u64, p: Vec2, octaves: u32) -> f32 {
    let (mut sum, mut norm, mut amp, mut freq) = (0.0, 0.0, 1.0, 1.0);
    for o in 0..octaves {
        sum += amp * value2(seed.wrapping_add(o as u64), p * freq);
        norm += amp;
        amp *= 0.5;
        freq *= 2.0;
    }
    if norm > 0.0 { sum / norm } else { 0.0 }
}

/// Fractal sum of `octaves` layers of [`value3`], normalized to [−1, 1] like [`fbm2`]: the
/// displacement of the particles' cube maps.
pub fn fbm3(seed: u64, p: Vec3, octaves: u32) -> f32 {
    let (mut sum, mut norm, mut amp, mut freq) = (0.0, 0.0, 1.0, 1.0);
    for o in 0..octaves {
        sum += amp * value3(seed.wrapping_add(o as u64), p * freq);
        norm += amp;
        amp *= 0.5;
        freq *= 2.0;
    }
    if norm > 0.0 { sum / norm } else { 0.0 }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn noise_is_bounded_continuous_and_hits_the_lattice_values() {
        for i in 0..2_000 {
            let p = Vec2::new(i as f32 * 0.173 - 50.0, i as f32 * 0.091 + 3.0);
            let v = value2(5, p);
            assert!((-1.0..=1.0).contains(&v), "{v} at {p}");
            // Continuity: a tiny step changes the value by little (the fade's slope is ≤ 1.875).
            let dv = (value2(5, p + Vec2::splat(1e-3)) - v).abs();
            assert!(dv < 1e-2, "jump {dv} at {p}");
            let q = Vec3::new(p.x, p.y, p.x * 0.5);
            assert!((-1.0..=1.0).contains(&value3(9, q)));
            assert!((-1.0..=1.0).contains(&fbm2(9, p, 4)));
            assert!((-1.0..=1.0).contains(&fbm3(9, q, 4)));
        }
        assert_eq!(value2(5, Vec2::new(3.0, -2.0)), lattice(5, 3, -2, 0));
        assert_eq!(value3(5, Vec3::new(1.0, 2.0, 3.0)), lattice(5, 1, 2, 3));
    }

    #[test]
    fn seeds_give_different_fields() {
        let p = Vec2::new(0.37, 0.61);
        let values: Vec<f32> = (0..8).map(|s| value2(s, p)).collect();
        let distinct = values.iter().filter(|&&v| v != values[0]).count();
        assert!(distinct >= 6, "{values:?}");
        assert!(fbm2(1, p, 4) != fbm2(2, p, 4));
    }
}
