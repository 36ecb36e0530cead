//! Evaluation for voxlod: how far an approximate render is from its ground truth, and reports
//! that put that error next to what it cost.
//!
//! - [`metrics`]: [`mse`], [`psnr`] and [`compare`] (MSE + PSNR + SSIM as one
//!   [`ImageMetrics`]), on 8-bit sRGB images ([`voxlod_scene::Srgb8Image`]) scaled to [0, 1] —
//!   what a user sees and what published tables score.
//! - [`mod@ssim`]: SSIM after Wang et al. 2004 (Gaussian window σ = 1.5, 11×11, K1 = 0.01,
//!   K2 = 0.03, L = 1, per channel then the mean), computed as scikit-image computes it, with
//!   the per-pixel [`SsimMap`].
//! - [`heatmap`]: per-pixel absolute error (and SSIM) as colour heat maps for reports.
//! - [`report`]: markdown tables, labelled PNG image grids, SVG plots of error against cost,
//!   animations, and a JSON summary, written atomically.
//! - [`animation`]: animated PNG (APNG) encoding and decoding of frame sequences (turntables).
//! - [`patterns`]: deterministic integer test images shared with the Python cross-check.
//! - [`json`]: JSON for infinite and NaN numbers (a PSNR of identical images is `+∞`).
//!
//! # Example
//! Score two approximations of an image, and write a report with a table and an error heat map.
//! ```
//! use voxlod_eval::report::{Column, ImageGrid, LabeledImage, NumberFormat, Report, Table};
//! use voxlod_eval::{Error, compare, error_heatmap, patterns};
//!
//! # fn main() -> voxlod_eval::Result<()> {
//! // A reference and two approximations of it (8-bit sRGB images).
//! let reference = patterns::checker(64, 48, 8);
//! let noisy = patterns::add_noise(&reference, 1, 16);
//! let blurred = patterns::box_blur(&reference);
//!
//! // MSE and PSNR on values in [0, 1], SSIM as scikit-image computes it: by both, the faint
//! // noise is closer to the reference than the blurred edges.
//! let (n, b) = (compare(&noisy, &reference)?, compare(&blurred, &reference)?);
//! assert!(n.mse < b.mse && n.ssim > b.ssim && b.ssim < 1.0);
//! assert_eq!(compare(&reference, &reference)?.psnr, f64::INFINITY);
//! let small = patterns::checker(32, 24, 8);
//! assert!(matches!(compare(&small, &reference), Err(Error::SizeMismatch { .. })));
//!
//! // A report: a table and the blur's error heat map, written to a directory.
//! let columns = vec![Column::text("image"), Column::number("SSIM", NumberFormat::Fixed(4))];
//! let mut table = Table::new("error", columns);
//! table.push_row(vec!["noisy".into(), n.ssim.into()])?;
//! table.push_row(vec!["blurred".into(), b.ssim.into()])?;
//! let heat = LabeledImage::new("|error|", error_heatmap(&blurred, &reference, 0.25)?);
//! let grid = ImageGrid::new(2, vec![LabeledImage::new("blurred", blurred), heat]);
//! let mut report = Report::new("Two approximations");
//! report.table(table).images("blurred", "The blur and its error.", grid);
//! let written = report.write(&std::env::temp_dir().join("voxlod-eval-example"))?;
//! let markdown = std::fs::read_to_string(&written.markdown).expect("report.md was written");
//! assert!(markdown.contains("| blurred |") && written.assets.len() == 3);
//! # Ok(())
//! # }
//! ```
//!
//! # Agreement with scikit-image
//! The target is `skimage.metrics.structural_similarity(a, b, gaussian_weights=True,
//! sigma=1.5, use_sample_covariance=False, data_range=1.0, channel_axis=-1)` on `uint8 / 255.0`
//! images, within 1e-4. [`mod@ssim`] reproduces each detail of scikit-image 0.26.0
//! (`skimage/metrics/_structural_similarity.py`) that published formulas leave open: the kernel
//! is scipy's `exp(−x²/2σ²)` normalized over radius `int(3.5·σ + 0.5) = 5`; moments use
//! population covariance; filtering runs over the whole image with `mode='reflect'`; the score
//! is the mean of the SSIM map after cropping `(11 − 1) / 2 = 5` pixels on every side; and
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
//! `|ours − skimage| ≤ 1e-4` for every value. A unit test also checks the banded separable
//! filter against a direct 11×11 sum.
//!
//! # Errors
//! Every fallible call returns [`Error`]: images of different sizes ([`Error::SizeMismatch`]),
//! too small for a metric ([`Error::ImageTooSmall`]) or whose buffer disagrees with their size
//! ([`Error::PixelCount`]); a parameter out of its domain ([`Error::InvalidParameter`]); a table
//! row of the wrong length ([`Error::RowLength`]); a report asset name that is invalid or
//! repeated ([`Error::InvalidAssetName`], [`Error::DuplicateAsset`]); an image grid or plot that
//! cannot be drawn ([`Error::InvalidGrid`], [`Error::Plot`]); an animation that cannot be encoded
//! or decoded ([`Error::Animation`]); and a failed PNG encoding, JSON
//! serialization or file write ([`Error::Encode`], [`Error::Json`], [`Error::Write`]). A report
//! is checked before anything is written.
//!
//! # What this crate does not do
//! - It does not render: it scores images that voxlod-cpu, voxlod-gpu or anything else rendered.
//! - Metrics are on 8-bit sRGB images only; linear or HDR images are converted by the caller.
//! - Single-scale SSIM only: no MS-SSIM, FLIP or learned metrics.
//! - Reports are markdown, JSON, PNG and SVG: no HTML, no interactive plots.
//!
//! It depends on voxlod-format (atomic output) and voxlod-scene (images), and on no GPU API.
//!
//! # References
//! - Wang, Bovik, Sheikh, Simoncelli 2004, "Image Quality Assessment: From Error Visibility to
//!   Structural Similarity", IEEE Transactions on Image Processing 13(4): [`mod@ssim`].
//! - van der Walt et al. 2014, "scikit-image: image processing in Python", PeerJ: the reference
//!   implementation of SSIM.

#![deny(missing_docs)]

pub mod animation;
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

/// The README's example, compiled and run as a doc test.
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
struct ReadmeDoctest;
pub use heatmap::{colour_ramp, error_heatmap};
pub use metrics::{ImageMetrics, compare, mse, psnr, psnr_from_mse};
pub use ssim::{SsimMap, ssim, ssim_map};
