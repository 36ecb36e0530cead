//! One cone marched front to back through an octree: the definitions every tracer of this
//! crate shares.
//!
//! # Definitions (the one place they are written; the code below is their only implementation)
//! - **Aperture** is the cone's **full** apex angle θ (the angle between two opposite
//!   generatrices), in \[0°, 180°). At distance `t` from the apex the cone's **diameter** is
//!   `d(t) = 2·t·tan(θ/2)`. θ = 0 is a ray.
//! - **Footprint**: a sample at distance `t` reads the octree with diameter `max(d(t), 1)` voxels,
//!   i.e. at the fractional level [`voxlod_octree::Octree::level_for_diameter`] (level 0 for a
//!   ray, the root for a near-180° cone), quadrilinearly.
//! - **Step**: the next sample is `step_factor · max(d(t), 1 voxel)` further along the axis.
//! - **Opacity correction**: a node of level `l` is `2^l` voxels wide and its opacity is that of
//!   crossing it; a step of length `s` crosses `s / 2^l` of it, so the sample's opacity becomes
//!   `α' = 1 − (1 − α)^(s / 2^l)`, with `s` capped at the distance left to the cube's exit (a
//!   near-180° cone's first step is astronomically long, but the matter it crosses is not).
//! - **Front-to-back accumulation**: `w = (1 − A)·α'`, `L += w·radiance`, `A += w`, stopping when
//!   `A ≥ opacity_cutoff`, beyond `max_distance`, or when the axis leaves the octree's cube
//!   (`[−1, 2^depth + 1]³` voxels).
//! - **Occlusion with falloff** (ambient occlusion): `O += w·f(r)`, where `r` is the distance of
//!   the sample from the shading point and `f(r) = max(0, 1 − r/R)` for AO radius `R`
//!   ([`falloff`], the function the ray-traced reference in voxlod-cpu uses with the hit
//!   distance). `f` is 0 from `R` on, so the AO radius never ends a march: a march that gathers
//!   AO and radiance from the same cones runs to `max_distance` for the radiance, and an
//!   AO-only march is given `max_distance = R + normal offset`.

use glam::{DVec3, Vec3};
use voxlod_octree::Octree;

use crate::medium::ConeMedium;

/// The AO falloff `f(r) = max(0, 1 − r/R)`: how much an occluder at distance `r` from the
/// shading point occludes, for AO radius `R > 0` (1 at the point, 0 from `R` on). The ray-traced
/// reference applies it to the first hit's distance.
#[inline]
pub fn falloff(r: f32, radius: f32) -> f32 {
    (1.0 - r / radius).clamp(0.0, 1.0)
}

/// A cone in world space.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Cone {
    /// Apex (world position).
    pub apex: Vec3,
    /// Unit axis direction.
    pub dir: Vec3,
    /// Full apex angle in radians, in \[0, π) (module docs).
    pub aperture: f32,
}

/// Where and how far a [`Cone`] marches.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct March {
    /// Distance of the first sample from the apex, in voxels (level-0 voxel edges).
    pub start_voxels: f32,
    /// Step length as a fraction of the footprint diameter (module docs), > 0.
    pub step_factor: f32,
    /// Stop beyond this distance from the apex (world units; `f32::INFINITY` for none).
    pub max_distance: f32,
    /// Stop when the accumulated opacity reaches this, in (0, 1\].
    pub opacity_cutoff: f32,
    /// For AO: the shading point (the apex minus the normal offset) and the radius `R` of
    /// [`falloff`]; `None` accumulates no occlusion.
    pub ao: Option<(Vec3, f32)>,
}

/// What a cone gathered.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ConeResult {
    /// Radiance arriving at the apex along the cone (front-to-back composited).
    pub radiance: Vec3,
    /// Accumulated opacity `A` in \[0, 1\].
    pub opacity: f32,
    /// Falloff-weighted occlusion `O` in \[0, 1\] (zero unless [`March::ao`] is set).
    pub occlusion: f32,
    /// Octree samples taken (each a quadrilinear read).
    pub steps: u32,
}

/// Parameter interval `[t0, t1]` where `o + t·d` lies inside the box `[lo, hi]³` (empty if
/// `t0 > t1`).
pub(crate) fn slab(o: Vec3, d: Vec3, lo: f32, hi: f32) -> (f32, f32) {
    let inv = d.recip();
    let a = (Vec3::splat(lo) - o) * inv;
    let b = (Vec3::splat(hi) - o) * inv;
    // Axis-parallel rays: inv = ±inf and a, b = ±inf (or NaN when o is on the plane: treated
    // as inside by max/min ignoring NaN).
    let t0 = a.min(b).max_element();
    let t1 = a.max(b).min_element();
    (t0, t1)
}

/// What the march knows about one sample, handed to [`trace_shaded`]'s radiance function.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SampleInfo {
    /// Sample position in grid coordinates (level-0 voxels, [`voxlod_format::GridSpec::to_grid`]).
    pub pos: Vec3,
    /// Distance from the apex along the axis, voxels.
    pub t: f32,
    /// Footprint diameter read, voxels (≥ 1).
    pub diameter: f32,
    /// Fractional level sampled ([`voxlod_octree::Octree::level_for_diameter`] of `diameter`).
    pub level: f32,
}

/// Marches `cone` through `tree` (module docs). Non-finite apex or direction gathers nothing.
pub fn trace<M: ConeMedium>(tree: &Octree<M>, cone: &Cone, march: &March) -> ConeResult {
    march_cone(tree, cone, march, 0.0, |s: &M, _: &SampleInfo| s.radiance())
}

/// [`trace`], with the radiance of every sample that adds opacity given by `radiance(sample,
/// info)` instead of [`ConeMedium::radiance`] (e.g. shading a pre-filtered colour and normal
/// under a light, as [`crate::primary`] does). Same march, same accumulation.
pub fn trace_shaded<M: ConeMedium>(
    tree: &Octree<M>,
    cone: &Cone,
    march: &March,
    radiance: impl FnMut(&M, &SampleInfo) -> Vec3,
) -> ConeResult {
    march_cone(tree, cone, march, 0.0, radiance)
}

/// The march of [`trace`] with a diameter `d0` voxels at the apex: the footprint at distance
/// `t` is `max(d0 + 2·t·tan(θ/2), 1)` (a cone whose apex is `d0` wide, e.g. a shadow cone
/// leaving a sample that already covers a pixel's footprint).
pub(crate) fn march_cone<M: ConeMedium>(
    tree: &Octree<M>,
    cone: &Cone,
    march: &March,
    d0: f32,
    mut radiance: impl FnMut(&M, &SampleInfo) -> Vec3,
) -> ConeResult {
    let mut out = ConeResult::default();
    let grid = tree.grid();
    let voxel = grid.voxel_size as f32;
    if !(cone.apex.is_finite() && cone.dir.is_finite() && voxel > 0.0) {
        return out;
    }
    let dir = cone.dir.normalize_or_zero();
    if dir == Vec3::ZERO {
        return out;
    }
    let d0 = if d0.is_finite() { d0.max(0.0) } else { 0.0 };
    let origin = grid.to_grid(DVec3::from(cone.apex)).as_vec3();
    let res = (1u64 << tree.depth()) as f32;
    let (enter, exit) = slab(origin, dir, -1.0, res + 1.0);
    let max_t = (march.max_distance / voxel).min(exit);
    let two_tan = 2.0 * (0.5 * cone.aperture.clamp(0.0, std::f32::consts::PI)).tan().max(0.0);
    let mut t = march.start_voxels.max(0.0).max(enter);
    let (ao_point, ao_radius) = match march.ao {
        Some((p, r)) => (grid.to_grid(DVec3::from(p)).as_vec3(), r / voxel),
        None => (origin, 0.0),
    };
    let mut a = 0.0f32;
    while t <= max_t && a < march.opacity_cutoff {
        let d = (d0 + two_tan * t).max(1.0);
        let d = if d.is_finite() { d } else { f32::MAX };
        let p = origin + dir * t;
        let level = tree.level_for_diameter(d);
        let s = tree.sample_at_level(p, level);
        out.steps += 1;
        let step = march.step_factor * d;
        let alpha = s.opacity_toward(dir).clamp(0.0, 1.0);
        if alpha > 0.0 {
            let node = level.exp2();
            let crossed = step.min((exit - t).max(0.0));
            let corrected = 1.0 - (1.0 - alpha).powf(crossed / node);
            let w = (1.0 - a) * corrected.clamp(0.0, 1.0);
            if w > 0.0 {
                let info = SampleInfo { pos: p, t, diameter: d, level };
                out.radiance += w * radiance(&s, &info);
            }
            if ao_radius > 0.0 {
                out.occlusion += w * falloff(p.distance(ao_point), ao_radius);
            }
            a += w;
        }
        // No stop at the AO radius here: a march that also gathers radiance (AO and diffuse
        // light from the same cones) must go on to `max_distance`; samples beyond R add
        // nothing to O (f = 0 there), and an AO-only march is ended by its `max_distance`
        // (the tracers set it to R plus the normal offset).
        t += step;
    }
    out.opacity = a.clamp(0.0, 1.0);
    out.occlusion = out.occlusion.clamp(0.0, 1.0);
    out
}
