//! [`Texture`]: an 8-bit RGBA image with a [`Sampler`], sampled bilinearly in linear space.

use std::sync::Arc;

use glam::{Vec2, Vec4};

/// How texture coordinates outside [0, 1] wrap (glTF sampler wrap modes).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum WrapMode {
    /// Tile the image.
    #[default]
    Repeat,
    /// Clamp to the edge texel.
    ClampToEdge,
    /// Tile, mirroring every other tile.
    MirroredRepeat,
}

/// Texture sampler state. Filtering is always bilinear (the ground truth box-filters over the
/// pixel with many rays, which is what mip-mapping would approximate).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Sampler {
    /// Wrap along u.
    pub wrap_u: WrapMode,
    /// Wrap along v.
    pub wrap_v: WrapMode,
}

/// An RGBA8 texture. Colour channels are sRGB-encoded when `srgb` is set (base colour
/// textures); alpha is always linear.
#[derive(Clone, Debug, PartialEq)]
pub struct Texture {
    /// Name, for messages.
    pub name: String,
    /// Width in texels.
    pub width: u32,
    /// Height in texels.
    pub height: u32,
    /// Texels, row-major from the top-left, `width × height` of them.
    pub texels: Arc<[[u8; 4]]>,
    /// Whether the colour channels are sRGB-encoded.
    pub srgb: bool,
    /// Wrap modes.
    pub sampler: Sampler,
}

pub use voxlod_format::records::quant::{linear_to_srgb, srgb_to_linear, srgb_to_linear_table};

/// Wraps texel index `i` (an integer-valued float, any magnitude) into `0..n`.
fn wrap(i: f64, n: u32, mode: WrapMode) -> u32 {
    let n = n as f64;
    (match mode {
        WrapMode::Repeat => i.rem_euclid(n),
        WrapMode::ClampToEdge => i.clamp(0.0, n - 1.0),
        WrapMode::MirroredRepeat => {
            let m = i.rem_euclid(2.0 * n);
            if m < n { m } else { 2.0 * n - 1.0 - m }
        }
    }) as u32
}

impl Texture {
    /// A texture of one colour (sRGB-encoded bytes), 1×1.
    pub fn solid(name: &str, rgba: [u8; 4]) -> Self {
        Self {
            name: name.into(),
            width: 1,
            height: 1,
            texels: Arc::from(vec![rgba]),
            srgb: true,
            sampler: Sampler::default(),
        }
    }

    /// Texel `(x, y)` decoded to linear RGBA.
    #[inline]
    pub fn texel(&self, x: u32, y: u32) -> Vec4 {
        let t = self.texels[(y as usize) * self.width as usize + x as usize];
        if self.srgb {
            let lut = srgb_to_linear_table();
            Vec4::new(
                lut[t[0] as usize],
                lut[t[1] as usize],
                lut[t[2] as usize],
                t[3] as f32 / 255.0,
            )
        } else {
            Vec4::from_array(t.map(|c| c as f32 / 255.0))
        }
    }

    /// Bilinear sample at `uv` (texel centres at half-integers, origin top-left), with the
    /// sampler's wrap modes, interpolating decoded linear values. Non-finite `uv` samples
    /// texel (0, 0).
    pub fn sample(&self, uv: Vec2) -> Vec4 {
        let uv = if uv.is_finite() { uv } else { Vec2::ZERO };
        let x = uv.x as f64 * self.width as f64 - 0.5;
        let y = uv.y as f64 * self.height as f64 - 0.5;
        let (x0, y0) = (x.floor(), y.floor());
        let (fx, fy) = ((x - x0) as f32, (y - y0) as f32);
        let (s, t) = (self.sampler.wrap_u, self.sampler.wrap_v);
        let xs = [wrap(x0, self.width, s), wrap(x0 + 1.0, self.width, s)];
        let ys = [wrap(y0, self.height, t), wrap(y0 + 1.0, self.height, t)];
        let top = self.texel(xs[0], ys[0]).lerp(self.texel(xs[1], ys[0]), fx);
        let bottom = self.texel(xs[0], ys[1]).lerp(self.texel(xs[1], ys[1]), fx);
        top.lerp(bottom, fy)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn checker(sampler: Sampler) -> Texture {
        Texture {
            name: "c".into(),
            width: 2,
            height: 2,
            texels: Arc::from(vec![
                [0, 0, 0, 255],
                [255, 255, 255, 255],
                [255, 255, 255, 255],
                [0, 0, 0, 255],
            ]),
            srgb: false,
            sampler,
        }
    }

    #[test]
    fn texel_centres_sample_exactly() {
        let t = checker(Sampler::default());
        assert_eq!(t.sample(Vec2::new(0.25, 0.25)).x, 0.0);
        assert_eq!(t.sample(Vec2::new(0.75, 0.25)).x, 1.0);
        assert!((t.sample(Vec2::new(0.5, 0.25)).x - 0.5).abs() < 1e-6);
    }

    #[test]
    fn wrap_modes() {
        assert_eq!(wrap(-1.0, 4, WrapMode::Repeat), 3);
        assert_eq!(wrap(-1.0, 4, WrapMode::ClampToEdge), 0);
        assert_eq!(wrap(-1.0, 4, WrapMode::MirroredRepeat), 0);
        assert_eq!(wrap(5.0, 4, WrapMode::MirroredRepeat), 2);
        assert_eq!(wrap(9.0, 4, WrapMode::Repeat), 1);
        assert_eq!(wrap(-1e30, 4, WrapMode::ClampToEdge), 0);
        assert!(wrap(1e30, 4, WrapMode::Repeat) < 4);
        let clamp =
            checker(Sampler { wrap_u: WrapMode::ClampToEdge, wrap_v: WrapMode::ClampToEdge });
        assert_eq!(clamp.sample(Vec2::new(-3.0, 0.25)).x, 0.0);
        let repeat = checker(Sampler::default());
        assert!((repeat.sample(Vec2::new(-0.25, 0.25)).x - 1.0).abs() < 1e-6);
        for uv in [Vec2::splat(1e30), Vec2::splat(-1e30), Vec2::new(f32::NAN, 0.0)] {
            assert!(repeat.sample(uv).is_finite());
        }
    }

    #[test]
    fn srgb_round_trip() {
        for i in 0..=255u8 {
            let c = i as f32 / 255.0;
            assert!((linear_to_srgb(srgb_to_linear(c)) - c).abs() < 1e-5);
        }
    }
}
