//! Images: [`Image`], linear float RGBA as renderers produce it, and [`Srgb8Image`], 8-bit sRGB
//! RGB as a user sees it (what PNGs hold and what metrics score).

use std::path::Path;

use glam::{Vec3, Vec4};

use crate::texture::{linear_to_srgb, srgb_to_linear_table};
use crate::{Error, Result};

/// A linear float RGBA image, row-major from the top-left. Alpha is coverage; colour is not
/// premultiplied unless a producer says so.
#[derive(Clone, Debug, PartialEq)]
pub struct Image {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// `width × height` pixels.
    pub pixels: Vec<Vec4>,
}

/// An 8-bit sRGB RGB image, row-major from the top-left.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Srgb8Image {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// `width × height` pixels.
    pub pixels: Vec<[u8; 3]>,
}

impl Image {
    /// An image filled with `fill`.
    pub fn new(width: u32, height: u32, fill: Vec4) -> Self {
        Self { width, height, pixels: vec![fill; width as usize * height as usize] }
    }

    /// Pixel `(x, y)`.
    #[inline]
    pub fn get(&self, x: u32, y: u32) -> Vec4 {
        self.pixels[y as usize * self.width as usize + x as usize]
    }

    /// Sets pixel `(x, y)`.
    #[inline]
    pub fn set(&mut self, x: u32, y: u32, v: Vec4) {
        self.pixels[y as usize * self.width as usize + x as usize] = v;
    }

    /// Converts to 8-bit sRGB (RGB only), clamping to [0, 1] and rounding to nearest; NaN
    /// becomes 0.
    pub fn to_srgb8(&self) -> Srgb8Image {
        let enc = |c: f32| (linear_to_srgb(c) * 255.0 + 0.5) as u8;
        Srgb8Image {
            width: self.width,
            height: self.height,
            pixels: self.pixels.iter().map(|p| [enc(p.x), enc(p.y), enc(p.z)]).collect(),
        }
    }

    /// Writes the image as an 8-bit sRGB PNG, atomically.
    pub fn save_png(&self, path: &Path) -> Result<()> {
        self.to_srgb8().save_png(path)
    }
}

impl Srgb8Image {
    /// An image of one colour.
    pub fn new(width: u32, height: u32, fill: [u8; 3]) -> Self {
        Self { width, height, pixels: vec![fill; width as usize * height as usize] }
    }

    /// Pixel `(x, y)`.
    #[inline]
    pub fn get(&self, x: u32, y: u32) -> [u8; 3] {
        self.pixels[y as usize * self.width as usize + x as usize]
    }

    /// Decodes to a linear float image with alpha 1.
    pub fn to_linear(&self) -> Image {
        let lut = srgb_to_linear_table();
        Image {
            width: self.width,
            height: self.height,
            pixels: self
                .pixels
                .iter()
                .map(|p| Vec3::from_array(p.map(|c| lut[c as usize])).extend(1.0))
                .collect(),
        }
    }

    /// Encodes as PNG bytes.
    pub fn encode_png(&self) -> Result<Vec<u8>> {
        let mut out = Vec::new();
        let raw: &[u8] = bytemuck::cast_slice(&self.pixels);
        image::ImageEncoder::write_image(
            image::codecs::png::PngEncoder::new(&mut out),
            raw,
            self.width,
            self.height,
            image::ExtendedColorType::Rgb8,
        )
        .map_err(|e| Error::Image { path: "<png encoder>".into(), reason: e.to_string() })?;
        Ok(out)
    }

    /// Writes the image as a PNG, atomically: a failure leaves any existing file untouched.
    pub fn save_png(&self, path: &Path) -> Result<()> {
        let bytes = self.encode_png()?;
        voxlod_format::io::write_bytes_atomic(path, &bytes).map_err(|e| match e {
            voxlod_format::Error::Io { op, path, source } => Error::Io { op, path, source },
            other => Error::Image { path: path.to_owned(), reason: other.to_string() },
        })
    }

    /// Loads a PNG (or JPEG) file as 8-bit sRGB RGB; alpha, if any, is dropped.
    pub fn load(path: &Path) -> Result<Self> {
        let bytes = std::fs::read(path).map_err(|source| Error::Io {
            op: "reading",
            path: path.to_owned(),
            source,
        })?;
        Self::decode(&bytes, path)
    }

    /// Decodes image bytes; `path` names the source in errors.
    pub fn decode(bytes: &[u8], path: &Path) -> Result<Self> {
        let img = image::load_from_memory(bytes)
            .map_err(|e| Error::Image { path: path.to_owned(), reason: e.to_string() })?
            .into_rgb8();
        let (width, height) = img.dimensions();
        let pixels = img.into_raw().chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect();
        Ok(Self { width, height, pixels })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn png_round_trip() {
        let mut img = Image::new(3, 2, Vec4::new(0.0, 0.5, 1.0, 1.0));
        img.set(2, 1, Vec4::new(2.0, f32::NAN, -1.0, 1.0));
        let s = img.to_srgb8();
        assert_eq!(s.get(0, 0), [0, 188, 255]);
        assert_eq!(s.get(2, 1), [255, 0, 0]);
        let dir = std::env::temp_dir().join(format!("voxlod-scene-png-{}", std::process::id()));
        let path = dir.join("a.png");
        s.save_png(&path).unwrap();
        assert_eq!(Srgb8Image::load(&path).unwrap(), s);
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn garbage_is_an_error_naming_the_file() {
        let err = Srgb8Image::decode(b"not a png", Path::new("x.png")).unwrap_err().to_string();
        assert!(err.contains("x.png"), "{err}");
    }
}
