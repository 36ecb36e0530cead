//! Paired differences with a bootstrap interval: how the paper setup says "A beats B" only when
//! the evidence does.
//!
//! Two measurements are *paired* when they come from the same view and the same seeds of every
//! random source; their difference removes what the view and the seed contribute to both. The
//! interval is the percentile bootstrap (Efron and Tibshirani 1993, §13.3) of the mean paired
//! difference: [`BOOTSTRAP_RESAMPLES`] resamples with replacement of the pairs, drawn from a
//! fixed-seed generator so a run reproduces its intervals exactly, and the 2.5th and 97.5th
//! percentiles of their means.

/// Resamples of the bootstrap.
pub const BOOTSTRAP_RESAMPLES: usize = 4000;

/// The mean of paired differences and its 95 % bootstrap interval.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct PairedDiff {
    /// Mean of `a − b` over the pairs.
    pub mean: f64,
    /// 2.5th percentile of the bootstrap means.
    pub lo: f64,
    /// 97.5th percentile of the bootstrap means.
    pub hi: f64,
    /// Number of pairs.
    pub pairs: usize,
}

impl PairedDiff {
    /// The paired differences `a[i] − b[i]` (the slices must be paired element by element and of
    /// equal, non-zero length; NaN otherwise).
    pub fn of(a: &[f64], b: &[f64]) -> Self {
        if a.len() != b.len() || a.is_empty() {
            return Self { mean: f64::NAN, lo: f64::NAN, hi: f64::NAN, pairs: 0 };
        }
        let d: Vec<f64> = a.iter().zip(b).map(|(x, y)| x - y).collect();
        let n = d.len();
        let mean = d.iter().sum::<f64>() / n as f64;
        let mut state = 0x9E37_79B9_7F4A_7C15_u64 ^ n as u64;
        let mut means: Vec<f64> = (0..BOOTSTRAP_RESAMPLES)
            .map(|_| {
                let s: f64 = (0..n).map(|_| d[(splitmix(&mut state) % n as u64) as usize]).sum();
                s / n as f64
            })
            .collect();
        means.sort_by(f64::total_cmp);
        let at =
            |q: f64| means[((q * (means.len() - 1) as f64).round() as usize).min(means.len() - 1)];
        Self { mean, lo: at(0.025).min(mean), hi: at(0.975).max(mean), pairs: n }
    }

    /// Whether the interval excludes zero (a resolved difference).
    pub fn resolved(&self) -> bool {
        self.lo > 0.0 || self.hi < 0.0
    }

    /// `mean [lo, hi]` in scientific notation with `digits` significant decimals.
    pub fn display_sci(&self, digits: usize) -> String {
        format!("{:+.d$e} [{:+.d$e}, {:+.d$e}]", self.mean, self.lo, self.hi, d = digits)
    }

    /// `mean [lo, hi]` with `digits` decimals.
    pub fn display_fixed(&self, digits: usize) -> String {
        format!("{:+.d$} [{:+.d$}, {:+.d$}]", self.mean, self.lo, self.hi, d = digits)
    }
}

/// SplitMix64 (Steele, Lea and Flood 2014): a small, well-mixed generator for the resampling.
fn splitmix(state: &mut u64) -> u64 {
    *state = state.wrapping_add(0x9E37_79B9_7F4A_7C15);
    let mut z = *state;
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_constant_shift_is_resolved_with_a_zero_width_interval() {
        let a = [0.3, 0.5, 0.1, 0.9];
        let b: Vec<f64> = a.iter().map(|x| x - 0.05).collect();
        let d = PairedDiff::of(&a, &b);
        assert!((d.mean - 0.05).abs() < 1e-12 && (d.lo - 0.05).abs() < 1e-12);
        assert!((d.hi - 0.05).abs() < 1e-12 && d.resolved());
    }

    #[test]
    fn differences_of_both_signs_are_not_resolved() {
        // Pairing matters: the views differ a lot, the methods differ by ±0.01 around zero.
        let a = [0.10, 0.50, 0.90, 0.30, 0.70, 0.20];
        let b = [0.11, 0.49, 0.91, 0.29, 0.71, 0.19];
        let d = PairedDiff::of(&a, &b);
        assert!(d.lo < 0.0 && d.hi > 0.0 && !d.resolved(), "{d:?}");
        assert!(d.lo >= -0.01 && d.hi <= 0.01, "{d:?}");
    }

    #[test]
    fn a_consistent_small_gain_under_large_view_variation_is_resolved() {
        // Unpaired, the views' spread (0.1–0.9) would swamp a 0.01 gain; paired it is clear.
        let a = [0.10, 0.50, 0.90, 0.30, 0.70, 0.20, 0.40, 0.60];
        let b: Vec<f64> =
            a.iter().enumerate().map(|(i, x)| x - 0.01 - 0.002 * (i % 3) as f64).collect();
        let d = PairedDiff::of(&a, &b);
        assert!(d.resolved() && d.lo > 0.009 && d.hi < 0.013, "{d:?}");
    }

    #[test]
    fn mismatched_or_empty_inputs_give_nan() {
        assert!(PairedDiff::of(&[], &[]).mean.is_nan());
        assert!(PairedDiff::of(&[1.0], &[1.0, 2.0]).mean.is_nan());
        assert!(!PairedDiff::of(&[1.0], &[1.0, 2.0]).resolved());
    }
}
