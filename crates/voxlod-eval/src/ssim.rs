//! SSIM (Wang, Bovik, Sheikh & Simoncelli 2004) computed the way scikit-image computes it, so
//! our numbers compare with published tables.
//!
//! Per channel, on values scaled to [0, 1] (L = 1): local means, variances and the covariance are
//! Gaussian-weighted (σ = 1.5, truncated at 3.5 σ: radius 5, an 11-tap kernel with unit sum)
//! and use population (not sample) covariance. The filter runs over the whole image with
//! scipy's `reflect` boundary (`d c b a | a b c d | d c b a`), giving an SSIM value at every
//! pixel; the score is the mean of that map with a 5-pixel border excluded (skimage's
//! `crop(S, pad)`), then the mean over the three channels. The border values are kept in
//! [`SsimMap`] for heat maps but never enter the score.
//!
//! The Gaussian is separable: a horizontal pass computes the five weighted moments (x, y, x², y²,
//! xy) of every pixel in f64, a vertical pass combines them and evaluates SSIM row by row; both
//! sum a symmetric kernel as scipy's `correlate1d` does (centre tap, then mirrored pairs). Bands
//! of 64 rows run in parallel (rayon), each streaming its rows through a ring of 11 filtered
//! rows; sums are taken per band and then over bands in order, so the result does not depend on
//! the thread count.

use rayon::prelude::*;
use voxlod_scene::Srgb8Image;

use crate::pair::check_pair;
use crate::{Result, heatmap};

/// Standard deviation of the Gaussian window, in pixels.
pub const SSIM_SIGMA: f64 = 1.5;
/// The window is truncated at this many standard deviations (scikit-image's choice).
pub const SSIM_TRUNCATE: f64 = 3.5;
/// Radius of the window: `int(3.5 · 1.5 + 0.5) = 5`, as `scipy.ndimage` rounds it.
pub const SSIM_RADIUS: u32 = (SSIM_TRUNCATE * SSIM_SIGMA + 0.5) as u32;
/// Side of the window (11) and the smallest image side SSIM accepts, as in scikit-image.
pub const SSIM_WINDOW: u32 = 2 * SSIM_RADIUS + 1;
/// Luminance stabilizer: `C1 = (K1 · L)²`.
pub const SSIM_K1: f64 = 0.01;
/// Contrast stabilizer: `C2 = (K2 · L)²`.
pub const SSIM_K2: f64 = 0.03;

const R: usize = SSIM_RADIUS as usize;
const WIN: usize = SSIM_WINDOW as usize;

/// The SSIM of two 8-bit sRGB images: the mean over the three channels of the mean SSIM map
/// without its border. 1 for identical images; in [−1, 1].
///
/// Errors: images of different sizes, or with a side below [`SSIM_WINDOW`] pixels.
pub fn ssim(a: &Srgb8Image, b: &Srgb8Image) -> Result<f64> {
    Ok(ssim_map(a, b)?.mean)
}

/// The full per-pixel SSIM map of two images, with the score ([`ssim`]) and per-channel scores.
pub fn ssim_map(a: &Srgb8Image, b: &Srgb8Image) -> Result<SsimMap> {
    check_pair(a, b, "SSIM", SSIM_WINDOW)?;
    let kernel = gaussian_kernel();
    let mut channel_means = [0.0; 3];
    let channels = [0, 1, 2].map(|c| {
        let (map, mean) = channel_map(a, b, c, &kernel);
        channel_means[c] = mean;
        map
    });
    let mean = channel_means.iter().sum::<f64>() / 3.0;
    Ok(SsimMap { width: a.width, height: a.height, channels, channel_means, mean })
}

/// A per-pixel SSIM map, border included.
#[derive(Clone, Debug, PartialEq)]
pub struct SsimMap {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// SSIM per pixel for red, green and blue, row-major from the top-left. Values within
    /// [`SSIM_RADIUS`] pixels of an edge use reflected neighbours and are not part of the score.
    pub channels: [Vec<f64>; 3],
    /// The score of each channel: the mean of its map without the border.
    pub channel_means: [f64; 3],
    /// The SSIM score: the mean of `channel_means`.
    pub mean: f64,
}

impl SsimMap {
    /// SSIM at pixel `(x, y)`, averaged over the three channels.
    pub fn pixel(&self, x: u32, y: u32) -> f64 {
        let i = y as usize * self.width as usize + x as usize;
        self.channels.iter().map(|c| c[i]).sum::<f64>() / 3.0
    }

    /// The mean over all pixels and channels, border included (the score excludes the border).
    pub fn full_mean(&self) -> f64 {
        let n = self.channels[0].len() * 3;
        self.channels.iter().flatten().sum::<f64>() / n as f64
    }

    /// A heat map of dissimilarity: `clamp(1 − SSIM, 0, 1)` per pixel (the channel mean) through
    /// [`heatmap::colour_ramp`] — black where the images agree, bright yellow where SSIM ≤ 0.
    pub fn to_heatmap(&self) -> Srgb8Image {
        let pixels = (0..self.height)
            .flat_map(|y| (0..self.width).map(move |x| (x, y)))
            .map(|(x, y)| heatmap::colour_ramp(1.0 - self.pixel(x, y)))
            .collect();
        Srgb8Image { width: self.width, height: self.height, pixels }
    }
}

/// scipy's `_gaussian_kernel1d(σ = 1.5, order 0, radius 5)`: `exp(−x² / 2σ²)`, normalized.
fn gaussian_kernel() -> [f64; WIN] {
    let sigma2 = SSIM_SIGMA * SSIM_SIGMA;
    let k: [f64; WIN] = std::array::from_fn(|i| {
        let x = i as f64 - R as f64;
        (-0.5 / sigma2 * (x * x)).exp()
    });
    let sum: f64 = k.iter().sum();
    k.map(|w| w / sum)
}

/// scipy's `reflect` boundary: index `i` of the infinite signal mirrored at the pixel edges
/// (`d c b a | a b c d | d c b a`), for any `i` and `n ≥ 1`.
fn reflect(i: isize, n: usize) -> usize {
    let period = 2 * n as isize;
    let m = i.rem_euclid(period) as usize;
    if m < n { m } else { 2 * n - 1 - m }
}

/// SSIM from the five Gaussian-weighted moments `[μx, μy, E[x²], E[y²], E[xy]]`, with
/// skimage's operation order.
#[inline]
fn ssim_from_moments(m: &[f64; 5]) -> f64 {
    let c1 = SSIM_K1 * SSIM_K1;
    let c2 = SSIM_K2 * SSIM_K2;
    let [ux, uy, uxx, uyy, uxy] = *m;
    let vx = uxx - ux * ux;
    let vy = uyy - uy * uy;
    let vxy = uxy - ux * uy;
    let a1 = 2.0 * ux * uy + c1;
    let a2 = 2.0 * vxy + c2;
    let b1 = ux * ux + uy * uy + c1;
    let b2 = vx + vy + c2;
    (a1 * a2) / (b1 * b2)
}

/// `out[x] = Σ_j k[j] · src[x + j]` for a symmetric kernel, summed as scipy's `correlate1d`
/// does for symmetric weights (centre tap first, then mirrored pairs). `src` holds `out.len() +
/// 2R` values. Loops run over x innermost so that they vectorize.
fn correlate_row(src: &[f64], out: &mut [f64], kernel: &[f64; WIN]) {
    let n = out.len();
    for (o, s) in out.iter_mut().zip(&src[R..R + n]) {
        *o = s * kernel[R];
    }
    for j in 1..=R {
        let (lo, hi) = (&src[R - j..R - j + n], &src[R + j..R + j + n]);
        for ((o, l), h) in out.iter_mut().zip(lo).zip(hi) {
            *o += (l + h) * kernel[R + j];
        }
    }
}

/// Rows per parallel band. Each band streams its rows through a ring of 11 horizontally
/// filtered rows (plus 10 halo rows per band), so the moments never make a full-image buffer:
/// at 1024² that buffer (40 MB per channel) made SSIM memory-bound.
const BAND: usize = 64;

/// Scratch space of one worker: padded source products, the ring, the vertical sums.
struct Scratch {
    src: Vec<f64>,
    ring: Vec<f64>,
    acc: Vec<f64>,
}

/// The SSIM map of channel `c` and the mean of its interior.
fn channel_map(a: &Srgb8Image, b: &Srgb8Image, c: usize, kernel: &[f64; WIN]) -> (Vec<f64>, f64) {
    let (w, h) = (a.width as usize, a.height as usize);
    let padded = w + 2 * R;

    // Horizontal pass for (virtual, possibly reflected) row `r`: the five filtered moments
    // x, y, x², y², xy, each as a run of `w` values in `out`.
    let horizontal = |r: isize, src: &mut [f64], out: &mut [f64]| {
        let y = reflect(r, h);
        let (row_a, row_b) = (&a.pixels[y * w..(y + 1) * w], &b.pixels[y * w..(y + 1) * w]);
        for i in 0..padded {
            let sx = reflect(i as isize - R as isize, w);
            let u = f64::from(row_a[sx][c]) / 255.0;
            let v = f64::from(row_b[sx][c]) / 255.0;
            for (q, m) in [u, v, u * u, v * v, u * v].into_iter().enumerate() {
                src[q * padded + i] = m;
            }
        }
        for (s, o) in src.chunks_exact(padded).zip(out.chunks_exact_mut(w)) {
            correlate_row(s, o, kernel);
        }
    };

    let mut map = vec![0.0f64; w * h];
    let band_sums: Vec<f64> = map
        .par_chunks_mut(BAND * w)
        .enumerate()
        .map_init(
            || Scratch {
                src: vec![0.0; 5 * padded],
                ring: vec![0.0; WIN * 5 * w],
                acc: vec![0.0; 5 * w],
            },
            |Scratch { src, ring, acc }, (band, out)| {
                let y0 = (band * BAND) as isize;
                // Virtual row r lives in ring slot (r − y0 + R) mod 11.
                let slot = |r: isize| (r - y0 + R as isize) as usize % WIN;
                for r in y0 - R as isize..y0 + R as isize {
                    let s = slot(r);
                    horizontal(r, src, &mut ring[s * 5 * w..(s + 1) * 5 * w]);
                }
                let mut sum = 0.0;
                for (dy, out) in out.chunks_exact_mut(w).enumerate() {
                    let y = y0 + dy as isize;
                    let s = slot(y + R as isize);
                    horizontal(y + R as isize, src, &mut ring[s * 5 * w..(s + 1) * 5 * w]);
                    let row = |r: isize, q: usize| {
                        let start = (slot(r) * 5 + q) * w;
                        &ring[start..start + w]
                    };
                    for (q, acc) in acc.chunks_exact_mut(w).enumerate() {
                        for (o, s) in acc.iter_mut().zip(row(y, q)) {
                            *o = s * kernel[R];
                        }
                        for j in 1..=R as isize {
                            let (lo, hi) = (row(y - j, q), row(y + j, q));
                            for ((o, l), h) in acc.iter_mut().zip(lo).zip(hi) {
                                *o += (l + h) * kernel[R + j as usize];
                            }
                        }
                    }
                    let (ux, rest) = acc.split_at(w);
                    let (uy, rest) = rest.split_at(w);
                    let (uxx, rest) = rest.split_at(w);
                    let (uyy, uxy) = rest.split_at(w);
                    for (x, o) in out.iter_mut().enumerate() {
                        *o = ssim_from_moments(&[ux[x], uy[x], uxx[x], uyy[x], uxy[x]]);
                    }
                    if (R..h - R).contains(&(y as usize)) {
                        sum += out[R..w - R].iter().sum::<f64>();
                    }
                }
                sum
            },
        )
        .collect();
    let count = (w - 2 * R) * (h - 2 * R);
    (map, band_sums.iter().sum::<f64>() / count as f64)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::patterns;

    #[test]
    fn kernel_is_normalized_and_symmetric() {
        let k = gaussian_kernel();
        assert!((k.iter().sum::<f64>() - 1.0).abs() < 1e-15);
        for i in 0..WIN {
            assert_eq!(k[i], k[WIN - 1 - i]);
        }
        assert!(k[R] > k[R + 1] && k[0] > 0.0);
        assert_eq!((SSIM_RADIUS, SSIM_WINDOW), (5, 11));
    }

    #[test]
    fn reflect_mirrors_like_scipy() {
        // n = 4: ... 1 0 | 0 1 2 3 | 3 2 ... and a period of 8.
        let got: Vec<usize> = (-5..10).map(|i| reflect(i, 4)).collect();
        assert_eq!(got, [3, 3, 2, 1, 0, 0, 1, 2, 3, 3, 2, 1, 0, 0, 1]);
        assert!((-7..7).all(|i| reflect(i, 1) == 0));
    }

    /// The obvious implementation: a direct 11×11 weighted sum per pixel with reflected indices.
    fn naive_map(a: &Srgb8Image, b: &Srgb8Image, c: usize) -> Vec<f64> {
        let (w, h) = (a.width as usize, a.height as usize);
        let k = gaussian_kernel();
        let mut map = Vec::with_capacity(w * h);
        for y in 0..h {
            for x in 0..w {
                let mut m = [0.0; 5];
                for (dy, ky) in k.iter().enumerate() {
                    for (dx, kx) in k.iter().enumerate() {
                        let sy = reflect(y as isize + dy as isize - R as isize, h);
                        let sx = reflect(x as isize + dx as isize - R as isize, w);
                        let u = f64::from(a.get(sx as u32, sy as u32)[c]) / 255.0;
                        let v = f64::from(b.get(sx as u32, sy as u32)[c]) / 255.0;
                        for (q, val) in [u, v, u * u, v * v, u * v].into_iter().enumerate() {
                            m[q] += ky * kx * val;
                        }
                    }
                }
                map.push(ssim_from_moments(&m));
            }
        }
        map
    }

    #[test]
    fn banded_separable_filter_matches_the_direct_2d_sum() {
        // 150 rows: three bands of 64 rows, the last one partial; 12 columns: barely above 11.
        let a = patterns::noise(12, 150, 7);
        let b = patterns::add_noise(&patterns::box_blur(&a), 8, 30);
        let fast = ssim_map(&a, &b).unwrap();
        for c in 0..3 {
            let slow = naive_map(&a, &b, c);
            for (i, (f, s)) in fast.channels[c].iter().zip(&slow).enumerate() {
                assert!((f - s).abs() < 1e-12, "channel {c} pixel {i}: fast {f} naive {s}");
            }
        }
        assert_eq!(ssim_map(&b, &a).unwrap().mean, fast.mean, "not symmetric");
    }

    #[test]
    fn identical_images_score_one_everywhere() {
        let a = patterns::noise(17, 13, 9);
        let m = ssim_map(&a, &a).unwrap();
        assert_eq!(m.mean, 1.0);
        assert!(m.channels.iter().flatten().all(|&s| (s - 1.0).abs() < 1e-12));
        let heat = m.to_heatmap();
        assert_eq!((heat.width, heat.height), (17, 13));
        assert!(heat.pixels.iter().all(|&p| p == heatmap::colour_ramp(0.0)));
    }

    #[test]
    fn too_small_images_are_rejected_naming_the_window() {
        let a = patterns::gradient(10, 40);
        let err = ssim(&a, &a).unwrap_err().to_string();
        assert!(err.contains("10×40") && err.contains("11×11"), "{err}");
        let a = patterns::gradient(11, 11);
        assert_eq!(ssim(&a, &a).unwrap(), 1.0);
    }

    #[test]
    fn score_is_the_mean_of_the_cropped_map() {
        let a = patterns::noise(23, 19, 1);
        let b = patterns::box_blur(&a);
        let m = ssim_map(&a, &b).unwrap();
        for c in 0..3 {
            let mut sum = 0.0;
            for y in R..19 - R {
                for x in R..23 - R {
                    sum += m.channels[c][y * 23 + x];
                }
            }
            let want = sum / ((23 - 2 * R) * (19 - 2 * R)) as f64;
            assert!((m.channel_means[c] - want).abs() < 1e-14);
        }
        assert!((m.full_mean() - m.mean).abs() > 1e-6, "border should differ here");
    }
}
