//! The check every metric runs first on the two images it compares.

use voxlod_scene::Srgb8Image;

use crate::{Error, Result};

/// Checks that two images can be compared by `metric`: consistent buffers, equal sizes, and
/// both sides at least `min` pixels.
pub(crate) fn check_pair(
    a: &Srgb8Image,
    b: &Srgb8Image,
    metric: &'static str,
    min: u32,
) -> Result<()> {
    for img in [a, b] {
        if img.pixels.len() as u64 != u64::from(img.width) * u64::from(img.height) {
            return Err(Error::PixelCount {
                width: img.width,
                height: img.height,
                pixels: img.pixels.len(),
            });
        }
    }
    if (a.width, a.height) != (b.width, b.height) {
        return Err(Error::SizeMismatch {
            a_width: a.width,
            a_height: a.height,
            b_width: b.width,
            b_height: b.height,
        });
    }
    if a.width < min || a.height < min {
        return Err(Error::ImageTooSmall { metric, width: a.width, height: a.height, min });
    }
    Ok(())
}
