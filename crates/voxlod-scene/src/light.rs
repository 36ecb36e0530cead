//! [`Light`]: one directional or point light. Quantities are irradiance-based so that a white
//! Lambertian surface facing a directional light of irradiance `E` has radiance `E/π`.

use glam::Vec3;

use crate::{Error, Result};

/// A light source.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Light {
    /// A light at infinity.
    Directional {
        /// Unit direction *toward* the light.
        to_light: Vec3,
        /// Linear RGB irradiance on a surface facing the light.
        irradiance: Vec3,
    },
    /// A point light.
    Point {
        /// Position.
        position: Vec3,
        /// Linear RGB radiant intensity: irradiance at distance d facing the light is I/d².
        intensity: Vec3,
    },
}

/// A light as seen from one shading point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LightSample {
    /// Unit direction from the point toward the light.
    pub to_light: Vec3,
    /// Distance to the light (`f32::INFINITY` for a directional light).
    pub distance: f32,
    /// Irradiance on a surface facing the light, before visibility.
    pub irradiance: Vec3,
}

impl Default for Light {
    fn default() -> Self {
        Light::Directional {
            to_light: Vec3::new(0.4, 0.8, 0.45).normalize(),
            irradiance: Vec3::splat(3.0),
        }
    }
}

impl Light {
    /// The light as seen from `p`. At the position of a point light the direction is +y and
    /// the irradiance is clamped to that at 1e-4 units.
    #[inline]
    pub fn sample(&self, p: Vec3) -> LightSample {
        match *self {
            Light::Directional { to_light, irradiance } => {
                LightSample { to_light, distance: f32::INFINITY, irradiance }
            }
            Light::Point { position, intensity } => {
                let d = position - p;
                let dist = d.length();
                let to_light = if dist > 0.0 { d / dist } else { Vec3::Y };
                LightSample {
                    to_light,
                    distance: dist,
                    irradiance: intensity / dist.max(1e-4).powi(2),
                }
            }
        }
    }

    /// Checks finiteness, non-negative power and a non-zero direction; normalizes the
    /// direction of a directional light.
    pub fn validated(self) -> Result<Self> {
        let bad = |reason: &str| {
            Err(Error::InvalidParameter {
                name: "light".into(),
                value: format!("{self:?}"),
                reason: reason.into(),
            })
        };
        match self {
            Light::Directional { to_light, irradiance } => {
                if !(to_light.is_finite() && irradiance.is_finite())
                    || irradiance.min_element() < 0.0
                {
                    return bad("direction and irradiance must be finite, irradiance ≥ 0");
                }
                match to_light.try_normalize() {
                    Some(d) => Ok(Light::Directional { to_light: d, irradiance }),
                    None => bad("direction is zero"),
                }
            }
            Light::Point { position, intensity } => {
                if !(position.is_finite() && intensity.is_finite()) || intensity.min_element() < 0.0
                {
                    return bad("position and intensity must be finite, intensity ≥ 0");
                }
                Ok(self)
            }
        }
    }
}
