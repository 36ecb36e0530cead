//! Quantizers shared by the voxel records: unsigned and signed normalized bytes, unit vectors
//! as three snorm8, sRGB bytes, and logarithmic bytes. Every quantizer rounds to nearest (the
//! HPG 2023 reference code truncates, which biases every field by −½ LSB). The WGSL mirrors of
//! the decoders must give the same floats: they are exact multiplications of small integers.

use std::sync::OnceLock;

use glam::Vec3;

/// `round(clamp(x, 0, 1) · 255)`; NaN encodes as 0.
#[inline]
pub fn unorm8(x: f32) -> u8 {
    if x.is_nan() { 0 } else { (x.clamp(0.0, 1.0) * 255.0 + 0.5) as u8 }
}

/// `b / 255`.
#[inline]
pub fn from_unorm8(b: u8) -> f32 {
    b as f32 * (1.0 / 255.0)
}

/// `round(clamp(x, −1, 1) · 127)`; NaN encodes as 0.
#[inline]
pub fn snorm8(x: f32) -> i8 {
    if x.is_nan() { 0 } else { (x.clamp(-1.0, 1.0) * 127.0).round() as i8 }
}

/// `max(b / 127, −1)`.
#[inline]
pub fn from_snorm8(b: i8) -> f32 {
    (b as f32 * (1.0 / 127.0)).max(-1.0)
}

/// A direction as three snorm8 (not renormalized before encoding: pass a unit vector, or zero
/// for "absent").
#[inline]
pub fn encode_dir(v: Vec3) -> [i8; 3] {
    [snorm8(v.x), snorm8(v.y), snorm8(v.z)]
}

/// The unit direction of three snorm8, renormalized; `(0, 0, 0)` decodes to zero.
#[inline]
pub fn decode_dir(b: [i8; 3]) -> Vec3 {
    Vec3::new(from_snorm8(b[0]), from_snorm8(b[1]), from_snorm8(b[2])).normalize_or_zero()
}

/// The sRGB electro-optical transfer function (IEC 61966-2-1), for one channel in [0, 1].
pub fn srgb_to_linear(c: f32) -> f32 {
    if c <= 0.04045 { c / 12.92 } else { ((c + 0.055) / 1.055).powf(2.4) }
}

/// Inverse of [`srgb_to_linear`], clamping to [0, 1] first (NaN becomes 0).
pub fn linear_to_srgb(c: f32) -> f32 {
    let c = if c.is_nan() { 0.0 } else { c.clamp(0.0, 1.0) };
    if c <= 0.003_130_8 { c * 12.92 } else { 1.055 * c.powf(1.0 / 2.4) - 0.055 }
}

/// sRGB byte → linear float, as a 256-entry table (the GPU uploads the same table).
pub fn srgb_to_linear_table() -> &'static [f32; 256] {
    static TABLE: OnceLock<[f32; 256]> = OnceLock::new();
    TABLE.get_or_init(|| std::array::from_fn(|i| srgb_to_linear(i as f32 / 255.0)))
}

/// A linear colour as three sRGB bytes (what metrics see, so quantization costs less than the
/// 8-bit output already does).
#[inline]
pub fn encode_srgb8(c: Vec3) -> [u8; 3] {
    [c.x, c.y, c.z].map(|v| unorm8(linear_to_srgb(v)))
}

/// The linear colour of three sRGB bytes.
#[inline]
pub fn decode_srgb8(b: [u8; 3]) -> Vec3 {
    let lut = srgb_to_linear_table();
    Vec3::new(lut[b[0] as usize], lut[b[1] as usize], lut[b[2] as usize])
}

/// A logarithmic byte over `[2^lo, 2^hi]`: code 0 is exactly 0, codes 1..=255 are
/// `2^(lo + (hi − lo)·(c − 1)/254)`. Values below half the first step's bottom encode as 0;
/// values above the range saturate at 255.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LogByte {
    /// Exponent of code 1.
    pub lo: f32,
    /// Exponent of code 255.
    pub hi: f32,
}

impl LogByte {
    /// The value of code `c`.
    #[inline]
    pub fn decode(self, c: u8) -> f32 {
        if c == 0 { 0.0 } else { (self.lo + (self.hi - self.lo) * (c - 1) as f32 / 254.0).exp2() }
    }

    /// The nearest code (in log space) to `x`; 0 for `x < 2^lo / 2` or NaN.
    #[inline]
    pub fn encode(self, x: f32) -> u8 {
        if x.is_nan() || x < self.lo.exp2() * 0.5 {
            return 0;
        }
        let t = (x.log2() - self.lo) / (self.hi - self.lo) * 254.0;
        (t.round().clamp(0.0, 254.0) as u8) + 1
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn byte_round_trips_are_exact_and_errors_within_half_an_lsb() {
        for b in 0..=255u8 {
            assert_eq!(unorm8(from_unorm8(b)), b);
            assert_eq!(encode_srgb8(decode_srgb8([b; 3])), [b; 3]);
        }
        for b in -127..=127i8 {
            assert_eq!(snorm8(from_snorm8(b)), b);
        }
        for i in 0..=1000 {
            let x = i as f32 / 1000.0;
            assert!((from_unorm8(unorm8(x)) - x).abs() <= 0.5 / 255.0 + 1e-7);
            assert!(
                (from_snorm8(snorm8(2.0 * x - 1.0)) - (2.0 * x - 1.0)).abs() <= 0.5 / 127.0 + 1e-7
            );
        }
        assert_eq!((unorm8(f32::NAN), snorm8(f32::NAN)), (0, 0));
        assert_eq!(decode_dir([0, 0, 0]), Vec3::ZERO);
        assert!(
            (decode_dir(encode_dir(Vec3::new(1.0, 2.0, 2.0) / 3.0)).length() - 1.0).abs() < 1e-6
        );
    }

    #[test]
    fn log_byte_covers_its_range_in_equal_ratios() {
        let q = LogByte { lo: -6.0, hi: 8.0 };
        assert_eq!((q.decode(0), q.decode(1), q.decode(255)), (0.0, 1.0 / 64.0, 256.0));
        for c in 0..=255u8 {
            assert_eq!(q.encode(q.decode(c)), c);
        }
        let ratio = q.decode(2) / q.decode(1);
        assert!((ratio - 2f32.powf(14.0 / 254.0)).abs() < 1e-5);
        assert_eq!((q.encode(0.0), q.encode(1e9), q.encode(f32::NAN)), (0, 255, 0));
        assert_eq!(q.encode(1.0 / 129.0), 0);
        assert_eq!(q.encode(1.0 / 127.0), 1);
    }
}
