//! Smith's model at the extremes: Λ against 50-digit values over `a ∈ [1e-12, 40]`, the `f32`
//! kernel arithmetic against `f64`, the limits the module docs promise, and Eqs. 16–17 and the
//! light visibility against quadrature of their integrals.

use std::f64::consts::SQRT_2;

use super::*;
use crate::microsurface::reference::LAMBDA;

fn rel(a: f64, b: f64) -> f64 {
    if a == b { 0.0 } else { (a - b).abs() / b.abs() }
}

/// The closed form of Eq. 6 with `erfc` taken as `1 − erf` (the shortcut a shader without
/// `erfc` takes), in `f64` and `f32`.
fn shortcut(a: f64) -> f64 {
    0.5 * ((-a * a).exp() / (a * SQRT_PI) - (1.0 - erf_f64(a)))
}

fn shortcut_f32(a: f32) -> f32 {
    0.5 * ((-a * a).exp() / (a * SQRT_PI as f32) - (1.0 - super::super::special::erf_f32(a)))
}

#[test]
fn lambda_matches_the_reference_from_grazing_to_normal_incidence() {
    let mut checked = 0;
    for &(a, want) in LAMBDA {
        let got = lambda_of_a(a);
        // Through (μ, σ): the same a for σ = 1/√2 and for σ = 1e-3 (a tiny roughness).
        let via_mu = lambda(a, 1.0 / SQRT_2);
        assert!(rel(via_mu, got) <= 1e-15, "a = {a}: {via_mu:e} vs {got:e}");
        if want >= f64::MIN_POSITIVE {
            let r = rel(got, want);
            assert!(r <= 1e-13, "Λ({a}) = {got:e}, reference {want:e}: relative {r:e}");
            checked += 1;
        } else {
            assert!((0.0..=1e-300).contains(&got), "Λ({a}) = {got:e}, reference {want:e}");
        }
    }
    assert!(checked > 120, "{checked}");
}

/// The reason for the stable form: the closed form with `erfc = 1 − erf` is wrong in the fourth
/// digit at `a = 5` and by two orders of magnitude at `a = 8` in `f64`; in `f32` by 1 % at
/// `a = 3.2` and by an order of magnitude (or negative) from `a = 4`. The stable forms keep
/// their relative accuracy.
#[test]
fn the_closed_form_cancels_and_the_stable_form_does_not() {
    let at = |a: f64| LAMBDA.iter().find(|(x, _)| (x - a).abs() < 1e-9 * a).unwrap().1;
    let a5 = 5.011_872_336_272_723;
    assert!(rel(shortcut(a5), at(a5)) > 1e-4, "{:e} vs {:e}", shortcut(a5), at(a5));
    assert!(rel(lambda_of_a(a5), at(a5)) < 1e-14);
    let a8 = 7.943_282_347_242_815;
    assert!(rel(shortcut(a8), at(a8)) > 10.0, "{:e} vs {:e}", shortcut(a8), at(a8));
    assert!(rel(lambda_of_a(a8), at(a8)) < 1e-14);
    for (a, off) in [(3.162_277_660_168_379_5f64, 1e-2), (3.981_071_705_534_973, 10.0), (a5, 10.0)]
    {
        let want = at(a);
        let naive = shortcut_f32(a as f32) as f64;
        assert!(naive <= 0.0 || rel(naive, want) > off, "a = {a}: {naive:e} vs {want:e}");
        // The kernel's Λ at the same a (σ = 1/√2, θ with cot θ = a).
        let theta = (1.0 / a).atan() as f32;
        let stable = lambda_cs_f32(theta.cos(), theta.sin(), std::f32::consts::FRAC_1_SQRT_2);
        assert!(rel(stable as f64, want) < 1e-4, "a = {a}: {stable:e} vs {want:e}");
    }
}

#[test]
fn lambda_has_its_limits() {
    let s = 0.3;
    // μ → 0⁺: Λ ≈ σ/(μ√(2π)) − ½, finite down to the smallest positive μ.
    for mu in [1e-6, 1e-100, 1e-300] {
        let asym = s / (mu * (2.0 * std::f64::consts::PI).sqrt()) - 0.5;
        assert!(rel(lambda(mu, s), asym) < 1e-9, "{mu}");
    }
    assert_eq!(lambda(f64::MIN_POSITIVE * 1e-10, 1e10), f64::INFINITY);
    // μ ≤ 0: below the macro-surface, nothing visible.
    for mu in [0.0, -0.0, -1e-300, -3.0, f64::NEG_INFINITY] {
        assert_eq!(lambda(mu, s), f64::INFINITY, "{mu}");
        assert_eq!(masking(mu, s), 0.0, "{mu}");
    }
    // μ → ∞, σ → 0: Λ → 0 (the unfiltered, smooth surface).
    for (mu, sigma) in [(f64::INFINITY, s), (1e10, s), (1.0, 0.0), (1.0, 1e-300), (1e300, 1e-10)] {
        assert_eq!(lambda(mu, sigma), 0.0, "({mu}, {sigma})");
        assert_eq!(masking(mu, sigma), 1.0, "({mu}, {sigma})");
    }
    // σ → ∞: everything masked.
    assert_eq!(lambda(1.0, f64::INFINITY), f64::INFINITY);
    assert!(lambda(1.0, 1e200) > 1e199);
    assert_eq!(masking(1.0, f64::INFINITY), 0.0);
    // Bad arguments.
    for (mu, sigma) in [(f64::NAN, s), (1.0, f64::NAN), (1.0, -1.0)] {
        assert!(lambda(mu, sigma).is_nan() && masking(mu, sigma).is_nan());
    }
}

#[test]
fn lambda_is_monotone_and_masking_is_its_stable_complement() {
    let mut prev = f64::INFINITY;
    for k in -600..=300 {
        let mu = 10f64.powf(k as f64 / 50.0);
        let l = lambda(mu, 1.0);
        assert!(l <= prev && l >= 0.0, "μ = {mu}: {l:e} after {prev:e}");
        prev = l;
        let g = masking(mu, 1.0);
        assert!((0.0..=1.0).contains(&g));
        if l.is_finite() {
            assert!(rel(g, 1.0 / (1.0 + l)) < 1e-13, "μ = {mu}");
        }
    }
}

/// `∫ f(h)·P(h) dh` for `P = N(0, σh²)` by the midpoint rule over ±12 σh.
fn integrate_h(sigma_h: f64, f: impl Fn(f64) -> f64) -> f64 {
    let n = 20_000;
    let (lo, hi) = (-12.0 * sigma_h, 12.0 * sigma_h);
    let dh = (hi - lo) / n as f64;
    let norm = 1.0 / (sigma_h * (2.0 * std::f64::consts::PI).sqrt());
    (0..n)
        .map(|i| {
            let h = lo + (i as f64 + 0.5) * dh;
            f(h) * norm * (-0.5 * (h / sigma_h).powi(2)).exp() * dh
        })
        .sum()
}

/// Eq. 15 integrated over heights: `∫ a(h) V(v,h) V(l,h) P(h) dh / ∫ V V P dh` with Smith's
/// `V = g(h)^Λ` (Eq. 4, [`height_cdf`]) and `a(h) = ā + aₛ·s(h)` ([`height_profile`]), against
/// Eq. 17; and the light visibility of the visible surface against its integral.
#[test]
fn eq17_and_light_visibility_match_their_integrals() {
    let (abar, aslope, sh) = (0.4, 0.3, 0.07);
    for (lv, ll) in [(0.0, 0.0), (0.05, 0.0), (0.7, 0.2), (3.0, 5.0), (40.0, 0.01)] {
        let v = |h: f64| height_cdf(h, sh).powf(lv + ll);
        let num = integrate_h(sh, |h| (abar + aslope * height_profile(h, sh)) * v(h));
        let want = num / integrate_h(sh, v);
        let got = abar + aslope * attribute_factor(lv, ll);
        assert!((got - want).abs() < 1e-7, "Λv {lv}, Λl {ll}: {got} vs {want}");
        let lit = integrate_h(sh, v) / integrate_h(sh, |h| height_cdf(h, sh).powf(lv));
        assert!((light_visibility(lv, ll) - lit).abs() < 1e-7, "Λv {lv}, Λl {ll}");
        let got32 = abar as f32 + aslope as f32 * attribute_factor_f32(lv as f32, ll as f32);
        assert!((got32 as f64 - want).abs() < 1e-6);
        assert!((light_visibility_f32(lv as f32, ll as f32) as f64 - lit).abs() < 1e-6);
    }
    // Masking is the integral of the visibility: G₁ = ∫ g^Λ P dh = 1/(1 + Λ).
    for mu in [0.1, 1.0, 3.0] {
        let l = lambda(mu, 0.4);
        let g1 = integrate_h(sh, |h| height_cdf(h, sh).powf(l));
        assert!((masking(mu, 0.4) - g1).abs() < 1e-7, "μ {mu}");
    }
    // Limits: smooth (Λ = 0) is the unfiltered colour, fully lit; grazing sees the tops.
    assert_eq!((attribute_factor(0.0, 0.0), light_visibility(0.0, 0.0)), (0.0, 1.0));
    let inf = f64::INFINITY;
    assert_eq!(attribute_factor(inf, 0.3), 1.0);
    assert_eq!(attribute_factor(inf, inf), 1.0);
    assert_eq!((light_visibility(inf, 0.3), light_visibility(0.3, inf)), (1.0, 0.0));
    assert_eq!(light_visibility(inf, inf), 0.0);
    let m = LAMBDA_MAX_F32;
    assert_eq!(attribute_factor_f32(m, m), 1.0);
    assert_eq!(light_visibility_f32(m, 0.3), 1.0);
    assert!(light_visibility_f32(0.3, m) < 1.5e-30);
}

#[test]
fn the_height_cdf_and_profile_have_their_limits() {
    assert_eq!(height_cdf(0.0, 0.7), 0.5);
    assert_eq!(height_profile(0.0, 0.7), 0.0);
    // Deep below the surface: g is tiny but exact (no 1 − 1 cancellation).
    let g = height_cdf(-30.0, 1.0);
    assert!(rel(g, 0.5 * erfc_f64(30.0 / SQRT_2)) < 1e-15 && g > 0.0);
    assert!(rel(2.0 * height_cdf(0.4, 0.3) - 1.0, height_profile(0.4, 0.3)) < 1e-14);
    // σh = 0: the step.
    assert_eq!([-1.0, 0.0, 1.0].map(|h| height_cdf(h, 0.0)), [0.0, 0.5, 1.0]);
    assert_eq!([-1.0, 0.0, 1.0].map(|h| height_profile(h, 0.0)), [-1.0, 0.0, 1.0]);
    // σh = ∞: every height is mid-distribution.
    assert_eq!(height_profile(5.0, f64::INFINITY), 0.0);
    assert!(height_cdf(f64::NAN, 1.0).is_nan() && height_profile(1.0, -1.0).is_nan());
}

/// The kernel's `f32` Λ against `f64` over the whole range of angles and roughnesses.
#[test]
fn lambda_f32_agrees_with_f64_within_its_bound() {
    let mut worst = 0.0f64;
    let mut compared = 0;
    for i in 0..=400 {
        // θ from 1e-6 rad to π/2 − 1e-7 on a log-spaced grid of both ends.
        let t = i as f64 / 400.0;
        let theta = 1e-6f64.powf(1.0 - t) * (std::f64::consts::FRAC_PI_2 - 1e-7).powf(t);
        for sigma in [1e-6f32, 1e-3, 0.05, 0.3, 1.0, 10.0, 1e6] {
            let (s, c) = (theta as f32).sin_cos();
            let got = lambda_cs_f32(c, s, sigma) as f64;
            // The reference at the f32 inputs.
            let want = lambda(c as f64 / s as f64, sigma as f64);
            assert!(got >= 0.0 && got <= LAMBDA_MAX_F32 as f64, "θ {theta}, σ {sigma}: {got}");
            if want > 1e-30 && want < 1e28 {
                let r = rel(got, want);
                worst = worst.max(r);
                compared += 1;
                assert!(r < 5e-5, "θ {theta}, σ {sigma}: {got:e} vs {want:e}, relative {r:e}");
            } else if want <= 1e-30 {
                assert!(got <= 1e-29, "θ {theta}, σ {sigma}: {got:e} vs {want:e}");
            }
        }
    }
    assert!(compared > 500 && worst > 0.0, "{compared} compared, worst {worst:e}");
    // Special inputs: normal incidence, σ = 0, below the horizon, grazing, NaN.
    assert_eq!(lambda_cs_f32(1.0, 0.0, 0.3), 0.0);
    assert_eq!(lambda_cs_f32(0.5, 0.8, 0.0), 0.0);
    assert_eq!(lambda_cs_f32(0.0, 1.0, 0.3), LAMBDA_MAX_F32);
    assert_eq!(lambda_cs_f32(-0.2, 0.9, 0.3), LAMBDA_MAX_F32);
    assert_eq!(lambda_cs_f32(1e-38, 1.0, 0.3), LAMBDA_MAX_F32);
    assert_eq!(lambda_cs_f32(0.5, 0.8, f32::MAX), LAMBDA_MAX_F32);
    assert!(lambda_cs_f32(f32::NAN, 1.0, 0.3).is_nan());
    assert!(lambda_cs_f32(0.5, 0.5, -1.0).is_nan());
}
