//! The error functions against 50-digit values (`reference.rs`), at the split, the tails and
//! the special values.

use super::*;
use crate::microsurface::reference::ERFC;

fn rel(a: f64, b: f64) -> f64 {
    if a == b { 0.0 } else { (a - b).abs() / b.abs() }
}

#[test]
fn erfc_f64_matches_the_reference_over_the_whole_range() {
    let mut worst = (0.0, 0.0);
    for &(x, want, _) in ERFC {
        let got = erfc_f64(x);
        if want >= f64::MIN_POSITIVE {
            let r = rel(got, want);
            assert!(r <= 5e-14, "erfc({x}) = {got:e}, reference {want:e}: relative {r:e}");
            worst = if r > worst.0 { (r, x) } else { worst };
        } else {
            // Below the normal range the true value is subnormal or zero: no garbage, no NaN.
            assert!((got - want).abs() <= 1e-310 && got >= 0.0, "erfc({x}) = {got:e}");
        }
    }
    assert!(worst.0 > 0.0, "the table exercised the code");
}

#[test]
fn erfcx_f64_stays_accurate_where_erfc_underflows() {
    for &(x, _, want) in ERFC.iter().filter(|e| e.0 >= 0.0) {
        let r = rel(erfcx_f64(x), want);
        assert!(r <= 5e-14, "erfcx({x}): relative {r:e}");
    }
    // Far beyond underflow: erfcx(x) ≈ 1/(x√π)·(1 − 1/(2x²)).
    for x in [1e3, 1e8, 1e150] {
        let asym = 1.0 / (x * SQRT_PI) * (1.0 - 0.5 / (x * x));
        assert!(rel(erfcx_f64(x), asym) <= 1e-12, "{x}");
    }
    assert_eq!(erfcx_f64(f64::INFINITY), 0.0);
    assert!(erfcx_f64(-1.0).is_nan() && erfcx_f64(f64::NAN).is_nan());
}

#[test]
fn erf_is_odd_continuous_at_the_split_and_has_its_limits() {
    for x in [1e-300, 1e-8, 0.3, 1.7, 1.999_999_999, 2.0, 2.000_000_001, 5.0, 30.0] {
        assert_eq!(erf_f64(-x), -erf_f64(x), "{x}");
        assert!((erf_f64(x) + erfc_f64(x) - 1.0).abs() <= 2e-16, "{x}");
        assert!((erfc_f64(-x) - (2.0 - erfc_f64(x))).abs() <= 4e-16, "{x}");
    }
    // Either side of the split agree to the reference's precision.
    let (lo, hi) = (erfc_f64(2.0 - 1e-12), erfc_f64(2.0));
    assert!(rel(lo, hi) < 1e-10, "{lo:e} vs {hi:e}");
    assert_eq!(erf_f64(0.0), 0.0);
    assert!(erf_f64(-0.0).is_sign_negative());
    assert_eq!((erf_f64(f64::INFINITY), erf_f64(f64::NEG_INFINITY)), (1.0, -1.0));
    assert_eq!((erfc_f64(f64::INFINITY), erfc_f64(f64::NEG_INFINITY)), (0.0, 2.0));
    assert!(erf_f64(f64::NAN).is_nan() && erfc_f64(f64::NAN).is_nan());
    // Small arguments: erf(x) ≈ 2x/√π, no underflow to 0.
    assert!(rel(erf_f64(1e-300), 2e-300 / SQRT_PI) < 1e-15);
}

#[test]
fn erfc_f32_is_within_its_bound_of_the_reference() {
    let mut worst = 0.0f64;
    for &(x, want, _) in ERFC.iter().filter(|e| e.0.abs() < 9.5) {
        let got = erfc_f32(x as f32) as f64;
        // The reference at the f32 argument: compare against f64 evaluated there.
        let want_at = erfc_f64(x as f32 as f64);
        assert!(rel(want_at, want) < 1e-6 || x as f32 as f64 != x);
        if want_at < 1e-37 {
            continue;
        }
        let r = rel(got, want_at);
        worst = worst.max(r);
        assert!(r <= 4e-6, "erfc_f32({x}) = {got:e}, f64 {want_at:e}: relative {r:e}");
    }
    assert!(worst > 1e-9, "f32 differs from f64 somewhere ({worst:e})");
    assert_eq!(erfc_f32(9.6), 0.0);
    assert_eq!(erfc_f32(f32::INFINITY), 0.0);
    assert_eq!(erfc_f32(f32::NEG_INFINITY), 2.0);
    assert!(erfc_f32(f32::NAN).is_nan());
    for x in [0.1f32, 1.0, 2.5, 20.0] {
        assert_eq!(erf_f32(-x), -erf_f32(x));
        assert!((erf_f32(x) as f64 - erf_f64(x as f64)).abs() < 3e-7, "{x}");
    }
}

#[test]
fn erf_approx_is_within_its_bound_everywhere() {
    let mut worst = 0.0f64;
    for i in -4000..=4000 {
        let x = i as f64 * 0.0025;
        worst = worst.max((erf_approx(x) - erf_f64(x)).abs());
        assert_eq!(erf_approx(-x), -erf_approx(x));
    }
    assert!(worst <= 1.5e-7 && worst > 1e-9, "{worst:e}");
    assert_eq!((erf_approx(f64::INFINITY), erf_approx(f64::NEG_INFINITY)), (1.0, -1.0));
    assert!(erf_approx(f64::NAN).is_nan());
}
