//! Binning (McNabb 2015, §5.5.1, Listing 5.1) and culling (§5.5).
//!
//! A particle goes into the bin of every metavoxel its **bounding sphere** (the outer radius)
//! overlaps: the metavoxels of its bounding box are enumerated and each is kept when the
//! squared distance from the sphere's centre to the metavoxel's box is at most the squared
//! radius, in voxel coordinates (one predicate, [`sphere_overlaps_box`], shared with the
//! brute-force check). Output: the occupied metavoxels sorted by [`VolumeSpec::key`], each with
//! its particle indices ascending. The (metavoxel, particle) pairs are produced in parallel,
//! collected in particle order and sorted, so the result does not depend on the thread count.
//!
//! Culling keeps a metavoxel when the box spanning its column from it down to the volume's
//! bottom meets the view frustum (conservatively: a box is dropped only when all 8 of its
//! corners are outside one of the frustum's 5 planes — 4 sides and the eye plane). A metavoxel
//! in view is kept; so is one above something in view, since its shadow falls there (the
//! light's view of §5.5).

use glam::Vec3;
use rayon::prelude::*;
use voxlod_scene::camera::CameraFrame;
use voxlod_scene::particles::DisplacedSphere;

use super::VolumeSpec;

/// A particle in voxel coordinates.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Prepared {
    /// Centre in voxel coordinates.
    pub center: Vec3,
    /// Inner radius in voxels.
    pub inner: f32,
    /// Displacement amplitude in voxels.
    pub amplitude: f32,
    /// Outer radius in voxels, `inner + amplitude`.
    pub outer: f32,
}

/// One occupied metavoxel and the particles that cover it.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Bin {
    /// Metavoxel coordinate.
    pub coord: [u32; 3],
    /// Indices of the particles, ascending.
    pub particles: Vec<u32>,
}

/// The output of [`bin`].
#[derive(Clone, Debug, PartialEq)]
pub struct Binning {
    /// The particles in voxel coordinates (same order as the input).
    pub prepared: Vec<Prepared>,
    /// Occupied metavoxels, sorted by key.
    pub bins: Vec<Bin>,
}

/// Converts particles to voxel coordinates.
pub fn prepare(spheres: &[DisplacedSphere], spec: &VolumeSpec) -> Vec<Prepared> {
    let f = &spec.frame;
    spheres
        .par_iter()
        .map(|s| {
            let inner = s.inner / f.voxel_size;
            let amplitude = s.amplitude / f.voxel_size;
            Prepared { center: f.to_voxel(s.center), inner, amplitude, outer: inner + amplitude }
        })
        .collect()
}

/// Whether the sphere `(center, radius)` overlaps the box `[lo, hi]` (closed), by the squared
/// distance from the centre to the box.
#[inline]
pub fn sphere_overlaps_box(center: Vec3, radius: f32, lo: Vec3, hi: Vec3) -> bool {
    let d = center - center.clamp(lo, hi);
    d.length_squared() <= radius * radius
}

/// The box of metavoxel `c` in voxel coordinates.
#[inline]
fn metavoxel_box(c: [u32; 3], m: u32) -> (Vec3, Vec3) {
    let lo = Vec3::new(c[0] as f32, c[1] as f32, c[2] as f32) * m as f32;
    (lo, lo + Vec3::splat(m as f32))
}

/// Metavoxel index range `[a, b]` on one axis covered by `[x − r, x + r]`, or `None` when it
/// misses `[0, K)`.
fn axis_range(x: f32, r: f32, m: u32, k: u32) -> Option<(u32, u32)> {
    let lo = ((x - r) / m as f32).floor();
    let hi = ((x + r) / m as f32).floor();
    if !(hi >= 0.0 && lo < k as f32) {
        return None;
    }
    Some((lo.max(0.0) as u32, hi.min((k - 1) as f32) as u32))
}

/// Bins `spheres` into the metavoxels of `spec` (Listing 5.1).
pub fn bin(spheres: &[DisplacedSphere], spec: &VolumeSpec) -> Binning {
    let prepared = prepare(spheres, spec);
    let (m, k) = (spec.metavoxel_edge, spec.metavoxels);
    let mut pairs: Vec<(u32, u32)> = prepared
        .par_iter()
        .enumerate()
        .flat_map_iter(|(i, p)| {
            let mut out = Vec::new();
            let ranges = (
                axis_range(p.center.x, p.outer, m, k),
                axis_range(p.center.y, p.outer, m, k),
                axis_range(p.center.z, p.outer, m, k),
            );
            if let (Some(x), Some(y), Some(z)) = ranges {
                for cz in z.0..=z.1 {
                    for cy in y.0..=y.1 {
                        for cx in x.0..=x.1 {
                            let c = [cx, cy, cz];
                            let (lo, hi) = metavoxel_box(c, m);
                            if sphere_overlaps_box(p.center, p.outer, lo, hi) {
                                out.push((spec.key(c), i as u32));
                            }
                        }
                    }
                }
            }
            out
        })
        .collect();
    pairs.par_sort_unstable();
    Binning { bins: group(spec, &pairs), prepared }
}

fn group(spec: &VolumeSpec, pairs: &[(u32, u32)]) -> Vec<Bin> {
    let k = spec.metavoxels;
    pairs
        .chunk_by(|a, b| a.0 == b.0)
        .map(|run| {
            let key = run[0].0;
            let coord = [key / (k * k), key / k % k, key % k];
            Bin { coord, particles: run.iter().map(|p| p.1).collect() }
        })
        .collect()
}

/// The brute-force binning: every particle against every metavoxel, with the same predicate.
/// The reference [`bin`] is checked against.
pub fn bin_brute_force(spheres: &[DisplacedSphere], spec: &VolumeSpec) -> Vec<Bin> {
    let prepared = prepare(spheres, spec);
    let (m, k) = (spec.metavoxel_edge, spec.metavoxels);
    let mut pairs = Vec::new();
    for cx in 0..k {
        for cy in 0..k {
            for cz in 0..k {
                let c = [cx, cy, cz];
                let (lo, hi) = metavoxel_box(c, m);
                for (i, p) in prepared.iter().enumerate() {
                    if sphere_overlaps_box(p.center, p.outer, lo, hi) {
                        pairs.push((spec.key(c), i as u32));
                    }
                }
            }
        }
    }
    pairs.sort_unstable();
    group(spec, &pairs)
}

/// The 5 inward plane normals of the frustum of `frame` (4 sides, then the eye plane), all
/// through the eye.
pub fn frustum_planes(frame: &CameraFrame) -> [Vec3; 5] {
    let f = frame.forward;
    let corners = [
        f - frame.right + frame.up,
        f + frame.right + frame.up,
        f + frame.right - frame.up,
        f - frame.right - frame.up,
    ];
    let mut planes = [f; 5];
    for i in 0..4 {
        let n = corners[i].cross(corners[(i + 1) % 4]);
        planes[i] = if n.dot(f) < 0.0 { -n } else { n };
    }
    planes
}

/// Keeps the bins whose column, from them down to the volume's bottom, meets the frustum.
pub fn cull(bins: Vec<Bin>, spec: &VolumeSpec, frame: &CameraFrame) -> Vec<Bin> {
    let planes = frustum_planes(frame);
    let m = spec.metavoxel_edge as f32;
    let bottom = spec.voxels_per_axis() as f32;
    bins.into_iter()
        .filter(|b| {
            let lo = Vec3::new(b.coord[0] as f32, b.coord[1] as f32, b.coord[2] as f32) * m;
            let hi = Vec3::new(lo.x + m, lo.y + m, bottom);
            box_in_frustum(spec, &planes, frame.eye, lo, hi)
        })
        .collect()
}

/// Whether the voxel-space box `[lo, hi]` may meet the frustum (false only when all its
/// corners are outside one plane).
pub fn box_in_frustum(
    spec: &VolumeSpec,
    planes: &[Vec3; 5],
    eye: Vec3,
    lo: Vec3,
    hi: Vec3,
) -> bool {
    let corners: [Vec3; 8] = std::array::from_fn(|c| {
        let q = Vec3::new(
            if c & 1 == 0 { lo.x } else { hi.x },
            if c & 2 == 0 { lo.y } else { hi.y },
            if c & 4 == 0 { lo.z } else { hi.z },
        );
        spec.frame.to_world(q) - eye
    });
    planes.iter().all(|n| corners.iter().any(|c| c.dot(*n) >= 0.0))
}
