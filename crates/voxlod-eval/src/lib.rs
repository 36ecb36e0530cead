//! Evaluation for voxlod: how far an approximate render is from the ground truth, and reports
//! that put error next to cost.
//!
//! - [`metrics`]: [`mse`], [`psnr`] and [`compare`] (MSE + PSNR + SSIM as one
//!   [`ImageMetrics`]), on 8-bit sRGB images ([`voxlod_scene::Srgb8Image`]) scaled to [0, 1] —
//!   what a user sees and what published tables score.
//! - [`mod@ssim`]: SSIM after Wang et al. 2004 (Gaussian window σ = 1.5, 11×11, K1 = 0.01,
//!   K2 = 0.03, L = 1, per channel then the mean), computed as scikit-image computes it, with
//!   the per-pixel [`SsimMap`].
//! - [`heatmap`]: per-pixel absolute error (and SSIM) as colour heat maps for reports.
//! - [`report`]: markdown tables, labelled PNG image grids, SVG plots of error against cost,
//!   and a JSON summary, written atomically.
//! - [`patterns`]: deterministic integer test images shared with the Python cross-check.
//! - [`json`]: JSON for infinite and NaN numbers (a PSNR of identical images is `+∞`).
//!
//! # How SSIM was checked against scikit-image
//!
//! The target is `skimage.metrics.structural_similarity(a, b, gaussian_weights=True,
//! sigma=1.5, use_sample_covariance=False, data_range=1.0, channel_axis=-1)` on `uint8 / 255.0`
//! images, within 1e-4. Reading `skimage/metrics/_structural_similarity.py` (0.26.0) fixed the
//! details that published formulas leave open, and [`mod@ssim`] reproduces each:
//! the kernel is scipy's `exp(−x²/2σ²)` normalized over radius `int(3.5·σ + 0.5) = 5`; moments
//! use population covariance; filtering runs over the whole image with `mode='reflect'`; the
//! score is the mean of the SSIM map after cropping `(11 − 1) / 2 = 5` pixels on every side; and
//! images need both sides ≥ 11 pixels (scikit-image raises below that when the window is
//! Gaussian — its often-quoted 7×7 minimum is for the default 7×7 uniform window).
//!
//! `tools/ssim_check/check.py` (pinned by `tools/ssim_check/requirements.txt`: scikit-image
//! 0.26.0, scipy 1.17.1, numpy 2.4.6) builds thirteen image pairs with the integer generators of
//! [`patterns`] — gradients, checkerboards, hash noise, blurs, shifts, inversions,
//! quantization, constants; square and non-square, odd sizes, 11×11, 11×40, 53×11 and 257×131 —
//! and prints scikit-image's MSE, PSNR, SSIM and full-map mean (border included, which checks
//! the `reflect` boundary) with an FNV-1a digest of every image. `tests/skimage_cross_check.rs`
//! pins those numbers, checks the digests (same images, bit for bit) and asserts
//! `|ours − skimage| ≤ 1e-4` for every value. The largest differences found: MSE 6e-17,
//! PSNR 7e-15 dB, SSIM 6e-14 (the constant-image case, where `E[x²] − μ²` cancels), full-map
//! mean 5e-14 — rounding, not method. A unit test also checks the banded separable filter
//! against a direct 11×11 sum.
//!
//! ```
//! use voxlod_eval::{compare, patterns};
//! let reference = patterns::gradient(64, 48);
//! let test = patterns::add_noise(&reference, 1, 16);
//! let m = compare(&test, &reference).unwrap();
//! assert!(m.ssim < 1.0 && m.psnr > 20.0);
//! assert_eq!(compare(&reference, &reference).unwrap().psnr, f64::INFINITY);
//! ```

#![deny(missing_docs)]

mod error;
pub mod heatmap;
pub mod json;
pub mod metrics;
pub mod npy;
mod pair;
pub mod patterns;
pub mod report;
pub mod ssim;

pub use error::{Error, Result};
pub use heatmap::{colour_ramp, error_heatmap};
pub use metrics::{ImageMetrics, compare, mse, psnr, psnr_from_mse};
pub use ssim::{SsimMap, ssim, ssim_map};
