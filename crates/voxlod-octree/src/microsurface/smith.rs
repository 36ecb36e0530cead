//! Smith's model of a Gaussian micro-surface (Smith 1967, as Heitz and Neyret 2012 §3 and §5.5
//! use it), written to be stable over the whole domain of every argument.
//!
//! The micro-surface has heights `h ~ N(0, σh²)` about its macro-surface and slopes of standard
//! deviation `σ` along the projected direction of interest. For a direction at angle `θ` from
//! the macro-normal, `μ = cot θ` and `a = μ/(√2·σ)`:
//! - **height CDF** (Eq. 5): `g(h) = 1 − ½·erfc(h/(√2·σh))` ([`height_cdf`]); the attribute
//!   profile `s(h) = 2g(h) − 1 = erf(h/(√2·σh))` ([`height_profile`]);
//! - **Λ** (Eq. 6): `Λ = ½·(e^{−a²}/(a√π) − erfc(a))` ([`lambda`]), and the visibility of a
//!   point at height `h` along the direction, `V = g(h)^Λ` (Eq. 4);
//! - **masking** `G₁ = ∫ g′(h)·g(h)^Λ dh = 1/(1 + Λ)` ([`masking`]);
//! - **light visibility of the visible micro-surface** `∫ g′ g^{Λv+Λl} / ∫ g′ g^{Λv} =
//!   (1 + Λv)/(1 + Λv + Λl)` ([`light_visibility`]: the `V̄(l)` of Eq. 13);
//! - **visible attribute** (Eq. 17) `ā(v, l) = ā + aₛ·(2(Λv + Λl + 1)/(Λv + Λl + 2) − 1) = ā +
//!   aₛ·S/(S + 2)`, `S = Λv + Λl` ([`attribute_factor`]).
//!
//! # Stability (each case has a test against a 50-digit reference or a limit)
//! - **`a → ∞`** (smooth surface, or a direction near the normal): the closed form of Eq. 6
//!   subtracts two numbers that agree to `1 − 1/(2a²)`, so it multiplies the relative error of
//!   its `erfc` by `2a²`; and where `erfc` is taken as `1 − erf` (WGSL has no `erfc`) it is
//!   lost entirely once `erfc(a)` falls below an ulp of 1 (`a ≈ 3.9` in `f32`, `5.9` in `f64`),
//!   giving zero, garbage or a negative Λ. From `a ≥ 1.5` on (both precisions) Λ is computed as `e^{−a²}·K/(2√π·a·(a + K))` with Laplace's continued fraction
//!   `K` (`special` module): no subtraction, the same relative error at every `a`, and `+0`
//!   only where the true value underflows.
//! - **`a → 0⁺`** (grazing direction, or `σ → ∞`): `Λ ≈ 1/(2a√π) − ½` grows without bound;
//!   `+∞` at `a = 0` in `f64`. [`masking`] is computed as `2a√π/(e^{−a²} + a√π(1 + erf a))`,
//!   which has no overflow and no 0/0.
//! - **`μ ≤ 0`** (the direction is below the macro-surface, e.g. a macro-normal interpolated
//!   past a silhouette): the analytic continuation of Eq. 6 gives `Λ ≤ −1` and a "visibility"
//!   above 1, which has no meaning; such a direction sees nothing of the micro-surface, so
//!   `Λ = +∞` (`G₁ = 0`, `V̄(l) = 0` for a light there).
//! - **`σ → 0`** (a perfectly smooth surface): `Λ = 0`, `G₁ = 1`, `ā(v, l) = ā`, `V̄(l) = 1`:
//!   the unfiltered result. **`σ = +∞`**: `Λ = +∞` for every `μ > 0`.
//! - **`f32`** (the GPU kernel's precision): [`lambda_cs_f32`] takes `cos θ` and `sin θ` rather
//!   than `μ = cos/sin` (no infinity at normal incidence), never produces an infinity (WGSL
//!   leaves them undefined: results are clamped to [`LAMBDA_MAX_F32`]) and returns `+0` above
//!   `a = 9.5`, where the true value is below `f32`'s normal range.
//!
//! NaN arguments give NaN; a negative `σ` is NaN.

use std::f64::consts::SQRT_2;

use super::special::{
    SPLIT_F32, SQRT_PI, cf_tail_f32, cf_tail_f64_terms, erf_f64, erfc_f32, erfc_f64,
};

/// Where [`lambda_of_a`] hands over from the closed form to the continued fraction (`f64`):
/// below it the closed form multiplies `erfc`'s error by at most `2a² + 1 ≈ 5.5`.
pub const LAMBDA_SPLIT: f64 = 1.5;
/// Continued-fraction depth of [`lambda_of_a`] (relative error below `1e-16` from
/// [`LAMBDA_SPLIT`] on).
pub const LAMBDA_CF_TERMS: u32 = 128;

/// Largest Λ the `f32` functions return (they never return an infinity; module docs).
pub const LAMBDA_MAX_F32: f32 = 1e30;

/// Λ as a function of `a = μ/(√2·σ) ≥ 0` (module docs), `f64`.
pub fn lambda_of_a(a: f64) -> f64 {
    if a.is_nan() || a < 0.0 {
        return f64::NAN;
    }
    if a == 0.0 {
        return f64::INFINITY;
    }
    if a == f64::INFINITY {
        return 0.0;
    }
    if a < LAMBDA_SPLIT {
        0.5 * ((-a * a).exp() / (a * SQRT_PI) - erfc_f64(a))
    } else {
        let k = cf_tail_f64_terms(a, LAMBDA_CF_TERMS);
        (-a * a).exp() * k / (2.0 * SQRT_PI * a * (a + k))
    }
}

/// Smith's Λ (Eq. 6) for `μ = cot θ` and slope standard deviation `σ ≥ 0` along the projected
/// direction (module docs: `μ ≤ 0` is `+∞`, `σ = 0` or `μ = +∞` is 0, `σ = +∞` is `+∞` for
/// finite `μ > 0`).
pub fn lambda(mu: f64, sigma: f64) -> f64 {
    if mu.is_nan() || sigma.is_nan() || sigma < 0.0 {
        return f64::NAN;
    }
    if mu <= 0.0 {
        return f64::INFINITY;
    }
    if mu == f64::INFINITY || sigma == 0.0 {
        return 0.0;
    }
    lambda_of_a(mu / (SQRT_2 * sigma))
}

/// The masking function `G₁ = 1/(1 + Λ)` in \[0, 1\], computed without cancellation or
/// overflow (module docs). Same special cases as [`lambda`].
pub fn masking(mu: f64, sigma: f64) -> f64 {
    if mu.is_nan() || sigma.is_nan() || sigma < 0.0 {
        return f64::NAN;
    }
    if mu <= 0.0 {
        return 0.0;
    }
    if mu == f64::INFINITY || sigma == 0.0 {
        return 1.0;
    }
    let a = mu / (SQRT_2 * sigma);
    if a == 0.0 {
        return 0.0;
    }
    if a == f64::INFINITY {
        return 1.0;
    }
    // 1 + Λ = ½·(e^{−a²}/(a√π) + 1 + erf a): every term positive.
    2.0 / ((-a * a).exp() / (a * SQRT_PI) + 1.0 + erf_f64(a))
}

/// The height CDF `g(h)` of Eq. 5 for height standard deviation `σh ≥ 0`, computed as
/// `½·erfc(−h/(√2·σh))` (no cancellation where `g` is small). `σh = 0` is the step at 0
/// (`g(0) = ½`, the limit of every `σh > 0`).
pub fn height_cdf(h: f64, sigma_h: f64) -> f64 {
    if h.is_nan() || sigma_h.is_nan() || sigma_h < 0.0 {
        return f64::NAN;
    }
    if sigma_h == 0.0 {
        return if h > 0.0 {
            1.0
        } else if h < 0.0 {
            0.0
        } else {
            0.5
        };
    }
    0.5 * erfc_f64(-h / (SQRT_2 * sigma_h))
}

/// The attribute profile `s(h) = 2g(h) − 1 = erf(h/(√2·σh))` in \[−1, 1\] (Heitz and Neyret's
/// H5bis); `σh = 0` gives the sign of `h` (0 at 0).
pub fn height_profile(h: f64, sigma_h: f64) -> f64 {
    if h.is_nan() || sigma_h.is_nan() || sigma_h < 0.0 {
        return f64::NAN;
    }
    if sigma_h == 0.0 {
        return if h == 0.0 { 0.0 } else { h.signum() };
    }
    erf_f64(h / (SQRT_2 * sigma_h))
}

/// Eq. 17's factor `S/(S + 2)`, `S = Λv + Λl`, in \[0, 1\]: `ā(v, l) = ā + aₛ·factor`. `+∞`
/// (a grazing or hidden direction) gives 1: only the highest heights are seen or lit.
pub fn attribute_factor(lambda_v: f64, lambda_l: f64) -> f64 {
    let s = lambda_v + lambda_l;
    if s == f64::INFINITY { 1.0 } else { s / (s + 2.0) }
}

/// `V̄(l) = (1 + Λv)/(1 + Λv + Λl)` in \[0, 1\]: the fraction of the visible micro-surface the
/// light reaches (module docs). `Λl = +∞` gives 0 (the light is at or below the horizon), else
/// `Λv = +∞` gives 1 (only the tops are seen, and they are lit).
pub fn light_visibility(lambda_v: f64, lambda_l: f64) -> f64 {
    if lambda_l == f64::INFINITY {
        0.0
    } else if lambda_v == f64::INFINITY {
        1.0
    } else {
        (1.0 + lambda_v) / (1.0 + lambda_v + lambda_l)
    }
}

/// Λ in `f32` from `cos θ`, `sin θ` (`sin θ ≥ 0`) and `σ ≥ 0`: the GPU kernel's arithmetic
/// (module docs). `cos θ ≤ 0` gives [`LAMBDA_MAX_F32`]; never infinite, never negative.
pub fn lambda_cs_f32(cos: f32, sin: f32, sigma: f32) -> f32 {
    if cos.is_nan() || sin.is_nan() || sigma.is_nan() || sigma < 0.0 {
        return f32::NAN;
    }
    if cos <= 0.0 {
        return LAMBDA_MAX_F32;
    }
    // a = cos / (√2·σ·sin), its extremes decided before dividing (no overflow, no infinity).
    let denom = std::f32::consts::SQRT_2 * sigma * sin.max(0.0);
    if denom <= cos * (1.0 / 9.5) {
        return 0.0; // a ≥ 9.5 (σ = 0 and normal incidence included)
    }
    if cos <= denom * 1e-30 {
        return LAMBDA_MAX_F32; // a ≤ 1e-30: Λ ≥ 2.8e29
    }
    let a = cos / denom;
    let sqrt_pi = SQRT_PI as f32;
    let l = if a < SPLIT_F32 {
        0.5 * ((-a * a).exp() / (a * sqrt_pi) - erfc_f32(a))
    } else {
        let k = cf_tail_f32(a);
        (-a * a).exp() * k / (2.0 * sqrt_pi * a * (a + k))
    };
    l.clamp(0.0, LAMBDA_MAX_F32)
}

/// [`attribute_factor`] in `f32` for Λ's from [`lambda_cs_f32`] (finite: no special case).
pub fn attribute_factor_f32(lambda_v: f32, lambda_l: f32) -> f32 {
    let s = lambda_v + lambda_l;
    s / (s + 2.0)
}

/// [`light_visibility`] in `f32` for Λ's from [`lambda_cs_f32`]. Both at [`LAMBDA_MAX_F32`]
/// (view and light exactly grazing, a set of measure zero) gives ½.
pub fn light_visibility_f32(lambda_v: f32, lambda_l: f32) -> f32 {
    (1.0 + lambda_v) / (1.0 + lambda_v + lambda_l)
}

#[cfg(test)]
mod tests;
