//! The virtual mesh of HPG 2023 §3.3 (design note §5): an octahedron in the SGGX eigenframe of a
//! voxel's sampled normals, whose eight faces each hold one colour and one to three normals (or
//! three extremal normals of a cone, interpolated barycentrically), sampled by projected area
//! from the view direction; with the 3×3×3 opacity subgrid of [`super::subgrid`] for its
//! directional opacity.
//!
//! # Build rules (each tested below)
//! - **Eigenframe**: the SGGX fit of [`super::sggx::estimate`] — eigenvectors of `E[nnᵀ]` by
//!   descending eigenvalue, canonical signs, right-handed. Vertex `2k` is `+T_k e_k`, vertex
//!   `2k+1` is `−T_k e_k`, with the SGGX semi-axes `T_k` ([`super::sggx::SggxFit::semi_axes`]).
//! - **Faces and octants**: the authors' face table [`FACES`]; face `f` covers the octant of
//!   the sign pattern of its three vertices ([`face_of`]).
//! - **Normal assignment**: a normal goes to the face of the octant of its eigen coordinates
//!   `(n·e0, n·e1, n·e2)`; coordinates with `|c| <` [`SNAP`] are snapped to 0 first and 0 counts
//!   as `+`, so exactly aligned normals land deterministically.
//! - **Distribution flag**: a greedy pass in sample order keeps the normals more than
//!   [`DISTINCT_ANGLE`] (5°) from every kept one (`acos` of the clamped dot product); a 4th kept
//!   normal makes the face a distribution, otherwise the ≤ 3 kept normals are its normals.
//! - **Cone** of a distribution face: axis = the *normalized* mean of the face's normals,
//!   `θmax = max acos(clamp(n·axis))`, floored at [`THETA_MIN`] (0.1 rad).
//! - **Extremal normals**: three normals at `θmax` from the axis, at azimuths 0°, 120°, 240° of
//!   the Hughes–Möller frame of the axis ([`hughes_moeller`], [`extremal_normals`]) — the
//!   authors' code on a normalized axis (the paper's data-driven placement is public nowhere).
//! - **Colour** of a face: the mean albedo of all normals assigned to it.
//! - **Encoding**: axes and normals snorm8×3 (renormalized at decode), semi-axes as
//!   [`SCALE_RANGE`] log bytes, colours sRGB8, all rounded; absent normal = `(0,0,0)`.
//!
//! # Shading rules
//! - A face is **visible** if any of its stored normals `n` has `n·v > 0` (`v` toward the
//!   viewer); its **weight** is its exact projected area `½|((B−A)×(C−A))·v|`.
//! - A distribution face is sampled at `K` fixed barycentric points ([`barycentric_point`]:
//!   the square-root warp of a `K`-point Hammersley set, default [`DEFAULT_SAMPLES_PER_FACE`]);
//!   the normal is `normalize(b0 N0 + b1 N1 + b2 N2)`, and samples with `n·v ≤ 0` are skipped.
//!   A fixed-set face uses each of its stored normals with `n·v > 0`.
//! - Each accepted normal gives [`shade`]`(albedo = face colour, n, v, …)`; a face's value is the
//!   mean over its accepted normals; the voxel's is the projected-area-weighted mean over faces
//!   with at least one accepted normal (equal weights if all those areas are 0), so the ambient
//!   term is the area-weighted face colour times `ambient`, as in the authors' code.
//! - **Fallback** when no normal is accepted: the mean of [`shade`] over all stored normals,
//!   without the visibility filter (what the ground truth does with back faces).
//! - **Opacity**: [`Opacity::Alpha`] of [`subgrid::directional_opacity`] under the grid's
//!   [`DirectionalRule`].

use glam::{DVec3, UVec3, Vec2, Vec3};
use voxlod_format::GridSpec;
use voxlod_format::records::quant::{encode_dir, encode_srgb8};
use voxlod_format::records::{SCALE_RANGE, SpecularRecord, VirtualMeshRecord};
use voxlod_scene::{LightSample, MaterialSample};

use super::RecordAppearance;
use super::sggx::{self, radical_inverse2};
use super::subgrid::{self, DirectionalRule};
use super::voxel_samples::VoxelSamples;
use super::{Appearance, AppearanceGrid, Opacity};
use crate::shading::shade;

/// Vertex indices of the eight octahedron faces (vertex `2k` = `+e_k`, `2k+1` = `−e_k`), the
/// authors' table: face `f` covers the eigen-octant of its vertices' signs.
pub const FACES: [[usize; 3]; 8] =
    [[0, 2, 4], [0, 4, 3], [0, 3, 5], [0, 5, 2], [1, 2, 5], [1, 5, 3], [1, 3, 4], [1, 4, 2]];

/// Face of each octant, indexed by `(x < 0)·4 + (y < 0)·2 + (z < 0)`.
const OCTANT_FACE: [usize; 8] = [0, 3, 1, 2, 7, 4, 6, 5];

/// Eigen coordinates below this magnitude are snapped to 0 before the octant test.
pub const SNAP: f64 = 1e-6;

/// Two normals closer than this angle (5°, in radians) are one for the distribution test.
pub const DISTINCT_ANGLE: f64 = 5.0 * std::f64::consts::PI / 180.0;

/// Floor of a cone's half-angle `θmax`, radians.
pub const THETA_MIN: f64 = 0.1;

/// Default number of barycentric samples per distribution face.
pub const DEFAULT_SAMPLES_PER_FACE: u32 = 16;

/// The face whose octant holds eigen coordinates `c` (snapped at [`SNAP`], 0 counts as `+`).
pub fn face_of(c: DVec3) -> usize {
    let neg = |x: f64| (x.abs() >= SNAP && x < 0.0) as usize;
    OCTANT_FACE[neg(c.x) << 2 | neg(c.y) << 1 | neg(c.z)]
}

/// The Hughes–Möller perpendicular of unit `d` (the authors' `hughes_moeller`):
/// `normalize(−d_y, d_x, 0)` if `|d_x| > |d_z|`, else `normalize(0, −d_z, d_y)`.
pub fn hughes_moeller(d: DVec3) -> DVec3 {
    if d.x.abs() > d.z.abs() {
        DVec3::new(-d.y, d.x, 0.0).normalize()
    } else {
        DVec3::new(0.0, -d.z, d.y).normalize()
    }
}

/// The three extremal normals of a cone with unit `axis` and half-angle `theta`: with
/// `b2 =` [`hughes_moeller`]`(axis)` and `b1 = b2 × axis`, normal `i` is
/// `sin θ (cos(2πi/3) b1 + sin(2πi/3) b2) + cos θ axis` (`axis` is renormalized first).
pub fn extremal_normals(axis: DVec3, theta: f64) -> [DVec3; 3] {
    let axis = axis.normalize();
    let b2 = hughes_moeller(axis);
    let b1 = b2.cross(axis);
    let (st, ct) = theta.sin_cos();
    std::array::from_fn(|i| {
        let (s, c) = (std::f64::consts::TAU * i as f64 / 3.0).sin_cos();
        ((b1 * c + b2 * s) * st + axis * ct).normalize()
    })
}

/// The dot products whose angle `acos(clamp(x, −1, 1))` exceeds [`DISTINCT_ANGLE`] are
/// exactly those below this bound: the smallest `x` whose `acos` does not, found once by
/// bisection over the ordered bit patterns of `[0, 1]` (`acos` is monotone there), so the
/// pass compares dot products instead of calling `acos` per pair, with the same outcome.
static DISTINCT_DOT: std::sync::LazyLock<f64> = std::sync::LazyLock::new(|| {
    let (mut lo, mut hi) = (0.0f64.to_bits(), 1.0f64.to_bits());
    // Invariant: acos(lo) > DISTINCT_ANGLE ≥ acos(hi).
    while hi - lo > 1 {
        let mid = lo + (hi - lo) / 2;
        if f64::from_bits(mid).acos() > DISTINCT_ANGLE { lo = mid } else { hi = mid }
    }
    f64::from_bits(hi)
});

/// The greedy 5° pass of a face (module docs): the kept normals (at most 4) in sample order,
/// and whether a 4th was reached (a distribution).
pub fn distinct_normals(normals: &[DVec3]) -> (Vec<DVec3>, bool) {
    let mut kept: Vec<DVec3> = Vec::with_capacity(4);
    for &n in normals {
        if kept.iter().all(|k| k.dot(n) < *DISTINCT_DOT) {
            kept.push(n);
            if kept.len() == 4 {
                return (kept, true);
            }
        }
    }
    (kept, false)
}

/// The cone of a face's normals: the normalized mean as axis and `θmax` floored at
/// [`THETA_MIN`]. `None` for an empty set.
pub fn cone(normals: &[DVec3]) -> Option<(DVec3, f64)> {
    let axis = normals.iter().copied().sum::<DVec3>().try_normalize()?;
    // `acos` decreases: the largest angle is that of the smallest dot product.
    let lowest = normals.iter().map(|n| n.dot(axis)).fold(1.0, f64::min);
    let theta = lowest.clamp(-1.0, 1.0).acos().max(THETA_MIN);
    Some((axis, theta))
}

/// The face of each normal in eigenframe `frame`: the octant of its eigen coordinates
/// (module docs).
pub fn assign_faces<'a>(
    normals: impl IntoIterator<Item = DVec3> + 'a,
    frame: &'a [DVec3; 3],
) -> impl Iterator<Item = usize> + 'a {
    normals.into_iter().map(move |n| face_in(frame, n))
}

/// The face of unit normal `n` in eigenframe `frame` (see [`assign_faces`]).
#[inline]
fn face_in(frame: &[DVec3; 3], n: DVec3) -> usize {
    face_of(DVec3::new(n.dot(frame[0]), n.dot(frame[1]), n.dot(frame[2])))
}

/// Fits a voxel's [`VirtualMeshRecord`] (module docs) from its case-(a) hits, with the 27
/// sub-cell opacities of [`subgrid::build`]. `None` when no line hit a front face inside the
/// voxel.
pub fn fit(samples: &VoxelSamples) -> Option<VirtualMeshRecord> {
    let sggx = sggx::estimate_samples(samples)?;
    Some(fit_with(samples, &sggx, subgrid::build(samples)))
}

/// The record of a voxel from its SGGX fit ([`sggx::estimate_samples`]) and its sub-cell
/// opacities, made already (a precompute that also builds the \[VJK21\] record shares them).
pub fn fit_with(
    samples: &VoxelSamples,
    sggx: &sggx::SggxFit,
    opacity: [u8; 27],
) -> VirtualMeshRecord {
    let e = sggx.frame;
    // The case-(a) hits as (face, normal, albedo), grouped by face in sample order (a stable
    // sort): one allocation per voxel instead of one per face.
    let mut hits: Vec<(usize, DVec3, Vec3)> = samples
        .surfaces()
        .map(|s| (s.normal.as_dvec3(), s.albedo))
        .filter(|(n, _)| n.is_finite() && n.length_squared() > 0.0)
        .map(|(n, a)| {
            let n = n.normalize();
            (face_in(&e, n), n, a)
        })
        .collect();
    hits.sort_by_key(|h| h.0);
    let normals: Vec<DVec3> = hits.iter().map(|h| h.1).collect();
    let mut rec = VirtualMeshRecord {
        axes: e.map(|a| encode_dir(a.as_vec3())),
        scales: sggx.semi_axes().map(|x| SCALE_RANGE.encode(x as f32)),
        opacity,
        ..Default::default()
    };
    let mut start = 0;
    for group in hits.chunk_by(|a, b| a.0 == b.0) {
        let (f, normals) = (group[0].0, &normals[start..start + group.len()]);
        start += group.len();
        let albedo = group.iter().map(|h| h.2).sum::<Vec3>() / group.len() as f32;
        rec.colors[f] = encode_srgb8(albedo);
        let (kept, distribution) = distinct_normals(normals);
        let stored: Vec<DVec3> = if distribution {
            rec.distribution |= 1 << f;
            // Normals of one closed octant never sum to zero; the fallback is unreachable.
            let (axis, theta) = cone(normals).unwrap_or((normals[0], THETA_MIN));
            extremal_normals(axis, theta).to_vec()
        } else {
            kept
        };
        for (slot, n) in stored.iter().enumerate() {
            rec.normals[f][slot] = encode_dir(n.as_vec3());
        }
    }
    rec
}

/// Barycentric sample `i` of `count` on a triangle: the square-root warp of the Hammersley
/// point `((i + ½)/count, φ₂(i))`, i.e. `(1 − √u, √u·v, √u·(1 − v))` — uniform over the
/// triangle, stratified, and the same on every face and backend.
#[inline]
pub fn barycentric_point(i: u32, count: u32) -> Vec3 {
    let u = Vec2::new((i as f32 + 0.5) / count as f32, radical_inverse2(i));
    let su = u.x.sqrt();
    Vec3::new(1.0 - su, su * u.y, su * (1.0 - u.y))
}

/// Radiance of one virtual-mesh voxel toward `to_viewer` (module docs, shading rules) with
/// `samples_per_face` barycentric samples per distribution face (0 reads as 1) and the
/// optional specular side record.
pub fn shade_record(
    rec: &VirtualMeshRecord,
    specular: Option<&SpecularRecord>,
    to_viewer: Vec3,
    light: &LightSample,
    visibility: f32,
    ambient: Vec3,
    samples_per_face: u32,
) -> Vec3 {
    let v = to_viewer.try_normalize().unwrap_or(Vec3::Z);
    let k = samples_per_face.max(1);
    let material = |f: usize| MaterialSample {
        albedo: rec.face_color(f),
        alpha: 1.0,
        specular: Vec3::splat(specular.map_or(0.0, |s| s.level())),
        shininess: specular.map_or(1.0, |s| s.exponent()),
    };
    let vertices: [Vec3; 6] = std::array::from_fn(|i| {
        let a = rec.axis(i / 2) * rec.scale(i / 2);
        if i % 2 == 0 { a } else { -a }
    });
    let (mut weighted, mut area_sum) = (Vec3::ZERO, 0.0f32);
    let (mut unweighted, mut faces) = (Vec3::ZERO, 0u32);
    for (f, tri) in FACES.iter().enumerate() {
        let ns = [0, 1, 2].map(|i| rec.normal(f, i));
        if !ns.iter().any(|n| n.dot(v) > 0.0) {
            continue;
        }
        let m = material(f);
        let (mut sum, mut count) = (Vec3::ZERO, 0u32);
        let mut accept = |n: Vec3| {
            if n.dot(v) > 0.0 {
                sum += shade(&m, n, v, light, visibility, ambient);
                count += 1;
            }
        };
        if rec.is_distribution(f) {
            for i in 0..k {
                let b = barycentric_point(i, k);
                let n = (ns[0] * b.x + ns[1] * b.y + ns[2] * b.z).normalize_or_zero();
                accept(n);
            }
        } else {
            ns.into_iter().filter(|n| *n != Vec3::ZERO).for_each(accept);
        }
        if count == 0 {
            continue;
        }
        let face_value = sum / count as f32;
        let [a, b, c] = tri.map(|i| vertices[i]);
        let area = 0.5 * (b - a).cross(c - a).dot(v).abs();
        weighted += face_value * area;
        area_sum += area;
        unweighted += face_value;
        faces += 1;
    }
    if faces > 0 {
        return if area_sum > 0.0 { weighted / area_sum } else { unweighted / faces as f32 };
    }
    // Fallback: every stored normal, no visibility filter.
    let (mut sum, mut count) = (Vec3::ZERO, 0u32);
    for f in 0..8 {
        let m = material(f);
        for i in 0..3 {
            let n = rec.normal(f, i);
            if n != Vec3::ZERO {
                sum += shade(&m, n, v, light, visibility, ambient);
                count += 1;
            }
        }
    }
    if count > 0 { sum / count as f32 } else { Vec3::ZERO }
}

/// How much of its largest projected area the record's normal distribution shows along unit
/// `dir`: `σ(ω)/max σ_k` of the SGGX ellipsoid the record stores (`σ(ω)² = Σ σ_k² (e_k·ω)²`,
/// with `σ_k = π T_j T_l` from the semi-axes `T`), in `[0, 1]`. A flat patch seen edge-on
/// shows the SGGX floor (0.1), face-on 1; normals spread over every direction show 1 from
/// every direction.
pub fn projected_area_ratio(rec: &VirtualMeshRecord, dir: Vec3) -> f32 {
    let t = [rec.scale(0), rec.scale(1), rec.scale(2)];
    let sigma: [f32; 3] =
        std::array::from_fn(|k| std::f32::consts::PI * t[(k + 1) % 3] * t[(k + 2) % 3]);
    let top = sigma[0].max(sigma[1]).max(sigma[2]);
    if top.is_nan() || top <= 0.0 || !dir.is_finite() {
        return 1.0;
    }
    let area2: f32 = (0..3).map(|k| (sigma[k] * rec.axis(k).dot(dir)).powi(2)).sum();
    (area2.sqrt() / top).min(1.0)
}

/// A grid of virtual-mesh records with the choice of directional-opacity rule (the report has a
/// row per rule) and the shading sample count.
#[derive(Clone, Debug)]
pub struct VirtualMeshGrid {
    /// The records (and specular side records).
    pub grid: AppearanceGrid<VirtualMeshRecord>,
    /// How the opacity subgrid is read along a direction.
    pub rule: DirectionalRule,
    /// Barycentric samples per distribution face when shading (0 reads as 1).
    pub samples_per_face: u32,
    /// Whether the subgrid's opacity is scaled by [`projected_area_ratio`] (see
    /// [`VirtualMeshParams::projected_area`]).
    pub projected_area: bool,
}

impl VirtualMeshGrid {
    /// The grid with the default rule ([`DirectionalRule::Lines`]),
    /// [`DEFAULT_SAMPLES_PER_FACE`] and no projected-area scaling.
    pub fn new(grid: AppearanceGrid<VirtualMeshRecord>) -> Self {
        let p = VirtualMeshParams::default();
        Self { grid, rule: p.rule, samples_per_face: p.samples_per_face, projected_area: false }
    }
}

/// Parameters of virtual-mesh records: the directional-opacity rule and the barycentric
/// shading samples per distribution face.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct VirtualMeshParams {
    /// How the opacity subgrid is read along a direction.
    pub rule: DirectionalRule,
    /// Barycentric samples per distribution face (0 reads as 1).
    pub samples_per_face: u32,
    /// Scale the subgrid's directional opacity by the record's [`projected_area_ratio`]: a
    /// flat patch seen edge-on becomes nearly transparent (the subgrid alone keeps the third
    /// of the footprint its layer of sub-cells covers, design note §6). Off by default: a
    /// voxel's opacity composes with its neighbours' as if uncorrelated, so a flat surface seen
    /// at a grazing angle (a ground, leaves), which the ray crosses over many weakly opaque
    /// voxels, lets light through that the surface stops; the filtered-appearance study of
    /// voxlod-studies measures both.
    pub projected_area: bool,
}

impl Default for VirtualMeshParams {
    fn default() -> Self {
        Self {
            rule: DirectionalRule::default(),
            samples_per_face: DEFAULT_SAMPLES_PER_FACE,
            projected_area: false,
        }
    }
}

impl RecordAppearance for VirtualMeshRecord {
    type Params = VirtualMeshParams;

    fn opacity(&self, p: VirtualMeshParams, dir: Vec3) -> Opacity {
        let alpha = subgrid::directional_opacity(&self.opacity, dir, p.rule);
        let ratio = if p.projected_area { projected_area_ratio(self, dir) } else { 1.0 };
        Opacity::Alpha(alpha * ratio)
    }

    fn radiance(
        &self,
        p: VirtualMeshParams,
        specular: Option<&SpecularRecord>,
        to_viewer: Vec3,
        light: &LightSample,
        visibility: f32,
        ambient: Vec3,
    ) -> Vec3 {
        shade_record(self, specular, to_viewer, light, visibility, ambient, p.samples_per_face)
    }
}

impl VirtualMeshGrid {
    /// The parameters its records are read with.
    pub fn params(&self) -> VirtualMeshParams {
        VirtualMeshParams {
            rule: self.rule,
            samples_per_face: self.samples_per_face,
            projected_area: self.projected_area,
        }
    }
}

impl Appearance for VirtualMeshGrid {
    fn grid(&self) -> &GridSpec {
        &self.grid.grid
    }

    fn len(&self) -> usize {
        self.grid.records.len()
    }

    fn index_of(&self, c: UVec3) -> Option<usize> {
        self.grid.records.index_of(c)
    }

    fn opacity(&self, index: usize, dir: Vec3) -> Opacity {
        self.grid.records.values()[index].opacity(self.params(), dir)
    }

    fn radiance(
        &self,
        index: usize,
        to_viewer: Vec3,
        light: &LightSample,
        visibility: f32,
        ambient: Vec3,
    ) -> Vec3 {
        let spec = self.grid.specular.as_ref().and_then(|s| s.get(index));
        let p = self.params();
        self.grid.records.values()[index].radiance(p, spec, to_viewer, light, visibility, ambient)
    }

    fn needs_visibility(&self, index: usize, to_viewer: Vec3, light: &LightSample) -> bool {
        self.grid.records.values()[index].needs_visibility(self.params(), to_viewer, light)
    }
}

#[cfg(test)]
mod tests {
    use std::f32::consts::PI;

    use super::*;
    use crate::appearance::nonexp::test_lines::plane;
    use crate::appearance::voxel_samples::{RaySample, SurfaceSample};
    use crate::random::rand_f32;
    use proptest::prelude::*;
    use voxlod_format::BrickMap;

    /// Samples whose case-(a) hits have the given normals and albedos.
    fn hits(normals: &[Vec3], albedo: impl Fn(usize) -> Vec3) -> VoxelSamples {
        let rays = normals
            .iter()
            .enumerate()
            .map(|(i, &n)| RaySample {
                dir: -n,
                entry: Vec3::splat(0.5) + n * 0.5,
                chord: 1.0,
                occluded: true,
                surface: Some(SurfaceSample {
                    point: Vec3::splat(0.5),
                    normal: n,
                    albedo: albedo(i),
                    specular: 0.0,
                    shininess: 1.0,
                }),
            })
            .collect();
        VoxelSamples { rays }
    }

    /// Normals of a sphere cap of half-angle `theta` around `axis` (a curved surface).
    fn cap(axis: Vec3, theta: f32, n: u32) -> Vec<Vec3> {
        let a = axis.normalize();
        let b = hughes_moeller(a.as_dvec3()).as_vec3();
        let c = b.cross(a);
        (0..n)
            .map(|i| {
                let t = theta * rand_f32(77, i, 0).sqrt();
                let p = std::f32::consts::TAU * rand_f32(77, i, 1);
                (a * t.cos() + (b * p.cos() + c * p.sin()) * t.sin()).normalize()
            })
            .collect()
    }

    fn light() -> LightSample {
        LightSample {
            to_light: Vec3::new(0.3, 0.5, 0.8).normalize(),
            distance: f32::INFINITY,
            irradiance: Vec3::splat(PI),
        }
    }

    fn present_faces(rec: &VirtualMeshRecord) -> Vec<usize> {
        (0..8).filter(|&f| rec.normals[f].iter().any(|n| *n != [0; 3])).collect()
    }

    #[test]
    fn face_table_covers_the_octants_of_its_vertices() {
        let axes = [DVec3::X, DVec3::NEG_X, DVec3::Y, DVec3::NEG_Y, DVec3::Z, DVec3::NEG_Z];
        let mut seen = [false; 8];
        for (f, tri) in FACES.iter().enumerate() {
            let centroid: DVec3 = tri.iter().map(|&i| axes[i]).sum();
            assert_eq!(face_of(centroid), f, "face {f} {tri:?}");
            // One vertex per axis.
            let mut k: Vec<usize> = tri.iter().map(|i| i / 2).collect();
            k.sort();
            assert_eq!(k, [0, 1, 2]);
            seen[f] = true;
        }
        assert!(seen.iter().all(|s| *s));
        // Snapping: tiny negative coordinates count as +.
        assert_eq!(face_of(DVec3::new(1.0, -1e-9, -1e-7)), 0);
        assert_eq!(face_of(DVec3::new(1.0, -1e-5, 0.0)), 1);
    }

    #[test]
    fn all_equal_normals_give_one_fixed_face_with_finite_vertices() {
        for n in [Vec3::Z, Vec3::new(0.0, 0.6, 0.8), Vec3::new(-1.0, 2.0, 0.5).normalize()] {
            let rec = fit(&hits(&[n; 30], |_| Vec3::splat(0.4))).unwrap();
            assert_eq!(present_faces(&rec), [0], "{n}");
            assert_eq!(rec.distribution, 0);
            assert!((rec.normal(0, 0) - n).length() < 0.01);
            assert_eq!((rec.normals[0][1], rec.normals[0][2]), ([0; 3], [0; 3]));
            for k in 0..3 {
                assert!(rec.axis(k).is_finite() && (rec.axis(k).length() - 1.0).abs() < 1e-5);
                assert!(rec.scale(k).is_finite() && rec.scale(k) > 0.0);
            }
            // The flat axis keeps its size: 0.1/√π = 0.0564 within a log step, not 0.039.
            assert!((rec.scale(0) / 0.0564 - 1.0).abs() < 0.02, "{}", rec.scale(0));
            assert!((rec.scale(1) / 0.5642 - 1.0).abs() < 0.02, "{}", rec.scale(1));
        }
    }

    #[test]
    fn a_triangle_on_a_voxel_face_gives_a_finite_record() {
        let s = plane(3, 150, Vec3::Z, Vec3::new(0.3, 0.6, 0.0), Vec3::splat(0.7), false);
        assert!(s.surfaces().count() > 10);
        let rec = fit(&s).unwrap();
        assert_eq!(present_faces(&rec).len(), 1);
        for v in [Vec3::Z, Vec3::NEG_Z, Vec3::X, Vec3::new(1.0, 1.0, 0.0)] {
            let r = shade_record(&rec, None, v, &light(), 1.0, Vec3::splat(0.05), 16);
            assert!(r.is_finite() && r.min_element() >= 0.0, "{v}: {r}");
        }
    }

    #[test]
    fn octant_assignment_is_stable_under_sign_flips() {
        let normals: Vec<DVec3> = (0..200)
            .map(|i| {
                let v = Vec3::new(
                    rand_f32(1, i, 0) - 0.5,
                    rand_f32(1, i, 1) - 0.5,
                    rand_f32(1, i, 2) - 0.2,
                );
                v.normalize().as_dvec3()
            })
            .collect();
        let fit = sggx::estimate(&normals.iter().map(|n| n.as_vec3()).collect::<Vec<_>>());
        let frame = fit.unwrap().frame;
        let base: Vec<usize> = assign_faces(normals.iter().copied(), &frame).collect();
        // Flipping axis k relabels faces by flipping sign k of their octant.
        let sign = |f: usize| {
            let mut c = DVec3::ZERO;
            for i in FACES[f] {
                c[i / 2] = if i % 2 == 0 { 1.0 } else { -1.0 };
            }
            c
        };
        for k in 0..3 {
            let mut flipped = frame;
            flipped[k] = -flipped[k];
            let got: Vec<usize> = assign_faces(normals.iter().copied(), &flipped).collect();
            for (a, b) in base.iter().zip(&got) {
                let mut s = sign(*a);
                s[k] = -s[k];
                assert_eq!(face_of(s), *b, "axis {k}");
            }
        }
        // The canonical frame does not depend on the normals' own signs: E is even.
        let neg: Vec<Vec3> = normals.iter().map(|n| -n.as_vec3()).collect();
        assert_eq!(sggx::estimate(&neg).unwrap().frame, frame);
    }

    #[test]
    fn extremal_normals_lie_on_the_cone_120_degrees_apart() {
        for (i, theta) in [0.1, 0.5, 1.2, 1.5].into_iter().enumerate() {
            let axis = Vec3::new(
                rand_f32(i as u32, 0, 0) - 0.5,
                rand_f32(i as u32, 0, 1) - 0.5,
                rand_f32(i as u32, 0, 2) - 0.5,
            )
            .as_dvec3()
            .normalize();
            let ns = extremal_normals(axis, theta);
            let proj: Vec<DVec3> =
                ns.iter().map(|n| (*n - axis * n.dot(axis)).normalize()).collect();
            for j in 0..3 {
                assert!((ns[j].length() - 1.0).abs() < 1e-12);
                assert!((ns[j].dot(axis).acos() - theta).abs() < 1e-9, "θ {theta}");
                let a = proj[j].dot(proj[(j + 1) % 3]).clamp(-1.0, 1.0).acos();
                assert!((a - std::f64::consts::TAU / 3.0).abs() < 1e-9, "{a}");
            }
            // Azimuth 0 is b1 = b2 × axis.
            let b1 = hughes_moeller(axis).cross(axis);
            assert!((proj[0] - b1).length() < 1e-9);
        }
        // Both Hughes–Möller branches give a unit perpendicular.
        for d in [DVec3::X, DVec3::Y, DVec3::Z, DVec3::new(0.6, 0.0, -0.8)] {
            let p = hughes_moeller(d);
            assert!(p.dot(d).abs() < 1e-15 && (p.length() - 1.0).abs() < 1e-15);
        }
    }

    #[test]
    fn distribution_rule_is_greedy_five_degrees_with_clamped_acos() {
        let rot = |deg: f64| DVec3::new(deg.to_radians().sin(), 0.0, deg.to_radians().cos());
        // Three inputs, the second a duplicate of the first: two kept, not a distribution (the
        // reference code's dead branch would keep input 2 twice).
        let (kept, d) = distinct_normals(&[rot(0.0), rot(1.0), rot(20.0)]);
        assert_eq!((kept, d), (vec![rot(0.0), rot(20.0)], false));
        // Identical normals whose dot product rounds above 1 count once (no NaN).
        let mut above_one = 0;
        for i in 0..200 {
            let n = DVec3::new(i as f64 + 1.0, 3.0, 7.0).normalize();
            above_one += (n.dot(n) > 1.0) as u32;
            assert_eq!(distinct_normals(&[n; 5]), (vec![n], false));
        }
        assert!(above_one > 0, "no candidate exercised dot > 1");
        // The threshold.
        assert_eq!(distinct_normals(&[rot(0.0), rot(4.9)]).0.len(), 1);
        assert_eq!(distinct_normals(&[rot(0.0), rot(5.1)]).0.len(), 2);
        // Four distinct normals make a distribution.
        let four = [rot(0.0), rot(6.0), rot(12.0), rot(18.0), rot(24.0)];
        let (kept, d) = distinct_normals(&four);
        assert!(d && kept.len() == 4);
    }

    /// The dot-product bound decides exactly as `acos` against 5° does: at the bound and its
    /// neighbours, and over a million dot products near it and across [−1.1, 1.1].
    #[test]
    fn distinct_dot_bound_agrees_with_acos() {
        let by_acos = |x: f64| x.clamp(-1.0, 1.0).acos() > DISTINCT_ANGLE;
        let b = *DISTINCT_DOT;
        assert!(!by_acos(b) && by_acos(f64::from_bits(b.to_bits() - 1)));
        for i in 0..1_000_000u64 {
            let near = f64::from_bits(b.to_bits() - 500_000 + i);
            let wide = -1.1 + 2.2 * i as f64 / 1e6;
            for x in [near, wide] {
                assert_eq!(x < b, by_acos(x), "{x}");
            }
        }
    }

    #[test]
    fn cone_axis_is_normalized_and_theta_is_floored() {
        // Normals on a 30° circle: θmax is 30°, not the 36° of an unnormalized mean.
        let ring: Vec<DVec3> = (0..12)
            .map(|i| {
                let p = std::f64::consts::TAU * i as f64 / 12.0;
                let t = 30f64.to_radians();
                DVec3::new(t.sin() * p.cos(), t.sin() * p.sin(), t.cos())
            })
            .collect();
        let (axis, theta) = cone(&ring).unwrap();
        assert!((axis - DVec3::Z).length() < 1e-12);
        assert!((theta - 30f64.to_radians()).abs() < 1e-9, "{}", theta.to_degrees());
        let (_, theta) = cone(&[DVec3::X, DVec3::X]).unwrap();
        assert_eq!(theta, THETA_MIN);
        assert!(cone(&[]).is_none());
    }

    #[test]
    fn curved_surface_gives_distribution_faces_with_face_colours() {
        // A cap of normals around a tilted axis, coloured by the sign of the x component.
        let ns = cap(Vec3::new(0.2, 0.1, 1.0), 0.8, 150);
        let colour = |n: Vec3| if n.x > 0.2 { Vec3::new(0.8, 0.1, 0.1) } else { Vec3::splat(0.3) };
        let s = hits(&ns, |i| colour(ns[i]));
        let rec = fit(&s).unwrap();
        assert!(rec.distribution != 0, "a curved surface is a distribution somewhere");
        let frame = sggx::estimate(&ns).unwrap().frame;
        let faces: Vec<usize> = assign_faces(ns.iter().map(|n| n.as_dvec3()), &frame).collect();
        for f in 0..8 {
            let members: Vec<usize> = (0..ns.len()).filter(|&i| faces[i] == f).collect();
            if members.is_empty() {
                assert_eq!(rec.normals[f], [[0; 3]; 3]);
                continue;
            }
            let mean = members.iter().map(|&i| colour(ns[i])).sum::<Vec3>() / members.len() as f32;
            assert!((rec.face_color(f) - mean).abs().max_element() < 0.01, "face {f}");
        }
        // Determinism: the same samples give the same bytes, also with shared fits.
        assert_eq!(fit(&s).unwrap(), rec);
        let shared = sggx::estimate_samples(&s).unwrap();
        assert_eq!(fit_with(&s, &shared, subgrid::build(&s)), rec);
    }

    #[test]
    fn weights_are_exact_projected_areas() {
        // A regular octahedron (identity frame, equal semi-axes) with two fixed-set faces:
        // face 0 (+++) white with normal (1,1,1)/√3, face 7 (−++) black with normal (−1,1,1)/√3.
        let mut rec = VirtualMeshRecord {
            axes: [[127, 0, 0], [0, 127, 0], [0, 0, 127]],
            scales: [SCALE_RANGE.encode(0.5); 3],
            ..Default::default()
        };
        rec.colors[0] = [255; 3];
        rec.normals[0][0] = encode_dir(Vec3::ONE.normalize());
        rec.normals[7][0] = encode_dir(Vec3::new(-1.0, 1.0, 1.0).normalize());
        let l = LightSample { to_light: Vec3::Y, distance: 1.0, irradiance: Vec3::splat(PI) };
        let v = Vec3::new(0.3, 0.4, 1.0).normalize();
        let r = shade_record(&rec, None, v, &l, 1.0, Vec3::ZERO, 16);
        // Face areas ∝ |n_f·v| for a regular octahedron; white shade = n0·l.
        let (a0, a7) = (Vec3::ONE.dot(v).abs(), Vec3::new(-1.0, 1.0, 1.0).dot(v).abs());
        let expected = a0 / (a0 + a7) * rec.normal(0, 0).dot(Vec3::Y);
        assert!((r.x - expected).abs() < 1e-5, "{r} vs {expected}");
        // Seen from below only the fallback applies: mean over both stored normals.
        let r = shade_record(&rec, None, Vec3::NEG_Y, &l, 1.0, Vec3::ZERO, 16);
        let expected = 0.5 * rec.normal(0, 0).dot(Vec3::Y);
        assert!((r.x - expected).abs() < 1e-5, "fallback {r} vs {expected}");
    }

    #[test]
    fn sixteen_samples_converge_to_256() {
        let ns = cap(Vec3::new(-0.3, 0.2, 1.0), 1.0, 150);
        let rec = fit(&hits(&ns, |_| Vec3::splat(0.8))).unwrap();
        let mut worst = 0.0f32;
        for i in 0..40 {
            let v = Vec3::new(rand_f32(9, i, 0) - 0.5, rand_f32(9, i, 1) - 0.5, rand_f32(9, i, 2))
                .normalize();
            let a = shade_record(&rec, None, v, &light(), 1.0, Vec3::splat(0.05), 16);
            let b = shade_record(&rec, None, v, &light(), 1.0, Vec3::splat(0.05), 256);
            worst = worst.max((a - b).abs().max_element() / b.max_element().max(0.05));
        }
        assert!(worst < 0.03, "relative difference 16 vs 256 samples: {worst}");
    }

    #[test]
    fn axis_aligned_and_face_perpendicular_views_are_finite() {
        let curved = fit(&hits(&cap(Vec3::Z, 1.2, 150), |_| Vec3::ONE)).unwrap();
        let flat = fit(&hits(&[Vec3::X; 10], |_| Vec3::ONE)).unwrap();
        for rec in [curved, flat] {
            let mut views = vec![Vec3::X, Vec3::NEG_X, Vec3::Y, Vec3::NEG_Y, Vec3::Z, Vec3::NEG_Z];
            for k in 0..3 {
                views.push(rec.axis(k));
            }
            let v: [Vec3; 6] = std::array::from_fn(|i| {
                let a = rec.axis(i / 2) * rec.scale(i / 2);
                if i % 2 == 0 { a } else { -a }
            });
            for tri in FACES {
                let n = (v[tri[1]] - v[tri[0]]).cross(v[tri[2]] - v[tri[0]]).normalize();
                views.push(n); // perpendicular to the face
                views.push((v[tri[1]] - v[tri[0]]).normalize()); // in the face's plane
            }
            for view in views {
                let r = shade_record(&rec, None, view, &light(), 1.0, Vec3::splat(0.1), 16);
                assert!(r.is_finite() && r.min_element() >= 0.0, "{view}: {r}");
            }
        }
    }

    #[test]
    fn grid_wrapper_selects_the_opacity_rule() {
        let grid = GridSpec::new(DVec3::ZERO, 1.0, UVec3::ONE).unwrap();
        let mut rec = fit(&hits(&[Vec3::Z; 4], |_| Vec3::ONE)).unwrap();
        // A thin plane: the middle z-layer opaque.
        rec.opacity = std::array::from_fn(|c| if c / 9 == 1 { 255 } else { 0 });
        let records = BrickMap::from_voxels(UVec3::ONE, [(UVec3::ZERO, rec)]).unwrap();
        let mut g = VirtualMeshGrid::new(AppearanceGrid { grid, records, specular: None });
        assert_eq!(g.len(), 1);
        assert_eq!(g.index_of(UVec3::ZERO), Some(0));
        let alpha = |g: &VirtualMeshGrid, d: Vec3| match g.opacity(0, d) {
            Opacity::Alpha(a) => a,
            other => panic!("{other:?}"),
        };
        let face_on = alpha(&g, Vec3::Z);
        let lines = alpha(&g, Vec3::X);
        g.rule = DirectionalRule::Circles;
        let circles = alpha(&g, Vec3::X);
        assert!(face_on >= 0.99, "{face_on}");
        assert_eq!(
            lines,
            subgrid::directional_opacity(&rec.opacity, Vec3::X, DirectionalRule::Lines)
        );
        assert_eq!(
            circles,
            subgrid::directional_opacity(&rec.opacity, Vec3::X, DirectionalRule::Circles)
        );
        assert_ne!(lines, circles);
        let r = g.radiance(0, Vec3::Z, &light(), 1.0, Vec3::ZERO);
        assert!(r.is_finite() && r.x > 0.0);
        // The specular side record reaches shade().
        g.grid.specular = Some(vec![SpecularRecord::new(1.0, 32.0)]);
        let l = LightSample { to_light: Vec3::Z, distance: 1.0, irradiance: Vec3::splat(PI) };
        let spec = g.radiance(0, Vec3::Z, &l, 1.0, Vec3::ZERO);
        assert!(spec.x > r.x, "{spec} vs {r}");
    }

    proptest! {
        #[test]
        fn shading_is_bounded(
            x in -1f32..1.0, y in -1f32..1.0, z in -1f32..1.0,
            lx in -1f32..1.0, ly in -1f32..1.0, theta in 0.05f32..1.5, ambient in 0f32..0.3,
        ) {
            let v = Vec3::new(x, y, z);
            let l = Vec3::new(lx, ly, 0.3);
            prop_assume!(v.length() > 1e-3);
            let rec = fit(&hits(&cap(Vec3::new(0.1, 0.9, 0.2), theta, 60), |i| {
                Vec3::new(0.9, 0.5, (i % 3) as f32 * 0.3)
            })).unwrap();
            let light = LightSample { to_light: l.normalize(), distance: 1.0, irradiance: Vec3::splat(2.0) };
            let r = shade_record(&rec, None, v, &light, 1.0, Vec3::splat(ambient), 16);
            prop_assert!(r.is_finite() && r.min_element() >= 0.0, "{}", r);
            prop_assert!(r.max_element() <= 0.9 * (2.0 / PI + ambient) + 1e-4, "{}", r);
        }
    }
}
