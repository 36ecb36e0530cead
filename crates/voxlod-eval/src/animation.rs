//! Animated PNG (APNG): a sequence of 8-bit sRGB frames in one lossless file that browsers,
//! image viewers and markdown renderers play, with no palette (unlike GIF's 256 colours), so a
//! turntable shows the very pixels that were scored.
//!
//! The file is a PNG whose default image is the first frame (viewers without APNG support show
//! it still), followed by the other frames; every frame covers the whole canvas, is drawn over
//! nothing (`APNG_BLEND_OP_SOURCE`, `APNG_DISPOSE_OP_NONE`) and shows for the same delay;
//! playback loops forever. Layout after the APNG specification (Mozilla, "APNG Specification"
//! 1.0): `acTL` (frame and play counts), then per frame `fcTL` (size, offset, delay
//! `num/den` s) and its data (`IDAT` for the first frame, `fdAT` after).
//!
//! ```
//! use voxlod_eval::animation::{self, Animation};
//! use voxlod_scene::Srgb8Image;
//! let frames = (0..3u8).map(|i| Srgb8Image::new(4, 2, [80 * i, 0, 255])).collect();
//! let anim = Animation::new(frames, 125).unwrap();
//! let bytes = animation::encode_apng(&anim).unwrap();
//! let back = animation::decode_apng(&bytes).unwrap();
//! assert_eq!((back.frames.len(), back.frame_ms), (3, 125));
//! assert_eq!(back.frames[2].get(3, 1), [160, 0, 255]);
//! ```

use std::path::Path;

use voxlod_scene::Srgb8Image;

use crate::{Error, Result};

/// Most frames an [`Animation`] holds: 3600 (a turntable of one frame per tenth of a degree).
pub const MAX_FRAMES: usize = 3600;

/// Frames of one size, each shown for `frame_ms` milliseconds, looping.
#[derive(Clone, Debug, PartialEq)]
pub struct Animation {
    /// The frames, in order, all of the same size.
    pub frames: Vec<Srgb8Image>,
    /// How long each frame shows, in milliseconds (1–65 535).
    pub frame_ms: u16,
}

impl Animation {
    /// An animation of `frames`, checked: at least one and at most [`MAX_FRAMES`] frames, all of
    /// the first frame's size ([`Error::SizeMismatch`] otherwise), each holding its pixels
    /// ([`Error::PixelCount`]), a non-zero size and a delay of at least 1 ms
    /// ([`Error::InvalidParameter`]).
    pub fn new(frames: Vec<Srgb8Image>, frame_ms: u16) -> Result<Self> {
        let anim = Self { frames, frame_ms };
        anim.validate()?;
        Ok(anim)
    }

    /// Checks what [`Animation::new`] checks (the fields are public).
    pub fn validate(&self) -> Result<()> {
        let invalid =
            |name, value: f64, reason| Err(Error::InvalidParameter { name, value, reason });
        let Some(first) = self.frames.first() else {
            return invalid("frames", 0.0, "an animation needs at least one frame");
        };
        if self.frames.len() > MAX_FRAMES {
            return invalid("frames", self.frames.len() as f64, "at most 3600 frames");
        }
        if self.frame_ms == 0 {
            return invalid("frame_ms", 0.0, "a frame shows for at least 1 ms");
        }
        if first.width == 0 || first.height == 0 {
            return invalid("frame width × height", 0.0, "frames need at least one pixel");
        }
        for f in &self.frames {
            if (f.width, f.height) != (first.width, first.height) {
                return Err(Error::SizeMismatch {
                    a_width: first.width,
                    a_height: first.height,
                    b_width: f.width,
                    b_height: f.height,
                });
            }
            if f.pixels.len() != f.width as usize * f.height as usize {
                return Err(Error::PixelCount {
                    width: f.width,
                    height: f.height,
                    pixels: f.pixels.len(),
                });
            }
        }
        Ok(())
    }

    /// Width and height of every frame.
    pub fn size(&self) -> (u32, u32) {
        self.frames.first().map_or((0, 0), |f| (f.width, f.height))
    }
}

/// The APNG bytes of `anim` (see the [module docs](self)); checks it first
/// ([`Animation::validate`]).
pub fn encode_apng(anim: &Animation) -> Result<Vec<u8>> {
    anim.validate()?;
    let (width, height) = anim.size();
    let failed = |e: png::EncodingError| Error::Animation { reason: e.to_string() };
    let mut bytes = Vec::new();
    {
        let mut encoder = png::Encoder::new(&mut bytes, width, height);
        encoder.set_color(png::ColorType::Rgb);
        encoder.set_depth(png::BitDepth::Eight);
        encoder.set_animated(anim.frames.len() as u32, 0).map_err(failed)?;
        encoder.set_frame_delay(anim.frame_ms, 1000).map_err(failed)?;
        encoder.set_blend_op(png::BlendOp::Source).map_err(failed)?;
        encoder.set_dispose_op(png::DisposeOp::None).map_err(failed)?;
        let mut writer = encoder.write_header().map_err(failed)?;
        for frame in &anim.frames {
            writer.write_image_data(frame.pixels.as_flattened()).map_err(failed)?;
        }
        writer.finish().map_err(failed)?;
    }
    Ok(bytes)
}

/// Writes `anim` as an APNG file, atomically (the old file, if any, is left untouched on error).
pub fn write_apng(path: &Path, anim: &Animation) -> Result<()> {
    let bytes = encode_apng(anim)?;
    voxlod_format::io::write_bytes_atomic(path, &bytes)
        .map_err(|source| Error::Write { path: path.to_owned(), source })
}

/// Decodes an APNG written by [`encode_apng`] (or any APNG of 8-bit RGB or RGBA frames that each
/// cover the whole canvas and share one delay): its frames and their delay in milliseconds.
/// A plain PNG decodes as one frame of delay 0. Errors ([`Error::Animation`]) name what is not
/// readable: a PNG error, another colour type or depth, a partial frame, unequal delays.
pub fn decode_apng(bytes: &[u8]) -> Result<Animation> {
    let bad = |reason: String| Error::Animation { reason };
    let decoder = png::Decoder::new(std::io::Cursor::new(bytes));
    let mut reader = decoder.read_info().map_err(|e| bad(e.to_string()))?;
    let info = reader.info();
    let (width, height) = (info.width, info.height);
    let channels = match (info.color_type, info.bit_depth) {
        (png::ColorType::Rgb, png::BitDepth::Eight) => 3,
        (png::ColorType::Rgba, png::BitDepth::Eight) => 4,
        (c, d) => {
            return Err(bad(format!("{c:?} at {d:?} bits: only 8-bit RGB and RGBA are read")));
        }
    };
    let count = info.animation_control.map_or(1, |a| a.num_frames) as usize;
    if count == 0 || count > MAX_FRAMES {
        return Err(bad(format!("{count} frames (1 to {MAX_FRAMES})")));
    }
    let mut frames = Vec::with_capacity(count);
    let mut delay: Option<u16> = None;
    let mut buf = vec![0u8; reader.output_buffer_size().ok_or_else(|| bad("too large".into()))?];
    for i in 0..count {
        let out = reader.next_frame(&mut buf).map_err(|e| bad(format!("frame {i}: {e}")))?;
        let ms = match reader.info().frame_control() {
            Some(fc) => {
                if (fc.width, fc.height, fc.x_offset, fc.y_offset) != (width, height, 0, 0) {
                    return Err(bad(format!("frame {i} does not cover the whole canvas")));
                }
                let den = if fc.delay_den == 0 { 100 } else { fc.delay_den as u32 };
                ((fc.delay_num as u32 * 1000 + den / 2) / den).min(u16::MAX as u32) as u16
            }
            None => 0,
        };
        if *delay.get_or_insert(ms) != ms {
            return Err(bad(format!("frame {i} shows for {ms} ms, frame 0 for {delay:?} ms")));
        }
        let data = &buf[..out.buffer_size()];
        let pixels =
            data.chunks_exact(channels).map(|p| [p[0], p[1], p[2]]).collect::<Vec<[u8; 3]>>();
        frames.push(Srgb8Image { width, height, pixels });
    }
    Ok(Animation { frames, frame_ms: delay.unwrap_or(0) })
}

#[cfg(test)]
mod tests;
