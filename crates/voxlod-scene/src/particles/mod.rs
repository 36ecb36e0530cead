//! Volume primitives for procedural participating media (McNabb 2015, "Sparse Procedural
//! Volume Rendering", §5.5.2): the **displaced sphere**.
//!
//! A [`Particle`] is a sphere of inner radius `radius` whose surface is pushed radially outward
//! by `displacement · n(direction)`, where `n ∈ [0, 1]` is read from a [`DisplacementMap`] (a
//! cube map of 3D fractal noise sampled on the unit sphere, the chapter's Figure 5.8). Every
//! point closer to the centre than `radius` is inside, every point farther than
//! `radius + displacement` (the *outer* radius) is outside, and between the two the cube map
//! decides: the fill's early accept/reject.
//!
//! Inside, a particle contributes its extinction `density` (per unit length, so images do not
//! depend on the voxel size) and a colour: constant, a radial ramp from `color` at the centre
//! to `color_outer` at the outer radius, or `color` darkened where the displacement is low (the
//! chapter's ambient-occlusion approximation, Figure 5.10). A particle is lit (its colour is an
//! albedo, modulated by the light propagated through the volume) or emissive (its colour is
//! radiance, added unshadowed: fire).
//!
//! Particles are animated: [`Particle::at`] evaluates one at time `t` into a
//! [`DisplacedSphere`] (moved by its velocity, grown, spun about the vertical, faded out over
//! its lifetime), which is what the volume pipeline of voxlod-cpu bins and fills. Both types
//! are `#[repr(C)]` `Pod`, the layout a GPU kernel reads.
//!
//! [`presets`] holds deterministic generators (smoke column, explosion, cloud bank) of up to
//! [`MAX_PARTICLES`] particles.

mod cubemap;
pub mod presets;
#[cfg(test)]
mod tests;

use bytemuck::{Pod, Zeroable};
use glam::{Vec3, Vec4};

pub use cubemap::DisplacementMap;
pub use presets::{CloudParams, ExplosionParams, SmokeParams, cloud_bank, explosion, smoke_column};

use crate::procedural::rng::sin_cos_turns;
use crate::{Error, Result};

/// Most particles a generator makes: 10⁵.
pub const MAX_PARTICLES: usize = 100_000;

/// How a particle's colour varies inside it (the `color_mode` field).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(u32)]
pub enum ColorMode {
    /// `color` everywhere.
    Constant = 0,
    /// `color` at the centre to `color_outer` at the outer radius, linear in the distance.
    RadialRamp = 1,
    /// `color · (AO_FLOOR + (1 − AO_FLOOR) · n)`, `n` the displacement in that direction: the
    /// valleys of the displaced surface are darker.
    DisplacementAo = 2,
}

/// Darkest factor of [`ColorMode::DisplacementAo`] (where the displacement is 0).
pub const AO_FLOOR: f32 = 0.35;

/// Bit of [`Particle::flags`]: the colour is emitted radiance, not an albedo.
pub const FLAG_EMISSIVE: u32 = 1;

/// An animated displaced sphere. 96 bytes, `Pod`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
#[repr(C)]
pub struct Particle {
    /// Centre at birth.
    pub center: Vec3,
    /// Inner radius at birth, ≥ 0.
    pub radius: f32,
    /// Velocity of the centre (units per unit time).
    pub velocity: Vec3,
    /// Displacement amplitude at birth, ≥ 0: the outer radius is `radius + displacement`.
    pub displacement: f32,
    /// Colour (albedo when lit, radiance when emissive), linear RGB, components ≥ 0.
    pub color: Vec3,
    /// Extinction per unit length at birth, ≥ 0.
    pub density: f32,
    /// Colour at the outer radius of [`ColorMode::RadialRamp`], components ≥ 0.
    pub color_outer: Vec3,
    /// Relative growth of both radii per unit time: scale `max(0, 1 + growth · age)`.
    pub growth: f32,
    /// Time of birth; the particle does not exist before.
    pub birth: f32,
    /// Lifetime (> 0, may be infinite); density fades linearly to 0 over it.
    pub lifetime: f32,
    /// Rotation of the displacement about the vertical at birth, in turns.
    pub spin: f32,
    /// Turns per unit time.
    pub spin_rate: f32,
    /// A [`ColorMode`] as `u32`.
    pub color_mode: u32,
    /// Bit set: [`FLAG_EMISSIVE`].
    pub flags: u32,
    /// Padding to a 16-byte multiple.
    pub _pad: [u32; 2],
}

/// A particle evaluated at one time: what binning and fill read. 64 bytes, `Pod`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
#[repr(C)]
pub struct DisplacedSphere {
    /// Centre.
    pub center: Vec3,
    /// Inner radius: every point closer is inside.
    pub inner: f32,
    /// Colour at the centre (see [`ColorMode`]).
    pub color: Vec3,
    /// Displacement amplitude: the outer radius is `inner + amplitude`.
    pub amplitude: f32,
    /// Colour at the outer radius ([`ColorMode::RadialRamp`]).
    pub color_outer: Vec3,
    /// Extinction per unit length.
    pub density: f32,
    /// Cosine of the rotation about +y applied to directions before the cube-map look-up.
    pub rot_cos: f32,
    /// Sine of that rotation.
    pub rot_sin: f32,
    /// A [`ColorMode`] as `u32`.
    pub color_mode: u32,
    /// [`FLAG_EMISSIVE`] or 0.
    pub flags: u32,
}

impl Particle {
    /// Checks every field: finite, radii/amplitude/density/colours ≥ 0, lifetime > 0 (infinity
    /// allowed), a known colour mode. The error names `index` and the field.
    pub fn validate(&self, index: usize) -> Result<()> {
        let err = |field: &'static str, value: String, reason: &'static str| {
            Err(Error::InvalidParticle { index, field, value, reason })
        };
        let vectors = [
            ("center", self.center),
            ("velocity", self.velocity),
            ("color", self.color),
            ("color_outer", self.color_outer),
        ];
        for (field, v) in vectors {
            if !v.is_finite() {
                return err(field, v.to_string(), "must be finite");
            }
        }
        let scalars = [
            ("radius", self.radius),
            ("displacement", self.displacement),
            ("density", self.density),
            ("growth", self.growth),
            ("birth", self.birth),
            ("spin", self.spin),
            ("spin_rate", self.spin_rate),
        ];
        for (field, v) in scalars {
            if !v.is_finite() {
                return err(field, v.to_string(), "must be finite");
            }
        }
        for (field, v) in [
            ("radius", self.radius),
            ("displacement", self.displacement),
            ("density", self.density),
        ] {
            if v < 0.0 {
                return err(field, v.to_string(), "must be ≥ 0");
            }
        }
        for (field, v) in [("color", self.color), ("color_outer", self.color_outer)] {
            if v.min_element() < 0.0 {
                return err(field, v.to_string(), "components must be ≥ 0");
            }
        }
        if self.lifetime.is_nan() || self.lifetime <= 0.0 {
            return err("lifetime", self.lifetime.to_string(), "must be > 0 (infinity allowed)");
        }
        if self.color_mode > ColorMode::DisplacementAo as u32 {
            return err("color_mode", self.color_mode.to_string(), "must be 0, 1 or 2");
        }
        Ok(())
    }

    /// The particle at time `t`, or `None` before its birth or after its lifetime (or when
    /// it has shrunk to nothing or faded out). Age `a = t − birth`: centre moved by
    /// `velocity · a`, radii scaled by `max(0, 1 + growth · a)`, density faded by
    /// `1 − a / lifetime`, displacement rotated by `spin + spin_rate · a` turns.
    pub fn at(&self, t: f32) -> Option<DisplacedSphere> {
        let age = t - self.birth;
        if !(age >= 0.0 && age <= self.lifetime) {
            return None;
        }
        let scale = (1.0 + self.growth * age).max(0.0);
        let fade = if self.lifetime.is_finite() { 1.0 - age / self.lifetime } else { 1.0 };
        let density = self.density * fade.max(0.0);
        let inner = self.radius * scale;
        let amplitude = self.displacement * scale;
        if inner + amplitude <= 0.0 || density <= 0.0 && self.flags & FLAG_EMISSIVE == 0 {
            return None;
        }
        let turns = self.spin + self.spin_rate * age;
        let (rot_sin, rot_cos) = sin_cos_turns(turns - turns.floor());
        let s = DisplacedSphere {
            center: self.center + self.velocity * age,
            inner,
            color: self.color,
            amplitude,
            color_outer: self.color_outer,
            density,
            rot_cos,
            rot_sin,
            color_mode: self.color_mode,
            flags: self.flags,
        };
        s.is_finite().then_some(s)
    }
}

impl DisplacedSphere {
    /// The outer radius, `inner + amplitude`: the bounding sphere of binning.
    #[inline]
    pub fn outer(&self) -> f32 {
        self.inner + self.amplitude
    }

    /// Whether the colour is emitted radiance.
    #[inline]
    pub fn emissive(&self) -> bool {
        self.flags & FLAG_EMISSIVE != 0
    }

    /// Whether every float field is finite (time evaluation of a valid particle at a huge time
    /// can overflow).
    pub fn is_finite(&self) -> bool {
        self.center.is_finite()
            && self.inner.is_finite()
            && self.amplitude.is_finite()
            && self.density.is_finite()
            && self.outer().is_finite()
    }

    /// The displacement `n ∈ [0, 1]` in the direction of `offset` (from the centre), the
    /// direction first rotated by the particle's spin about +y.
    #[inline(always)]
    pub fn displacement(&self, map: &DisplacementMap, offset: Vec3) -> f32 {
        let (c, s) = (self.rot_cos, self.rot_sin);
        map.sample(Vec3::new(c * offset.x + s * offset.z, offset.y, c * offset.z - s * offset.x))
    }

    /// Four displacements at once: lane `i` is [`DisplacedSphere::displacement`] of offset
    /// `(x[i], y[i], z[i])`, the same bits for finite offsets ([`DisplacementMap::sample4`]).
    #[inline(always)]
    pub fn displacement4(&self, map: &DisplacementMap, x: Vec4, y: Vec4, z: Vec4) -> Vec4 {
        let (c, s) = (Vec4::splat(self.rot_cos), Vec4::splat(self.rot_sin));
        map.sample4(c * x + s * z, y, c * z - s * x)
    }

    /// Radius of the displaced surface for displacement `n`: `inner + amplitude · n`, within
    /// `[inner, outer]` for `n ∈ [0, 1]`.
    #[inline]
    pub fn surface_radius(&self, n: f32) -> f32 {
        self.inner + self.amplitude * n
    }

    /// The colour at distance `dist` from the centre with displacement `n` there (see
    /// [`ColorMode`]; an unknown mode is constant).
    #[inline]
    pub fn color_at(&self, dist: f32, n: f32) -> Vec3 {
        match self.color_mode {
            1 => {
                let t =
                    if self.outer() > 0.0 { (dist / self.outer()).clamp(0.0, 1.0) } else { 0.0 };
                self.color + (self.color_outer - self.color) * t
            }
            2 => self.color * (AO_FLOOR + (1.0 - AO_FLOOR) * n),
            _ => self.color,
        }
    }

    /// Whether the colour needs the displacement `n` (so that an early-accepted point still
    /// reads the cube map).
    #[inline]
    pub fn color_needs_displacement(&self) -> bool {
        self.color_mode == ColorMode::DisplacementAo as u32
    }
}

/// Particles and the cube map their displacement reads.
#[derive(Clone, Debug, PartialEq)]
pub struct ParticleSystem {
    /// The particles.
    pub particles: Vec<Particle>,
    /// The displacement cube map shared by all particles (each reads it rotated by its spin).
    pub displacement: DisplacementMap,
    /// The time a generator meant to be shown (a frame of the effect in full development).
    pub time: f32,
}

impl ParticleSystem {
    /// Validates every particle (the first bad one is named) and the particle count.
    pub fn validate(&self) -> Result<()> {
        if self.particles.len() > MAX_PARTICLES {
            return Err(Error::InvalidParameter {
                name: "particle count".into(),
                value: self.particles.len().to_string(),
                reason: format!("at most {MAX_PARTICLES}"),
            });
        }
        self.particles.iter().enumerate().try_for_each(|(i, p)| p.validate(i))
    }

    /// The particles alive at time `t`, evaluated, in particle order (dead ones dropped).
    /// Validate first: an invalid particle may evaluate to anything finite or be dropped.
    pub fn at(&self, t: f32) -> Vec<DisplacedSphere> {
        self.particles.iter().filter_map(|p| p.at(t)).collect()
    }
}

/// The bounds (min, max) of the outer spheres of `spheres`, `None` when empty.
pub fn bounds(spheres: &[DisplacedSphere]) -> Option<(Vec3, Vec3)> {
    spheres.iter().fold(None, |acc, s| {
        let (lo, hi) = (s.center - s.outer(), s.center + s.outer());
        Some(match acc {
            None => (lo, hi),
            Some((a, b)) => (a.min(lo), b.max(hi)),
        })
    })
}
