//! Filling a metavoxel (McNabb 2015, §5.5.2): every voxel centre is tested against the particles of
//! the metavoxel's bin, in particle order; a covered voxel adds the particle's extinction to its
//! density (the sum) and raises its colour to the particle's colour there (the max, per
//! channel; albedo and emission kept apart so that only the albedo is lit).
//!
//! Coverage of the displaced sphere, in voxel units with squared distances (no square root on
//! the fast paths): in the shell the voxel is inside when `d² ≤ r²`,
//! `r = inner + amplitude · n(direction)`. The early exits use the cube map's bounds
//! `[n_lo, n_hi]` ([`DisplacementMap::bounds`], the texel range widened for rounding), within
//! `[0, 1]` and usually well inside it: `d² > r_hi²` is outside without reading the cube map
//! (early reject), `d² ≤ max(inner, r_lo)²` is inside without reading it (early accept, unless
//! the colour mode needs the displacement), `r_lo, r_hi` the radii at `n_lo, n_hi`. Since `r`
//! is non-decreasing in `n` in floating point too, the early exits never change the answer:
//! [`fill_unaccelerated`] (every particle, every voxel, always the cube map) gives bit-identical
//! voxels, which a test checks.

use glam::{Vec3, Vec4};
use rayon::prelude::*;
use voxlod_scene::particles::{ColorMode, DisplacedSphere, DisplacementMap};

use super::binning::{Bin, Prepared};
use super::{Metavoxel, VolumeSpec};

/// Lane offsets of four consecutive voxels of a row.
const LANES: Vec4 = Vec4::new(0.0, 1.0, 2.0, 3.0);

/// Per-voxel accumulator of one particle's contribution.
#[inline]
fn accumulate(
    s: &DisplacedSphere,
    dist: f32,
    n: f32,
    voxel: &mut Vec4,
    emission: &mut Option<Vec<Vec3>>,
    index: usize,
    len: usize,
) {
    // One load and one store of the voxel (writing `w` alone and then reading the whole
    // voxel back stalled on store-to-load forwarding).
    let v = *voxel;
    let w = v.w + s.density;
    let c = s.color_at(dist, n);
    if s.emissive() {
        let e = emission.get_or_insert_with(|| vec![Vec3::ZERO; len]);
        e[index] = e[index].max(c);
        *voxel = v.truncate().extend(w);
    } else {
        *voxel = c.max(v.truncate()).extend(w);
    }
}

/// Layers (`c`) of a metavoxel that one parallel task fills: a metavoxel holding many
/// particles is split across the cores, each task writing its own whole layers (no sharing).
const SLAB_LAYERS: usize = 8;

/// What one slab's fill returns: the box of the voxels it wrote and its emission.
type Slab = ([[u32; 3]; 2], Option<Vec<Vec3>>);

/// Fills the metavoxel of `bin`: voxels as (albedo max, density sum), and the emission (max)
/// when an emissive particle covers any voxel. Lighting comes after ([`super::propagate`]).
///
/// Per particle only its voxel box clipped to the metavoxel is visited, and in it only the
/// x-span of each row that the sphere of radius `r_hi` can reach (solved per row with a
/// one-voxel margin, so that the per-voxel `d² > r_hi²` test still decides). The span is
/// walked four voxels at a time ([`DisplacedSphere::displacement4`]: one 4-lane cube-map
/// look-up), each lane doing the scalar loop's arithmetic for its voxel: the same voxels and
/// the same arithmetic per voxel as the plain loop, so the same bits ([`fill_unaccelerated`]).
/// Slabs of `SLAB_LAYERS` (8) layers run in parallel; each voxel still sees its particles in
/// particle order. The box of the voxels written is kept ([`Metavoxel::occupied`]) for the
/// later stages.
pub fn fill(
    spheres: &[DisplacedSphere],
    prepared: &[Prepared],
    map: &DisplacementMap,
    spec: &VolumeSpec,
    bin: &Bin,
) -> (Metavoxel, Option<Vec<Vec3>>) {
    fill_with(spheres, prepared, map, spec, bin, true)
}

/// [`fill`], compiled for AVX2 when `detect` and the CPU has it (the same source and the same
/// bits: AVX2 does not bring FMA, and nothing is reassociated; VEX encoding, blends for the
/// selects); the portable (SSE2) build otherwise. The tests run both.
pub(crate) fn fill_with(
    spheres: &[DisplacedSphere],
    prepared: &[Prepared],
    map: &DisplacementMap,
    spec: &VolumeSpec,
    bin: &Bin,
    detect: bool,
) -> (Metavoxel, Option<Vec<Vec3>>) {
    #[cfg(target_arch = "x86_64")]
    let avx2 = detect && std::arch::is_x86_feature_detected!("avx2");
    #[cfg(not(target_arch = "x86_64"))]
    let _ = detect;
    let m = spec.metavoxel_edge as usize;
    let m3 = m * m * m;
    let layers = SLAB_LAYERS.min(m);
    let mut voxels = vec![Vec4::ZERO; m3];
    let slabs: Vec<Slab> = voxels
        .par_chunks_mut(layers * m * m)
        .enumerate()
        .map(|(i, chunk)| {
            let c0 = i * layers;
            #[cfg(target_arch = "x86_64")]
            if avx2 {
                // SAFETY: the CPU has AVX2 (checked above).
                return unsafe { fill_slab_avx2(spheres, prepared, map, spec, bin, c0, chunk) };
            }
            fill_slab(spheres, prepared, map, spec, bin, c0, chunk)
        })
        .collect();
    let (mut lo, mut hi) = ([u32::MAX; 3], [0u32; 3]);
    for ([a, b], _) in &slabs {
        if a[0] < b[0] {
            lo = [lo[0].min(a[0]), lo[1].min(a[1]), lo[2].min(a[2])];
            hi = [hi[0].max(b[0]), hi[1].max(b[1]), hi[2].max(b[2])];
        }
    }
    if lo[0] == u32::MAX {
        (lo, hi) = ([0; 3], [0; 3]);
    }
    let emission = slabs.iter().any(|s| s.1.is_some()).then(|| {
        let mut e = Vec::with_capacity(m3);
        for (_, part) in &slabs {
            match part {
                Some(p) => e.extend_from_slice(p),
                None => e.resize(e.len() + layers * m * m, Vec3::ZERO),
            }
        }
        e.truncate(m3);
        e
    });
    let mv = Metavoxel {
        coord: bin.coord,
        particles: bin.particles.len(),
        voxels,
        light_top: vec![1.0; m * m],
        occupied: [lo, hi],
    };
    (mv, emission)
}

/// [`fill_slab`] compiled with AVX2 enabled.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn fill_slab_avx2(
    spheres: &[DisplacedSphere],
    prepared: &[Prepared],
    map: &DisplacementMap,
    spec: &VolumeSpec,
    bin: &Bin,
    c0: usize,
    voxels: &mut [Vec4],
) -> Slab {
    fill_slab(spheres, prepared, map, spec, bin, c0, voxels)
}

/// Fills layers `c0..` of the metavoxel of `bin` into `voxels` (whole layers); returns the box
/// of the voxels written (metavoxel-local, `[lo, hi)`, `lo[0] ≥ hi[0]` when none) and the
/// slab's emission.
#[inline(always)]
fn fill_slab(
    spheres: &[DisplacedSphere],
    prepared: &[Prepared],
    map: &DisplacementMap,
    spec: &VolumeSpec,
    bin: &Bin,
    c0: usize,
    voxels: &mut [Vec4],
) -> Slab {
    let m = spec.metavoxel_edge as usize;
    let len = voxels.len();
    let c_end = c0 + len / (m * m);
    let base = Vec3::new(bin.coord[0] as f32, bin.coord[1] as f32, bin.coord[2] as f32)
        * spec.metavoxel_edge as f32;
    let f = &spec.frame;
    let mut emission = None;
    let (mut occ_lo, mut occ_hi) = ([u32::MAX; 3], [0u32; 3]);
    let [n_lo, n_hi] = map.bounds();
    for &pi in &bin.particles {
        let (s, p) = (&spheres[pi as usize], &prepared[pi as usize]);
        // The surface radius `r = inner + amplitude · n` is non-decreasing in `n` (rounding
        // included), so the map's bounds bound it: a voxel beyond `r_hi` is outside and one
        // within `r_lo` inside whatever the map says there. `r_hi ≤ outer` unless the map
        // reaches 1; it is the radius that decides below.
        let (r_lo, r_hi) = (p.inner + p.amplitude * n_lo, p.inner + p.amplitude * n_hi);
        // The particle's voxel range inside this metavoxel (voxel centres within `r_hi` lie
        // in it, with a margin for the rounding), then inside this slab.
        let reach = r_hi * (1.0 + 1e-5) + 1e-3;
        let lo = (p.center - reach - base - 0.5).ceil().max(Vec3::ZERO);
        let hi = (p.center + reach - base - 0.5).floor().min(Vec3::splat((m - 1) as f32));
        if lo.cmpgt(hi).any() {
            continue;
        }
        let (z0, z1) = ((lo.z as usize).max(c0), (hi.z as usize + 1).min(c_end));
        if z0 >= z1 {
            continue;
        }
        let accept = p.inner.max(r_lo);
        let (accept2, reject2) = (accept * accept, r_hi * r_hi);
        let needs_n = s.color_needs_displacement();
        let ramp = s.color_mode == ColorMode::RadialRamp as u32;
        // Rows whose (y, z) distance exceeds this cannot hold a voxel within `r_hi` (the
        // relative margin covers the rounding of the per-voxel d²).
        let reach2 = reject2 * (1.0 + 1e-5);
        let centre_a = p.center.x - base.x - 0.5;
        // Lane-wise constants of the per-voxel arithmetic below.
        let (accept2v, reject2v) = (Vec4::splat(accept2), Vec4::splat(reject2));
        let (bx, cx) = (Vec4::splat(base.x), Vec4::splat(p.center.x));
        let (ux, uy, uz) = (Vec4::splat(f.u.x), Vec4::splat(f.u.y), Vec4::splat(f.u.z));
        let (p_inner, p_amp) = (Vec4::splat(p.inner), Vec4::splat(p.amplitude));
        let vs = Vec4::splat(f.voxel_size);
        for c in z0..z1 {
            let qz = base.z + c as f32 + 0.5 - p.center.z;
            let wz = f.w * qz;
            for b in lo.y as usize..=hi.y as usize {
                let qy = base.y + b as f32 + 0.5 - p.center.y;
                let yz2 = qy * qy + qz * qz;
                if yz2 > reach2 {
                    continue;
                }
                // The row's x-span, widened by a voxel (and by the truncation toward zero,
                // which is within a voxel of the ceiling or floor): any superset of the
                // voxels within the outer radius gives the same voxels, the per-voxel test
                // deciding.
                let half = (reach2 - yz2).sqrt() + 1.0;
                let a0 = ((centre_a - half) as i32).max(lo.x as i32);
                let a1 = ((centre_a + half) as i32).min(hi.x as i32);
                if a1 < a0 {
                    continue;
                }
                let (a0, a1) = (a0 as usize, a1 as usize);
                let vy = f.v * qy;
                let (qy2, qz2) = (Vec4::splat(qy * qy), Vec4::splat(qz * qz));
                let (vyx, vyy, vyz) = (Vec4::splat(vy.x), Vec4::splat(vy.y), Vec4::splat(vy.z));
                let (wzx, wzy, wzz) = (Vec4::splat(wz.x), Vec4::splat(wz.y), Vec4::splat(wz.z));
                let row = ((c - c0) * m + b) * m;
                let (mut first, mut last) = (usize::MAX, 0usize);
                // Four voxels of the row at a time, every lane computing exactly what the
                // scalar loop of `fill_unaccelerated` computes for its voxel.
                for a in (a0..=a1).step_by(4) {
                    let lanes = Vec4::splat(a as f32) + LANES;
                    let qx = bx + lanes + 0.5 - cx;
                    let d2 = qx * qx + qy2 + qz2; // `Vec3::length_squared`, same order
                    let live = lanes.cmple(Vec4::splat(a1 as f32)) & d2.cmple(reject2v);
                    if !live.any() {
                        continue; // early reject of all four
                    }
                    let inside = d2.cmple(accept2v);
                    let (n, covered) = if !needs_n && (live & !inside).bitmask() == 0 {
                        (Vec4::ZERO, live) // early accept: the displacement is not needed
                    } else {
                        // `LightSpace::offset_to_world(q)`, the products of y and z hoisted.
                        let ox = (ux * qx + vyx + wzx) * vs;
                        let oy = (uy * qx + vyy + wzy) * vs;
                        let oz = (uz * qx + vyz + wzz) * vs;
                        let n = s.displacement4(map, ox, oy, oz);
                        let r = p_inner + p_amp * n;
                        let covered = live & (inside | d2.cmple(r * r));
                        // The scalar loop does not read the map for an early accept.
                        let n = if needs_n { n } else { Vec4::select(inside, Vec4::ZERO, n) };
                        (n, covered)
                    };
                    let mut bits = covered.bitmask();
                    if bits == 0 {
                        continue;
                    }
                    let (n, d2) = (n.to_array(), d2.to_array());
                    first = first.min(a + bits.trailing_zeros() as usize);
                    last = a + 31 - bits.leading_zeros() as usize;
                    while bits != 0 {
                        let i = bits.trailing_zeros() as usize;
                        bits &= bits - 1;
                        let index = row + a + i;
                        // Only the radial ramp reads the distance.
                        let dist = if ramp { d2[i].sqrt() * f.voxel_size } else { 0.0 };
                        accumulate(s, dist, n[i], &mut voxels[index], &mut emission, index, len);
                    }
                }
                if first <= last {
                    let (a, b, c) = (first as u32, b as u32, c as u32);
                    occ_lo = [occ_lo[0].min(a), occ_lo[1].min(b), occ_lo[2].min(c)];
                    occ_hi = [
                        occ_hi[0].max(last as u32 + 1),
                        occ_hi[1].max(b + 1),
                        occ_hi[2].max(c + 1),
                    ];
                }
            }
        }
    }
    ([occ_lo, occ_hi], emission)
}

/// The unaccelerated fill: every voxel of the metavoxel against every particle, in particle
/// order, always reading the cube map and testing `d² ≤ r²`. The reference [`fill`] (bins,
/// voxel ranges, early accept/reject) is checked against.
pub fn fill_unaccelerated(
    spheres: &[DisplacedSphere],
    prepared: &[Prepared],
    map: &DisplacementMap,
    spec: &VolumeSpec,
    coord: [u32; 3],
) -> (Vec<Vec4>, Option<Vec<Vec3>>) {
    let m = spec.metavoxel_edge as usize;
    let m3 = m * m * m;
    let base =
        Vec3::new(coord[0] as f32, coord[1] as f32, coord[2] as f32) * spec.metavoxel_edge as f32;
    let mut voxels = vec![Vec4::ZERO; m3];
    let mut emission = None;
    for (s, p) in spheres.iter().zip(prepared) {
        for c in 0..m {
            for b in 0..m {
                for a in 0..m {
                    let q = base + Vec3::new(a as f32, b as f32, c as f32) + 0.5 - p.center;
                    let d2 = q.length_squared();
                    let n = s.displacement(map, spec.frame.offset_to_world(q));
                    let r = p.inner + p.amplitude * n;
                    if d2 > r * r {
                        continue;
                    }
                    let index = (c * m + b) * m + a;
                    let dist = d2.sqrt() * spec.frame.voxel_size;
                    accumulate(s, dist, n, &mut voxels[index], &mut emission, index, m3);
                }
            }
        }
    }
    (voxels, emission)
}
