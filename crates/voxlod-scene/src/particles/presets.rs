//! Deterministic particle generators: a smoke column, an explosion and a cloud bank. Each is a
//! pure function of its parameters (randomness from [`Rng::stream`], one stream per particle),
//! returns a validated [`ParticleSystem`] and its intended frame time, and accepts up to
//! [`MAX_PARTICLES`] particles.
//!
//! Units: the ground is y = 0, y up, sizes in scene units (think metres).

use glam::Vec3;

use super::{ColorMode, DisplacementMap, FLAG_EMISSIVE, MAX_PARTICLES, Particle, ParticleSystem};
use crate::procedural::Rng;
use crate::{Error, Result};

/// Parameters of [`smoke_column`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SmokeParams {
    /// Number of particles, 1..=[`MAX_PARTICLES`].
    pub count: usize,
    /// Seed.
    pub seed: u64,
    /// Rise speed (units per unit time); the column is about `rise · lifetime` tall.
    pub rise: f32,
    /// Lifetime of a puff; births are spread over one lifetime before the frame time.
    pub lifetime: f32,
    /// Inner radius of a puff at birth.
    pub radius: f32,
    /// Extinction per unit length of a puff at birth.
    pub density: f32,
    /// Horizontal wind (units per unit time) bending the column.
    pub wind: Vec3,
}

impl Default for SmokeParams {
    fn default() -> Self {
        Self {
            count: 10_000,
            seed: 1,
            rise: 2.0,
            lifetime: 4.0,
            radius: 0.12,
            density: 6.0,
            wind: Vec3::new(0.35, 0.0, 0.1),
        }
    }
}

/// Parameters of [`explosion`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ExplosionParams {
    /// Number of particles, 1..=[`MAX_PARTICLES`].
    pub count: usize,
    /// Seed.
    pub seed: u64,
    /// Largest outward speed.
    pub speed: f32,
    /// Inner radius of a fireball particle at birth.
    pub radius: f32,
    /// Extinction per unit length at birth.
    pub density: f32,
}

impl Default for ExplosionParams {
    fn default() -> Self {
        Self { count: 4_000, seed: 2, speed: 3.0, radius: 0.25, density: 4.0 }
    }
}

/// Parameters of [`cloud_bank`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CloudParams {
    /// Number of particles, 1..=[`MAX_PARTICLES`].
    pub count: usize,
    /// Seed.
    pub seed: u64,
    /// Horizontal extent (the bank covers `[−extent, extent]` in x and half that in z).
    pub extent: f32,
    /// Base altitude of the bank.
    pub altitude: f32,
    /// Inner radius of a cloud puff.
    pub radius: f32,
    /// Extinction per unit length.
    pub density: f32,
}

impl Default for CloudParams {
    fn default() -> Self {
        Self { count: 3_000, seed: 3, extent: 6.0, altitude: 3.0, radius: 0.45, density: 2.0 }
    }
}

fn check_count(count: usize) -> Result<()> {
    if count == 0 || count > MAX_PARTICLES {
        return Err(Error::InvalidParameter {
            name: "particle count".into(),
            value: count.to_string(),
            reason: format!("must be in 1..={MAX_PARTICLES}"),
        });
    }
    Ok(())
}

fn finish(particles: Vec<Particle>, seed: u64, time: f32) -> Result<ParticleSystem> {
    let system =
        ParticleSystem { particles, displacement: DisplacementMap::noise(seed, 32, 3.0, 4)?, time };
    system.validate()?;
    Ok(system)
}

/// A column of grey smoke rising from the origin, widening as puffs grow, bent by the wind;
/// colour darkened in the valleys of the displacement ([`ColorMode::DisplacementAo`]). The
/// frame time is one lifetime after the first birth, so puffs of every age are present.
pub fn smoke_column(p: &SmokeParams) -> Result<ParticleSystem> {
    check_count(p.count)?;
    let particles = (0..p.count)
        .map(|i| {
            let mut rng = Rng::stream(p.seed, &[1, i as u64]);
            let birth = p.lifetime * (i as f32 + rng.next_f32()) / p.count as f32;
            let jitter = rng.in_unit_ball() * Vec3::new(0.6, 0.2, 0.6) * p.radius * 2.0;
            let drift = rng.in_unit_ball() * 0.15 * p.rise;
            let grey = rng.range(0.55, 0.8);
            Particle {
                center: jitter,
                radius: p.radius * rng.range(0.6, 1.0),
                velocity: Vec3::new(0.0, p.rise, 0.0) + p.wind + drift,
                displacement: p.radius * rng.range(0.4, 0.8),
                color: Vec3::splat(grey),
                density: p.density * rng.range(0.5, 1.0),
                color_outer: Vec3::splat(grey),
                growth: rng.range(0.3, 0.6),
                birth,
                lifetime: p.lifetime,
                spin: rng.next_f32(),
                spin_rate: rng.range(-0.2, 0.2),
                color_mode: ColorMode::DisplacementAo as u32,
                flags: 0,
                _pad: [0; 2],
            }
        })
        .collect();
    finish(particles, p.seed, p.lifetime)
}

/// An explosion: emissive particles flung out of a point at y = 1, a white-yellow core ramping
/// to red at the outer radius ([`ColorMode::RadialRamp`]), slowing (speeds spread), growing and
/// fading; one in four particles is dark lit smoke. Frame time 0.35.
pub fn explosion(p: &ExplosionParams) -> Result<ParticleSystem> {
    check_count(p.count)?;
    let origin = Vec3::new(0.0, 1.0, 0.0);
    let particles = (0..p.count)
        .map(|i| {
            let mut rng = Rng::stream(p.seed, &[2, i as u64]);
            let dir = rng.unit_vector();
            let speed = p.speed * rng.next_f32().sqrt();
            let smoke = rng.below(4) == 0;
            let (color, color_outer, flags) = if smoke {
                (Vec3::splat(0.25), Vec3::splat(0.15), 0)
            } else {
                (Vec3::new(4.0, 3.2, 1.4), Vec3::new(1.2, 0.2, 0.02), FLAG_EMISSIVE)
            };
            Particle {
                center: origin + dir * p.radius * rng.next_f32(),
                radius: p.radius * rng.range(0.5, 1.0),
                velocity: dir * speed + Vec3::new(0.0, 0.5, 0.0),
                displacement: p.radius * rng.range(0.3, 0.7),
                color,
                density: p.density * rng.range(0.5, 1.0),
                color_outer,
                growth: rng.range(1.5, 3.0),
                birth: rng.range(0.0, 0.1),
                lifetime: rng.range(0.8, 1.5),
                spin: rng.next_f32(),
                spin_rate: rng.range(-1.0, 1.0),
                color_mode: ColorMode::RadialRamp as u32,
                flags,
                _pad: [0; 2],
            }
        })
        .collect();
    finish(particles, p.seed, 0.35)
}

/// A flat bank of white cumulus-like puffs, denser and taller towards its middle, drifting
/// slowly; infinite lifetime, colour darkened in the displacement's valleys. Frame time 0.
pub fn cloud_bank(p: &CloudParams) -> Result<ParticleSystem> {
    check_count(p.count)?;
    let particles = (0..p.count)
        .map(|i| {
            let mut rng = Rng::stream(p.seed, &[3, i as u64]);
            let x = rng.range(-1.0, 1.0);
            let z = rng.range(-1.0, 1.0);
            // Taller in the middle of the bank: a dome profile.
            let dome = (1.0 - 0.5 * (x * x + z * z)).max(0.0);
            let y = p.altitude + rng.next_f32().powi(2) * dome * p.extent * 0.25;
            let white = rng.range(0.85, 1.0);
            Particle {
                center: Vec3::new(x * p.extent, y, z * p.extent * 0.5),
                radius: p.radius * rng.range(0.5, 1.0) * (0.6 + dome),
                velocity: Vec3::new(0.05, 0.0, 0.0),
                displacement: p.radius * rng.range(0.3, 0.6),
                color: Vec3::splat(white),
                density: p.density * rng.range(0.5, 1.0),
                color_outer: Vec3::splat(white),
                growth: 0.0,
                birth: 0.0,
                lifetime: f32::INFINITY,
                spin: rng.next_f32(),
                spin_rate: 0.0,
                color_mode: ColorMode::DisplacementAo as u32,
                flags: 0,
                _pad: [0; 2],
            }
        })
        .collect();
    finish(particles, p.seed, 0.0)
}
