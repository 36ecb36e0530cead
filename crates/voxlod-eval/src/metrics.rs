//! Pixel-wise metrics on 8-bit sRGB images scaled to [0, 1] — what a user sees and what
//! published tables score: [`mse`], [`psnr`], and [`compare`], which gives all three of MSE,
//! PSNR and SSIM ([`crate::ssim()`]) as an [`ImageMetrics`] that serializes to JSON (an infinite
//! PSNR becomes the string `"inf"`).

use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use voxlod_scene::Srgb8Image;

use crate::pair::check_pair;
use crate::{Result, ssim};

/// MSE, PSNR and SSIM of one image against a reference.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct ImageMetrics {
    /// Mean squared error over pixels and channels, values in [0, 1].
    pub mse: f64,
    /// `10 · log10(1 / mse)` in dB; `f64::INFINITY` for identical images (`"inf"` in JSON).
    #[serde(with = "crate::json::non_finite")]
    pub psnr: f64,
    /// Mean SSIM ([`ssim::ssim`]).
    pub ssim: f64,
}

/// Mean squared error of two images of the same size, on values scaled to [0, 1], averaged over
/// pixels and channels. 0 for identical images.
///
/// ```
/// use voxlod_scene::Srgb8Image;
/// let a = Srgb8Image::new(2, 2, [0, 0, 0]);
/// let b = Srgb8Image::new(2, 2, [255, 0, 0]);
/// assert!((voxlod_eval::mse(&a, &b).unwrap() - 1.0 / 3.0).abs() < 1e-15);
/// ```
pub fn mse(a: &Srgb8Image, b: &Srgb8Image) -> Result<f64> {
    check_pair(a, b, "MSE", 1)?;
    let w = a.width as usize;
    let row_sums: Vec<f64> = a
        .pixels
        .par_chunks(w)
        .zip(b.pixels.par_chunks(w))
        .map(|(ra, rb)| {
            let mut sum = 0.0;
            for (pa, pb) in ra.iter().zip(rb) {
                for c in 0..3 {
                    let d = f64::from(pa[c]) / 255.0 - f64::from(pb[c]) / 255.0;
                    sum += d * d;
                }
            }
            sum
        })
        .collect();
    Ok(row_sums.iter().sum::<f64>() / (a.pixels.len() * 3) as f64)
}

/// PSNR in dB for a data range of 1: `10 · log10(1 / mse)`; `f64::INFINITY` when `mse` is 0.
pub fn psnr_from_mse(mse: f64) -> f64 {
    10.0 * (1.0 / mse).log10()
}

/// PSNR of two images of the same size in dB ([`psnr_from_mse`] of [`mse`]).
pub fn psnr(a: &Srgb8Image, b: &Srgb8Image) -> Result<f64> {
    mse(a, b).map(psnr_from_mse)
}

/// MSE, PSNR and SSIM of `test` against `reference`. Errors as [`ssim::ssim`] (sizes differ or
/// are below 11×11).
pub fn compare(test: &Srgb8Image, reference: &Srgb8Image) -> Result<ImageMetrics> {
    let ssim = ssim::ssim(test, reference)?;
    let mse = mse(test, reference)?;
    Ok(ImageMetrics { mse, psnr: psnr_from_mse(mse), ssim })
}

#[cfg(test)]
mod tests {
    use proptest::prelude::*;

    use super::*;
    use crate::Error;
    use crate::patterns;

    #[test]
    fn identical_images_have_zero_error_infinite_psnr_and_ssim_one() {
        let a = patterns::gradient(40, 30);
        let m = compare(&a, &a).unwrap();
        assert_eq!(m, ImageMetrics { mse: 0.0, psnr: f64::INFINITY, ssim: 1.0 });
        let json = serde_json::to_string(&m).unwrap();
        assert_eq!(json, r#"{"mse":0.0,"psnr":"inf","ssim":1.0}"#);
        assert_eq!(serde_json::from_str::<ImageMetrics>(&json).unwrap(), m);
    }

    #[test]
    fn constant_images() {
        let black = patterns::constant(16, 12, [0, 0, 0]);
        let white = patterns::constant(16, 12, [255, 255, 255]);
        let m = compare(&black, &white).unwrap();
        assert_eq!(m.mse, 1.0);
        assert_eq!(m.psnr, 0.0);
        // Zero variance on both sides: SSIM is the luminance term C1 / (1 + C1).
        let c1 = SSIM_C1;
        assert!((m.ssim - c1 / (1.0 + c1)).abs() < 1e-12, "{}", m.ssim);
        let grey = patterns::constant(16, 12, [128, 128, 128]);
        assert_eq!(compare(&grey, &grey).unwrap().ssim, 1.0);
    }
    const SSIM_C1: f64 = ssim::SSIM_K1 * ssim::SSIM_K1;

    #[test]
    fn one_pixel_difference() {
        let a = patterns::constant(20, 20, [100, 100, 100]);
        let mut b = a.clone();
        b.pixels[10 * 20 + 10] = [100, 151, 100];
        let m = compare(&a, &b).unwrap();
        let d = 151.0 / 255.0 - 100.0 / 255.0;
        assert!((m.mse - d * d / 1200.0).abs() < 1e-18, "{}", m.mse);
        assert!((m.psnr - psnr_from_mse(d * d / 1200.0)).abs() < 1e-12);
        assert!(m.ssim < 1.0 && m.ssim > 0.9, "{}", m.ssim);
        // Only the green channel moved.
        let map = ssim::ssim_map(&a, &b).unwrap();
        assert_eq!(map.channel_means[0], 1.0);
        assert!(map.channel_means[1] < 1.0);
    }

    #[test]
    fn size_mismatch_names_both_sizes() {
        let a = patterns::gradient(20, 30);
        let b = patterns::gradient(30, 20);
        for err in [mse(&a, &b).unwrap_err(), compare(&a, &b).unwrap_err()] {
            let msg = err.to_string();
            assert!(msg.contains("20×30") && msg.contains("30×20"), "{msg}");
        }
    }

    #[test]
    fn malformed_and_empty_images_are_errors() {
        let mut a = patterns::gradient(4, 4);
        a.pixels.pop();
        let b = patterns::gradient(4, 4);
        assert!(matches!(mse(&a, &b), Err(Error::PixelCount { pixels: 15, .. })));
        let e = Srgb8Image::new(0, 5, [0; 3]);
        assert!(matches!(mse(&e, &e), Err(Error::ImageTooSmall { metric: "MSE", .. })));
        // MSE itself works down to one pixel.
        let p = Srgb8Image::new(1, 1, [255, 255, 255]);
        assert_eq!(mse(&p, &Srgb8Image::new(1, 1, [0, 0, 0])).unwrap(), 1.0);
    }

    fn image_pair() -> impl Strategy<Value = (Srgb8Image, Srgb8Image)> {
        (11u32..24, 11u32..24).prop_flat_map(|(w, h)| {
            let n = (w * h) as usize;
            let px = proptest::collection::vec(any::<[u8; 3]>(), n);
            (px.clone(), px).prop_map(move |(pa, pb)| {
                (
                    Srgb8Image { width: w, height: h, pixels: pa },
                    Srgb8Image { width: w, height: h, pixels: pb },
                )
            })
        })
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(48))]

        #[test]
        fn ssim_is_bounded_and_symmetric((a, b) in image_pair()) {
            let ab = ssim::ssim(&a, &b).unwrap();
            let ba = ssim::ssim(&b, &a).unwrap();
            prop_assert!((-1.0..=1.0).contains(&ab), "ssim {}", ab);
            prop_assert!((ab - ba).abs() < 1e-12, "ssim(a,b) {} ssim(b,a) {}", ab, ba);
            let map = ssim::ssim_map(&a, &b).unwrap();
            prop_assert!(map.channels.iter().flatten().all(|s| (-1.0 - 1e-12..=1.0 + 1e-12).contains(s)));
        }

        #[test]
        fn mse_is_non_negative_symmetric_and_zero_on_itself((a, b) in image_pair()) {
            let ab = mse(&a, &b).unwrap();
            prop_assert!((0.0..=1.0).contains(&ab));
            prop_assert_eq!(ab, mse(&b, &a).unwrap());
            prop_assert_eq!(mse(&a, &a).unwrap(), 0.0);
            prop_assert!(ab > 0.0 || a == b);
        }
    }
}
