#!/usr/bin/env python3
"""Reference MSE / PSNR / SSIM from scikit-image for voxlod-eval's cross-check.

Usage:
    python3 check.py            # the built-in cases: one line per image pair
    python3 check.py --rust     # the same, as the Rust array pinned in
                                # crates/voxlod-eval/tests/skimage_cross_check.rs
    python3 check.py a.png b.png  # score two PNG files

The built-in cases are generated with integer arithmetic only; every generator here has a twin of
the same name in crates/voxlod-eval/src/patterns.rs that produces the same uint8 images bit for bit
(the FNV-1a digest printed for each image lets the Rust test check that).

Metrics, on 8-bit sRGB images scaled to [0, 1]:
    MSE  = mean over pixels and channels of (a - b)^2
    PSNR = 10 log10(1 / MSE)               (inf for identical images)
    SSIM = structural_similarity(a, b, gaussian_weights=True, sigma=1.5,
                                 use_sample_covariance=False, data_range=1.0, channel_axis=-1)
    SSIM_MAP_MEAN = mean of the full SSIM map (full=True), border included: it checks the
                    'reflect' boundary handling that the cropped mean never sees.
"""

import sys

import numpy as np
import scipy
import skimage
from skimage.metrics import mean_squared_error, peak_signal_noise_ratio, structural_similarity

M32 = 0xFFFFFFFF


def hash32(x):
    x &= M32
    x ^= x >> 16
    x = (x * 0x7FEB352D) & M32
    x ^= x >> 15
    x = (x * 0x846CA68B) & M32
    x ^= x >> 16
    return x


def fnv1a64(img):
    h = 0xCBF29CE484222325
    for b in img.astype(np.uint8).tobytes():
        h = ((h ^ b) * 0x100000001B3) & 0xFFFFFFFFFFFFFFFF
    return h


def from_fn(w, h, f):
    img = np.zeros((h, w, 3), dtype=np.uint8)
    for y in range(h):
        for x in range(w):
            img[y, x] = f(x, y)
    return img


def gradient(w, h):
    def ramp(t, n):
        return 0 if n == 0 else t * 255 // n

    return from_fn(w, h, lambda x, y: (ramp(x, w - 1), ramp(y, h - 1), ramp(x + y, w + h - 2)))


def checker(w, h, cell):
    return from_fn(
        w, h, lambda x, y: (230, 200, 170) if (x // cell + y // cell) % 2 == 0 else (20, 40, 60)
    )


def noise(w, h, seed):
    offset = (seed * 0x9E3779B9) & M32

    def px(x, y):
        base = ((y * w + x) * 3) & M32
        return tuple(hash32((base + c + offset) & M32) >> 24 for c in range(3))

    return from_fn(w, h, px)


def constant(w, h, rgb):
    return from_fn(w, h, lambda x, y: rgb)


def box_blur(img):
    h, w, _ = img.shape
    src = img.astype(np.int64)

    def px(x, y):
        s = np.zeros(3, dtype=np.int64)
        for dy in (-1, 0, 1):
            for dx in (-1, 0, 1):
                s += src[min(max(y + dy, 0), h - 1), min(max(x + dx, 0), w - 1)]
        return tuple((s + 4) // 9)

    return from_fn(w, h, px)


def shift(img, dx, dy):
    h, w, _ = img.shape
    return from_fn(w, h, lambda x, y: img[min(max(y - dy, 0), h - 1), min(max(x - dx, 0), w - 1)])


def add_noise(img, seed, amplitude):
    h, w, _ = img.shape
    offset = (seed * 0x9E3779B9) & M32
    out = img.astype(np.int64).copy()
    for i in range(w * h):
        y, x = divmod(i, w)
        for c in range(3):
            hv = hash32((i * 3 + c + offset) & M32)
            out[y, x, c] += hv % (2 * amplitude + 1) - amplitude
    return np.clip(out, 0, 255).astype(np.uint8)


def invert(img):
    return (255 - img.astype(np.int64)).astype(np.uint8)


def quantize(img, step):
    return (img // step * step).astype(np.uint8)


# (name, a, b): keep in the same order as CASES in the Rust test.
def cases():
    cb37 = checker(37, 29, 4)
    n11 = noise(11, 11, 3)
    cb53 = checker(53, 11, 5)
    n257 = noise(257, 131, 5)
    cb100 = checker(100, 75, 7)
    return [
        ("identical_gradient_32x24", gradient(32, 24), gradient(32, 24)),
        ("gradient_vs_noisy_64x48", gradient(64, 48), add_noise(gradient(64, 48), 1, 16)),
        ("checker_vs_blurred_37x29", cb37, box_blur(cb37)),
        ("noise_vs_noise_23x41", noise(23, 41, 1), noise(23, 41, 2)),
        ("gradient_shifted_50x50", gradient(50, 50), shift(gradient(50, 50), 2, 1)),
        ("checker_vs_inverted_16x16", checker(16, 16, 3), invert(checker(16, 16, 3))),
        ("minimum_noise_vs_blurred_11x11", n11, box_blur(n11)),
        ("gradient_vs_quantized_11x40", gradient(11, 40), quantize(gradient(11, 40), 32)),
        ("checker_shifted_53x11", cb53, shift(cb53, 1, 0)),
        ("constant_128_vs_131_20x20", constant(20, 20, (128, 128, 128)),
         constant(20, 20, (131, 131, 131))),
        ("constant_vs_noise_19x17", constant(19, 17, (128, 128, 128)), noise(19, 17, 4)),
        ("noise_vs_twice_blurred_257x131", n257, box_blur(box_blur(n257))),
        ("noisy_checker_vs_blurred_100x75", add_noise(cb100, 6, 40), box_blur(cb100)),
    ]


def metrics(a, b):
    fa = a.astype(np.float64) / 255.0
    fb = b.astype(np.float64) / 255.0
    mse = mean_squared_error(fa, fb)
    with np.errstate(divide="ignore"):
        psnr = peak_signal_noise_ratio(fa, fb, data_range=1.0)
    kw = dict(gaussian_weights=True, sigma=1.5, use_sample_covariance=False, data_range=1.0,
              channel_axis=-1)
    ssim = structural_similarity(fa, fb, **kw)
    _, smap = structural_similarity(fa, fb, full=True, **kw)
    return float(mse), float(psnr), float(ssim), float(smap.mean(dtype=np.float64))


def rust_f64(v):
    return "f64::INFINITY" if v == float("inf") else repr(v)


def main(argv):
    versions = (f"scikit-image {skimage.__version__}, scipy {scipy.__version__}, "
                f"numpy {np.__version__}")
    if len(argv) == 2 and not argv[0].startswith("-"):
        from skimage.io import imread

        def load(path):
            img = imread(path)
            if img.ndim == 2:  # greyscale: R = G = B, as voxlod's loader does
                img = np.stack([img] * 3, axis=-1)
            if img.dtype != np.uint8:
                raise SystemExit(f"{path}: expected 8-bit channels, got {img.dtype}")
            return img[..., :3]  # alpha, if any, is dropped

        a, b = load(argv[0]), load(argv[1])
        if a.shape != b.shape:
            raise SystemExit(f"images differ in size: {a.shape[1]}x{a.shape[0]} and "
                             f"{b.shape[1]}x{b.shape[0]}")
        mse, psnr, ssim, smap = metrics(a, b)
        print(f"# {versions}")
        print(f"mse {mse!r}\npsnr {psnr!r}\nssim {ssim!r}\nssim_map_mean {smap!r}")
        return 0
    rust = argv == ["--rust"]
    if argv and not rust:
        print(__doc__, file=sys.stderr)
        return 2
    print(f"// {versions}" if rust else f"# {versions}")
    if not rust:
        print("# name width height fnv1a64(a) fnv1a64(b) mse psnr ssim ssim_map_mean")
    for name, a, b in cases():
        h, w, _ = a.shape
        mse, psnr, ssim, smap = metrics(a, b)
        ha, hb = fnv1a64(a), fnv1a64(b)
        if rust:
            print(f"    Reference {{ name: \"{name}\", fnv_a: {ha:#018x}, fnv_b: {hb:#018x}, "
                  f"mse: {rust_f64(mse)}, psnr: {rust_f64(psnr)}, ssim: {rust_f64(ssim)}, "
                  f"ssim_map_mean: {rust_f64(smap)} }},")
        else:
            print(f"{name} {w} {h} {ha:#018x} {hb:#018x} {mse!r} {psnr!r} {ssim!r} {smap!r}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
