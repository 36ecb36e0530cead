//! Heat maps for reports: where two images differ. [`error_heatmap`] maps the absolute error of
//! every pixel through [`colour_ramp`]; [`crate::SsimMap::to_heatmap`] does the same for SSIM.
//!
//! The ramp is a five-stop approximation of matplotlib's "inferno" (black → purple → red →
//! orange → pale yellow): monotone in lightness, so it reads in greyscale print too.

use voxlod_scene::Srgb8Image;

use crate::pair::check_pair;
use crate::{Error, Result};

/// Stops of the ramp at t = 0, 0.25, 0.5, 0.75, 1 (inferno's values there, sRGB).
const STOPS: [[f64; 3]; 5] = [
    [0.0, 0.0, 4.0],
    [87.0, 16.0, 110.0],
    [188.0, 55.0, 84.0],
    [249.0, 142.0, 9.0],
    [252.0, 255.0, 164.0],
];

/// The ramp's colour at `t`, clamped to [0, 1]; NaN maps to the top of the ramp (an error that
/// cannot be measured is shown as the largest).
pub fn colour_ramp(t: f64) -> [u8; 3] {
    let t = if t.is_nan() { 1.0 } else { t.clamp(0.0, 1.0) };
    let pos = t * (STOPS.len() - 1) as f64;
    let i = (pos.floor() as usize).min(STOPS.len() - 2);
    let f = pos - i as f64;
    let (lo, hi) = (STOPS[i], STOPS[i + 1]);
    std::array::from_fn(|c| (lo[c] + (hi[c] - lo[c]) * f).round() as u8)
}

/// A heat map of the per-pixel absolute error of `test` against `reference`: the mean over the
/// three channels of `|a − b|` on values in [0, 1], divided by `full_scale` and mapped through
/// [`colour_ramp`] (errors at or above `full_scale` saturate). A `full_scale` of 0.1 suits
/// renders that are close; 1.0 shows the whole range.
///
/// Errors: images of different sizes, an empty image, or `full_scale` not finite and positive.
pub fn error_heatmap(
    test: &Srgb8Image,
    reference: &Srgb8Image,
    full_scale: f64,
) -> Result<Srgb8Image> {
    if !(full_scale.is_finite() && full_scale > 0.0) {
        return Err(Error::InvalidParameter {
            name: "full_scale",
            value: full_scale,
            reason: "must be finite and positive",
        });
    }
    check_pair(test, reference, "error heat map", 1)?;
    let pixels = test
        .pixels
        .iter()
        .zip(&reference.pixels)
        .map(|(a, b)| {
            let sum: u32 = (0..3).map(|c| u32::from(a[c].abs_diff(b[c]))).sum();
            colour_ramp(f64::from(sum) / (3.0 * 255.0) / full_scale)
        })
        .collect();
    Ok(Srgb8Image { width: test.width, height: test.height, pixels })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::patterns;

    #[test]
    fn ramp_hits_its_stops_and_is_monotone_in_lightness() {
        assert_eq!(colour_ramp(0.0), [0, 0, 4]);
        assert_eq!(colour_ramp(0.5), [188, 55, 84]);
        assert_eq!(colour_ramp(1.0), [252, 255, 164]);
        assert_eq!(colour_ramp(-3.0), colour_ramp(0.0));
        assert_eq!(colour_ramp(7.0), colour_ramp(1.0));
        assert_eq!(colour_ramp(f64::NAN), colour_ramp(1.0));
        let luma = |p: [u8; 3]| 0.2126 * p[0] as f64 + 0.7152 * p[1] as f64 + 0.0722 * p[2] as f64;
        let mut last = -1.0;
        for i in 0..=100 {
            let l = luma(colour_ramp(i as f64 / 100.0));
            assert!(l >= last - 0.5, "lightness drops at t = {}", i as f64 / 100.0);
            last = l;
        }
    }

    #[test]
    fn heatmap_is_dark_where_equal_and_bright_where_different() {
        let a = patterns::constant(4, 3, [10, 10, 10]);
        let mut b = a.clone();
        b.pixels[5] = [10, 10, 255];
        let heat = error_heatmap(&a, &b, 0.25).unwrap();
        assert_eq!(heat.pixels[0], colour_ramp(0.0));
        // Mean absolute error of that pixel: 245 / 765 = 0.32 ≥ 0.25, so it saturates.
        assert_eq!(heat.pixels[5], colour_ramp(1.0));
        let heat = error_heatmap(&a, &b, 1.0).unwrap();
        assert_eq!(heat.pixels[5], colour_ramp(245.0 / 765.0));
    }

    #[test]
    fn bad_scale_and_size_mismatch_are_errors() {
        let a = patterns::gradient(4, 4);
        for s in [0.0, -1.0, f64::NAN, f64::INFINITY] {
            let err = error_heatmap(&a, &a, s).unwrap_err().to_string();
            assert!(err.contains("full_scale"), "{err}");
        }
        let b = patterns::gradient(4, 5);
        let err = error_heatmap(&a, &b, 1.0).unwrap_err().to_string();
        assert!(err.contains("4×4") && err.contains("4×5"), "{err}");
    }
}
