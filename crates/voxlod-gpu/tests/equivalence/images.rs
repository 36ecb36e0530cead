//! Image comparison for the renderer kernels: 8-bit sRGB images (as a user sees them, and as
//! the metrics see them) compared pixel by pixel against a per-pixel bound, with the fraction
//! of pixels that must meet it; on failure the actual, expected and difference images are
//! written under `target/equivalence/`.

use voxlod_scene::{Image, Srgb8Image};

use crate::harness::{Measure, target_dir};

/// A per-pixel bound and the fraction of pixels that must meet it.
#[derive(Clone, Copy, Debug)]
pub struct ImageBound {
    /// Largest allowed difference of any channel, in 8-bit sRGB steps.
    pub per_pixel: u8,
    /// Fraction of pixels that must be within `per_pixel`.
    pub fraction: f64,
}

/// Compares `actual` with `expected` (both linear, converted to 8-bit sRGB); the measure's
/// error is the fraction of pixels over the per-pixel bound, its bound `1 − fraction`.
pub fn compare(name: &str, actual: &Image, expected: &Image, bound: ImageBound) -> Measure {
    let (a, e) = (actual.to_srgb8(), expected.to_srgb8());
    if (a.width, a.height) != (e.width, e.height) {
        return Measure {
            max_error: f64::INFINITY,
            bound: 1.0 - bound.fraction,
            pass: false,
            note: format!("{name}: size {}×{} vs {}×{}", a.width, a.height, e.width, e.height),
        };
    }
    let diff: Vec<u8> = a
        .pixels
        .iter()
        .zip(&e.pixels)
        .map(|(p, q)| (0..3).map(|c| p[c].abs_diff(q[c])).max().unwrap())
        .collect();
    let over = diff.iter().filter(|&&d| d > bound.per_pixel).count();
    let worst = diff.iter().copied().max().unwrap_or(0);
    let over_fraction = over as f64 / diff.len().max(1) as f64;
    // Coverage (alpha) too: a flipped sample moves it by 1/spp, like a colour.
    let coverage = actual
        .pixels
        .iter()
        .zip(&expected.pixels)
        .map(|(p, q)| (p.w - q.w).abs())
        .fold(0.0f32, f32::max);
    let pass = over_fraction <= 1.0 - bound.fraction;
    let mut note = format!(
        "{name}: {}×{}, {over} of {} pixels over {} sRGB step(s) (allowed {:.2} %), worst {worst}, \
         max coverage diff {coverage:.4}",
        a.width,
        a.height,
        diff.len(),
        bound.per_pixel,
        100.0 * (1.0 - bound.fraction)
    );
    if !pass {
        match write_failure(name, &a, &e, &diff) {
            Ok(dir) => note += &format!("; images in {dir}"),
            Err(err) => note += &format!("; could not write images: {err}"),
        }
    }
    Measure { max_error: over_fraction, bound: 1.0 - bound.fraction, pass, note }
}

fn write_failure(
    name: &str,
    a: &Srgb8Image,
    e: &Srgb8Image,
    diff: &[u8],
) -> Result<String, String> {
    let dir = target_dir().join("equivalence");
    std::fs::create_dir_all(&dir).map_err(|e| e.to_string())?;
    // Differences amplified 16× (a one-step difference is visible), grey.
    let d = Srgb8Image {
        width: a.width,
        height: a.height,
        pixels: diff.iter().map(|&x| [x.saturating_mul(16); 3]).collect(),
    };
    for (suffix, img) in [("actual", a), ("expected", e), ("difference", &d)] {
        img.save_png(&dir.join(format!("{name}-{suffix}.png"))).map_err(|e| e.to_string())?;
    }
    Ok(dir.display().to_string())
}

/// The largest difference of any channel of any pixel, in 8-bit sRGB steps (0 for images of
/// different sizes, which [`compare`] reports).
pub fn worst_step(actual: &Image, expected: &Image) -> u8 {
    let (a, e) = (actual.to_srgb8(), expected.to_srgb8());
    a.pixels
        .iter()
        .zip(&e.pixels)
        .map(|(p, q)| (0..3).map(|c| p[c].abs_diff(q[c])).max().unwrap())
        .max()
        .unwrap_or(0)
}
