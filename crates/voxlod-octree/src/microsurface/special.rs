//! The error functions the Gaussian micro-surface needs, written out (the standard library's
//! are not stable) so that the GPU kernel can mirror them operation for operation: `erf`,
//! `erfc` and the scaled `erfcx(x) = e^{x²}·erfc(x)`, in `f64` (the CPU reference) and in `f32`
//! (the arithmetic the WGSL kernel runs, mirrored here so that its accuracy is tested on the
//! CPU).
//!
//! # Method (the same in both precisions, only the term counts differ)
//! - `0 ≤ x < 2`: `erf(x) = (2/√π)·e^{−x²}·Σ_{n≥0} x·(2x²)^n / (1·3·5···(2n+1))` (Abramowitz &
//!   Stegun 7.1.6): every term is positive, so the sum has no cancellation; `erfc = 1 − erf`,
//!   which loses at most `log10(1/erfc(2)) ≈ 2.3` digits at the top of the range.
//! - `x ≥ 2` (`f64`; `x ≥ 1.5` in `f32`): the continued fraction of Laplace (A&S 7.1.14),
//!   `√π·erfcx(x) = 1/(x + K(x))`, `K(x) = (1/2)/(x + 1/(x + (3/2)/(x + 2/(x + …))))`,
//!   evaluated backwards from a fixed depth ([`CF_TERMS_F64`], [`CF_TERMS_F32`]: enough for
//!   the precision at the split, where it converges slowest). `erfc = e^{−x²}·erfcx` never cancels and underflows only where the
//!   true value does (`x > 26.6` in `f64`, `x > 9.2` in `f32`, both returning `+0`).
//! - Negative arguments by symmetry: `erf(−x) = −erf(x)`, `erfc(−x) = 2 − erfc(x)`.
//! - NaN gives NaN; `±∞` the limits (`erf(±∞) = ±1`, `erfc(+∞) = 0`, `erfc(−∞) = 2`).
//!
//! [`K`](cf_tail_f64) is exposed because Smith's Λ uses it directly: `1 − x√π·erfcx(x) =
//! K/(x + K)` is the quantity whose closed form cancels (`smith` module).
//!
//! Accuracy against a 50-digit reference (tests): `f64` within `5e-14` relative for `erfc` on
//! `[−10, 26]` (the worst just below the split, where `1 − erf` loses two digits), `f32`
//! within `4e-6` relative on `[0, 9]` (where `erfc ≥ 1e-37`).

/// `√π`.
pub const SQRT_PI: f64 = 1.772_453_850_905_516;
use std::f64::consts::FRAC_2_SQRT_PI;

/// Continued-fraction depth in `f64` (relative error below `1e-16` from `x = 2` on).
pub const CF_TERMS_F64: u32 = 64;
/// Continued-fraction depth in `f32` (relative error below `1e-7` from [`SPLIT_F32`] on).
pub const CF_TERMS_F32: u32 = 30;
/// Positive-term series length in `f64` (`x < 2`).
const SERIES_TERMS_F64: u32 = 60;
/// Positive-term series length in `f32` (`x < 2`).
pub const SERIES_TERMS_F32: u32 = 24;
/// Where the series hands over to the continued fraction, `f64`.
pub const SPLIT: f64 = 2.0;
/// Where the series hands over to the continued fraction, `f32` (lower than in `f64`: `1 − erf`
/// would lose a larger share of `f32`'s fewer digits).
pub const SPLIT_F32: f32 = 1.5;

/// The continued-fraction tail `K(x)` of the module docs, for `x > 0` (`f64`), with
/// [`CF_TERMS_F64`] terms.
pub fn cf_tail_f64(x: f64) -> f64 {
    cf_tail_f64_terms(x, CF_TERMS_F64)
}

/// [`cf_tail_f64`] with `terms` terms (128 reach `1e-16` from `x = 1.5` on, 210 from `x = 1`).
pub fn cf_tail_f64_terms(x: f64, terms: u32) -> f64 {
    let mut t = 0.0;
    for k in (1..=terms).rev() {
        t = (0.5 * k as f64) / (x + t);
    }
    t
}

/// `erf` on `0 ≤ x < 2` by the positive series (module docs), `f64`.
fn erf_series_f64(x: f64) -> f64 {
    let two_x2 = 2.0 * x * x;
    let mut term = x;
    let mut sum = x;
    for n in 1..SERIES_TERMS_F64 {
        term *= two_x2 / (2 * n + 1) as f64;
        sum += term;
    }
    FRAC_2_SQRT_PI * (-x * x).exp() * sum
}

/// The error function, `f64` (module docs).
pub fn erf_f64(x: f64) -> f64 {
    if x.is_nan() {
        return x;
    }
    let a = x.abs();
    let r = if a < SPLIT { erf_series_f64(a) } else { 1.0 - erfc_positive_f64(a) };
    r.copysign(x)
}

/// `erfc` for `x ≥ 2` (or `+∞`), `f64`.
fn erfc_positive_f64(x: f64) -> f64 {
    if x == f64::INFINITY {
        return 0.0;
    }
    (-x * x).exp() / (SQRT_PI * (x + cf_tail_f64(x)))
}

/// The complementary error function `1 − erf(x)`, `f64` (module docs).
pub fn erfc_f64(x: f64) -> f64 {
    if x.is_nan() {
        return x;
    }
    let a = x.abs();
    let r = if a < SPLIT { 1.0 - erf_series_f64(a) } else { erfc_positive_f64(a) };
    if x < 0.0 { 2.0 - r } else { r }
}

/// The scaled complementary error function `e^{x²}·erfc(x)` for `x ≥ 0`, `f64`: finite and
/// accurate where `erfc` underflows (`erfcx(x) ≈ 1/(x√π)` for large `x`). NaN below 0.
pub fn erfcx_f64(x: f64) -> f64 {
    if x.is_nan() || x < 0.0 {
        return f64::NAN;
    }
    if x < SPLIT {
        (x * x).exp() * (1.0 - erf_series_f64(x))
    } else if x == f64::INFINITY {
        0.0
    } else {
        1.0 / (SQRT_PI * (x + cf_tail_f64(x)))
    }
}

/// [`cf_tail_f64`] in `f32` with [`CF_TERMS_F32`] terms (the WGSL kernel's arithmetic).
pub fn cf_tail_f32(x: f32) -> f32 {
    let mut t = 0.0f32;
    let mut k = CF_TERMS_F32;
    while k > 0 {
        t = (0.5 * k as f32) / (x + t);
        k -= 1;
    }
    t
}

fn erf_series_f32(x: f32) -> f32 {
    let two_x2 = 2.0 * x * x;
    let mut term = x;
    let mut sum = x;
    let mut n = 1u32;
    while n < SERIES_TERMS_F32 {
        term *= two_x2 / (2 * n + 1) as f32;
        sum += term;
        n += 1;
    }
    FRAC_2_SQRT_PI as f32 * (-x * x).exp() * sum
}

/// [`erfc_f64`] in `f32` (the WGSL kernel's arithmetic). Arguments above 9.5 return `+0`
/// directly (the true value is below `3e-41`, under `f32`'s normal range, which GPUs may flush).
pub fn erfc_f32(x: f32) -> f32 {
    if x.is_nan() {
        return x;
    }
    let a = x.abs();
    let r = if a < SPLIT_F32 {
        1.0 - erf_series_f32(a)
    } else if a > 9.5 {
        0.0
    } else {
        (-a * a).exp() / (SQRT_PI as f32 * (a + cf_tail_f32(a)))
    };
    if x < 0.0 { 2.0 - r } else { r }
}

/// [`erf_f64`] in `f32` (the WGSL kernel's arithmetic).
pub fn erf_f32(x: f32) -> f32 {
    if x.is_nan() {
        return x;
    }
    let a = x.abs();
    let r = if a < SPLIT_F32 { erf_series_f32(a) } else { 1.0 - erfc_f32(a) };
    r.copysign(x)
}

/// `erf` to within `1.5e-7` absolute (Abramowitz & Stegun 7.1.26: one `exp` and a degree-5
/// polynomial in `1/(1 + 0.3275911·|x|)`), for statistics that are stored in `f32` anyway
/// (the pre-filter's colour profile, evaluated many times per node). Odd; NaN gives NaN.
pub fn erf_approx(x: f64) -> f64 {
    let a = x.abs();
    let t = 1.0 / (1.0 + 0.327_591_1 * a);
    let poly = t
        * (0.254_829_592
            + t * (-0.284_496_736
                + t * (1.421_413_741 + t * (-1.453_152_027 + t * 1.061_405_429))));
    (1.0 - poly * (-a * a).exp()).copysign(x)
}

#[cfg(test)]
mod tests;
