//! Re-centring: the `f64` offset that moves a box far from the world origin next to it, so its
//! coordinates can be stored in `f32` without losing the precision of the box's own scale.
//!
//! Models exported from CAD and GIS tools sit at geo-referenced coordinates of 10⁶–10⁷, where
//! `f32` holds only a few of their digits (its spacing is 0.06 at 10⁶, 1 at 10⁷). voxlod keeps
//! such a model as `f32` positions *local* to an `f64` origin (`world = local + origin`), and
//! chooses the origin with [`recentring_origin`]:
//!
//! - per axis, it is the **roundest** number — the one with the most trailing zero bits — within
//!   half the box's longest extent of the box's centre ([`roundest_in`]). So local coordinates
//!   stay within the box's longest extent of zero (at most one bit of `f32` precision is lost
//!   against a perfectly centred box);
//! - a box that already reaches within that distance of the world origin gets origin 0 (zero is
//!   the roundest number of all): ordinary scenes keep their world coordinates unchanged;
//! - the choice does not depend on where the box sits, only on its shape and on the position's
//!   binary digits: a box moved by a multiple of 2ᵏ, with 2ᵏ wider than its longest extent, gets
//!   its origin moved by exactly the same amount. Local `f64` coordinates are then equal to
//!   within the rounding of the input, and the `f32` positions are usually bit-identical (see
//!   [`recentring_origin`] for when they are not).

use glam::DVec3;

/// The number with the most trailing zero bits in `[lo, hi]` (0 when the interval holds it);
/// `None` when the interval is empty or not finite. Every step is exact in `f64`.
///
/// It is unique: were two numbers with the most trailing zeros, `k`, in the interval, a
/// multiple of 2ᵏ⁺¹ would lie between them.
///
/// ```
/// use voxlod_format::origin::roundest_in;
/// assert_eq!(roundest_in(-3.0, 5.0), Some(0.0));
/// assert_eq!(roundest_in(100.0, 110.0), Some(104.0)); // 0b1101000
/// assert_eq!(roundest_in(1e7 - 0.4, 1e7 + 0.4), Some(1e7)); // 1e7 = 78125 · 2⁷
/// assert_eq!(roundest_in(-0.3, -0.2), Some(-0.25));
/// assert_eq!(roundest_in(2.0, 1.0), None);
/// ```
pub fn roundest_in(lo: f64, hi: f64) -> Option<f64> {
    if !(lo.is_finite() && hi.is_finite()) || lo > hi {
        return None;
    }
    if lo <= 0.0 && hi >= 0.0 {
        return Some(0.0);
    }
    if hi < 0.0 {
        return roundest_in(-hi, -lo).map(|v| -v);
    }
    // 0 < lo ≤ hi: the first power of two 2ᵏ (from above) with a multiple in [lo, hi]. 2ᵏ ≤ hi
    // is needed; the loop ends by 2⁻¹⁰⁷⁴ at the latest, where every f64 is a multiple.
    let mut k = hi.log2().floor() as i32 + 1;
    loop {
        let step = pow2(k);
        let m = (lo / step).ceil() * step;
        if m <= hi {
            return Some(m);
        }
        k -= 1;
    }
}

/// 2ᵏ exactly, for `k` in `-1074..=1023` (subnormal below -1022).
fn pow2(k: i32) -> f64 {
    if k >= -1022 {
        f64::from_bits(((k + 1023) as u64) << 52)
    } else {
        f64::from_bits(1u64 << (k + 1074).max(0))
    }
}

/// The re-centring origin of the box `[min, max]`: per axis the [`roundest_in`] number within
/// half the box's longest extent of its centre; zero on every axis where that range reaches the
/// world origin. `None` when the box is not finite or empty (`max < min` on an axis).
///
/// Subtracting it, in `f64`, from coordinates read in `f64` is exact when they lie in the box;
/// what remains inexact is the input itself: a file that writes a coordinate near 10⁷ in `f64`
/// (or in decimal with as many digits) resolves it to 2⁻²⁹ ≈ 1.9·10⁻⁹, so the same model written
/// at 0 and at 10⁷ may differ by that much after re-centring, and `f32` positions of magnitude
/// above 2⁻⁶ (whose spacing is wider than 2⁻²⁹) may round to a neighbouring `f32` — one unit in
/// the last place — when the input's rounding crosses an `f32` rounding boundary.
///
/// ```
/// use glam::DVec3;
/// use voxlod_format::origin::recentring_origin;
/// // A box around the world origin keeps it.
/// let near = recentring_origin(DVec3::new(-5.0, 0.0, -4.0), DVec3::new(5.0, 9.7, 3.8));
/// assert_eq!(near, Some(DVec3::ZERO));
/// // The same box at 10⁶ + (0, 0, 0) moves with it, exactly.
/// let d = DVec3::splat(1e6);
/// let far = recentring_origin(DVec3::new(-5.0, 0.0, -4.0) + d, DVec3::new(5.0, 9.7, 3.8) + d);
/// assert_eq!(far, Some(d));
/// ```
pub fn recentring_origin(min: DVec3, max: DVec3) -> Option<DVec3> {
    if !(min.is_finite() && max.is_finite()) || max.cmplt(min).any() {
        return None;
    }
    let half = ((max - min) * 0.5).max_element();
    let centre = (min + max) * 0.5;
    let axis = |c: f64| roundest_in(c - half, c + half);
    Some(DVec3::new(axis(centre.x)?, axis(centre.y)?, axis(centre.z)?))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Trailing zero bits of a finite non-zero f64 (its 2-adic valuation).
    fn valuation(v: f64) -> i32 {
        let bits = v.abs().to_bits();
        let (exp, mant) = ((bits >> 52) as i32, bits & ((1 << 52) - 1));
        let (exp, mant) = if exp == 0 { (-1074, mant) } else { (exp - 1075, mant | (1 << 52)) };
        exp + mant.trailing_zeros() as i32
    }

    #[test]
    fn roundest_is_in_range_and_no_number_in_range_is_rounder() {
        let cases = [
            (1.0, 1.0),
            (0.1, 0.1),
            (3.0, 3.5),
            (1e7 - 1e-3, 1e7 + 1e-3),
            (12_345.678, 12_345.9),
            (5e-310, 6e-310),
            (1.0e300, 1.5e300),
            (-7.3, -7.1),
        ];
        for (lo, hi) in cases {
            let r = roundest_in(lo, hi).unwrap();
            assert!(lo <= r && r <= hi, "{r} outside [{lo}, {hi}]");
            // A multiple of twice r's power of two in range would be rounder.
            let step = pow2(valuation(r) + 1);
            let m = (lo / step).ceil() * step;
            assert!(m > hi, "[{lo}, {hi}]: {m} is rounder than {r}");
        }
        assert_eq!(roundest_in(f64::NAN, 1.0), None);
        assert_eq!(roundest_in(1.0, f64::INFINITY), None);
    }

    #[test]
    fn origin_moves_with_the_box_by_multiples_of_its_size() {
        let (lo, hi) = (DVec3::new(-4.96, -0.003, -3.73), DVec3::new(4.95, 9.65, 3.81));
        assert_eq!(recentring_origin(lo, hi), Some(DVec3::ZERO));
        let off_centre = (lo + DVec3::splat(40.0), hi + DVec3::splat(40.0));
        let o = recentring_origin(off_centre.0, off_centre.1).unwrap();
        assert_ne!(o, DVec3::ZERO);
        for d in [1e4, 1e6, 1e7, -3.2e6, 2f64.powi(40)] {
            let d = DVec3::new(d, -d, 0.5 * d);
            assert_eq!(recentring_origin(lo + d, hi + d), Some(d), "offset {d}");
            let moved = recentring_origin(off_centre.0 + d, off_centre.1 + d).unwrap();
            assert_eq!(moved, o + d, "offset {d}");
        }
        // Local coordinates stay within the longest extent of zero.
        let (lo, hi) = (DVec3::new(100.0, 3.0, -4.0), DVec3::new(110.0, 3.5, -3.0));
        let o = recentring_origin(lo, hi).unwrap();
        assert_eq!(o, DVec3::new(104.0, 0.0, 0.0));
        assert!((lo - o).abs().max((hi - o).abs()).max_element() <= (hi - lo).max_element());
        assert_eq!(recentring_origin(hi, lo), None);
    }
}
