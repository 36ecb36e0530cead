//! Mean and range of a metric over views, and the millisecond conversion every study uses.

use std::time::Duration;

/// Mean and range of a metric over the views.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct Spread {
    /// Mean.
    pub mean: f64,
    /// Minimum.
    pub min: f64,
    /// Maximum.
    pub max: f64,
}

impl Spread {
    /// Mean, min and max of `values` (NaN for none).
    pub fn of(values: &[f64]) -> Self {
        if values.is_empty() {
            return Self { mean: f64::NAN, min: f64::NAN, max: f64::NAN };
        }
        Self {
            mean: values.iter().sum::<f64>() / values.len() as f64,
            min: values.iter().copied().fold(f64::INFINITY, f64::min),
            max: values.iter().copied().fold(f64::NEG_INFINITY, f64::max),
        }
    }

    /// The spread of `f` applied to each statistic (for monotone `f`, e.g. `1 − x` swaps min and
    /// max).
    pub fn map(self, f: impl Fn(f64) -> f64) -> Self {
        let (a, b) = (f(self.min), f(self.max));
        Self { mean: f(self.mean), min: a.min(b), max: a.max(b) }
    }

    /// `mean (min–max)` with `digits` decimals.
    pub fn display(&self, digits: usize) -> String {
        format!("{:.d$} ({:.d$}–{:.d$})", self.mean, self.min, self.max, d = digits)
    }
}

pub(crate) fn ms(d: Duration) -> f64 {
    d.as_secs_f64() * 1e3
}
