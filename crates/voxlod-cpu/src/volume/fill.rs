//! Filling a metavoxel (seed 001 §5.5.2): every voxel centre is tested against the particles of
//! the metavoxel's bin, in particle order; a covered voxel adds the particle's extinction to its
//! density (the sum) and raises its colour to the particle's colour there (the max, per
//! channel; albedo and emission kept apart so that only the albedo is lit).
//!
//! Coverage of the displaced sphere, in voxel units with squared distances (no square root on
//! the fast paths): `d² > outer²` is outside without reading the cube map (early reject),
//! `d² ≤ inner²` is inside without reading it (early accept, unless the colour mode needs the
//! displacement), and in the shell between them the voxel is inside when `d² ≤ r²`,
//! `r = inner + amplitude · n(direction)`. Since `n ∈ [0, 1]`, `inner ≤ r ≤ outer` in floating
//! point too, so the early exits never change the answer: [`fill_unaccelerated`] (every
//! particle, every voxel, always the cube map) gives bit-identical voxels, which a test checks.

use glam::{Vec3, Vec4};
use voxlod_scene::particles::{DisplacedSphere, DisplacementMap};

use super::binning::{Bin, Prepared};
use super::{Metavoxel, VolumeSpec};

/// Per-voxel accumulator of one particle's contribution.
#[inline]
fn accumulate(
    s: &DisplacedSphere,
    dist: f32,
    n: f32,
    voxel: &mut Vec4,
    emission: &mut Option<Vec<Vec3>>,
    index: usize,
    m3: usize,
) {
    voxel.w += s.density;
    let c = s.color_at(dist, n);
    if s.emissive() {
        let e = emission.get_or_insert_with(|| vec![Vec3::ZERO; m3]);
        e[index] = e[index].max(c);
    } else {
        *voxel = c.max(voxel.truncate()).extend(voxel.w);
    }
}

/// Fills the metavoxel of `bin`: voxels as (albedo max, density sum), and the emission (max)
/// when an emissive particle covers any voxel. Lighting comes after ([`super::propagate`]).
pub fn fill(
    spheres: &[DisplacedSphere],
    prepared: &[Prepared],
    map: &DisplacementMap,
    spec: &VolumeSpec,
    bin: &Bin,
) -> (Metavoxel, Option<Vec<Vec3>>) {
    let m = spec.metavoxel_edge as usize;
    let m3 = m * m * m;
    let base = Vec3::new(bin.coord[0] as f32, bin.coord[1] as f32, bin.coord[2] as f32)
        * spec.metavoxel_edge as f32;
    let mut voxels = vec![Vec4::ZERO; m3];
    let mut emission = None;
    for &pi in &bin.particles {
        let (s, p) = (&spheres[pi as usize], &prepared[pi as usize]);
        // The particle's voxel range inside this metavoxel (voxel centres within the outer
        // radius lie in it).
        let lo = (p.center - p.outer - base - 0.5).ceil().max(Vec3::ZERO);
        let hi = (p.center + p.outer - base - 0.5).floor().min(Vec3::splat((m - 1) as f32));
        if lo.cmpgt(hi).any() {
            continue;
        }
        let (inner2, outer2) = (p.inner * p.inner, p.outer * p.outer);
        let needs_n = s.color_needs_displacement();
        for c in lo.z as usize..=hi.z as usize {
            for b in lo.y as usize..=hi.y as usize {
                for a in lo.x as usize..=hi.x as usize {
                    let q = base + Vec3::new(a as f32, b as f32, c as f32) + 0.5 - p.center;
                    let d2 = q.length_squared();
                    if d2 > outer2 {
                        continue; // early reject
                    }
                    let n = if d2 <= inner2 && !needs_n {
                        0.0 // early accept: the displacement is not needed
                    } else {
                        let n = s.displacement(map, spec.frame.offset_to_world(q));
                        if d2 > inner2 {
                            let r = p.inner + p.amplitude * n;
                            if d2 > r * r {
                                continue;
                            }
                        }
                        n
                    };
                    let index = (c * m + b) * m + a;
                    let dist = d2.sqrt() * spec.frame.voxel_size;
                    accumulate(s, dist, n, &mut voxels[index], &mut emission, index, m3);
                }
            }
        }
    }
    let mv = Metavoxel {
        coord: bin.coord,
        particles: bin.particles.len(),
        voxels,
        light_top: vec![1.0; m * m],
    };
    (mv, emission)
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
