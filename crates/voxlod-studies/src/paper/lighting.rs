//! The paper's lighting and background, and images lit by several lights.
//!
//! Brito, Poulin and Teichrieb (2023) light their scenes with a directional light "above to the
//! right" (§5) and their public code shades with a point light (diffuse, from the voxel centre);
//! their figures sit on a white background, with a red one where transparency must show
//! (Fig. 10). voxlod's renderers take one light, so an image under several lights is the sum of
//! one render per light: every renderer here is linear in the light — opacity, transmittance
//! and coverage do not depend on it, and shading is linear in the irradiance — so the sum is the
//! image under all lights at once (the ambient term and the background are added by the first
//! render only). The point light falls off with the squared distance (the authors' sample code
//! uses a constant intensity); its intensity is set so that it delivers, at the scene's centre,
//! the same irradiance as the sun.

use glam::{Vec3, Vec4};
use voxlod_scene::{Camera, Image, Light, Scene};

use crate::Error;

/// The background of the paper setup.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
pub enum Background {
    /// White, as the paper's figures.
    White,
    /// Red, as the paper's Fig. 10 (transparency against specularity).
    Red,
    /// The scene's own background (voxlod's default runs).
    Scene,
}

impl Background {
    /// Linear RGB colour (the scene's own for [`Background::Scene`]).
    pub fn colour(self, scene: &Scene) -> Vec3 {
        match self {
            Self::White => Vec3::ONE,
            Self::Red => Vec3::new(1.0, 0.0, 0.0),
            Self::Scene => scene.background,
        }
    }

    /// Short name for tables.
    pub fn name(self) -> &'static str {
        match self {
            Self::White => "white",
            Self::Red => "red",
            Self::Scene => "scene's",
        }
    }
}

/// The lights of the paper setup.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
pub enum Lighting {
    /// The scene's directional sun and a point light on the camera's side, each with half of
    /// the sun's irradiance at the scene's centre.
    SunAndPoint,
    /// The scene's light alone, at full strength (voxlod's default runs).
    Sun,
}

impl Lighting {
    /// Short name for tables.
    pub fn name(self) -> &'static str {
        match self {
            Self::SunAndPoint => "sun + point",
            Self::Sun => "sun only",
        }
    }

    /// The lights for `scene` seen first from `camera`: the point light sits above and to the
    /// right of the camera by half the scene's bounding radius, fixed in the world for every
    /// view.
    pub fn lights(self, scene: &Scene, camera: &Camera) -> Result<Vec<Light>, Error> {
        let sun = scene.light();
        if self == Self::Sun {
            return Ok(vec![sun]);
        }
        let (lo, hi) = scene.bounds()?;
        let centre = (lo + hi) * 0.5;
        let radius = ((hi - lo) * 0.5).length().max(1e-6);
        let sun_irradiance = match sun {
            Light::Directional { irradiance, .. } => irradiance,
            Light::Point { position, intensity } => {
                intensity / (position - centre).length_squared().max(1e-12)
            }
        };
        let half = sun_irradiance * 0.5;
        let sun = match sun {
            Light::Directional { to_light, .. } => {
                Light::Directional { to_light, irradiance: half }
            }
            Light::Point { position, intensity } => {
                Light::Point { position, intensity: intensity * 0.5 }
            }
        };
        let forward = (camera.target - camera.eye).normalize_or(Vec3::NEG_Z);
        let right = forward.cross(camera.up).normalize_or(Vec3::X);
        let up = right.cross(forward);
        let position = camera.eye + (right + up) * (0.5 * radius);
        let intensity = half * (position - centre).length_squared();
        Ok(vec![sun, Light::Point { position, intensity }])
    }
}

/// Sums one render per light: `render(light, ambient, background)` is called with the ambient
/// term and the background for the first light and with zero for the others. Coverage (alpha)
/// is the first render's.
pub fn superpose(
    lights: &[Light],
    ambient: Vec3,
    background: Vec3,
    mut render: impl FnMut(&Light, Vec3, Vec3) -> Result<Image, Error>,
) -> Result<Image, Error> {
    let mut sum: Option<Image> = None;
    for (i, light) in lights.iter().enumerate() {
        let (a, b) = if i == 0 { (ambient, background) } else { (Vec3::ZERO, Vec3::ZERO) };
        let image = render(light, a, b)?;
        match &mut sum {
            None => sum = Some(image),
            Some(s) => {
                for (p, q) in s.pixels.iter_mut().zip(&image.pixels) {
                    *p += Vec4::new(q.x, q.y, q.z, 0.0);
                }
            }
        }
    }
    sum.ok_or_else(|| Error::InvalidConfig {
        study: "paper setup",
        field: "lights",
        value: "[]".into(),
        expected: "at least one light",
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use voxlod_cpu::render::ground_truth;

    /// The ground truth under two lights at once equals the sum of one render per light: the
    /// premise of [`superpose`], checked on a scene with shadows and a point light.
    #[test]
    fn two_lights_superpose_exactly_in_the_ground_truth() {
        let scene = voxlod_scene::procedural::builtin("cornell", &[]).unwrap();
        let geometry = scene.geometry();
        let bvh = voxlod_cpu::raycast::Bvh::new(&geometry).unwrap();
        let camera = scene.default_camera().unwrap();
        let lights = Lighting::SunAndPoint.lights(&scene, &camera).unwrap();
        assert_eq!(lights.len(), 2);
        let options = |ambient| ground_truth::Options {
            width: 16,
            height: 16,
            spp: 4,
            seed: 0,
            ambient,
            shadows: true,
            light_filter: None,
        };
        let ambient = Vec3::splat(0.1);
        let sum = superpose(&lights, ambient, scene.background, |l, a, b| {
            let mut s = scene.clone();
            s.lights = vec![*l];
            s.background = b;
            Ok(ground_truth::render(&s, &geometry, &bvh, &camera, &options(a))?.image)
        })
        .unwrap();
        // The same image by hand: shading is linear in the light, so each pixel is the sum.
        let mut one = scene.clone();
        one.lights = vec![lights[0]];
        let a = ground_truth::render(&one, &geometry, &bvh, &camera, &options(ambient)).unwrap();
        one.lights = vec![lights[1]];
        one.background = Vec3::ZERO;
        let b = ground_truth::render(&one, &geometry, &bvh, &camera, &options(Vec3::ZERO)).unwrap();
        let mut lit_by_both = 0;
        for ((s, a), b) in sum.pixels.iter().zip(&a.image.pixels).zip(&b.image.pixels) {
            assert!((s.truncate() - (a.truncate() + b.truncate())).abs().max_element() < 1e-6);
            lit_by_both += usize::from(b.truncate().max_element() > 1e-3);
        }
        // The point light reaches a good share of the pixels (it is not behind everything).
        assert!(lit_by_both > 16 * 16 / 4, "{lit_by_both} pixels lit by the point light");
    }

    #[test]
    fn the_point_light_delivers_half_the_sun_at_the_centre() {
        let scene = voxlod_scene::procedural::builtin("sphere", &[]).unwrap();
        let camera = scene.default_camera().unwrap();
        let lights = Lighting::SunAndPoint.lights(&scene, &camera).unwrap();
        let (lo, hi) = scene.bounds().unwrap();
        let Light::Directional { irradiance: full, .. } = scene.light() else { panic!() };
        let Light::Point { position, intensity } = lights[1] else { panic!() };
        let at_centre = intensity / (position - (lo + hi) * 0.5).length_squared();
        assert!((at_centre - full * 0.5).abs().max_element() < 1e-4 * full.max_element());
        assert_eq!(Lighting::Sun.lights(&scene, &camera).unwrap(), vec![scene.light()]);
        assert!(superpose(&[], Vec3::ZERO, Vec3::ZERO, |_, _, _| unreachable!()).is_err());
    }
}
