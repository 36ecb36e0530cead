//! The 3×3×3 opacity subgrid of a voxel (HPG 2023 §3.2, §3.4; design note §1, §6): how it is
//! built from a voxel's sampling lines ([`build`]) and how it answers "how opaque is this voxel
//! along a direction" ([`directional_opacity`]).
//!
//! Sub-cell `(x, y, z)`, each in `0..3`, covers `[x/3, (x+1)/3] × …` of the unit voxel and has
//! index `c = x + 3y + 9z`.
//!
//! # Build rules
//! - **Whole chord, unweighted.** Every sampling line books one ray, and one occlusion if it is
//!   occluded, on every sub-cell its chord through the voxel crosses with positive length
//!   ([`crossed_subcells`]). Zero-length touches (a line through a sub-cell edge
//!   or corner, or segments shorter than [`TOUCH`]) are not booked; the reference code counts
//!   them.
//! - **Front-hit mark.** A case-(a) hit marks exactly one sub-cell, `clamp(⌊3p⌋, 0, 2)` per
//!   axis ([`subcell_of`]): a hit on a shared sub-cell face marks the cell above it (the
//!   reference code's closed boxes mark both).
//! - **Clearing.** A sub-cell without a mark, or crossed by no line, gets 0; the others get
//!   `round(255 · occluded / rays)`.
//!
//! # Directional opacity
//! [`DirectionalRule::Lines`] (the default), the paper's circles made exact for solids
//! ([`DirectionalRule::Circles`]; the design note §6 measures both against exact cube
//! footprints), and the rule of the authors' public code as it stands
//! ([`DirectionalRule::Authors`], not normalized). A solid subgrid gives exactly 1 and an empty
//! one 0 under every rule, from any direction.
//! Neither can make a thin plane seen edge-on nearly transparent: the plane's layer of sub-cells
//! covers a third of the voxel's footprint, so the floor is about 1/3 (Lines measure 0.31).

use std::f32::consts::PI;

use glam::{Vec2, Vec3, Vec3A, Vec4};
use voxlod_format::records::quant::unorm8;

use super::line_sampler::{choose_face, chord, entry_point};
use super::voxel_samples::VoxelSamples;

/// A line whose overlap with a sub-cell is no longer than this (voxel units) only touches it.
pub const TOUCH: f32 = 1e-6;

/// Number of lines of [`DirectionalRule::Lines`].
pub const LINES: u32 = 32;

/// Radius of a sub-cell's circle under [`DirectionalRule::Circles`], voxel units:
/// 0.9 × the sub-cell's circumradius `√3/6`.
pub const CIRCLE_RADIUS: f32 = 0.9 * 0.288_675_13;

/// Index `x + 3y + 9z` of the sub-cell holding the voxel-local point `p`, each coordinate
/// `clamp(⌊3p⌋, 0, 2)`: exactly one cell, also on shared faces and outside the voxel.
#[inline]
pub fn subcell_of(p: Vec3) -> usize {
    // Truncation equals `floor` wherever the clamp keeps the result (`floor` is a libm call
    // on targets without SSE4.1); NaN gives 0 either way.
    let c = |v: f32| ((3.0 * v) as i32).clamp(0, 2) as usize;
    c(p.x) + 3 * c(p.y) + 9 * c(p.z)
}

/// The sub-cells the segment `entry + t·d`, `t ∈ [0, chord]`, crosses with positive length,
/// as a mask (bit `x + 3y + 9z`; at most 7 bits set). `entry` is voxel-local on the voxel's
/// boundary and `chord` the line's length inside it (see [`chord`]).
///
/// A cell is crossed when the segment's overlap with its closed box is longer than [`TOUCH`]:
/// a line through a sub-cell edge or corner skips the cells it only touches, and a line
/// starting on a sub-cell boundary is only in the cell it goes into. A line running exactly
/// inside a sub-cell face (`d_k = 0` on a boundary) is booked in the cell above it
/// (`⌊3·entry_k⌋`). Branch-free (per axis the three slab intervals, then 27 overlaps), since
/// which cells a random line crosses is unpredictable.
#[inline(always)]
pub fn crossed_subcells(entry: Vec3, d: Vec3, chord: f32) -> u32 {
    if chord.is_nan() || chord <= TOUCH {
        return 0;
    }
    // The three reciprocals in one SIMD division (lane by lane the same `1/d_j`).
    let inv = (Vec3A::ONE / Vec3A::from(d)).to_array();
    let (e, d) = (entry.to_array(), d.to_array());
    // Per axis, the three slab intervals [lo, hi] in SIMD lanes: the four boundary crossings
    // t = (b − e)·(1/d) of one axis at once, then min/max of neighbouring pairs.
    let slabs = |j: usize| -> (Vec3A, Vec3A) {
        if d[j] == 0.0 {
            // A line that does not move along axis j stays in its home slab for all t:
            // `⌊3e⌋` clamped to 0..=2, by truncation (equal under the clamp, see `subcell_of`).
            let home = ((3.0 * e[j]) as i32).clamp(0, 2) as usize;
            let lo =
                std::array::from_fn(|s| if s == home { f32::NEG_INFINITY } else { f32::INFINITY });
            let lo = Vec3A::from_array(lo);
            return (lo, -lo);
        }
        let t = (Vec4::new(0.0, 1.0 / 3.0, 2.0 / 3.0, 1.0) - Vec4::splat(e[j])) * inv[j];
        let (a, b) = (Vec3A::new(t.x, t.y, t.z), Vec3A::new(t.y, t.z, t.w));
        (a.min(b), a.max(b))
    };
    let (lo_x, hi_x) = slabs(0);
    let (lo_y, hi_y) = slabs(1);
    let (lo_z, hi_z) = slabs(2);
    // The y slabs side by side, clipped to [0, chord]; then per (y, z) the three x slabs in
    // SIMD lanes: one compare and one bit mask per pair. No operand is NaN, so the order of
    // the min/max operations does not change a bit.
    let lo_y = lo_y.max(Vec3A::ZERO);
    let hi_y = hi_y.min(Vec3A::splat(chord));
    let (lo_z, hi_z) = (lo_z.to_array(), hi_z.to_array());
    let mut mask = 0;
    for z in 0..3 {
        let l_yz = lo_y.max(Vec3A::splat(lo_z[z])).to_array();
        let h_yz = hi_y.min(Vec3A::splat(hi_z[z])).to_array();
        for y in 0..3 {
            let length = hi_x.min(Vec3A::splat(h_yz[y])) - lo_x.max(Vec3A::splat(l_yz[y]));
            mask |= length.cmpgt(Vec3A::splat(TOUCH)).bitmask() << (3 * y + 9 * z);
        }
    }
    mask
}

/// Visits the sub-cells of [`crossed_subcells`] in index order until `visit` returns `false`.
#[inline]
pub fn for_each_subcell(entry: Vec3, d: Vec3, chord: f32, mut visit: impl FnMut(usize) -> bool) {
    let mut mask = crossed_subcells(entry, d, chord);
    while mask != 0 {
        if !visit(mask.trailing_zeros() as usize) {
            return;
        }
        mask &= mask - 1;
    }
}

/// Builds the 27 sub-cell opacities of a voxel from its sampling lines (module docs: whole
/// chord, one-cell front-hit mark, clearing), `round(255·α)` at index `x + 3y + 9z`.
pub fn build(samples: &VoxelSamples) -> [u8; 27] {
    // Clearing first: only marked sub-cells can end non-zero, so the lines book only those
    // (bit by bit over the crossed ∩ marked mask, at most 7 bits), and a voxel without a
    // front hit books nothing at all.
    let marked = samples.surfaces().fold(0u32, |m, s| m | 1 << subcell_of(s.point));
    let mut rays = [0u32; 27];
    let mut occluded = [0u32; 27];
    if marked != 0 {
        for r in &samples.rays {
            let o = r.occluded as u32;
            let mut m = crossed_subcells(r.entry, r.dir, r.chord) & marked;
            while m != 0 {
                let c = m.trailing_zeros() as usize;
                rays[c] += 1;
                occluded[c] += o;
                m &= m - 1;
            }
        }
    }
    std::array::from_fn(
        |c| {
            if rays[c] > 0 { unorm8(occluded[c] as f32 / rays[c] as f32) } else { 0 }
        },
    )
}

/// How [`directional_opacity`] reads a subgrid (design note §6).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum DirectionalRule {
    /// [`LINES`] = 32 parallel lines through the voxel along the view direction, placed over
    /// its projection by the sampler's exact face choice with a fixed pattern: line `k` uses
    /// `u = (k + ½)/K` for the face choice, the choice's remainder as its first in-face
    /// coordinate and `φ₂(k) + 1/(2K)` (the base-2 radical inverse, moved to the centre of
    /// its stratum so that no line runs along a voxel edge) as the second. A line's opacity
    /// is the largest α of the sub-cells it crosses with positive length ([`crossed_subcells`]);
    /// the voxel's is the
    /// mean over the lines with a positive chord. The limit of the paper's rule with
    /// point-sized pixels and exact footprints; no randomness, identical on CPU and GPU.
    #[default]
    Lines,
    /// The paper's rule, made exact for solids: a 4×4 window over the bounding rectangle of
    /// the voxel's projection in the Hughes–Möller basis of the direction; each sub-cell a
    /// circle of radius [`CIRCLE_RADIUS`] around its projected centre, each pixel a circle of
    /// radius `min(step)/2`; per pixel the largest `α·coverage` (analytic lens area over the
    /// pixel circle's area, clamped `acos`), summed over the 16 pixels and **normalized** by the
    /// same sum for a solid voxel.
    Circles,
    /// The rule of the authors' public code (Brito, Poulin and Teichrieb 2023, §3.4;
    /// `SubgridOfOpacities::computeOcclusion` and `projectionKernel` of their
    /// `representations.h`), step by step and **not normalized**, evaluated for the ray
    /// direction `r = −dir` (their camera ray, travelling from the viewer into the voxel):
    /// - the Hughes–Möller basis `(u, v)` of `r` (as in [`DirectionalRule::Circles`]); the window
    ///   is the bounding rectangle of the 8 projected voxel corners, split into 4×4 pixels of
    ///   `step = extent/4` per axis (a rectangle, not a square);
    /// - every sub-cell with a non-zero opacity is a circle of radius `√2·step_u` (larger than
    ///   the sub-cell's circumradius) around its projected centre, which falls in pixel
    ///   `(⌊(p_u − min_u)/step_u⌋, ⌊(p_v − min_v)/step_v⌋)` (truncation);
    /// - only the 3×3 pixels around that pixel (clipped to the window) are visited: each a
    ///   circle of radius `step_u/2` around its centre, covered by `lens area / pixel-circle
    ///   area`, clamped to [0, 1] with a NaN (a rounding past `acos`'s domain) reading as 1, as
    ///   their `clampf` does; the pixel keeps the largest `α·coverage`;
    /// - the voxel's opacity is the mean of the 16 pixels.
    ///
    /// [`AUTHORS_SPHERE_RADIUS`] and [`AUTHORS_PIXEL_RADIUS`] give the two radii. The sub-cell
    /// circles are so much larger than the pixel circles that a solid subgrid covers every
    /// pixel fully (1 from every direction tested), and a lone sub-cell covers about a quarter
    /// to a third of the window (where the exact footprint of a sub-cell is a ninth or less
    /// of the voxel's): the rule extends opacities, as the paper notes of its maximum test (§5).
    Authors,
}

/// Radius of a sub-cell's circle under [`DirectionalRule::Authors`], in units of the window's
/// pixel width `step_u`: `√2`.
pub const AUTHORS_SPHERE_RADIUS: f32 = std::f32::consts::SQRT_2;

/// Radius of a pixel's circle under [`DirectionalRule::Authors`], in units of `step_u`: `½`.
pub const AUTHORS_PIXEL_RADIUS: f32 = 0.5;

/// The opacity in [0, 1] of a voxel with sub-cell opacities `alpha` (`round(255·α)`, index
/// `x + 3y + 9z`) seen along `dir` (any length; a zero or non-finite `dir` reads as +z), under
/// `rule`. All zero gives exactly 0, all 255 exactly 1 (computed under
/// [`DirectionalRule::Authors`], which reaches 1 on every direction tested); the result depends
/// only on the line, not on the sign of `dir`, up to the fixed pattern's placement (and, for
/// the authors' rule, the pixel a projected centre lying exactly on a pixel boundary falls in).
pub fn directional_opacity(alpha: &[u8; 27], dir: Vec3, rule: DirectionalRule) -> f32 {
    let (lo, hi) = alpha.iter().fold((255u8, 0u8), |(lo, hi), &a| (lo.min(a), hi.max(a)));
    if hi == 0 {
        return 0.0;
    }
    if lo == 255 && rule != DirectionalRule::Authors {
        return 1.0;
    }
    let d = dir.try_normalize().unwrap_or(Vec3::Z);
    match rule {
        DirectionalRule::Lines => lines(alpha, d),
        DirectionalRule::Circles => circles(alpha, d),
        DirectionalRule::Authors => authors(alpha, -d),
    }
}

/// Base-2 radical inverse of `k` in [0, 1).
#[inline]
fn radical_inverse(k: u32) -> f32 {
    (k.reverse_bits() >> 8) as f32 * (1.0 / 16_777_216.0)
}

/// [`DirectionalRule::Lines`] for a unit `d`.
fn lines(alpha: &[u8; 27], d: Vec3) -> f32 {
    let k_inv = 1.0 / LINES as f32;
    let (mut sum, mut count) = (0u32, 0u32);
    for k in 0..LINES {
        let (face, s) = choose_face(d, (k as f32 + 0.5) * k_inv);
        let t = radical_inverse(k) + 0.5 * k_inv;
        let entry = entry_point(d, face, s, t);
        let (mut max, mut crossed) = (0u8, false);
        for_each_subcell(entry, d, chord(entry, d), |c| {
            crossed = true;
            max = max.max(alpha[c]);
            max < 255
        });
        if crossed {
            sum += max as u32;
            count += 1;
        }
    }
    if count == 0 { 0.0 } else { (sum as f32 / (255.0 * count as f32)).clamp(0.0, 1.0) }
}

/// The Hughes–Möller basis `(u, v)` orthogonal to the unit `d`, as the reference code builds
/// it: `v = normalize(−d_y, d_x, 0)` if `|d_x| > |d_z|`, else `normalize(0, −d_z, d_y)`;
/// `u = v × d`.
fn hughes_moeller(d: Vec3) -> (Vec3, Vec3) {
    let v =
        if d.x.abs() > d.z.abs() { Vec3::new(-d.y, d.x, 0.0) } else { Vec3::new(0.0, -d.z, d.y) }
            .normalize();
    (v.cross(d), v)
}

/// Area of the intersection of two discs of radii `r1`, `r2` whose centres are `dist` apart.
fn lens_area(dist: f32, r1: f32, r2: f32) -> f32 {
    if dist >= r1 + r2 {
        return 0.0;
    }
    let small = r1.min(r2);
    if dist <= (r1 - r2).abs() {
        return PI * small * small;
    }
    let acos = |x: f32| x.clamp(-1.0, 1.0).acos();
    let a1 = r1 * r1 * acos((dist * dist + r1 * r1 - r2 * r2) / (2.0 * dist * r1));
    let a2 = r2 * r2 * acos((dist * dist + r2 * r2 - r1 * r1) / (2.0 * dist * r2));
    let k = (-dist + r1 + r2) * (dist + r1 - r2) * (dist - r1 + r2) * (dist + r1 + r2);
    (a1 + a2 - 0.5 * k.max(0.0).sqrt()).clamp(0.0, PI * small * small)
}

/// [`DirectionalRule::Circles`] for a unit `d`.
fn circles(alpha: &[u8; 27], d: Vec3) -> f32 {
    let (u, v) = hughes_moeller(d);
    let project = |p: Vec3| Vec2::new(p.dot(u), p.dot(v));
    let (mut lo, mut hi) = (Vec2::INFINITY, Vec2::NEG_INFINITY);
    for c in 0..8u32 {
        let q = project(Vec3::new((c & 1) as f32, (c >> 1 & 1) as f32, (c >> 2 & 1) as f32));
        lo = lo.min(q);
        hi = hi.max(q);
    }
    let step = (hi - lo) / 4.0;
    let rp = 0.5 * step.min_element();
    let pixel_area = PI * rp * rp;
    if pixel_area.is_nan() || pixel_area <= 0.0 {
        return 0.0;
    }
    let centres: [Vec2; 27] = std::array::from_fn(|c| {
        let (x, y, z) = (c % 3, c / 3 % 3, c / 9);
        project((Vec3::new(x as f32, y as f32, z as f32) + 0.5) / 3.0)
    });
    let (mut num, mut den) = (0.0f32, 0.0f32);
    for j in 0..4 {
        for i in 0..4 {
            let pixel = lo + Vec2::new(i as f32 + 0.5, j as f32 + 0.5) * step;
            let (mut best, mut solid) = (0.0f32, 0.0f32);
            for (c, &centre) in centres.iter().enumerate() {
                let cover = lens_area(centre.distance(pixel), CIRCLE_RADIUS, rp) / pixel_area;
                solid = solid.max(cover);
                best = best.max(alpha[c] as f32 * (1.0 / 255.0) * cover);
            }
            num += best;
            den += solid;
        }
    }
    if den > 0.0 { (num / den).clamp(0.0, 1.0) } else { 0.0 }
}

/// The area the authors' `circleIntersection` gives for two discs of radii `r1`, `r2` whose
/// centres are `dist` apart, `None` when they do not meet (`dist > r1 + r2`): containment
/// gives the smaller disc, otherwise the two circular segments `½r²(θ − sin θ)` with the
/// unclamped `acos` (NaN where rounding leaves its domain, as theirs).
fn authors_lens(dist: f32, r1: f32, r2: f32) -> Option<f32> {
    if dist > r1 + r2 {
        return None;
    }
    let small = r1.min(r2);
    if dist <= (r2 - r1).abs() {
        return Some(PI * small * small);
    }
    let alpha = ((r1 * r1 + dist * dist - r2 * r2) / (2.0 * r1 * dist)).acos() * 2.0;
    let beta = ((r2 * r2 + dist * dist - r1 * r1) / (2.0 * r2 * dist)).acos() * 2.0;
    let a1 = 0.5 * beta * r2 * r2 - 0.5 * r2 * r2 * beta.sin();
    let a2 = 0.5 * alpha * r1 * r1 - 0.5 * r1 * r1 * alpha.sin();
    Some(a1 + a2)
}

/// [`DirectionalRule::Authors`] for the unit ray direction `r` (already `−dir`), in
/// voxel-local coordinates centred on the voxel (the authors project relative to the camera;
/// a translation of the plane moves nothing but rounding).
fn authors(alpha: &[u8; 27], r: Vec3) -> f32 {
    let (u, v) = hughes_moeller(r);
    let project = |p: Vec3| Vec2::new(p.dot(u), p.dot(v));
    let (mut lo, mut hi) = (Vec2::INFINITY, Vec2::NEG_INFINITY);
    for c in 0..8u32 {
        let corner = Vec3::new((c & 1) as f32, (c >> 1 & 1) as f32, (c >> 2 & 1) as f32);
        let q = project(corner - 0.5);
        lo = lo.min(q);
        hi = hi.max(q);
    }
    let step = (hi - lo) / 4.0;
    let (r_sphere, r_pixel) = (step.x * AUTHORS_SPHERE_RADIUS, step.x * AUTHORS_PIXEL_RADIUS);
    let pixel_area = PI * r_pixel * r_pixel;
    if pixel_area.is_nan() || pixel_area <= 0.0 {
        return 0.0;
    }
    let centre = |i: i32, j: i32| lo + Vec2::new(i as f32 + 0.5, j as f32 + 0.5) * step;
    let mut grid = [[0.0f32; 4]; 4];
    for (c, &a) in alpha.iter().enumerate().filter(|(_, a)| **a > 0) {
        let (x, y, z) = (c % 3, c / 3 % 3, c / 9);
        let p = project((Vec3::new(x as f32, y as f32, z as f32) + 0.5) / 3.0 - 0.5);
        let cell = ((p - lo) / step).to_array().map(|w| w as i32);
        let a = a as f32 / 255.0;
        for i in cell[0] - 1..=cell[0] + 1 {
            for j in cell[1] - 1..=cell[1] + 1 {
                if !(0..4).contains(&i) || !(0..4).contains(&j) {
                    continue;
                }
                let Some(area) = authors_lens(p.distance(centre(i, j)), r_sphere, r_pixel) else {
                    continue;
                };
                // A NaN area covers fully, as `fmaxf(0, fminf(x, 1))` does (`clamp` would
                // keep the NaN).
                let ratio = area / pixel_area;
                let cover = if ratio.is_nan() { 1.0 } else { ratio.clamp(0.0, 1.0) };
                let slot = &mut grid[i as usize][j as usize];
                *slot = slot.max(a * cover);
            }
        }
    }
    (grid.iter().flatten().sum::<f32>() / 16.0).clamp(0.0, 1.0)
}

#[cfg(test)]
mod tests;
