//! The deterministic least-squares fit of the \[VJK21\] transmittance parameters σ (extinction
//! per voxel size, a [`SIGMA_RANGE`] log byte) and γ (blend, unorm8) of one voxel to its
//! sampling lines (design note §4(d)).
//!
//! Rules (each tested below):
//! - **Data**: per sampling line `i`, its chord `ℓᵢ` in voxel units and its visibility
//!   `vᵢ = 1` for a line with no hit at all, `0` for any hit (inside or outside the voxel,
//!   front- or back-facing — the same booking as the Averages opacity).
//! - **Objective**: `L(σ, γ) = Σᵢ (f(σℓᵢ, γ) − vᵢ)²` with the transmittance `f` of
//!   [`super::transmittance`], evaluated in f64, its sums in four interleaved lanes combined
//!   in a fixed order (`Sums`): the same bits on every target, SIMD or not.
//! - **γ profiled out**: `f = a + γ·b` is affine in γ (`a = max(1 − τ/2, 0)`,
//!   `b = e^(−τ) − a`), so for a fixed σ the optimum is `γ* = clamp(Σb(v − a)/Σb², 0, 1)`,
//!   rounded to the nearest byte (the lattice optimum of a convex quadratic). Where `Σb² = 0`
//!   the loss does not depend on γ: γ = 1 at σ = 0 (no extinction is the exponential limit) and
//!   γ = 0 otherwise (every chord saturated: surface-like).
//! - **σ search** over the 256 codes: a coarse pass over codes `0, 8, …, 248, 255` on
//!   [`CHORD_BINS`] chord bins uniform in `∛(ℓ/√3)` (count, visible count, mean chord per
//!   bin), then an exact pass on the raw lines: from the coarse best, descend step by step
//!   toward larger codes while the loss falls (ties continue upward), else toward smaller
//!   ones, never beyond ±7 codes (the coarse spacing).
//! - **Ties** (equal loss) go to the larger σ (safer for surfaces); no line blocked gives σ = 0
//!   with γ = 1.
//! - **All lines blocked** gives code 255 with γ = 0 directly. The loss's infimum (0) is then
//!   reached only as σ → ∞, where γ no longer matters; at the top code the least-squares γ
//!   would be decided by the few chords shorter than ~1/100 voxel (where `e^(−τ)` lies below
//!   the line) and come out near 1, leaving `T = e^(−4) ≈ 0.018` at a chord of 1/64. The linear
//!   blend is the representable stand-in of the σ = ∞ limit: it is exactly 0 for every chord
//!   ≥ 2/256, the exponential never is.

use voxlod_format::records::SIGMA_RANGE;
use voxlod_format::records::quant::from_unorm8;

use super::voxel_samples::RaySample;

/// Number of chord-length bins of the coarse pass, uniform in `∛(ℓ/√3)` over `[0, √3]`.
pub const CHORD_BINS: usize = 32;

/// The fitted transmittance parameters of one voxel, as the bytes the records store.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct VjkFit {
    /// Extinction code: 0 = none, 1..=255 = [`SIGMA_RANGE`] log byte.
    pub sigma_code: u8,
    /// Blend γ as unorm8 (255 = exponential, 0 = linear).
    pub gamma_byte: u8,
}

impl VjkFit {
    /// Extinction σ per voxel size.
    pub fn sigma(self) -> f32 {
        SIGMA_RANGE.decode(self.sigma_code)
    }
    /// Blend γ in [0, 1].
    pub fn gamma(self) -> f32 {
        from_unorm8(self.gamma_byte)
    }
}

/// `f(τ, γ)` split as `(a, b)` with `f = a + γ·b`, in f64.
#[inline(always)]
fn affine_parts(tau: f64) -> (f64, f64) {
    affine_parts_with(tau, exp_neg(tau))
}

/// [`affine_parts`] of `tau` given its exponential `e = e^(−τ)`.
#[inline(always)]
fn affine_parts_with(tau: f64, e: f64) -> (f64, f64) {
    let a = (1.0 - 0.5 * tau).max(0.0);
    (a, e - a)
}

/// `e^(−x)` for `x ≥ 0` (and 0 for `x > 708` or NaN), within 3 ulp of libm's `exp` (tested): the
/// fit evaluates it a few thousand times per voxel, where libm's `exp` was a third of the
/// \[VJK21\] precompute. Range reduction `x = (32q + j)·ln 2/32 + r`, `|r| ≤ ln 2/64`, with
/// `ln 2` split in two parts so that `n·ln2_hi` is exact; then `2^(−q)` through the exponent
/// bits, `2^(−j/32)` from a table and the degree-6 Taylor polynomial of `e^(−r)` (remainder
/// < 0.011⁷/7! ≈ 4·10⁻¹⁸), evaluated in Estrin's scheme for a short dependency chain. Only
/// additions and multiplications without fused multiply-add, so every target computes the
/// same bits.
// The split ln 2 constants are fdlibm's digits, and `!(x <= 708)` also catches NaN: both meant.
#[allow(
    clippy::excessive_precision,
    clippy::neg_cmp_op_on_partial_ord,
    reason = "fdlibm's split of ln 2 digit for digit; `!(x <= 708)` is also true for NaN"
)]
#[inline(always)]
fn exp_neg(x: f64) -> f64 {
    const SCALE: f64 = 32.0 * std::f64::consts::LOG2_E;
    // ln 2 = LN2_HI + LN2_LO, LN2_HI with its low 32 mantissa bits zero (as in fdlibm), so
    // `n·LN2_HI/32` is exact for the n < 2²¹ that occur here.
    const LN2_HI_32: f64 = 6.931_471_803_691_238_2e-1 / 32.0;
    const LN2_LO_32: f64 = 1.908_214_929_270_587_7e-10 / 32.0;
    // Branch-free (selects, not an early return), so that the loss's lanes vectorize.
    let inside = x <= 708.0;
    let x = if inside { x.max(0.0) } else { 0.0 };
    // 0 ≤ x ≤ 708: truncation of `y + 0.5` rounds to nearest (ties up) without a libm call,
    // and n ≤ 32 687 fits an i32 (whose conversions have SIMD instructions).
    // SAFETY: 0 ≤ x·SCALE + 0.5 ≤ 32 688 (x is clamped just above), finite and in range of
    // i32; the unchecked conversion (a plain truncation, unlike `as`, which saturates) is
    // what lets the loops over this function use SIMD conversions.
    let n: i32 = unsafe { (x * SCALE + 0.5).to_int_unchecked() };
    let nf = n as f64;
    let y = nf * LN2_HI_32 - x + nf * LN2_LO_32; // −r
    let y2 = y * y;
    let p = (1.0 + y)
        + y2 * ((0.5 + y * (1.0 / 6.0))
            + y2 * ((1.0 / 24.0 + y * (1.0 / 120.0)) + y2 * (1.0 / 720.0)));
    // 2^(−q) for q = n/32 ≤ 1021 (x ≤ 708).
    let q = (n >> 5) as u64;
    // The power-of-two scaling is exact (no subnormals for x ≤ 708): one rounding.
    let e = p * (EXP2_NEG_32NDS[(n & 31) as usize] * f64::from_bits((1023 - q) << 52));
    if inside { e } else { 0.0 }
}

/// `2^(−j/32)` for `j = 0..32` (entry 16 is 1/√2: a table of digits, not a named constant).
#[allow(clippy::approx_constant, reason = "entry 16 is 2^(−1/2) = 1/√2 by construction")]
static EXP2_NEG_32NDS: [f64; 32] = [
    1.0,
    0.978_572_062_087_700_1,
    0.957_603_280_698_573_7,
    0.937_083_817_055_15,
    0.917_004_043_204_671_2,
    0.897_354_537_501_553_6,
    0.878_126_080_186_649_7,
    0.859_309_649_061_239,
    0.840_896_415_253_714_5,
    0.822_877_739_076_982_5,
    0.805_245_165_974_627_1,
    0.787_990_422_553_943_2,
    0.771_105_412_703_970_4,
    0.754_582_213_796_711_4,
    0.738_413_072_969_749_7,
    0.722_590_403_488_523_3,
    0.707_106_781_186_547_6,
    0.691_954_940_981_916,
    0.677_127_773_468_446_3,
    0.662_618_321_579_870_7,
    0.648_419_777_325_504_8,
    0.634_525_478_595_866_6,
    0.620_928_906_036_742,
    0.607_623_679_990_234_5,
    0.594_603_557_501_360_5,
    0.581_862_429_388_788_7,
    0.569_394_317_378_345_8,
    0.557_193_371_297_946_2,
    0.545_253_866_332_628_8,
    0.533_570_200_338_411_8,
    0.522_136_891_213_706_9,
    0.510_948_574_327_058_3,
];

/// Sufficient statistics of a group of lines sharing one chord: the number of lines, how many
/// are visible, and the chord.
#[derive(Clone, Copy, Debug, Default)]
struct Group {
    count: f64,
    visible: f64,
    chord: f64,
}

/// Lanes of the loss sums.
const LANES: usize = 4;

/// The sums the profiled loss is made of, in [`LANES`] lanes: group `i` (in slice order) adds
/// into lane `i % 4`, and the lanes are combined as `(l₀ + l₁) + (l₂ + l₃)`. A fixed order,
/// so every target gets the same bits, and four independent chains instead of one, which the
/// loop runs in SIMD lanes.
#[derive(Clone, Copy, Debug, Default)]
struct Sums {
    saa: [f64; LANES],
    sab: [f64; LANES],
    sbb: [f64; LANES],
    sma: [f64; LANES],
    smb: [f64; LANES],
    m: [f64; LANES],
}

impl Sums {
    /// Adds group `g` into `lane`, with `f = a + γ·b` at its chord ([`affine_parts`]).
    #[inline(always)]
    fn add(&mut self, lane: usize, g: &Group, (a, b): (f64, f64)) {
        self.saa[lane] += g.count * a * a;
        self.sab[lane] += g.count * a * b;
        self.sbb[lane] += g.count * b * b;
        self.sma[lane] += g.visible * a;
        self.smb[lane] += g.visible * b;
        self.m[lane] += g.visible;
    }

    /// The byte γ that minimizes the loss at σ code `code`, and the loss there.
    fn optimum(&self, code: u8) -> (u8, f64) {
        let total = |l: [f64; LANES]| (l[0] + l[1]) + (l[2] + l[3]);
        let (saa, sab, sbb) = (total(self.saa), total(self.sab), total(self.sbb));
        let (sma, smb, m) = (total(self.sma), total(self.smb), total(self.m));
        let gamma_byte = if sbb > 0.0 {
            let g = ((smb - sab) / sbb).clamp(0.0, 1.0);
            (g * 255.0).round() as u8
        } else if code == 0 {
            255
        } else {
            0
        };
        let g = from_unorm8(gamma_byte) as f64;
        let loss = saa + 2.0 * g * sab + g * g * sbb - 2.0 * sma - 2.0 * g * smb + m;
        (gamma_byte, loss.max(0.0))
    }
}

/// The profiled loss at σ code `code`: the byte γ that minimizes it and the loss there, from
/// one pass of sums ([`Sums`]): with `n` lines and `m` visible per group, `L(γ) = Σn a² +
/// 2γ Σn ab + γ² Σn b² − 2Σm a − 2γ Σm b + Σm`. Compiled for AVX2 where the CPU has it
/// (selected at run time): four groups per step, their exponentials and sums in SIMD lanes,
/// the same operations lane by lane as the plain build, so the same bits.
fn profile(groups: &[Group], code: u8) -> (u8, f64) {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx2") {
        // SAFETY: the CPU has AVX2 (checked just above).
        return unsafe { profile_avx2(groups, code) };
    }
    profile_any(groups, code)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn profile_avx2(groups: &[Group], code: u8) -> (u8, f64) {
    profile_any(groups, code)
}

/// The loop of [`profile`]: per batch of 64 groups (a multiple of [`LANES`], so that group
/// `i` stays in lane `i % 4`), the exponentials in one loop, then the sums four groups at a
/// time.
#[inline(always)]
fn profile_any(groups: &[Group], code: u8) -> (u8, f64) {
    const BATCH: usize = 64;
    let sigma = SIGMA_RANGE.decode(code) as f64;
    let mut sums = Sums::default();
    let (mut tau, mut e) = ([0.0; BATCH], [0.0; BATCH]);
    for chunk in groups.chunks(BATCH) {
        let (tau, e) = (&mut tau[..chunk.len()], &mut e[..chunk.len()]);
        for (t, g) in tau.iter_mut().zip(chunk) {
            *t = sigma * g.chord;
        }
        for (e, &t) in e.iter_mut().zip(tau.iter()) {
            *e = exp_neg(t);
        }
        let mut quads = chunk.chunks_exact(LANES);
        let (mut ts, mut es) = (tau.chunks_exact(LANES), e.chunks_exact(LANES));
        for ((q, t), e) in (&mut quads).zip(&mut ts).zip(&mut es) {
            for j in 0..LANES {
                sums.add(j, &q[j], affine_parts_with(t[j], e[j]));
            }
        }
        let rest = quads.remainder().iter().zip(ts.remainder()).zip(es.remainder());
        for (j, ((g, &t), &e)) in rest.enumerate() {
            sums.add(j, g, affine_parts_with(t, e));
        }
    }
    sums.optimum(code)
}

fn raw_groups(rays: &[RaySample]) -> Vec<Group> {
    rays.iter()
        .map(|r| Group {
            count: 1.0,
            visible: if r.occluded { 0.0 } else { 1.0 },
            // A non-finite chord (bad input) counts as 0; no chord exceeds √3.
            chord: if r.chord.is_finite() { r.chord.clamp(0.0, 1.75) as f64 } else { 0.0 },
        })
        .collect()
}

/// Best of `codes` (ascending) by the profiled loss over `groups`; ties to the larger code.
fn search(groups: &[Group], codes: impl Iterator<Item = u8>) -> VjkFit {
    let mut best = (VjkFit { sigma_code: 0, gamma_byte: 255 }, f64::INFINITY);
    for code in codes {
        let (gamma_byte, loss) = profile(groups, code);
        if loss <= best.1 {
            best = (VjkFit { sigma_code: code, gamma_byte }, loss);
        }
    }
    best.0
}

/// The loss `Σᵢ (f(σℓᵢ, γ) − vᵢ)²` of the stored bytes over `rays` (f64).
pub fn loss(rays: &[RaySample], fit: VjkFit) -> f64 {
    let (sigma, gamma) = (fit.sigma() as f64, fit.gamma() as f64);
    raw_groups(rays)
        .iter()
        .map(|g| {
            let (a, b) = affine_parts(sigma * g.chord);
            (a + gamma * b - g.visible).powi(2)
        })
        .sum()
}

/// The deterministic \[VJK21\] fit of note §4(d) (module docs): coarse pass over 33 codes on
/// chord bins, exact descent within ±7 codes on the raw lines, γ in closed form, ties to
/// larger σ.
/// An empty slice gives σ = 0, γ = 1 (nothing observed, nothing blocks).
pub fn fit(rays: &[RaySample]) -> VjkFit {
    if rays.is_empty() {
        return VjkFit { sigma_code: 0, gamma_byte: 255 };
    }
    if let Some(f) = all_blocked(rays) {
        return f;
    }
    let raw = raw_groups(rays);
    let mut bins = [Group::default(); CHORD_BINS];
    for g in &raw {
        let k = chord_bin(g.chord).min(CHORD_BINS - 1);
        bins[k].count += 1.0;
        bins[k].visible += g.visible;
        bins[k].chord += g.chord;
    }
    for b in &mut bins {
        if b.count > 0.0 {
            b.chord /= b.count;
        }
    }
    let binned: Vec<Group> = bins.into_iter().filter(|b| b.count > 0.0).collect();
    let coarse = (0..=31u8).map(|k| k * 8).chain([255]);
    let c = search(&binned, coarse).sigma_code;
    descend(&raw, c, c.saturating_sub(7), c.saturating_add(7))
}

/// The exact pass: from code `c`, steps on the raw lines' profiled loss toward the larger and
/// then the smaller codes while the loss decreases (ties: up, not down), within `[lo, hi]`.
/// On the loss's usual single minimum near the coarse best this finds what a scan of the
/// whole window finds, with 3–6 evaluations instead of 15.
fn descend(raw: &[Group], c: u8, lo: u8, hi: u8) -> VjkFit {
    let (gamma_byte, loss) = profile(raw, c);
    let mut best = (VjkFit { sigma_code: c, gamma_byte }, loss);
    for up in [true, false] {
        let mut k = c;
        loop {
            let next = if up {
                k.checked_add(1).filter(|&n| n <= hi)
            } else {
                k.checked_sub(1).filter(|&n| n >= lo)
            };
            let Some(next) = next else { break };
            let (gamma_byte, loss) = profile(raw, next);
            let better = if up { loss <= best.1 } else { loss < best.1 };
            if !better {
                break;
            }
            best = (VjkFit { sigma_code: next, gamma_byte }, loss);
            k = next;
        }
        if best.0.sigma_code != c {
            // The loss fell toward larger codes: the smaller side is not searched.
            break;
        }
    }
    best.0
}

/// Bin of a chord: uniform in `∛(ℓ/√3)`, so short chords (which decide high σ, where only
/// they can be visible) get narrow bins. Measured on 600 synthetic voxels against the
/// exhaustive search: uniform bins in ℓ found the optimum in 90% with a max excess of
/// 2.6·10⁻³ per line, √ bins 97% / 2·10⁻⁴, ∛ bins 97% / 5.5·10⁻⁵.
fn chord_bin(chord: f64) -> usize {
    // Bin k holds ℓ with (k/N)³·√3 ≤ ℓ < ((k+1)/N)³·√3: the number of lower edges ≤ ℓ,
    // minus one (a table search instead of a cube root per line).
    CHORD_BIN_EDGES.partition_point(|&e| e <= chord).saturating_sub(1)
}

/// Lower edges `(k/N)³·√3` of the chord bins, `k = 0..N` (`N` = [`CHORD_BINS`]).
static CHORD_BIN_EDGES: std::sync::LazyLock<[f64; CHORD_BINS]> = std::sync::LazyLock::new(|| {
    std::array::from_fn(|k| (k as f64 / CHORD_BINS as f64).powi(3) * 3f64.sqrt())
});

/// The exhaustive reference: the profiled loss on the raw lines at all 256 codes (ties to the
/// larger σ). What [`fit`] approximates with about a twentieth of the evaluations of `f`
/// (33·32 + 3–6·R against 256·R); compared in the tests.
pub fn fit_exhaustive(rays: &[RaySample]) -> VjkFit {
    if let Some(f) = all_blocked(rays) {
        return f;
    }
    search(&raw_groups(rays), 0..=255u8)
}

/// The fit of a non-empty set of lines that are all blocked (module docs), else `None`.
fn all_blocked(rays: &[RaySample]) -> Option<VjkFit> {
    (!rays.is_empty() && rays.iter().all(|r| r.occluded))
        .then_some(VjkFit { sigma_code: 255, gamma_byte: 0 })
}

/// Deterministic sampling lines for tests of this module and its siblings: isotropic lines
/// through the unit voxel (the exact face-choice construction of note §1) and a plane's hits.
#[cfg(test)]
pub(crate) mod test_lines {
    use glam::Vec3;

    use super::super::voxel_samples::{RaySample, SurfaceSample, VoxelSamples};
    use crate::random::rand_f32;

    /// Line `i` of voxel `id`: a uniform direction, then a uniform point over the voxel's
    /// projection (face `k` with probability ∝ |d_k|). Returns (dir, entry, chord).
    pub fn line(id: u32, i: u32) -> (Vec3, Vec3, f32) {
        let z = 1.0 - 2.0 * rand_f32(id, i, 0);
        let phi = std::f32::consts::TAU * rand_f32(id, i, 1);
        let r = (1.0 - z * z).max(0.0).sqrt();
        let d = Vec3::new(r * phi.cos(), r * phi.sin(), z);
        let a = d.abs();
        let u = rand_f32(id, i, 2) * (a.x + a.y + a.z);
        let k = if u < a.x {
            0
        } else if u < a.x + a.y {
            1
        } else {
            2
        };
        let (p, q) = (rand_f32(id, i, 3), rand_f32(id, i, 4));
        let mut e = Vec3::ZERO;
        e[k] = if d[k] > 0.0 { 0.0 } else { 1.0 };
        e[(k + 1) % 3] = p;
        e[(k + 2) % 3] = q;
        // Exit: the smallest positive slab distance.
        let mut t = f32::INFINITY;
        for j in 0..3 {
            if d[j] > 0.0 {
                t = t.min((1.0 - e[j]) / d[j]);
            } else if d[j] < 0.0 {
                t = t.min(-e[j] / d[j]);
            }
        }
        (d, e, t)
    }

    /// `n` lines through voxel `id` against the infinite plane `{p : normal·(p − point) = 0}`
    /// (voxel-local coordinates) with colour `albedo`. Every non-parallel line is occluded
    /// (the plane extends past the voxel); a hit inside the voxel on the front side is a
    /// surface sample (on both sides if `double_sided`, with the normal flipped toward the
    /// line's origin).
    pub fn plane(
        id: u32,
        n: u32,
        normal: Vec3,
        point: Vec3,
        albedo: Vec3,
        double_sided: bool,
    ) -> VoxelSamples {
        let normal = normal.normalize();
        let rays = (0..n)
            .map(|i| {
                let (dir, entry, chord) = line(id, i);
                let dn = dir.dot(normal);
                let mut ray = RaySample { dir, entry, chord, occluded: dn != 0.0, surface: None };
                if dn != 0.0 {
                    let t = normal.dot(point - entry) / dn;
                    let p = entry + dir * t;
                    let inside = p.cmpge(Vec3::ZERO).all() && p.cmple(Vec3::ONE).all();
                    if inside && (dn < 0.0 || double_sided) {
                        ray.surface = Some(SurfaceSample {
                            point: p,
                            normal: if dn < 0.0 { normal } else { -normal },
                            albedo,
                            specular: 0.0,
                            shininess: 1.0,
                        });
                    }
                }
                ray
            })
            .collect();
        VoxelSamples { rays }
    }
}

#[cfg(test)]
mod tests;
