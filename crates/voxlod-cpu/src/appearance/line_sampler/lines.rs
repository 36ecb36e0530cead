//! The sampling lines of §1 as pure functions of integers: a uniform direction, the exact
//! face choice over the voxel's projection, the entry point and the chord, one line at a time
//! ([`sample_line`]) or a batch at once ([`LineBatch::fill`], the same numbers computed with
//! wide SIMD where the CPU has it). The directional-opacity pattern reuses the face choice.

use glam::Vec3;

use crate::random::{rand_f32, rand_u32};

/// The largest `f32` below 1.
const ONE_BELOW: f32 = 1.0 - f32::EPSILON / 2.0;

/// Half the step of [`rand_f32`] (2⁻²⁵): added to a random number, it maps `[0, 1)` into the
/// open interval `(0, 1)`.
const HALF_STEP: f32 = 1.0 / 33_554_432.0;

/// Picks the entry face of a line of direction `d` from a uniform `u ∈ [0, 1)`: axis `k` with
/// probability `|d_k| / Σ|d|` (the share of face `k` in the voxel's projected area along `d`).
/// Also returns the remainder `(u·Σ|d| − Σ_{j<k}|d_j|) / |d_k|` ∈ [0, 1), which is uniform and
/// independent of the choice (the directional-opacity pattern reuses it as an in-face
/// coordinate). A zero or non-finite `d` gives axis 2 and `u`.
#[inline]
pub fn choose_face(d: Vec3, u: f32) -> (usize, f32) {
    let a = d.abs();
    let sum = a.x + a.y + a.z;
    if !(sum > 0.0 && sum.is_finite()) {
        return (2, u);
    }
    // Branch-free: the choice is random, so branches on it would mispredict half the time.
    let x = u * sum;
    let ab = a.x + a.y;
    let k = (x >= a.x) as usize + (x >= ab) as usize;
    let (below, share) = ([0.0, a.x, ab][k], [a.x, a.y, a.z][k]);
    if share > 0.0 {
        (k, ((x - below) / share).clamp(0.0, ONE_BELOW))
    } else {
        // Rounding put u on an axis of zero share: take the dominant axis instead.
        (a.max_position(), u)
    }
}

/// The point where a line of direction `d` enters the unit voxel through face axis `k`
/// (`0` on that axis if `d_k > 0`, `1` otherwise), with in-face coordinates `s` on axis
/// `(k+1) mod 3` and `t` on axis `(k+2) mod 3`.
#[inline]
pub fn entry_point(d: Vec3, k: usize, s: f32, t: f32) -> Vec3 {
    // Indexed stores rather than branches on k, which is random.
    let mut e = [0.0; 3];
    e[k] = if d.to_array()[k] > 0.0 { 0.0 } else { 1.0 };
    e[[1, 2, 0][k]] = s;
    e[[2, 0, 1][k]] = t;
    Vec3::from_array(e)
}

/// Length of `entry + t·d`, `t ≥ 0`, inside the closed unit voxel, for a unit `d` and an
/// `entry` on the voxel's boundary: voxel units. Zero when the line leaves at once (it only
/// touches the voxel) or `d` is zero.
#[inline]
pub fn chord(entry: Vec3, d: Vec3) -> f32 {
    // Slabs: the exit parameter per axis is the larger of its two plane crossings; an axis
    // with d = 0 never ends the chord.
    let inv = d.recip();
    let far = (-entry * inv).max((Vec3::ONE - entry) * inv);
    let t = Vec3::select(d.cmpeq(Vec3::ZERO), Vec3::INFINITY, far).min_element();
    if t.is_finite() { t.max(0.0) } else { 0.0 }
}

/// A uniform direction on the unit sphere from two uniform numbers in `[0, 1)`:
/// `z = 1 − 2·u0`, azimuth `2π·u1`.
#[inline]
pub fn uniform_direction(u0: f32, u1: f32) -> Vec3 {
    let z = 1.0 - 2.0 * u0;
    let r = (1.0 - z * z).max(0.0).sqrt();
    let (s, c) = sin_cos_turns(u1);
    Vec3::new(r * c, r * s, z)
}

/// `(sin 2πu, cos 2πu)` for `u ∈ [0, 1)`: the quadrant from `⌊4u⌋` (mod 4), then Taylor polynomials of
/// degree 11 and 12 on `[0, π/2)` (error below 10⁻⁷), arithmetic a WGSL mirror repeats
/// exactly, unlike a platform `sin_cos`.
#[inline]
pub fn sin_cos_turns(u: f32) -> (f32, f32) {
    let q4 = 4.0 * u;
    let q = q4 as i32; // u ≥ 0: truncation is ⌊4u⌋ (and avoids a libm call)
    let x = (q4 - q as f32) * std::f32::consts::FRAC_PI_2;
    let x2 = x * x;
    let s = x
        * (1.0
            + x2 * (-1.0 / 6.0
                + x2 * (1.0 / 120.0
                    + x2 * (-1.0 / 5040.0 + x2 * (1.0 / 362_880.0 + x2 * (-1.0 / 39_916_800.0))))));
    let c = 1.0
        + x2 * (-0.5
            + x2 * (1.0 / 24.0
                + x2 * (-1.0 / 720.0
                    + x2 * (1.0 / 40_320.0
                        + x2 * (-1.0 / 3_628_800.0 + x2 * (1.0 / 479_001_600.0))))));
    // Quadrant q: (s, c), (c, −s), (−s, −c), (−c, s), without branches (q is random).
    let swap = 0u32.wrapping_sub(q as u32 & 1);
    let (sb, cb) = (s.to_bits(), c.to_bits());
    let (s1, c1) = ((sb & !swap) | (cb & swap), (cb & !swap) | ((sb ^ 0x8000_0000) & swap));
    let flip = (q as u32 & 2) << 30;
    (f32::from_bits(s1 ^ flip), f32::from_bits(c1 ^ flip))
}

/// The line of ray `ray` of the voxel with id `voxel` for random dimensions `base..base + 5`
/// (module docs): unit direction, voxel-local entry point, chord in voxel units (> 0).
#[inline]
pub fn sample_line(voxel: u32, ray: u32, base: u32) -> (Vec3, Vec3, f32) {
    let r = |k: u32| rand_f32(voxel, ray, base.wrapping_add(k));
    line_of([r(0), r(1), r(2), r(3), r(4)])
}

/// The line of five uniform numbers: direction from `u[0..2]`, face from `u[2]`, in-face
/// point from `u[3..5]` (each moved into (0, 1)). Written without branches on the random
/// values, so that a loop over lines vectorizes ([`LineBatch::fill`]); the same arithmetic as
/// [`choose_face`] and [`entry_point`], so both give the same bits.
#[inline(always)]
fn line_of(u: [f32; 5]) -> (Vec3, Vec3, f32) {
    let d = uniform_direction(u[0], u[1]);
    let a = d.abs();
    let x = u[2] * (a.x + a.y + a.z);
    let (past_x, past_y) = (x >= a.x, x >= a.x + a.y);
    let share = if past_y {
        a.z
    } else if past_x {
        a.y
    } else {
        a.x
    };
    // The zero-share fallback of `choose_face`: glam's `max_position` tie rule.
    let (dom_x, dom_y) = (a.x >= a.y && a.x >= a.z, !(a.x >= a.y && a.x >= a.z) && a.y >= a.z);
    let zero = share.is_nan() || share <= 0.0;
    let fx = if zero { dom_x } else { !past_x };
    let fy = if zero { dom_y } else { past_x && !past_y };
    let (s, t) = (u[3] + HALF_STEP, u[4] + HALF_STEP);
    let face = |dk: f32| if dk > 0.0 { 0.0 } else { 1.0 };
    let entry = Vec3::new(
        if fx {
            face(d.x)
        } else if fy {
            t
        } else {
            s
        },
        if fx {
            s
        } else if fy {
            face(d.y)
        } else {
            t
        },
        if fx {
            t
        } else if fy {
            s
        } else {
            face(d.z)
        },
    );
    (d, entry, chord(entry, d))
}

/// The lines of a batch of rays in structure-of-arrays form (component `c` of ray `j` at
/// `dir[c][j]`, `entry[c][j]`), reused across voxels.
#[derive(Clone, Debug, Default)]
pub struct LineBatch {
    /// Direction components.
    pub dir: [Vec<f32>; 3],
    /// Entry point components (voxel-local).
    pub entry: [Vec<f32>; 3],
    /// Chords (voxel units).
    pub chord: Vec<f32>,
}

impl LineBatch {
    /// Replaces the batch with rays `first..first + count` of voxel `voxel` drawn from
    /// dimensions `base..base + 5`: exactly [`sample_line`]'s numbers, bit for bit. On x86-64
    /// CPUs with AVX2 (detected at run time) the loop runs 8 lines per instruction; IEEE
    /// arithmetic without contraction gives the same bits either way.
    pub fn fill(&mut self, voxel: u32, first: u32, count: u32, base: u32) {
        let n = count as usize;
        for v in self.dir.iter_mut().chain(self.entry.iter_mut()).chain([&mut self.chord]) {
            v.clear();
            v.resize(n, 0.0);
        }
        #[cfg(target_arch = "x86_64")]
        if std::arch::is_x86_feature_detected!("avx2") {
            // SAFETY: the CPU has AVX2 (checked just above).
            unsafe { self.fill_avx2(voxel, first, base) };
            return;
        }
        self.fill_any(voxel, first, base);
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    fn fill_avx2(&mut self, voxel: u32, first: u32, base: u32) {
        self.fill_any(voxel, first, base);
    }

    /// The loop of [`LineBatch::fill`], over the already sized arrays.
    #[inline(always)]
    fn fill_any(&mut self, voxel: u32, first: u32, base: u32) {
        let n = self.chord.len();
        let [dx, dy, dz] = &mut self.dir;
        let [ex, ey, ez] = &mut self.entry;
        let (dx, dy, dz) = (&mut dx[..n], &mut dy[..n], &mut dz[..n]);
        let (ex, ey, ez, ch) = (&mut ex[..n], &mut ey[..n], &mut ez[..n], &mut self.chord[..n]);
        for j in 0..n {
            let ray = first.wrapping_add(j as u32);
            let r = |k: u32| rand_f32(voxel, ray, base.wrapping_add(k));
            let (d, e, c) = line_of([r(0), r(1), r(2), r(3), r(4)]);
            (dx[j], dy[j], dz[j]) = (d.x, d.y, d.z);
            (ex[j], ey[j], ez[j]) = (e.x, e.y, e.z);
            ch[j] = c;
        }
    }
}

/// The first random dimension of seed `seed`: `8·seed` (wrapping).
#[inline]
pub fn dimension_base(seed: u32) -> u32 {
    seed.wrapping_mul(8)
}

/// The key of the stochastic alpha of `Blend` materials for seed `seed`:
/// `rand_u32(seed, 4, 0x5EED)`.
#[inline]
pub fn blend_key(seed: u32) -> u32 {
    rand_u32(seed, 4, 0x5EED)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The batch (vectorized where the CPU allows), its portable loop and one line at a time
    /// give the same bits; so does the face rule of `choose_face` + `entry_point`.
    #[test]
    fn batches_equal_single_lines_bit_for_bit() {
        let (mut fast, mut portable) = (LineBatch::default(), LineBatch::default());
        for voxel in [0u32, 1, 77, u32::MAX] {
            for (first, count, base) in [(0u32, 150u32, 0u32), (150, 37, 8), (u32::MAX - 3, 9, 16)]
            {
                fast.fill(voxel, first, count, base);
                portable.fill(voxel, first, count, base);
                portable.fill_any(voxel, first, base);
                for j in 0..count as usize {
                    let ray = first.wrapping_add(j as u32);
                    let (d, e, c) = sample_line(voxel, ray, base);
                    for b in [&fast, &portable] {
                        let bd = Vec3::new(b.dir[0][j], b.dir[1][j], b.dir[2][j]);
                        let be = Vec3::new(b.entry[0][j], b.entry[1][j], b.entry[2][j]);
                        assert_eq!(
                            (bd.to_array().map(f32::to_bits), be.to_array().map(f32::to_bits)),
                            (d.to_array().map(f32::to_bits), e.to_array().map(f32::to_bits))
                        );
                        assert_eq!(b.chord[j].to_bits(), c.to_bits());
                    }
                    let r = |k: u32| rand_f32(voxel, ray, base.wrapping_add(k));
                    let (k, _) = choose_face(d, r(2));
                    assert_eq!(entry_point(d, k, r(3) + HALF_STEP, r(4) + HALF_STEP), e);
                }
            }
        }
    }

    /// The zero-share fallback: a direction with an exactly zero component and a face draw
    /// that rounds onto it picks the dominant axis in both forms.
    #[test]
    fn zero_share_falls_back_to_the_dominant_axis() {
        for u1 in [0.0, 0.1, 0.3, 0.7] {
            // u0 = ½: z = 0 exactly.
            let (d, e, c) = line_of([0.5, u1, ONE_BELOW, 0.25, 0.75]);
            assert_eq!(d.z, 0.0);
            let (k, _) = choose_face(d, ONE_BELOW);
            assert_ne!(k, 2, "{d}");
            assert_eq!(e, entry_point(d, k, 0.25 + HALF_STEP, 0.75 + HALF_STEP));
            assert!(c > 0.0);
        }
        assert_eq!(choose_face(Vec3::new(0.0, 0.0, 0.0), 0.3), (2, 0.3));
    }
}
