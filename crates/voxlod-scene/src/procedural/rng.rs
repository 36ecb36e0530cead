//! Deterministic random numbers and trigonometry for the procedural scenes, so that a scene is a
//! pure function of its parameters and seed, bit for bit on every platform.
//!
//! - [`Rng`] is SplitMix64 (Steele, Lea and Flood, OOPSLA 2014): a 64-bit counter passed through a
//!   bijective mixer. [`Rng::stream`] hashes a seed with counters (tree index, blade index…) into
//!   an independent generator, so every object draws from its own stream and a generator could be
//!   parallelized per object without changing its output.
//! - [`sin_cos_turns`]: `f32::sin`/`cos` call the platform's libm, whose last bit may differ
//!   between platforms and releases. This one reduces the angle exactly (in turns) and evaluates a
//!   Taylor polynomial in `f64` with `+`, `−`, `×` only, which IEEE 754 rounds identically
//!   everywhere. Together with `sqrt` (also correctly rounded) it is all the generators use.

use glam::Vec3;

/// The golden-ratio increment of SplitMix64.
const GOLDEN: u64 = 0x9E37_79B9_7F4A_7C15;

/// SplitMix64's finalizer: a bijective mix of all 64 bits.
#[inline]
pub fn mix64(mut z: u64) -> u64 {
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// A SplitMix64 generator. Not cryptographic; statistically sound for procedural content.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Rng {
    state: u64,
}

impl Rng {
    /// A generator seeded with `seed`.
    pub fn new(seed: u64) -> Self {
        Self { state: mix64(seed) }
    }

    /// An independent generator for the object identified by `ids` (e.g. `[STREAM_TREES, i]`)
    /// within the scene seeded with `seed`. Different `ids` give unrelated sequences.
    pub fn stream(seed: u64, ids: &[u64]) -> Self {
        let mut s = mix64(seed ^ 0x5EED_5EED_5EED_5EED);
        for &id in ids {
            s = mix64(s ^ mix64(id.wrapping_add(GOLDEN)));
        }
        Self { state: s }
    }

    /// The next 64 random bits.
    #[inline]
    pub fn next_u64(&mut self) -> u64 {
        self.state = self.state.wrapping_add(GOLDEN);
        mix64(self.state)
    }

    /// Uniform in [0, 1), with 24 random bits (every value exactly representable).
    #[inline]
    pub fn next_f32(&mut self) -> f32 {
        (self.next_u64() >> 40) as f32 * (1.0 / (1u32 << 24) as f32)
    }

    /// Uniform in [`lo`, `hi`).
    #[inline]
    pub fn range(&mut self, lo: f32, hi: f32) -> f32 {
        lo + (hi - lo) * self.next_f32()
    }

    /// Uniform integer in `0..n` (`n > 0`), by Lemire's multiply-shift on 32 bits (bias below
    /// 2⁻³² · n, irrelevant here).
    #[inline]
    pub fn below(&mut self, n: u32) -> u32 {
        (((self.next_u64() >> 32) * n as u64) >> 32) as u32
    }

    /// A uniformly distributed unit vector (Archimedes: uniform height, uniform azimuth).
    #[inline]
    pub fn unit_vector(&mut self) -> Vec3 {
        let y = 1.0 - 2.0 * self.next_f32();
        let r = (1.0 - y * y).max(0.0).sqrt();
        let (s, c) = sin_cos_turns(self.next_f32());
        Vec3::new(r * c, y, r * s)
    }

    /// A uniform point in the unit ball, by rejection from the cube (on average 1.9 draws).
    #[inline]
    pub fn in_unit_ball(&mut self) -> Vec3 {
        loop {
            let p = Vec3::new(self.range(-1.0, 1.0), self.range(-1.0, 1.0), self.range(-1.0, 1.0));
            if p.length_squared() <= 1.0 {
                return p;
            }
        }
    }
}

/// Coefficients of sin t = Σ cₖ t^(2k+1): (−1)ᵏ/(2k+1)!, k = 0..=8.
const SIN_TAYLOR: [f64; 9] = [
    1.0,
    -1.0 / 6.0,
    1.0 / 120.0,
    -1.0 / 5_040.0,
    1.0 / 362_880.0,
    -1.0 / 39_916_800.0,
    1.0 / 6_227_020_800.0,
    -1.0 / 1_307_674_368_000.0,
    1.0 / 355_687_428_096_000.0,
];

/// `sin(2π·x)` for `x` in [−¼, ¼], by its Taylor series to degree 17: the first omitted term is
/// below (π/2)¹⁹/19! < 5e−14.
fn sin_quarter(x: f64) -> f64 {
    let t = x * std::f64::consts::TAU;
    let t2 = t * t;
    SIN_TAYLOR.iter().rev().fold(0.0, |acc, &c| acc * t2 + c) * t
}

/// `sin(2π·x)` for any finite `x`: exact reduction to [−½, ½] (subtracting the nearest integer
/// is exact in `f64`), then the symmetry sin(π − θ) = sin θ folds it to [−¼, ¼].
fn sin_turns(x: f64) -> f64 {
    let r = x - x.round();
    let r = if r > 0.25 {
        0.5 - r
    } else if r < -0.25 {
        -0.5 - r
    } else {
        r
    };
    sin_quarter(r)
}

/// `(sin, cos)` of the angle `t` given in turns (1 turn = 2π radians), deterministic on every
/// platform (see the module docs). Absolute error below 1e−7 (the `f32` rounding).
#[inline]
pub fn sin_cos_turns(t: f32) -> (f32, f32) {
    let x = t as f64;
    (sin_turns(x) as f32, sin_turns(x + 0.25) as f32)
}

/// `(sin, cos)` of an angle in degrees, deterministic on every platform.
#[inline]
pub fn sin_cos_deg(deg: f32) -> (f32, f32) {
    let x = deg as f64 / 360.0;
    (sin_turns(x) as f32, sin_turns(x + 0.25) as f32)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn splitmix_matches_the_reference_sequence() {
        // Reference values of SplitMix64 seeded with state 0 (Vigna's splitmix64.c): the first
        // output is mix64(0x9E3779B97F4A7C15).
        let mut r = Rng { state: 0 };
        assert_eq!(r.next_u64(), 0xE220_A839_7B1D_CDAF);
        assert_eq!(r.next_u64(), 0x6E78_9E6A_A1B9_65F4);
    }

    #[test]
    fn streams_are_distinct_and_reproducible() {
        let a: Vec<u64> = (0..4).map(|_| Rng::stream(7, &[1, 2]).next_u64()).collect();
        assert!(a.windows(2).all(|w| w[0] == w[1]));
        let b = Rng::stream(7, &[2, 1]).next_u64();
        let c = Rng::stream(8, &[1, 2]).next_u64();
        assert!(a[0] != b && a[0] != c && b != c);
    }

    #[test]
    fn uniform_draws_stay_in_range_and_fill_it() {
        let mut r = Rng::new(3);
        let (mut lo, mut hi, mut sum) = (1.0f32, 0.0f32, 0.0f64);
        let mut bins = [0u32; 5];
        for _ in 0..20_000 {
            let x = r.next_f32();
            assert!((0.0..1.0).contains(&x));
            lo = lo.min(x);
            hi = hi.max(x);
            sum += x as f64;
            bins[r.below(5) as usize] += 1;
        }
        assert!(lo < 1e-3 && hi > 0.999, "{lo} {hi}");
        assert!((sum / 20_000.0 - 0.5).abs() < 0.01, "mean {}", sum / 20_000.0);
        assert!(bins.iter().all(|&b| (3_600..4_400).contains(&b)), "{bins:?}");
    }

    #[test]
    fn unit_vectors_are_unit_and_balanced() {
        let mut r = Rng::new(11);
        let mut mean = Vec3::ZERO;
        for _ in 0..10_000 {
            let v = r.unit_vector();
            assert!((v.length() - 1.0).abs() < 1e-5, "{v}");
            mean += v;
            assert!(r.in_unit_ball().length_squared() <= 1.0);
        }
        assert!((mean / 10_000.0).length() < 0.03, "{mean}");
    }

    #[test]
    fn deterministic_trig_agrees_with_std() {
        let mut worst = 0.0f64;
        for i in -2_000..=2_000 {
            let t = i as f32 * 0.001_37;
            let (s, c) = sin_cos_turns(t);
            let a = t as f64 * std::f64::consts::TAU;
            worst = worst.max((s as f64 - a.sin()).abs()).max((c as f64 - a.cos()).abs());
        }
        assert!(worst < 2e-7, "worst error {worst:e}");
        assert_eq!(sin_cos_deg(90.0), (1.0, 0.0));
        assert_eq!(sin_cos_deg(0.0), (0.0, 1.0));
        assert_eq!(sin_cos_turns(0.5).1, -1.0);
    }
}
