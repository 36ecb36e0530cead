//! Cone tracing from shading points: ambient occlusion, diffuse indirect light and a specular
//! cone ([`ConeTracer`]), with its options ([`TraceOptions`]).
//!
//! # Definitions (written once here; [`crate::cone`] defines aperture, steps and falloff)
//! - **Self-occlusion offset**: every cone's apex is the shading point moved along its unit
//!   normal by `normal_offset_voxels` level-0 voxel edges (default [`NORMAL_OFFSET_VOXELS`]), and
//!   its first sample is `start_voxels` further along the axis (default [`START_VOXELS`]). A
//!   point's own surface voxels lie within `√3/2` voxel of it and their trilinear support
//!   reaches one voxel further, so with these defaults a cone along the normal starts clear of
//!   them; wide cones still see them through the coarse levels (the known VCT self-occlusion).
//! - **Diffuse cones**: `n` directions cosine-distributed over the hemisphere around the normal
//!   (a Fibonacci spiral in the unit disk, lifted: `(r cos φ, r sin φ, √(1 − r²))`,
//!   `r = √((i + ½)/n)`, `φ = i·golden angle`; `n = 1` is the normal). Because the directions
//!   already follow `cos θ`, every cone has weight `1/n`: [`ConeTracer::diffuse`] returns
//!   `E/π ≈ (1/n)·Σ L_i`, and the outgoing diffuse indirect radiance is `albedo · E/π`, the same
//!   estimator as the cosine-weighted path tracer of voxlod-cpu.
//! - **Ambient occlusion**: `AO = 1 − (1/n)·Σ O_i` over the diffuse directions, `O_i` the
//!   falloff-weighted occlusion of cone `i` (radius `ao_radius`, world units) — 1 unoccluded,
//!   0 fully occluded; the ray-traced reference is `1 − mean f(t_hit)` over cosine-distributed
//!   rays.
//! - **Specular cone**: along the mirror direction of the view vector, full aperture
//!   `30° − 29°·glossiness` (glossiness in \[0, 1\], clamped: 0 → 30°, 1 → 1°).
//!
//! Shading inputs are per pixel, so they are not errors: a non-finite position or normal gives
//! the unoccluded answer (AO 1, no radiance), and glossiness is clamped.

use glam::Vec3;
use voxlod_octree::Octree;

use crate::cone::{Cone, ConeResult, March, trace};
use crate::error::check;
use crate::medium::ConeMedium;
use crate::{Error, Result};

/// Default self-occlusion offset along the normal, in voxels (module docs).
pub const NORMAL_OFFSET_VOXELS: f32 = 1.0;
/// Default distance of a cone's first sample from its apex, in voxels (module docs).
pub const START_VOXELS: f32 = 1.0;
/// Default full aperture of the diffuse cones (the paper's 30°).
pub const DIFFUSE_APERTURE_DEG: f32 = 30.0;
/// Specular aperture at glossiness 0 (full angle, degrees).
pub const SPECULAR_APERTURE_MAX_DEG: f32 = 30.0;
/// Specular aperture at glossiness 1 (full angle, degrees).
pub const SPECULAR_APERTURE_MIN_DEG: f32 = 1.0;

/// Options of a [`ConeTracer`]. Cost grows with `diffuse_cones` and `1/step_factor`, and with
/// narrower apertures (smaller steps, finer levels).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TraceOptions {
    /// Diffuse (and AO) cones per shading point, ≥ 1 (default 6).
    pub diffuse_cones: u32,
    /// Full aperture of the diffuse and AO cones in degrees, in \[0, 180) (default 30°).
    pub diffuse_aperture_deg: f32,
    /// Step as a fraction of the footprint diameter, in \[0.05, 4\] (default 0.5).
    pub step_factor: f32,
    /// Apex offset along the normal, voxels, ≥ 0 (default [`NORMAL_OFFSET_VOXELS`]).
    pub normal_offset_voxels: f32,
    /// First sample's distance from the apex, voxels, ≥ 0 (default [`START_VOXELS`]).
    pub start_voxels: f32,
    /// AO radius `R` in world units, > 0 (the falloff `max(0, 1 − r/R)`, [`crate::cone::falloff`]).
    pub ao_radius: f32,
    /// Longest distance a diffuse or specular cone travels, world units (`f32::INFINITY`:
    /// until it leaves the octree).
    pub max_distance: f32,
    /// Accumulated opacity at which a cone stops, in (0, 1\] (default 0.99).
    pub opacity_cutoff: f32,
}

impl Default for TraceOptions {
    fn default() -> Self {
        Self {
            diffuse_cones: 6,
            diffuse_aperture_deg: DIFFUSE_APERTURE_DEG,
            step_factor: 0.5,
            normal_offset_voxels: NORMAL_OFFSET_VOXELS,
            start_voxels: START_VOXELS,
            ao_radius: 1.0,
            max_distance: f32::INFINITY,
            opacity_cutoff: 0.99,
        }
    }
}

impl TraceOptions {
    /// Checks every field against its documented range.
    pub fn validate(&self) -> Result<()> {
        if self.diffuse_cones == 0 {
            return Err(Error::InvalidParameter {
                name: "diffuse_cones",
                value: "0".into(),
                reason: "at least one cone",
            });
        }
        let a = self.diffuse_aperture_deg;
        check((0.0..180.0).contains(&a), "diffuse_aperture_deg", a, "a full angle in [0, 180)")?;
        let s = self.step_factor;
        check((0.05..=4.0).contains(&s), "step_factor", s, "in [0.05, 4]")?;
        let o = self.normal_offset_voxels;
        check(o.is_finite() && o >= 0.0, "normal_offset_voxels", o, "finite and >= 0")?;
        let o = self.start_voxels;
        check(o.is_finite() && o >= 0.0, "start_voxels", o, "finite and >= 0")?;
        let r = self.ao_radius;
        check(r.is_finite() && r > 0.0, "ao_radius", r, "finite and > 0")?;
        let m = self.max_distance;
        check(m > 0.0, "max_distance", m, "> 0 (infinity allowed)")?;
        let c = self.opacity_cutoff;
        check(c > 0.0 && c <= 1.0, "opacity_cutoff", c, "in (0, 1]")?;
        Ok(())
    }
}

/// The full specular aperture in radians for a glossiness (clamped to \[0, 1\]; NaN → 0).
pub fn specular_aperture(glossiness: f32) -> f32 {
    let g = if glossiness.is_nan() { 0.0 } else { glossiness.clamp(0.0, 1.0) };
    (SPECULAR_APERTURE_MAX_DEG - (SPECULAR_APERTURE_MAX_DEG - SPECULAR_APERTURE_MIN_DEG) * g)
        .to_radians()
}

/// The `n` cosine-distributed unit directions around +z of the diffuse cones (module docs).
pub fn hemisphere_directions(n: u32) -> Vec<Vec3> {
    if n <= 1 {
        return vec![Vec3::Z];
    }
    let golden = std::f32::consts::PI * (3.0 - 5f32.sqrt());
    (0..n)
        .map(|i| {
            let r = ((i as f32 + 0.5) / n as f32).sqrt();
            let phi = i as f32 * golden;
            Vec3::new(r * phi.cos(), r * phi.sin(), (1.0 - r * r).max(0.0).sqrt())
        })
        .collect()
}

/// An orthonormal basis `(t, b)` completing unit `n` (Duff et al. 2017, branchless).
pub fn basis(n: Vec3) -> (Vec3, Vec3) {
    let sign = 1f32.copysign(n.z);
    let a = -1.0 / (sign + n.z);
    let b = n.x * n.y * a;
    (
        Vec3::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x),
        Vec3::new(b, sign + n.y * n.y * a, -n.y),
    )
}

/// Traces cones from shading points through one octree (module docs for the definitions).
#[derive(Clone, Debug)]
pub struct ConeTracer<'a, M> {
    tree: &'a Octree<M>,
    options: TraceOptions,
    directions: Vec<Vec3>,
    voxel: f32,
}

impl<'a, M: ConeMedium> ConeTracer<'a, M> {
    /// A tracer over `tree` (a radiance octree from [`crate::inject()`], or any
    /// [`ConeMedium`] octree for AO). Errors on options outside their ranges.
    pub fn new(tree: &'a Octree<M>, options: TraceOptions) -> Result<Self> {
        options.validate()?;
        let voxel = tree.grid().voxel_size as f32;
        Ok(Self { tree, options, directions: hemisphere_directions(options.diffuse_cones), voxel })
    }

    /// The options.
    pub fn options(&self) -> &TraceOptions {
        &self.options
    }

    fn march(&self, ao: Option<(Vec3, f32)>, max_distance: f32) -> March {
        March {
            start_voxels: self.options.start_voxels,
            step_factor: self.options.step_factor,
            max_distance,
            opacity_cutoff: self.options.opacity_cutoff,
            ao,
        }
    }

    fn apex(&self, p: Vec3, n: Vec3) -> Vec3 {
        p + n * (self.options.normal_offset_voxels * self.voxel)
    }

    /// The diffuse cones' world directions around unit normal `n`.
    pub fn diffuse_directions(&self, n: Vec3) -> impl Iterator<Item = Vec3> + '_ {
        let (t, b) = basis(n);
        self.directions.iter().map(move |d| (t * d.x + b * d.y + n * d.z).normalize())
    }

    fn valid(p: Vec3, n: Vec3) -> Option<Vec3> {
        if !p.is_finite() || !n.is_finite() {
            return None;
        }
        n.try_normalize()
    }

    /// One cone along `dir` from shading point `p` with normal `n`, full `aperture` (radians),
    /// with the tracer's offsets and limits. With `ao` it is an AO cone: falloff accumulated,
    /// and the march ends at the AO radius (plus the normal offset), so its radiance covers
    /// only that far; [`ConeTracer::ao_and_diffuse`] gathers both over the full distance.
    pub fn cone(&self, p: Vec3, n: Vec3, dir: Vec3, aperture: f32, ao: bool) -> ConeResult {
        let Some(n) = Self::valid(p, n) else { return ConeResult::default() };
        let apex = self.apex(p, n);
        let (ao, max) = if ao {
            let r = self.options.ao_radius;
            (
                Some((p, r)),
                (r + self.options.normal_offset_voxels * self.voxel).min(self.options.max_distance),
            )
        } else {
            (None, self.options.max_distance)
        };
        trace(self.tree, &Cone { apex, dir, aperture }, &self.march(ao, max))
    }

    /// Ambient occlusion in \[0, 1\] at `p` with normal `n` (1: unoccluded; module docs).
    pub fn ambient_occlusion(&self, p: Vec3, n: Vec3) -> f32 {
        self.ao_and_diffuse(p, n, true, false).0
    }

    /// Diffuse incoming radiance `E/π` at `p` with normal `n` (module docs); multiply by the
    /// albedo for the outgoing diffuse indirect light.
    pub fn diffuse(&self, p: Vec3, n: Vec3) -> Vec3 {
        self.ao_and_diffuse(p, n, false, true).1
    }

    /// AO and `E/π` from the same diffuse cones, each computed if asked for (one march per
    /// cone serves both when both are, up to the AO radius only when only AO is), and the
    /// octree samples taken.
    pub fn ao_and_diffuse(&self, p: Vec3, n: Vec3, ao: bool, diffuse: bool) -> (f32, Vec3, u32) {
        let Some(n) = Self::valid(p, n) else { return (1.0, Vec3::ZERO, 0) };
        let aperture = self.options.diffuse_aperture_deg.to_radians();
        let apex = self.apex(p, n);
        let radius = self.options.ao_radius;
        let max = if diffuse {
            self.options.max_distance
        } else {
            (radius + self.options.normal_offset_voxels * self.voxel).min(self.options.max_distance)
        };
        let march = self.march(ao.then_some((p, radius)), max);
        let (mut occ, mut l, mut steps) = (0.0, Vec3::ZERO, 0);
        for dir in self.diffuse_directions(n) {
            let r = trace(self.tree, &Cone { apex, dir, aperture }, &march);
            occ += r.occlusion;
            l += r.radiance;
            steps += r.steps;
        }
        let inv = 1.0 / self.directions.len() as f32;
        ((1.0 - occ * inv).clamp(0.0, 1.0), l * inv, steps)
    }

    /// Radiance arriving along the specular cone at `p` (normal `n`, unit `to_viewer`), full
    /// aperture from `glossiness` ([`specular_aperture`]); multiply by the specular colour.
    pub fn specular(&self, p: Vec3, n: Vec3, to_viewer: Vec3, glossiness: f32) -> ConeResult {
        let Some(n) = Self::valid(p, n) else { return ConeResult::default() };
        let Some(v) = to_viewer.try_normalize() else { return ConeResult::default() };
        let r = (2.0 * n.dot(v) * n - v).normalize_or(n);
        self.cone(p, n, r, specular_aperture(glossiness), false)
    }
}
