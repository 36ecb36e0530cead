//! Renderers and what they share.
//!
//! - [`ground_truth`]: the mesh ray cast through the BVH with many stratified rays per pixel,
//!   and its G-buffer: the reference every voxel representation is scored against.
//! - [`baseline`]: the first voxel renderer, each occupied voxel an opaque cube of its
//!   triangles' average colour.
//! - [`dda`]: the voxel walk every voxel renderer and voxel shadow ray uses, with
//!   [`bricks`] for the brick look-ups it skips empty space with.
//! - [`pixel_samples`]: sub-pixel patterns and random streams.
//! - [`indirect`]: ray-traced AO and one-bounce diffuse indirect light, the references of
//!   voxel cone tracing.
//!
//! Every renderer calls [`crate::shading::shade`], generates camera rays with
//! `CameraFrame::ray_dir`, draws random numbers from [`crate::random`], and returns a linear
//! float `Image` whose alpha is coverage.

pub mod baseline;
pub mod bricks;
pub mod dda;
pub mod filtered;
pub mod ground_truth;
pub mod indirect;
pub(crate) mod lanes;
pub mod pixel_samples;
pub(crate) mod surface;

#[cfg(test)]
pub(crate) mod test_scenes;

use crate::{Error, Result};

/// Largest image edge a renderer accepts.
pub const MAX_IMAGE_EDGE: u32 = 1 << 15;

/// Largest pixel count a renderer accepts (2²⁸, a 16k × 16k image): pixel indices are `u32`
/// counters of the random streams, and the float image alone is then 4 GiB.
pub const MAX_IMAGE_PIXELS: u64 = 1 << 28;

/// Checks a colour term of the shading (an ambient irradiance, a background): finite and
/// non-negative in every channel; the error names it.
pub fn check_colour(name: &'static str, v: glam::Vec3) -> Result<()> {
    if !(v.is_finite() && v.min_element() >= 0.0) {
        return Err(Error::InvalidParameter {
            name,
            value: v.to_string(),
            reason: "must be finite and non-negative".into(),
        });
    }
    Ok(())
}

/// Checks an image size: both edges in `1..=MAX_IMAGE_EDGE`, at most `MAX_IMAGE_PIXELS`.
pub fn check_image_size(width: u32, height: u32) -> Result<()> {
    let pixels = width as u64 * height as u64;
    if width == 0 || height == 0 || width.max(height) > MAX_IMAGE_EDGE || pixels > MAX_IMAGE_PIXELS
    {
        return Err(Error::InvalidParameter {
            name: "image size",
            value: format!("{width}×{height}"),
            reason: format!(
                "each edge must be in 1..={MAX_IMAGE_EDGE} and the image at most \
                 {MAX_IMAGE_PIXELS} pixels"
            ),
        });
    }
    Ok(())
}
