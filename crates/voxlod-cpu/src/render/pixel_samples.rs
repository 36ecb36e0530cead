//! Where the rays of a pixel go, as pure functions of integers (the WGSL mirror is the same
//! arithmetic): the stratified pattern of the ground truth ([`stratified`]), the fixed 4-ray
//! pattern of the voxel renderers ([`PATTERN_4`]), and the random streams of a render
//! ([`Streams`]) drawn from [`crate::random`].

use glam::Vec2;

use crate::random::{rand_f32, rand_u32};

/// The fixed sub-pixel positions of the voxel renderers' 4 rays per pixel: the rotated-grid
/// pattern of 4× MSAA (Direct3D's standard 4-sample positions), the same in every pixel, so a
/// voxel render has no noise and the GPU reproduces it exactly.
pub const PATTERN_4: [Vec2; 4] = [
    Vec2::new(0.375, 0.125),
    Vec2::new(0.875, 0.375),
    Vec2::new(0.125, 0.625),
    Vec2::new(0.625, 0.875),
];

/// Position in `[0, 1)²` of sample `sample` of `count` in a pixel, with `jitter ∈ [0, 1)²`.
///
/// Stratification: `rows = ⌊√count⌋` rows of samples; the first `count mod rows` rows hold
/// `⌊count/rows⌋ + 1` samples, the others `⌊count/rows⌋`. A row of `n` samples is `n/count`
/// high and split into `n` equal columns, so every sample owns a cell of area exactly
/// `1/count` and the cells tile the pixel: the average is an unbiased, stratified box filter.
/// For a square `count = k²` this is the `k × k` jittered grid. `count` must be ≥ 1.
#[inline]
pub fn stratified(sample: u32, count: u32, jitter: Vec2) -> Vec2 {
    let (lo, size) = cell(sample, count);
    // Rounding could reach the cell's far edge; keep the half-open pixel.
    (lo + jitter * size).min(Vec2::splat(ONE_BELOW))
}

/// The cell of sample `sample` of `count` (see [`stratified`]): its min corner and size.
#[inline]
fn cell(sample: u32, count: u32) -> (Vec2, Vec2) {
    let rows = count.isqrt().max(1);
    let base = count / rows;
    let long = (count % rows) * (base + 1); // samples in the rows of `base + 1`
    let (n, i, before) = if sample < long {
        (base + 1, sample % (base + 1), sample / (base + 1) * (base + 1))
    } else {
        let s = sample - long;
        (base, s % base, long + s / base * base)
    };
    let lo = Vec2::new(i as f32 / n as f32, before as f32 / count as f32);
    (lo, Vec2::new(1.0 / n as f32, n as f32 / count as f32))
}

/// The largest `f32` below 1.
const ONE_BELOW: f32 = 1.0 - f32::EPSILON / 2.0;

/// The random dimensions a render draws from, each a key derived from the render's seed, so
/// that two seeds give independent images and the purposes never share numbers. A number is
/// `rand_f32(pixel index, sample index, key)`; an alpha decision on triangle `t` uses key
/// `alpha_* ^ t`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Streams {
    /// Sub-pixel jitter, x.
    pub jitter_x: u32,
    /// Sub-pixel jitter, y.
    pub jitter_y: u32,
    /// Stochastic coverage of alpha-blended surfaces met by camera rays.
    pub alpha_primary: u32,
    /// Stochastic coverage of alpha-blended surfaces met by shadow rays.
    pub alpha_shadow: u32,
}

impl Streams {
    /// The keys of `seed`: `rand_u32(seed, purpose, 0x5EED)` for purposes 0, 1, 2, 3.
    pub fn new(seed: u32) -> Self {
        let key = |purpose| rand_u32(seed, purpose, 0x5EED);
        Self { jitter_x: key(0), jitter_y: key(1), alpha_primary: key(2), alpha_shadow: key(3) }
    }

    /// The jitter of sample `sample` in pixel `pixel`.
    #[inline]
    pub fn jitter(&self, pixel: u32, sample: u32) -> Vec2 {
        Vec2::new(rand_f32(pixel, sample, self.jitter_x), rand_f32(pixel, sample, self.jitter_y))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every count's cells tile the pixel: their areas sum to 1 and each point of a fine grid
    /// lies in exactly one cell.
    #[test]
    fn cells_tile_the_pixel_for_any_count() {
        for count in [1, 2, 3, 4, 5, 7, 8, 10, 16, 17, 63, 64, 100, 1000, 1024] {
            let cells: Vec<(Vec2, Vec2)> = (0..count).map(|s| cell(s, count)).collect();
            let area: f64 = cells.iter().map(|(_, s)| (s.x * s.y) as f64).sum();
            assert!((area - 1.0).abs() < 1e-4, "count {count}: cells cover {area}");
            for i in 0..20 {
                for j in 0..20 {
                    let p = Vec2::new(i as f32 + 0.5, j as f32 + 0.5) / 20.0;
                    let owners = cells
                        .iter()
                        .filter(|(lo, size)| p.cmpge(*lo).all() && p.cmplt(*lo + *size).all());
                    assert_eq!(owners.count(), 1, "count {count}, point {p}");
                }
            }
            for s in 0..count {
                let p = stratified(s, count, Vec2::splat(0.999_999_9));
                assert!(p.cmpge(Vec2::ZERO).all() && p.cmplt(Vec2::ONE).all(), "{count}: {p}");
            }
        }
    }

    #[test]
    fn square_counts_are_jittered_grids() {
        let p = stratified(5, 16, Vec2::splat(0.5));
        assert_eq!(p, Vec2::new(1.5 / 4.0, 1.5 / 4.0));
        assert_eq!(stratified(0, 1, Vec2::new(0.25, 0.75)), Vec2::new(0.25, 0.75));
    }

    #[test]
    fn seeds_give_distinct_streams() {
        let (a, b) = (Streams::new(0), Streams::new(1));
        let keys = |s: Streams| [s.jitter_x, s.jitter_y, s.alpha_primary, s.alpha_shadow];
        let all: std::collections::HashSet<u32> = keys(a).into_iter().chain(keys(b)).collect();
        assert_eq!(all.len(), 8);
        assert_eq!(Streams::new(7), Streams::new(7));
        assert_ne!(a.jitter(3, 4), b.jitter(3, 4));
    }
}
