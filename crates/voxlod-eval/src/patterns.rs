//! Deterministic 8-bit test images built from integer arithmetic only — gradients, checkerboards,
//! hash noise, and box blurs, shifts, noise, inversion and quantization of them — so that
//! `tools/ssim_check/check.py` builds bit-identical images in Python and the metrics can be
//! checked against scikit-image (see the crate docs). Benchmarks use them as inputs.
//!
//! Every function here has a twin of the same name in `check.py`; change both or neither. The
//! [`fnv1a64`] digest of an image lets a test tell "the images differ" apart from "the metric
//! differs".

use voxlod_scene::Srgb8Image;

/// Wellons' `lowbias32` integer hash on wrapping `u32` arithmetic.
pub fn hash32(mut x: u32) -> u32 {
    x ^= x >> 16;
    x = x.wrapping_mul(0x7feb_352d);
    x ^= x >> 15;
    x = x.wrapping_mul(0x846c_a68b);
    x ^= x >> 16;
    x
}

/// 64-bit FNV-1a over the image's RGB bytes, row-major from the top-left.
pub fn fnv1a64(img: &Srgb8Image) -> u64 {
    img.pixels
        .iter()
        .flatten()
        .fold(0xcbf2_9ce4_8422_2325, |h, &b| (h ^ u64::from(b)).wrapping_mul(0x0000_0100_0000_01b3))
}

fn from_fn(width: u32, height: u32, f: impl Fn(u32, u32) -> [u8; 3]) -> Srgb8Image {
    let pixels = (0..height).flat_map(|y| (0..width).map(move |x| (x, y))).map(|(x, y)| f(x, y));
    Srgb8Image { width, height, pixels: pixels.collect() }
}

fn map_channels(img: &Srgb8Image, f: impl Fn(usize, u8, usize) -> u8) -> Srgb8Image {
    let pixels = img.pixels.iter().enumerate().map(|(i, p)| [0, 1, 2].map(|c| f(i, p[c], c)));
    Srgb8Image { width: img.width, height: img.height, pixels: pixels.collect() }
}

/// Red ramps along x, green along y, blue along the diagonal, each from 0 to 255
/// (`v = t · 255 / (n − 1)`, integer division).
pub fn gradient(width: u32, height: u32) -> Srgb8Image {
    let ramp = |t: u32, n: u32| (t * 255).checked_div(n).unwrap_or(0) as u8;
    from_fn(width, height, |x, y| {
        [ramp(x, width - 1), ramp(y, height - 1), ramp(x + y, width + height - 2)]
    })
}

/// A checkerboard of `cell`-pixel squares, `[230, 200, 170]` where `x/cell + y/cell` is even
/// and `[20, 40, 60]` where it is odd. `cell` must be positive.
pub fn checker(width: u32, height: u32, cell: u32) -> Srgb8Image {
    from_fn(width, height, |x, y| {
        if (x / cell + y / cell).is_multiple_of(2) { [230, 200, 170] } else { [20, 40, 60] }
    })
}

/// Uniform noise: channel `c` of pixel `(x, y)` is the top byte of
/// `hash32(((y·width + x)·3 + c) + seed·0x9E3779B9)` (wrapping).
pub fn noise(width: u32, height: u32, seed: u32) -> Srgb8Image {
    let offset = seed.wrapping_mul(0x9e37_79b9);
    from_fn(width, height, |x, y| {
        let base = y.wrapping_mul(width).wrapping_add(x).wrapping_mul(3);
        [0, 1, 2].map(|c| (hash32(base.wrapping_add(c).wrapping_add(offset)) >> 24) as u8)
    })
}

/// An image of one colour.
pub fn constant(width: u32, height: u32, rgb: [u8; 3]) -> Srgb8Image {
    Srgb8Image::new(width, height, rgb)
}

/// 3×3 box blur with clamped edges, rounded: `(sum + 4) / 9`.
pub fn box_blur(img: &Srgb8Image) -> Srgb8Image {
    let (w, h) = (img.width as i64, img.height as i64);
    from_fn(img.width, img.height, |x, y| {
        let mut sum = [0u32; 3];
        for dy in -1..=1 {
            for dx in -1..=1 {
                let sx = (x as i64 + dx).clamp(0, w - 1) as u32;
                let sy = (y as i64 + dy).clamp(0, h - 1) as u32;
                let p = img.get(sx, sy);
                for c in 0..3 {
                    sum[c] += u32::from(p[c]);
                }
            }
        }
        sum.map(|s| ((s + 4) / 9) as u8)
    })
}

/// The image moved by `(dx, dy)` pixels: `out(x, y) = in(clamp(x − dx), clamp(y − dy))`.
pub fn shift(img: &Srgb8Image, dx: i32, dy: i32) -> Srgb8Image {
    let (w, h) = (i64::from(img.width), i64::from(img.height));
    from_fn(img.width, img.height, |x, y| {
        let sx = (i64::from(x) - i64::from(dx)).clamp(0, w - 1) as u32;
        let sy = (i64::from(y) - i64::from(dy)).clamp(0, h - 1) as u32;
        img.get(sx, sy)
    })
}

/// Adds integer noise in `[−amplitude, amplitude]` to every channel and clamps to `[0, 255]`:
/// channel `c` of pixel `i` gets `hash32(i·3 + c + seed·0x9E3779B9) mod (2·amplitude + 1) −
/// amplitude`.
pub fn add_noise(img: &Srgb8Image, seed: u32, amplitude: u32) -> Srgb8Image {
    let offset = seed.wrapping_mul(0x9e37_79b9);
    map_channels(img, |i, v, c| {
        let h = hash32((i as u32).wrapping_mul(3).wrapping_add(c as u32).wrapping_add(offset));
        let delta = i64::from(h % (2 * amplitude + 1)) - i64::from(amplitude);
        (i64::from(v) + delta).clamp(0, 255) as u8
    })
}

/// `255 − v` per channel.
pub fn invert(img: &Srgb8Image) -> Srgb8Image {
    map_channels(img, |_, v, _| 255 - v)
}

/// Quantizes every channel down to a multiple of `step`: `(v / step) · step`. `step` must be
/// positive.
pub fn quantize(img: &Srgb8Image, step: u8) -> Srgb8Image {
    map_channels(img, |_, v, _| v / step * step)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hash_matches_the_python_twin() {
        // hash32(1) as printed by the Python twin: `python3 -c "import check;
        // print(hex(check.hash32(1)))"` in tools/ssim_check.
        assert_eq!(hash32(0), 0);
        assert_eq!(hash32(1), 0x6889_90c0);
    }

    #[test]
    fn gradient_spans_the_full_range() {
        let g = gradient(5, 3);
        assert_eq!(g.get(0, 0), [0, 0, 0]);
        assert_eq!(g.get(4, 2), [255, 255, 255]);
        assert_eq!(g.get(2, 1), [127, 127, 127]);
        // Degenerate sizes do not divide by zero.
        assert_eq!(gradient(1, 1).get(0, 0), [0, 0, 0]);
    }

    #[test]
    fn blur_of_a_constant_is_the_constant_and_shift_clamps() {
        let c = constant(4, 3, [7, 100, 255]);
        assert_eq!(box_blur(&c), c);
        let g = gradient(6, 4);
        let s = shift(&g, 2, -1);
        assert_eq!(s.get(0, 0), g.get(0, 1));
        assert_eq!(s.get(5, 3), g.get(3, 3));
    }

    #[test]
    fn noise_depends_on_the_seed_and_add_noise_stays_in_bounds() {
        assert_ne!(noise(8, 8, 1), noise(8, 8, 2));
        assert_eq!(noise(8, 8, 1), noise(8, 8, 1));
        let n = add_noise(&constant(8, 8, [0, 128, 255]), 3, 40);
        let greens: Vec<u8> = n.pixels.iter().map(|p| p[1]).collect();
        assert!(greens.iter().all(|g| (88..=168).contains(g)), "{greens:?}");
        assert!(greens.iter().any(|&g| g != greens[0]), "no noise added");
        assert!(n.pixels.iter().any(|p| p[0] == 0) && n.pixels.iter().any(|p| p[2] == 255));
        assert_eq!(invert(&invert(&n)), n);
        assert!(quantize(&n, 32).pixels.iter().flatten().all(|v| v % 32 == 0));
    }
}
