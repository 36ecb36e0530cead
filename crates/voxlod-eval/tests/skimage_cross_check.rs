//! Cross-check of MSE, PSNR and SSIM against scikit-image: every value must agree with
//! scikit-image's `structural_similarity(..., gaussian_weights=True, sigma=1.5,
//! use_sample_covariance=False, data_range=1.0, channel_axis=-1)` (and its MSE and PSNR) within
//! 1e-4.
//!
//! The reference numbers below were measured, not typed: they are the output of
//!
//! ```text
//! python3 -m venv /tmp/skvenv && /tmp/skvenv/bin/pip install -r tools/ssim_check/requirements.txt
//! /tmp/skvenv/bin/python tools/ssim_check/check.py --rust
//! ```
//!
//! with scikit-image 0.26.0, scipy 1.17.1, numpy 2.4.6 (Python 3.11.7), pasted verbatim.
//! `check.py` builds each pair with the Python twins of `voxlod_eval::patterns`; the FNV-1a
//! digests prove both sides scored the same bytes. `ssim_map_mean` is the mean of skimage's full
//! SSIM map (`full=True`), border included, which checks the `reflect` boundary as well.

use voxlod_eval::patterns::{
    add_noise, box_blur, checker, constant, fnv1a64, gradient, invert, noise, quantize, shift,
};
use voxlod_scene::Srgb8Image;

/// The agreement required with scikit-image, per value.
const TOLERANCE: f64 = 1e-4;

const METRICS: [&str; 4] = ["MSE", "PSNR", "SSIM", "SSIM map mean"];

struct Reference {
    name: &'static str,
    fnv_a: u64,
    fnv_b: u64,
    mse: f64,
    psnr: f64,
    ssim: f64,
    ssim_map_mean: f64,
}

#[rustfmt::skip]
const REFERENCES: [Reference; 13] = [
    Reference { name: "identical_gradient_32x24", fnv_a: 0x6fe21b3ee4c45901, fnv_b: 0x6fe21b3ee4c45901, mse: 0.0, psnr: f64::INFINITY, ssim: 1.0, ssim_map_mean: 1.0 },
    Reference { name: "gradient_vs_noisy_64x48", fnv_a: 0xfc2f2bfd166d0fa2, fnv_b: 0x1fd9da59e1e37532, mse: 0.0013577677122047077, psnr: 28.671745230869142, ssim: 0.613058514205672, ssim_map_mean: 0.6125413032022754 },
    Reference { name: "checker_vs_blurred_37x29", fnv_a: 0xf9417f536c8f0d5b, fnv_b: 0x595a2d12a679d463, mse: 0.0426186358175381, psnr: 13.70400455757373, ssim: 0.6696309116268888, ssim_map_mean: 0.6732234234859413 },
    Reference { name: "noise_vs_noise_23x41", fnv_a: 0xdb9bfcfec882acbd, fnv_b: 0x751d9e56d8cd4548, mse: 0.1681083804268663, psnr: 7.7441063586199395, ssim: 0.015749367425620053, ssim_map_mean: -0.0065708320417617195 },
    Reference { name: "gradient_shifted_50x50", fnv_a: 0xa999f2bbd6d7250c, fnv_b: 0x3618ceb135513c4a, mse: 0.0009727991798026399, psnr: 30.119768042384226, ssim: 0.9923783534495061, ssim_map_mean: 0.969509071510386 },
    Reference { name: "checker_vs_inverted_16x16", fnv_a: 0xac21954f7b0427d5, fnv_b: 0x89f6f3040390fde5, mse: 0.4228181468665897, psnr: 3.7384638154697223, ssim: -0.9753849205391308, ssim_map_mean: -0.9657973247185033 },
    Reference { name: "minimum_noise_vs_blurred_11x11", fnv_a: 0x6ec016e0bf807279, fnv_b: 0xf4ee3a77cbc337a9, mse: 0.06653757878671374, psnr: 11.769330065736163, ssim: 0.127788796385707, ssim_map_mean: 0.23537353311765472 },
    Reference { name: "gradient_vs_quantized_11x40", fnv_a: 0xaf60f6fd73efc81e, fnv_b: 0x5e90fed478e84465, mse: 0.005241725210583343, psnr: 22.805257500157786, ssim: 0.8225096067214386, ssim_map_mean: 0.7621972405726719 },
    Reference { name: "checker_shifted_53x11", fnv_a: 0x6026a162f91c3273, fnv_b: 0x05c79b8b4e627c6b, mse: 0.07911809439523744, psnr: 11.017241815170388, ssim: 0.5958468253926, ssim_map_mean: 0.5670393382341302 },
    Reference { name: "constant_128_vs_131_20x20", fnv_a: 0x27cd979df38a84e5, fnv_b: 0xc4dc51103d32e015, mse: 0.00013840830449826888, psnr: 38.588378514285886, ssim: 0.9997317556791979, ssim_map_mean: 0.9997317556791984 },
    Reference { name: "constant_vs_noise_19x17", fnv_a: 0x1f686d74d0787a3f, fnv_b: 0xfa8bf2cdbc32fed1, mse: 0.08010055670419687, psnr: 10.963644655297378, ssim: 0.01199956125671326, ssim_map_mean: 0.01203767576120061 },
    Reference { name: "noise_vs_twice_blurred_257x131", fnv_a: 0x50ac1264da325562, fnv_b: 0xff27c97d77244bf8, mse: 0.06957705859540159, psnr: 11.57533935214585, ssim: 0.17738286317317872, ssim_map_mean: 0.17902365488702204 },
    Reference { name: "noisy_checker_vs_blurred_100x75", fnv_a: 0xee3c5c793d45648d, fnv_b: 0x7044a5bade3192b9, mse: 0.031770235379554874, psnr: 14.979795675567633, ssim: 0.7036086353551269, ssim_map_mean: 0.6998958073894721 },
];

/// The pairs of `cases()` in `check.py`, in the same order.
fn cases() -> Vec<(&'static str, Srgb8Image, Srgb8Image)> {
    let cb37 = checker(37, 29, 4);
    let n11 = noise(11, 11, 3);
    let cb53 = checker(53, 11, 5);
    let n257 = noise(257, 131, 5);
    let cb100 = checker(100, 75, 7);
    vec![
        ("identical_gradient_32x24", gradient(32, 24), gradient(32, 24)),
        ("gradient_vs_noisy_64x48", gradient(64, 48), add_noise(&gradient(64, 48), 1, 16)),
        ("checker_vs_blurred_37x29", cb37.clone(), box_blur(&cb37)),
        ("noise_vs_noise_23x41", noise(23, 41, 1), noise(23, 41, 2)),
        ("gradient_shifted_50x50", gradient(50, 50), shift(&gradient(50, 50), 2, 1)),
        ("checker_vs_inverted_16x16", checker(16, 16, 3), invert(&checker(16, 16, 3))),
        ("minimum_noise_vs_blurred_11x11", n11.clone(), box_blur(&n11)),
        ("gradient_vs_quantized_11x40", gradient(11, 40), quantize(&gradient(11, 40), 32)),
        ("checker_shifted_53x11", cb53.clone(), shift(&cb53, 1, 0)),
        ("constant_128_vs_131_20x20", constant(20, 20, [128; 3]), constant(20, 20, [131; 3])),
        ("constant_vs_noise_19x17", constant(19, 17, [128; 3]), noise(19, 17, 4)),
        ("noise_vs_twice_blurred_257x131", n257.clone(), box_blur(&box_blur(&n257))),
        ("noisy_checker_vs_blurred_100x75", add_noise(&cb100, 6, 40), box_blur(&cb100)),
    ]
}

/// |a − b|, 0 when both are the same infinity.
fn diff(a: f64, b: f64) -> f64 {
    if a == b { 0.0 } else { (a - b).abs() }
}

#[test]
fn metrics_agree_with_scikit_image() {
    let cases = cases();
    assert_eq!(cases.len(), REFERENCES.len());
    // The largest difference per metric, and the case where it occurs.
    let mut worst = [(0.0f64, ""); 4];
    for ((name, a, b), r) in cases.iter().zip(&REFERENCES) {
        assert_eq!(*name, r.name, "case order differs from check.py");
        assert_eq!(
            (fnv1a64(a), fnv1a64(b)),
            (r.fnv_a, r.fnv_b),
            "{name}: the Rust pattern generators no longer match check.py"
        );
        let map = voxlod_eval::ssim_map(a, b).unwrap();
        let m = voxlod_eval::compare(a, b).unwrap();
        assert_eq!(m.ssim, map.mean);
        let got = [m.mse, m.psnr, m.ssim, map.full_mean()];
        let want = [r.mse, r.psnr, r.ssim, r.ssim_map_mean];
        for (k, what) in METRICS.iter().enumerate() {
            let (g, w) = (got[k], want[k]);
            let d = diff(g, w);
            assert!(
                d <= TOLERANCE,
                "{name}: {what} ours {g} skimage {w}: |difference| {d:e} > {TOLERANCE:e}"
            );
            if d > worst[k].0 {
                worst[k] = (d, name);
            }
        }
    }
    for (what, (d, name)) in METRICS.iter().zip(worst) {
        println!("largest |ours − skimage| of {what}: {d:e} ({name})");
    }
}

#[test]
fn images_below_the_gaussian_window_are_refused_as_skimage_does() {
    // skimage raises "win_size exceeds image extent" for 10×N and N×10 with gaussian_weights.
    for (w, h) in [(10, 40), (40, 10), (7, 7)] {
        let a = gradient(w, h);
        let err = voxlod_eval::ssim(&a, &a).unwrap_err().to_string();
        assert!(err.contains(&format!("{w}×{h}")), "{err}");
    }
}
