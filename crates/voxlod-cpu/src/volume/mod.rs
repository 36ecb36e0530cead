//! Sparse procedural volumes with metavoxels: the CPU reference of McNabb's (2015, "Sparse
//! Procedural Volume Rendering", GPU Pro), for displaced-sphere particles
//! ([`voxlod_scene::particles`]).
//!
//! The volume is a cube of `K³` *metavoxels* of `M³` voxels each, **oriented to the light**
//! (§5.3): its third axis `w` points away from the one directional light, so a voxel's light
//! depends only on the voxel above it in its column ([`LightSpace`]). Per frame:
//!
//! 1. [`binning`] (Listing 5.1): each particle's bounding sphere (outer radius) into the bins of
//!    the metavoxels it covers; exact, deterministic per-metavoxel lists in particle order.
//! 2. Culling (§5.5): only binned metavoxels that the eye sees (their column from them down to
//!    the volume's bottom meets the view frustum: they are in view, or they shadow something in
//!    view) are kept. Nothing is allocated for the others: memory follows the kept metavoxels.
//! 3. [`fill`] (§5.5.2): density the sum, colour the max over the particles of the bin, with
//!    the inner/outer radius early accept/reject.
//! 4. [`propagate`] (Listing 5.2): light down each voxel column through the metavoxels, top to
//!    bottom, starting at 0 below where the mesh blocks the light (the scene's shadow on the
//!    volume); [`Volume::transmittance_to_light`] gives the volume's shadow on the scene.
//! 5. [`march`] (Listing 5.3 and §5.5.5): eye rays through the metavoxels in the chapter's
//!    sort order, over blending above the perpendicular and under blending below it, stopping
//!    at the mesh depth; a premultiplied RGBA image to [`composite`] over the mesh render.
//!
//! Attenuation is selectable ([`Attenuation`]): the chapter's `1/(1 + τ)`, Beer–Lambert
//! `e^(−τ)`, and an exact reference. All results are deterministic (no dependence on the thread
//! count) and finite for any valid input, density 0 to 10⁶ included.

pub mod binning;
pub mod fill;
pub mod march;
pub mod propagate;
#[cfg(test)]
mod tests;

use std::time::{Duration, Instant};

use glam::{Vec3, Vec4};
use rayon::prelude::*;
use voxlod_scene::camera::CameraFrame;
use voxlod_scene::particles::{DisplacedSphere, DisplacementMap};

use crate::raycast::Bvh;
use crate::{Error, Result};

pub use binning::{Bin, Binning};
pub use march::{MarchOptions, composite};

/// Largest `K` (metavoxels per axis): the metavoxel index table holds `K³` `u32`s.
pub const MAX_METAVOXELS_PER_AXIS: u32 = 128;
/// Largest `M` (voxels per metavoxel edge).
pub const MAX_METAVOXEL_EDGE: u32 = 128;
/// Default `M`, the chapter's 32.
pub const DEFAULT_METAVOXEL_EDGE: u32 = 32;

/// How a voxel of optical depth `τ = σ · length` attenuates light, in light propagation and in
/// the eye march alike.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Attenuation {
    /// The chapter's `1/(1 + τ)` (Listings 5.2 and 5.3): cheap, and too transparent for dense
    /// voxels (it decays like `1/τ`, not exponentially).
    Chapter,
    /// Beer–Lambert `e^(−τ)`, one sample per step.
    BeerLambert,
    /// The reference: Beer–Lambert integrated exactly over the piecewise-constant voxel field —
    /// the eye ray walks every voxel it crosses with its exact segment length (the limit of an
    /// infinitely fine step) and integrates the in-scattered light in closed form; the light a
    /// voxel receives is the exact mean over its depth of the exponentially decaying light.
    Exact,
}

impl Attenuation {
    /// Transmittance of optical depth `tau ≥ 0` (1 for `tau = 0`, in (0, 1], never NaN).
    #[inline]
    pub fn transmittance(self, tau: f32) -> f32 {
        match self {
            Attenuation::Chapter => 1.0 / (1.0 + tau),
            Attenuation::BeerLambert | Attenuation::Exact => (-tau).exp(),
        }
    }

    /// Short name for tables.
    pub fn name(self) -> &'static str {
        match self {
            Attenuation::Chapter => "1/(1+d)",
            Attenuation::BeerLambert => "exp(-d)",
            Attenuation::Exact => "reference",
        }
    }
}

/// The volume's frame, oriented to the light: origin (the corner of voxel `(0, 0, 0)`), an
/// orthonormal right-handed basis `u, v, w` with `w` pointing *away* from the light (down the
/// columns), and the voxel edge. Voxel `(i, j, k)` covers `origin + ([i, i+1)·u + [j, j+1)·v +
/// [k, k+1)·w) · voxel_size`; `k = 0` is the top (nearest the light).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LightSpace {
    /// World position of the volume's corner.
    pub origin: Vec3,
    /// First horizontal axis (unit).
    pub u: Vec3,
    /// Second horizontal axis (unit).
    pub v: Vec3,
    /// Unit direction of propagation, `−to_light`.
    pub w: Vec3,
    /// Voxel edge in world units.
    pub voxel_size: f32,
}

impl LightSpace {
    /// The basis for unit `to_light` (`w = −to_light`; `u` from the world axis least aligned
    /// with `w`), with the given origin and voxel size.
    pub fn new(to_light: Vec3, origin: Vec3, voxel_size: f32) -> Self {
        let w = -to_light;
        let helper = if w.y.abs() < 0.9 { Vec3::Y } else { Vec3::X };
        let u = helper.cross(w).normalize();
        let v = w.cross(u);
        Self { origin, u, v, w, voxel_size }
    }

    /// World point → voxel coordinates.
    #[inline]
    pub fn to_voxel(&self, p: Vec3) -> Vec3 {
        let d = p - self.origin;
        Vec3::new(d.dot(self.u), d.dot(self.v), d.dot(self.w)) / self.voxel_size
    }

    /// World direction → voxel coordinates (so that `t` stays the world ray parameter).
    #[inline]
    pub fn dir_to_voxel(&self, d: Vec3) -> Vec3 {
        Vec3::new(d.dot(self.u), d.dot(self.v), d.dot(self.w)) / self.voxel_size
    }

    /// Voxel coordinates → world point.
    #[inline]
    pub fn to_world(&self, q: Vec3) -> Vec3 {
        self.origin + (self.u * q.x + self.v * q.y + self.w * q.z) * self.voxel_size
    }

    /// Voxel-space offset → world direction (not normalized, scaled by the voxel size).
    #[inline]
    pub fn offset_to_world(&self, q: Vec3) -> Vec3 {
        (self.u * q.x + self.v * q.y + self.w * q.z) * self.voxel_size
    }
}

/// The shape of a volume: its light-oriented frame, `K` metavoxels per axis and `M` voxels per
/// metavoxel edge.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct VolumeSpec {
    /// The frame.
    pub frame: LightSpace,
    /// `K`, metavoxels per axis, in `1..=MAX_METAVOXELS_PER_AXIS`.
    pub metavoxels: u32,
    /// `M`, voxels per metavoxel edge, in `1..=MAX_METAVOXEL_EDGE`.
    pub metavoxel_edge: u32,
}

impl VolumeSpec {
    /// The cube of `k³` metavoxels of `m³` voxels oriented to `to_light` that holds the world
    /// box `[lo, hi]` (its light-space bounding box, centred, the largest extent fitting
    /// `k · m` voxels with a 0.1 % margin). Errors on non-finite or inverted bounds, a zero or
    /// non-finite light direction, `k` or `m` out of range.
    pub fn fit(lo: Vec3, hi: Vec3, to_light: Vec3, k: u32, m: u32) -> Result<Self> {
        let bad = |name: &'static str, value: String, reason: &str| {
            Err(Error::InvalidParameter { name, value, reason: reason.into() })
        };
        if !(1..=MAX_METAVOXELS_PER_AXIS).contains(&k) {
            return bad("metavoxels per axis", k.to_string(), "must be in 1..=128");
        }
        if !(1..=MAX_METAVOXEL_EDGE).contains(&m) {
            return bad("metavoxel edge", m.to_string(), "must be in 1..=128");
        }
        if !(lo.is_finite() && hi.is_finite()) || lo.cmpgt(hi).any() {
            return bad("volume bounds", format!("{lo}..{hi}"), "must be finite with lo ≤ hi");
        }
        let Some(l) = to_light.is_finite().then(|| to_light.try_normalize()).flatten() else {
            return bad("light direction", to_light.to_string(), "must be finite and non-zero");
        };
        let basis = LightSpace::new(l, Vec3::ZERO, 1.0);
        let (mut a, mut b) = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
        for c in 0..8 {
            let p = Vec3::new(
                if c & 1 == 0 { lo.x } else { hi.x },
                if c & 2 == 0 { lo.y } else { hi.y },
                if c & 4 == 0 { lo.z } else { hi.z },
            );
            let q = basis.to_voxel(p);
            a = a.min(q);
            b = b.max(q);
        }
        let extent = (b - a).max_element().max(f32::MIN_POSITIVE.sqrt()) * 1.001;
        let voxel_size = extent / (k * m) as f32;
        if !(voxel_size.is_finite() && voxel_size > 0.0) {
            return bad("volume bounds", format!("{lo}..{hi}"), "extent too large or too small");
        }
        let corner = (a + b) * 0.5 - Vec3::splat(extent * 0.5);
        let origin = basis.offset_to_world(corner);
        Ok(Self { frame: LightSpace::new(l, origin, voxel_size), metavoxels: k, metavoxel_edge: m })
    }

    /// Voxels per axis, `K · M`.
    pub fn voxels_per_axis(&self) -> u32 {
        self.metavoxels * self.metavoxel_edge
    }

    /// Bytes a dense volume of the same resolution would take with this crate's voxel record
    /// (16 bytes: radiance RGB + extinction).
    pub fn dense_bytes(&self) -> u64 {
        (self.voxels_per_axis() as u64).pow(3) * std::mem::size_of::<Vec4>() as u64
    }

    /// Linear index of metavoxel `c`: column-major, `(i·K + j)·K + k`, so the metavoxels of one
    /// column are consecutive and top to bottom.
    #[inline]
    pub fn key(&self, c: [u32; 3]) -> u32 {
        let k = self.metavoxels;
        (c[0] * k + c[1]) * k + c[2]
    }
}

/// How [`build`] lights and culls.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BuildSettings {
    /// Attenuation model of the propagation (and of the march of the built volume).
    pub attenuation: Attenuation,
    /// Irradiance of the directional light (linear RGB); a lit voxel's radiance is
    /// `albedo · (irradiance / π · light + ambient) + emission`.
    pub irradiance: Vec3,
    /// Unshadowed ambient irradiance term (zero for none).
    pub ambient: Vec3,
    /// Upper bound on the voxel storage, in bytes: a build that would need more is an
    /// [`Error::OutOfMemory`] before anything is allocated.
    pub max_bytes: u64,
}

impl Default for BuildSettings {
    fn default() -> Self {
        Self {
            attenuation: Attenuation::BeerLambert,
            irradiance: Vec3::splat(3.0),
            ambient: Vec3::splat(0.15),
            max_bytes: 4 << 30,
        }
    }
}

/// Wall-clock time of each build stage.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct StageTimes {
    /// Evaluating and binning the particles.
    pub binning: Duration,
    /// Culling against the view.
    pub culling: Duration,
    /// Filling the kept metavoxels.
    pub fill: Duration,
    /// Light propagation (scene shadow rays included).
    pub propagation: Duration,
}

/// Counts of a build.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct BuildStats {
    /// Particles binned.
    pub particles: usize,
    /// (metavoxel, particle) pairs in the bins.
    pub bin_entries: usize,
    /// Metavoxels holding at least one particle.
    pub occupied: usize,
    /// Metavoxels kept after culling (filled and lit).
    pub kept: usize,
}

/// One filled and lit metavoxel.
#[derive(Clone, Debug, PartialEq)]
pub struct Metavoxel {
    /// Metavoxel coordinate `(i, j, k)`.
    pub coord: [u32; 3],
    /// Particles binned into it.
    pub particles: usize,
    /// `M³` voxels, index `(c·M + b)·M + a` for local voxel `(a, b, c)`: RGB the radiance
    /// toward the eye (lit albedo plus emission), A the extinction per unit length.
    pub voxels: Vec<Vec4>,
    /// `M²` transmittances toward the light at the top of each voxel column (index `b·M + a`),
    /// the volume only (no scene shadow): what [`Volume::transmittance_to_light`] continues.
    pub light_top: Vec<f32>,
    /// The box of the voxels the fill wrote, local voxel coordinates `[lo, hi)` per axis
    /// (`[0; 3], [0; 3]` when none): every voxel outside it is zero, so propagation and the
    /// march skip it (empty-space skipping).
    pub occupied: [[u32; 3]; 2],
}

impl Metavoxel {
    /// Whether the fill wrote no voxel (it holds particles whose spheres miss every centre).
    #[inline]
    pub fn is_empty(&self) -> bool {
        self.occupied[0][0] >= self.occupied[1][0]
    }
}

/// A built volume: the kept metavoxels, filled and lit, column-major and top to bottom.
#[derive(Clone, Debug, PartialEq)]
pub struct Volume {
    /// The shape.
    pub spec: VolumeSpec,
    /// The attenuation model it was lit with and marches with.
    pub attenuation: Attenuation,
    /// Kept metavoxels, sorted by [`VolumeSpec::key`].
    pub metavoxels: Vec<Metavoxel>,
    /// `K³` entries: index into `metavoxels`, or `u32::MAX` for an empty or culled metavoxel.
    index: Vec<u32>,
    /// Counts.
    pub stats: BuildStats,
    /// Stage times.
    pub times: StageTimes,
}

impl Volume {
    /// The kept metavoxel at `c`, if any.
    #[inline]
    pub fn metavoxel(&self, c: [u32; 3]) -> Option<&Metavoxel> {
        let i = *self.index.get(self.spec.key(c) as usize)?;
        self.metavoxels.get(i as usize)
    }

    /// A volume from lit metavoxels built elsewhere (the GPU backend's read-back): sorted by
    /// key with their `K³` index rebuilt. Errors when a metavoxel is outside the spec, has the
    /// wrong number of voxels or light values, or the keys are not strictly increasing.
    pub fn from_parts(
        spec: VolumeSpec,
        attenuation: Attenuation,
        metavoxels: Vec<Metavoxel>,
        stats: BuildStats,
        times: StageTimes,
    ) -> Result<Self> {
        let (k, m) = (spec.metavoxels, spec.metavoxel_edge as usize);
        let mut index = vec![u32::MAX; (k as usize).pow(3)];
        let mut previous = None;
        for (i, mv) in metavoxels.iter().enumerate() {
            let ok = mv.coord.iter().all(|&c| c < k)
                && mv.voxels.len() == m * m * m
                && mv.light_top.len() == m * m
                && previous.is_none_or(|p| p < spec.key(mv.coord));
            if !ok {
                return Err(Error::InvalidParameter {
                    name: "metavoxel",
                    value: format!("{i}: {:?}", mv.coord),
                    reason: format!(
                        "must lie in the {k}³ metavoxels, hold {m}³ voxels and {m}² light values,                          keys strictly increasing"
                    ),
                });
            }
            previous = Some(spec.key(mv.coord));
            index[spec.key(mv.coord) as usize] = i as u32;
        }
        Ok(Self { spec, attenuation, metavoxels, index, stats, times })
    }

    /// Heap bytes of the volume: the kept metavoxels' voxels and light, plus the `K³` index.
    pub fn bytes(&self) -> u64 {
        let per: u64 = self
            .metavoxels
            .iter()
            .map(|m| {
                (m.voxels.capacity() * size_of::<Vec4>()
                    + m.light_top.capacity() * size_of::<f32>()
                    + size_of::<Metavoxel>()) as u64
            })
            .sum();
        per + (self.index.capacity() * size_of::<u32>()) as u64
    }
}

/// Checks `spheres` (finite, non-negative radii and density) and names the first bad one.
pub fn validate_spheres(spheres: &[DisplacedSphere]) -> Result<()> {
    for (i, s) in spheres.iter().enumerate() {
        let ok = s.center.is_finite()
            && s.inner.is_finite()
            && s.inner >= 0.0
            && s.amplitude.is_finite()
            && s.amplitude >= 0.0
            && s.outer().is_finite()
            && s.density.is_finite()
            && s.density >= 0.0
            && s.color.is_finite()
            && s.color_outer.is_finite()
            && s.rot_cos.is_finite()
            && s.rot_sin.is_finite();
        if !ok {
            return Err(Error::InvalidParameter {
                name: "particle",
                value: format!("{i}: {s:?}"),
                reason: "centre, radii, density and colours must be finite, radii and density ≥ 0"
                    .into(),
            });
        }
    }
    Ok(())
}

/// The checks [`build`] makes before any work: every particle ([`validate_spheres`]) and the
/// light terms of `settings` (finite, ≥ 0). Other backends of the build (voxlod-gpu) call it,
/// so bad input gets the same errors.
pub fn validate_build(spheres: &[DisplacedSphere], settings: &BuildSettings) -> Result<()> {
    validate_spheres(spheres)?;
    if !(settings.irradiance.is_finite()
        && settings.irradiance.min_element() >= 0.0
        && settings.ambient.is_finite()
        && settings.ambient.min_element() >= 0.0)
    {
        return Err(Error::InvalidParameter {
            name: "irradiance/ambient",
            value: format!("{} / {}", settings.irradiance, settings.ambient),
            reason: "must be finite and ≥ 0".into(),
        });
    }
    Ok(())
}

/// The memory check of [`build`] once culling has chosen `kept` metavoxels: each needs
/// `16·M³ + 4·M²` bytes; over `settings.max_bytes` is [`Error::OutOfMemory`] with the numbers.
/// Shared with voxlod-gpu's build (same estimate, same error).
pub fn check_budget(kept: usize, spec: &VolumeSpec, settings: &BuildSettings) -> Result<()> {
    let m = spec.metavoxel_edge as u64;
    let needed = kept as u64 * (m * m * m * 16 + m * m * 4);
    if needed > settings.max_bytes {
        let n = spec.voxels_per_axis();
        return Err(Error::OutOfMemory {
            dims: [n; 3],
            estimated_bytes: needed,
            limit_bytes: settings.max_bytes,
        });
    }
    Ok(())
}

/// Bins, culls, fills and lights `spheres` in `spec`. `view` (the camera frame of the image to
/// render) enables culling; without it every occupied metavoxel is kept. `blocker` (the mesh's
/// BVH, opaque) casts the scene's shadow on the volume.
pub fn build(
    spheres: &[DisplacedSphere],
    map: &DisplacementMap,
    spec: &VolumeSpec,
    settings: &BuildSettings,
    view: Option<&CameraFrame>,
    blocker: Option<&Bvh>,
) -> Result<Volume> {
    validate_build(spheres, settings)?;
    let mut times = StageTimes::default();
    let t = Instant::now();
    let binning = binning::bin(spheres, spec);
    times.binning = t.elapsed();
    let t = Instant::now();
    let occupied = binning.bins.len();
    let bin_entries = binning.bins.iter().map(|b| b.particles.len()).sum();
    let bins = match view {
        Some(frame) => binning::cull(binning.bins, spec, frame),
        None => binning.bins,
    };
    times.culling = t.elapsed();
    check_budget(bins.len(), spec, settings)?;
    let t = Instant::now();
    let prepared = &binning.prepared;
    let mut filled: Vec<(Metavoxel, Option<Vec<Vec3>>)> =
        bins.par_iter().map(|bin| fill::fill(spheres, prepared, map, spec, bin)).collect();
    times.fill = t.elapsed();
    let t = Instant::now();
    propagate::propagate(&mut filled, spec, settings, blocker);
    times.propagation = t.elapsed();
    let metavoxels: Vec<Metavoxel> = filled.into_iter().map(|(mv, _)| mv).collect();
    let k = spec.metavoxels as usize;
    let mut index = vec![u32::MAX; k * k * k];
    for (i, mv) in metavoxels.iter().enumerate() {
        index[spec.key(mv.coord) as usize] = i as u32;
    }
    let stats =
        BuildStats { particles: spheres.len(), bin_entries, occupied, kept: metavoxels.len() };
    Ok(Volume { spec: *spec, attenuation: settings.attenuation, metavoxels, index, stats, times })
}
