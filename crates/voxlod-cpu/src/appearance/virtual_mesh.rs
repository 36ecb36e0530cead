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
//!   [`FaceSampling::Random`] samples as the authors' code does instead (up to `K` = 40 random
//!   points, each retried until its normal faces the viewer).
//!   A fixed-set face uses each of its stored normals with `n·v > 0`.
//! - Each accepted normal gives [`shade`]`(albedo = face colour, n, v, …)`; a face's value is the
//!   mean over its accepted normals; the voxel's is the projected-area-weighted mean over faces
//!   with at least one accepted normal (equal weights if all those areas are 0), so the ambient
//!   term is the area-weighted face colour times `ambient`, as in the authors' code.
//! - **Fallback** when no normal is accepted: the mean of [`shade`] over all stored normals,
//!   without the visibility filter (what the ground truth does with back faces); or, as the
//!   authors' code does, no radiance at all ([`ShadingFallback::Unshaded`]).
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
use crate::random::{rand_f32, rand_u32};
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

/// The authors' number of shading samples per visible distribution face (Brito, Poulin and
/// Teichrieb 2023, §4: "as many as 40 samples per visible face"; their sample program).
pub const AUTHORS_SAMPLES_PER_FACE: u32 = 40;

/// The authors' attempts per sample at a point whose normal faces the viewer (their
/// `getSampleVMesh` is called with `nbAttempts = 5`).
pub const AUTHORS_ATTEMPTS: u32 = 5;

/// How a distribution face of the virtual mesh is sampled for shading (Brito, Poulin and
/// Teichrieb 2023, §3.3 "Projected Area Sampling" and §4).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum FaceSampling {
    /// Ours: the `samples_per_face` fixed barycentric points of [`barycentric_point`]
    /// (stratified, no randomness, the same on every backend); samples whose normal faces away
    /// from the viewer are skipped.
    #[default]
    Stratified,
    /// The authors' (`VirtualMesh::shadeWithVirtualMesh` and `getSampleVMesh` of their
    /// `representations.h`): `samples_per_face` samples (40 in their program,
    /// [`AUTHORS_SAMPLES_PER_FACE`]), each drawing up to `attempts` ([`AUTHORS_ATTEMPTS`])
    /// uniform points of the projected face until one's interpolated normal faces the viewer;
    /// a sample whose attempts all fail is dropped. Their numbers `u₀, u₁` are clamped to
    /// `[0, 0.999]` and warped as their `samplingTriangle` does, and their ray–triangle
    /// intersection hands the barycentrics to the vertex normals rotated by one
    /// (`n = (1 − √u₀) N₀ + √u₀ u₁ N₁ + √u₀ (1 − u₁) N₂`, the same uniform distribution).
    /// The numbers are `rand_f32(key, sample, dimension)` of [`crate::random`] with
    /// `key` = [`record_key`] of the record and the dimensions drawn from `seed`: the same
    /// record seen from the same direction always gives the same value (what a per-voxel
    /// cache keeps), and another seed gives an independent draw.
    Random {
        /// Points tried per sample.
        attempts: u32,
        /// Seed of the random numbers.
        seed: u32,
    },
}

impl FaceSampling {
    /// The authors' sampling with `seed`: [`AUTHORS_ATTEMPTS`] attempts per sample.
    pub fn authors(seed: u32) -> Self {
        Self::Random { attempts: AUTHORS_ATTEMPTS, seed }
    }
}

/// What a virtual-mesh voxel shades with when no sampled or stored normal faces the viewer.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum ShadingFallback {
    /// Ours: the mean of [`shade`] over every stored normal, without the visibility filter
    /// (what the ground truth does with back faces seen through).
    #[default]
    AllStoredNormals,
    /// The authors': the voxel is left unshaded — `shadeWithVirtualMesh` returns black with
    /// `shaded = false` and a zero average colour (their ambient colour), so the voxel
    /// composites no radiance, only its opacity.
    Unshaded,
}

/// A 32-bit key of a record's bytes (FNV-1a over its 136 bytes, then one PCG3D round): the
/// random id of [`FaceSampling::Random`], a function of the record alone.
pub fn record_key(rec: &VirtualMeshRecord) -> u32 {
    let h = bytemuck::bytes_of(rec)
        .iter()
        .fold(0x811c_9dc5u32, |h, &b| (h ^ b as u32).wrapping_mul(0x0100_0193));
    rand_u32(h, 0, 0x7EC0)
}

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
/// `samples_per_face` fixed barycentric samples per distribution face (0 reads as 1), our
/// fallback and the optional specular side record: [`shade_record_with`] with
/// [`FaceSampling::Stratified`] and [`ShadingFallback::AllStoredNormals`].
pub fn shade_record(
    rec: &VirtualMeshRecord,
    specular: Option<&SpecularRecord>,
    to_viewer: Vec3,
    light: &LightSample,
    visibility: f32,
    ambient: Vec3,
    samples_per_face: u32,
) -> Vec3 {
    let p = VirtualMeshParams { samples_per_face, ..Default::default() };
    shade_record_with(rec, specular, to_viewer, light, visibility, ambient, &p)
}

/// Radiance of one virtual-mesh voxel toward `to_viewer` (module docs, shading rules) with the
/// shading choices of `p` ([`VirtualMeshParams::samples_per_face`],
/// [`VirtualMeshParams::sampling`], [`VirtualMeshParams::fallback`]).
pub fn shade_record_with(
    rec: &VirtualMeshRecord,
    specular: Option<&SpecularRecord>,
    to_viewer: Vec3,
    light: &LightSample,
    visibility: f32,
    ambient: Vec3,
    p: &VirtualMeshParams,
) -> Vec3 {
    let v = to_viewer.try_normalize().unwrap_or(Vec3::Z);
    let k = p.samples_per_face.max(1);
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
    // The random streams of the authors' sampling (module docs of `FaceSampling::Random`).
    let random = match p.sampling {
        FaceSampling::Stratified => None,
        FaceSampling::Random { attempts, seed } => {
            let dims = [rand_u32(seed, 0, 0xFACE), rand_u32(seed, 1, 0xFACE)];
            Some((record_key(rec), attempts.max(1), dims))
        }
    };
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
        match (rec.is_distribution(f), random) {
            (true, None) => {
                for i in 0..k {
                    let b = barycentric_point(i, k);
                    let n = (ns[0] * b.x + ns[1] * b.y + ns[2] * b.z).normalize_or_zero();
                    accept(n);
                }
            }
            (true, Some((key, attempts, dims))) => {
                for i in 0..k {
                    for a in 0..attempts {
                        let draw =
                            (f as u32).wrapping_mul(k).wrapping_add(i).wrapping_mul(attempts) + a;
                        let u0 = rand_f32(key, draw, dims[0]).clamp(0.0, 0.999);
                        let u1 = rand_f32(key, draw, dims[1]).clamp(0.0, 0.999);
                        let su = u0.sqrt();
                        let b = Vec3::new(1.0 - su, su * u1, su * (1.0 - u1));
                        let n = (ns[0] * b.x + ns[1] * b.y + ns[2] * b.z).normalize_or_zero();
                        if n.dot(v) > 0.0 {
                            accept(n);
                            break;
                        }
                    }
                }
            }
            (false, _) => ns.into_iter().filter(|n| *n != Vec3::ZERO).for_each(accept),
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
    if p.fallback == ShadingFallback::Unshaded {
        return Vec3::ZERO;
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
    /// How distribution faces are sampled when shading.
    pub sampling: FaceSampling,
    /// What a voxel shades with when no normal faces the viewer.
    pub fallback: ShadingFallback,
}

impl VirtualMeshGrid {
    /// The grid with the default parameters ([`VirtualMeshParams::default`]).
    pub fn new(grid: AppearanceGrid<VirtualMeshRecord>) -> Self {
        Self::with_params(grid, VirtualMeshParams::default())
    }

    /// The grid read with parameters `p`.
    pub fn with_params(grid: AppearanceGrid<VirtualMeshRecord>, p: VirtualMeshParams) -> Self {
        Self {
            grid,
            rule: p.rule,
            samples_per_face: p.samples_per_face,
            projected_area: p.projected_area,
            sampling: p.sampling,
            fallback: p.fallback,
        }
    }
}

/// Parameters of virtual-mesh records: the directional-opacity rule, the shading samples per
/// distribution face, how they are drawn and the shading fallback.
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
    /// How distribution faces are sampled when shading (ours: fixed points).
    pub sampling: FaceSampling,
    /// What a voxel shades with when no normal faces the viewer (ours: every stored normal).
    pub fallback: ShadingFallback,
}

impl Default for VirtualMeshParams {
    fn default() -> Self {
        Self {
            rule: DirectionalRule::default(),
            samples_per_face: DEFAULT_SAMPLES_PER_FACE,
            projected_area: false,
            sampling: FaceSampling::default(),
            fallback: ShadingFallback::default(),
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
        shade_record_with(self, specular, to_viewer, light, visibility, ambient, &p)
    }
}

impl VirtualMeshGrid {
    /// The parameters its records are read with.
    pub fn params(&self) -> VirtualMeshParams {
        VirtualMeshParams {
            rule: self.rule,
            samples_per_face: self.samples_per_face,
            projected_area: self.projected_area,
            sampling: self.sampling,
            fallback: self.fallback,
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
mod tests;
