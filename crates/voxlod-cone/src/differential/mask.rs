//! Coverage masks (Heitz and Neyret 2012 §5.4, after Carpenter's A-buffer, 1984): which of a
//! pixel's rays a cone element's macro-surface plane covers, as 128 bits.
//!
//! # Definitions
//! - **Rays**: [`MASK_BITS`] = 128 points `ω` in the pixel's footprint, the square `[−1, 1]²`
//!   in units of half the footprint's width (the ground truth box-filters square pixels),
//!   placed by Mitchell's best-candidate algorithm (a Poisson-disk-like set) from a fixed
//!   seed. Point `k` is bit `k % 32` of word `k / 32` of a [`Mask`] (four `u32`, the paper's
//!   "four 32-bit integers").
//! - **Element**: a cylinder along the cone's axis, half-width `r`, half-length `l`, around the
//!   sample point; the plane through the sample's centroid with unit normal `n` (in the
//!   pixel's frame: `x̄` image right, `ȳ` image up, `z̄` the axis), at signed distance `h` from
//!   the sample point (positive on the normal's side, outside). The ray through `ω` meets the
//!   solid side of the plane inside the element iff one end of its segment is there:
//!   `r·(ω_x n_x + ω_y n_y) − l·|n_z| + h ≤ 0`, i.e. `ω·(cos θ, sin θ) ≤ v` with
//!   `(n_x, n_y) = |n_xy|·(cos θ, sin θ)` and `v = (l·|n_z| − h)/(r·|n_xy|)`.
//! - **Table**: [`TABLE_SIDE`]² masks indexed by `θ ∈ [0, 2π)` and `v ∈ [−√2, √2]` (the range
//!   of `ω·(cos θ, sin θ)` over the square), each computed at its cell's centre; a lookup takes
//!   the cell that contains `(θ, v)` ("nearest"). Outside the table `v < −√2` covers nothing
//!   and `v ≥ √2` everything, exactly; `θ` wraps around. A plane perpendicular to the footprint
//!   (`|n_xy| = 0`, or `|n_xy|·r` negligible against `l·|n_z| − h`) covers all rays or none.
//! - **Accumulation** (§5.3): `L += L_d·popcount(mask ∖ α)/128`, `α |= mask`, where `α` is the
//!   pixel's mask so far.

use std::sync::LazyLock;

use glam::Vec2;

/// Rays (bits) per pixel.
pub const MASK_BITS: u32 = 128;
/// Cells per side of the mask table (θ and v).
pub const TABLE_SIDE: usize = 256;
/// Half the range of `v` the table covers: `√2`.
pub const V_MAX: f32 = std::f32::consts::SQRT_2;

/// A set of the pixel's rays: bit `k % 32` of word `k / 32` is ray `k`.
pub type Mask = [u32; 4];

/// The empty mask.
pub const EMPTY: Mask = [0; 4];
/// The full mask.
pub const FULL: Mask = [u32::MAX; 4];

/// Number of rays in `m`.
#[inline]
pub fn count(m: &Mask) -> u32 {
    m.iter().map(|w| w.count_ones()).sum()
}

/// `a ∖ b`.
#[inline]
pub fn minus(a: &Mask, b: &Mask) -> Mask {
    [a[0] & !b[0], a[1] & !b[1], a[2] & !b[2], a[3] & !b[3]]
}

/// `a ∪ b`.
#[inline]
pub fn union(a: &Mask, b: &Mask) -> Mask {
    [a[0] | b[0], a[1] | b[1], a[2] | b[2], a[3] | b[3]]
}

/// A counter-based hash to `[0, 1)` (PCG-style), for the fixed point set.
fn hash01(i: u32, j: u32) -> f32 {
    let mut x = i.wrapping_mul(747_796_405).wrapping_add(j.wrapping_mul(2_891_336_453));
    x ^= x >> 16;
    x = x.wrapping_mul(0x7feb_352d);
    x ^= x >> 15;
    x = x.wrapping_mul(0x846c_a68b);
    x ^= x >> 16;
    (x >> 8) as f32 * (1.0 / 16_777_216.0)
}

/// Candidates per point already placed (Mitchell's best candidate).
const CANDIDATES: u32 = 16;

fn best_candidate_points() -> [Vec2; MASK_BITS as usize] {
    let mut pts = [Vec2::ZERO; MASK_BITS as usize];
    for i in 0..MASK_BITS as usize {
        let mut best = (f32::NEG_INFINITY, Vec2::ZERO);
        for c in 0..(CANDIDATES * i as u32).max(1) {
            let id = (i as u32) << 16 | c;
            let p = Vec2::new(hash01(id, 0), hash01(id, 1)) * 2.0 - 1.0;
            let d = pts[..i].iter().map(|q| q.distance_squared(p)).fold(f32::INFINITY, f32::min);
            if d > best.0 {
                best = (d, p);
            }
        }
        pts[i] = best.1;
    }
    pts
}

/// The 128 rays of a pixel (module docs), in bit order.
pub fn points() -> &'static [Vec2; MASK_BITS as usize] {
    static POINTS: LazyLock<[Vec2; MASK_BITS as usize]> = LazyLock::new(best_candidate_points);
    &POINTS
}

/// The exact mask of the half-plane `ω·(cos θ, sin θ) ≤ v`.
pub fn half_plane(theta: f32, v: f32) -> Mask {
    let (s, c) = theta.sin_cos();
    let mut m = EMPTY;
    for (k, p) in points().iter().enumerate() {
        if p.x * c + p.y * s <= v {
            m[k / 32] |= 1 << (k % 32);
        }
    }
    m
}

/// The mask table (module docs): `TABLE_SIDE × TABLE_SIDE` masks, row `θ`, column `v`.
pub struct MaskTable {
    masks: Vec<Mask>,
}

impl std::fmt::Debug for MaskTable {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "MaskTable({}×{} masks)", TABLE_SIDE, TABLE_SIDE)
    }
}

impl MaskTable {
    /// The table, built once per process.
    pub fn get() -> &'static MaskTable {
        static TABLE: LazyLock<MaskTable> = LazyLock::new(MaskTable::build);
        &TABLE
    }

    fn build() -> Self {
        let n = TABLE_SIDE;
        let mut masks = Vec::with_capacity(n * n);
        for i in 0..n {
            let theta = (i as f32 + 0.5) * (std::f32::consts::TAU / n as f32);
            for j in 0..n {
                let v = -V_MAX + (j as f32 + 0.5) * (2.0 * V_MAX / n as f32);
                masks.push(half_plane(theta, v));
            }
        }
        Self { masks }
    }

    /// The masks, row-major (`θ` index × [`TABLE_SIDE`] + `v` index): what the GPU uploads.
    pub fn masks(&self) -> &[Mask] {
        &self.masks
    }

    /// The mask of `ω·(cos θ, sin θ) ≤ v` by nearest lookup (module docs); `θ` in radians, any
    /// finite value (wrapped), `v` any value (NaN covers nothing).
    pub fn lookup(&self, theta: f32, v: f32) -> Mask {
        if v.is_nan() || v < -V_MAX {
            return EMPTY;
        }
        if v >= V_MAX {
            return FULL;
        }
        let n = TABLE_SIDE as f32;
        let turns = theta * (1.0 / std::f32::consts::TAU);
        let turns = turns - turns.floor();
        let i = ((turns * n) as usize).min(TABLE_SIDE - 1);
        let j = (((v + V_MAX) * (n / (2.0 * V_MAX))) as usize).min(TABLE_SIDE - 1);
        self.masks[i * TABLE_SIDE + j]
    }

    /// The mask of a cone element (module docs): `n` the plane's unit normal in the pixel's
    /// frame, `h` the sample point's signed distance to it, `r` and `l` the element's half-width
    /// and half-length (all in the same unit).
    pub fn element(&self, n: glam::Vec3, h: f32, r: f32, l: f32) -> Mask {
        let rhs = l * n.z.abs() - h;
        let nxy = (n.x * n.x + n.y * n.y).sqrt();
        let across = r * nxy;
        // A plane perpendicular to the footprint, or one whose tilt across it is negligible
        // against its distance: all or nothing.
        if across.is_nan() || rhs.is_nan() {
            return EMPTY;
        }
        if across <= rhs.abs() * (1.0 / 65_536.0) {
            return if rhs >= 0.0 { FULL } else { EMPTY };
        }
        self.lookup(n.y.atan2(n.x), rhs / across)
    }
}

#[cfg(test)]
mod tests {
    use glam::Vec3;

    use super::*;

    #[test]
    fn the_points_are_spread_and_inside_the_footprint() {
        let p = points();
        assert!(p.iter().all(|q| q.abs().max_element() <= 1.0));
        let mut min = f32::INFINITY;
        for i in 0..p.len() {
            for j in 0..i {
                min = min.min(p[i].distance(p[j]));
            }
        }
        // Hexagonal packing of 128 points in area 4 has spacing 0.19; random points would
        // come within 0.01 of each other.
        assert!(min > 0.1, "closest pair {min}");
        // Balanced: the mean is near the centre, each quadrant holds about a quarter.
        let mean = p.iter().copied().sum::<Vec2>() / 128.0;
        assert!(mean.length() < 0.05, "{mean}");
        for (sx, sy) in [(1.0, 1.0), (-1.0, 1.0), (1.0, -1.0), (-1.0, -1.0)] {
            let n = p.iter().filter(|q| q.x * sx > 0.0 && q.y * sy > 0.0).count();
            assert!((28..=36).contains(&n), "quadrant ({sx}, {sy}): {n}");
        }
    }

    /// Exact area of `{ω ∈ [−1,1]² : ω·(cos θ, sin θ) ≤ v}` over 4, by fine sampling.
    fn area(theta: f32, v: f32) -> f32 {
        let (s, c) = theta.sin_cos();
        let n = 200;
        let mut inside = 0;
        for i in 0..n {
            for j in 0..n {
                let x = -1.0 + (i as f32 + 0.5) * 2.0 / n as f32;
                let y = -1.0 + (j as f32 + 0.5) * 2.0 / n as f32;
                if x * c + y * s <= v {
                    inside += 1;
                }
            }
        }
        inside as f32 / (n * n) as f32
    }

    #[test]
    fn table_masks_cover_the_area_of_their_half_plane() {
        let t = MaskTable::get();
        let mut worst = 0.0f32;
        for k in 0..400 {
            let theta = k as f32 * 0.0731;
            let v = -1.5 + (k % 31) as f32 * 0.1;
            let got = count(&t.lookup(theta, v)) as f32 / 128.0;
            let want = area(theta, v);
            worst = worst.max((got - want).abs());
        }
        // 128 rays: a discrepancy of a few rays (and half a table cell) at most.
        assert!(worst < 0.06, "worst coverage error {worst}");
        // Monotone in v; complementary half-planes partition the rays (up to the cell).
        for k in 0..64 {
            let theta = k as f32 * 0.1;
            let mut prev = 0;
            for j in 0..=40 {
                let c = count(&t.lookup(theta, -2.0 + j as f32 * 0.1));
                assert!(c >= prev, "θ {theta}: not monotone");
                prev = c;
            }
        }
    }

    #[test]
    fn the_table_edges_wrap_and_saturate() {
        let t = MaskTable::get();
        assert_eq!(t.lookup(0.3, -V_MAX - 1e-6), EMPTY);
        assert_eq!(t.lookup(0.3, V_MAX), FULL);
        assert_eq!(t.lookup(0.3, f32::INFINITY), FULL);
        assert_eq!(t.lookup(0.3, f32::NEG_INFINITY), EMPTY);
        assert_eq!(t.lookup(0.3, f32::NAN), EMPTY);
        // The last v cell inside the table covers every ray; the first none.
        assert_eq!(t.lookup(1.0, V_MAX - 1e-4), FULL);
        assert_eq!(t.lookup(1.0, -V_MAX + 1e-4), EMPTY);
        // θ wraps: −π/2 and 3π/2, 0 and 2π read the same row.
        let tau = std::f32::consts::TAU;
        assert_eq!(
            t.lookup(-std::f32::consts::FRAC_PI_2, 0.2),
            t.lookup(1.5 * std::f32::consts::PI, 0.2)
        );
        assert_eq!(t.lookup(0.0, 0.2), t.lookup(tau, 0.2));
        // Either side of θ = 0 (first and last rows): nearly the same rays.
        let (a, b) = (t.lookup(1e-7, 0.2), t.lookup(tau - 1e-3, 0.2));
        assert!(count(&minus(&a, &b)) + count(&minus(&b, &a)) <= 4);
    }

    #[test]
    fn element_masks_follow_the_plane() {
        let t = MaskTable::get();
        // A plane facing the viewer (n = −axis) one unit ahead: the element of half-length 2
        // reaches it (all rays), one of half-length 0.5 does not.
        let n = Vec3::NEG_Z;
        assert_eq!(t.element(n, 1.0, 1.0, 2.0), FULL);
        assert_eq!(t.element(n, 1.0, 1.0, 0.5), EMPTY);
        // Behind the solid side: everything covered.
        assert_eq!(t.element(n, -3.0, 1.0, 0.5), FULL);
        // Edge-on plane through the axis, normal +x: the left half of the rays (ω_x ≤ 0).
        let half = t.element(Vec3::X, 0.0, 1.0, 1.0);
        let left = points().iter().filter(|p| p.x <= 0.0).count() as u32;
        assert!(count(&half).abs_diff(left) <= 3, "{} vs {left}", count(&half));
        // Shifted by a quarter of the footprint: three quarters / one quarter.
        let c = count(&t.element(Vec3::X, -0.5, 1.0, 1.0));
        assert!((86..=106).contains(&c), "{c}");
        // Tiny tilt against a large distance: all or nothing, no division by ~0.
        assert_eq!(t.element(Vec3::new(1e-9, 0.0, 1.0), 5.0, 1.0, 1.0), EMPTY);
        assert_eq!(t.element(Vec3::new(1e-9, 0.0, 1.0), -5.0, 1.0, 1.0), FULL);
        assert_eq!(t.element(Vec3::new(0.6, 0.0, 0.8), f32::NAN, 1.0, 1.0), EMPTY);
    }

    #[test]
    fn accumulation_counts_each_ray_once() {
        let t = MaskTable::get();
        let a = t.element(Vec3::X, 0.0, 1.0, 1.0);
        let b = t.element(Vec3::X, -0.5, 1.0, 1.0);
        let alpha = union(&EMPTY, &a);
        let new = minus(&b, &alpha);
        assert_eq!(count(&new) + count(&a), count(&union(&a, &b)));
        assert_eq!(count(&minus(&a, &alpha)), 0, "correlated: nothing new");
        assert_eq!(count(&FULL), MASK_BITS);
    }
}
