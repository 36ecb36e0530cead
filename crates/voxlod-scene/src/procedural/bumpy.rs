//! `bumpy-sphere` and `bumpy-specular`: a closed sphere displaced by fine fractal noise, the
//! surfaces of Heitz and Neyret's (2012) examples, inside their model's domain (a solid whose
//! sub-pixel detail is a height field on a locally planar macro-surface):
//!
//! - **`bumpy-sphere`** (their Figs. 9 and 11): colour correlated with height through a ramp
//!   texture — red in the valleys, yellow halfway, green on the tops — so that what a pixel
//!   sees depends on the view and the light (masking hides the valleys at grazing angles,
//!   shadowing darkens them), and a plain mean colour is wrong away from normal incidence.
//! - **`bumpy-specular`** (their Fig. 12): one grey glossy Blinn-Phong material on
//!   higher-frequency bumps: the bumps are geometry up close and must turn into a wider,
//!   dimmer highlight (roughness) at a distance.
//!
//! Geometry: an icosphere of radius 1 at the origin (`20·4^subdiv` triangles, vertices shared,
//! so the surface stays closed), each vertex moved along its direction by
//! `amplitude · fbm3(direction · frequency)` with `octaves` octaves of value noise, normals
//! recomputed from the displaced triangles. The height ramp's `u` is the displacement mapped
//! from `[−amplitude, amplitude]` to `[0, 1]`.

use std::sync::Arc;

use glam::{Vec2, Vec3};

use super::noise::fbm3;
use super::param::{check_f32, check_u32};
use super::primitives::{MAX_ICOSPHERE_SUBDIVISIONS, icosphere};
use super::{SKY, framing, sun};
use crate::texture::{Sampler, WrapMode};
use crate::{Material, Result, Scene, Texture, TextureRef};

/// Parameters of [`bumpy`].
#[derive(Clone, Debug, PartialEq)]
pub struct BumpyParams {
    /// Icosphere subdivisions, 0..=7 (`20·4^subdiv` triangles). Default 6 (81 920).
    pub subdiv: u32,
    /// Largest displacement, in (0, 0.5] (the sphere's radius is 1). Default 0.1.
    pub amplitude: f32,
    /// Frequency of the first octave on the unit sphere, in (0, 1e4]. Default 12 (slopes of
    /// order 1: the relief masks and shadows itself away from normal incidence).
    pub frequency: f32,
    /// Octaves of noise, 1..=12, each at twice the frequency and half the amplitude. Default 3
    /// (the finest, 48 per unit, still resolved by subdivision 6's triangles: finer octaves
    /// would be aliased by the mesh).
    pub octaves: u32,
    /// Random seed of the noise. Default 1.
    pub seed: u64,
    /// Colour from the height ramp (red valleys, green tops), else one grey.
    pub height_colour: bool,
    /// Specular level of the material, in \[0, 1\] (0: diffuse). Default 0.
    pub specular: f32,
    /// Blinn-Phong exponent, in \[0, 1e4\]. Default 0.
    pub shininess: f32,
}

impl Default for BumpyParams {
    fn default() -> Self {
        Self {
            subdiv: 6,
            amplitude: 0.1,
            frequency: 12.0,
            octaves: 3,
            seed: 1,
            height_colour: true,
            specular: 0.0,
            shininess: 0.0,
        }
    }
}

impl BumpyParams {
    /// `bumpy-specular`'s defaults: grey, glossy, finer and lower bumps.
    pub fn specular() -> Self {
        Self {
            amplitude: 0.03,
            frequency: 20.0,
            octaves: 2,
            height_colour: false,
            specular: 0.5,
            shininess: 200.0,
            ..Self::default()
        }
    }

    /// Checks every field against its documented range; errors name `scene.key`.
    pub fn validate(&self, scene: &str) -> Result<()> {
        check_u32(scene, "subdiv", self.subdiv, 0, MAX_ICOSPHERE_SUBDIVISIONS)?;
        check_f32(scene, "amplitude", self.amplitude, 0.0, 0.5)?;
        check_f32(scene, "frequency", self.frequency, 0.0, 1e4)?;
        check_u32(scene, "octaves", self.octaves, 1, 12)?;
        // 0 is allowed for both (a diffuse material).
        if self.specular != 0.0 {
            check_f32(scene, "specular", self.specular, 0.0, 1.0)?;
        }
        if self.shininess != 0.0 {
            check_f32(scene, "shininess", self.shininess, 0.0, 1e4)?;
        }
        Ok(())
    }
}

/// The height ramp, red in the valleys to green on the tops, each channel monotone in height
/// (linear `(0.6, 0.05, 0.02)`, `(0.45, 0.2, 0.03)`, `(0.25, 0.35, 0.04)`, `(0.05, 0.5, 0.05)`),
/// as sRGB bytes: the mean is a yellow-brown, the tops alone green.
const RAMP: [[u8; 4]; 4] =
    [[203, 63, 39, 255], [179, 124, 48, 255], [137, 160, 56, 255], [63, 188, 63, 255]];

/// The displaced sphere of `p` (module docs), named `name`.
pub fn bumpy(name: &str, p: &BumpyParams) -> Result<Scene> {
    p.validate(name)?;
    let mut mesh = icosphere(Vec3::ZERO, 1.0, p.subdiv);
    let heights: Vec<f32> = mesh
        .normals
        .iter()
        .map(|&d| p.amplitude * fbm3(p.seed, d * p.frequency, p.octaves))
        .collect();
    for ((pos, &d), &h) in mesh.positions.iter_mut().zip(&mesh.normals).zip(&heights) {
        *pos = d * (1.0 + h);
    }
    mesh.uvs = heights
        .iter()
        .map(|&h| Vec2::new((0.5 + 0.5 * h / p.amplitude).clamp(0.0, 1.0), 0.5))
        .collect();
    mesh.compute_normals();
    mesh.name = name.into();
    let mut material = Material {
        specular: Vec3::splat(p.specular),
        shininess: p.shininess,
        ..Material::diffuse(name, Vec3::splat(0.6))
    };
    let mut textures = Vec::new();
    if p.height_colour {
        // The ramp's texels sit at u = (i + ½)/4: clamp so valleys and tops reach the ends.
        textures.push(Texture {
            name: format!("{name}/height ramp"),
            width: RAMP.len() as u32,
            height: 1,
            texels: Arc::from(RAMP.to_vec()),
            srgb: true,
            sampler: Sampler { wrap_u: WrapMode::ClampToEdge, wrap_v: WrapMode::ClampToEdge },
        });
        material.base_color = glam::Vec4::ONE;
        material.base_color_texture = Some(TextureRef { texture: 0 });
    }
    let to_light = Vec3::new(0.6, 0.7, 0.4);
    let camera = framing(Vec3::new(0.3, 0.35, 1.0), Vec3::ZERO, 1.0 + p.amplitude, 35.0);
    let scene = Scene {
        name: name.into(),
        meshes: vec![mesh],
        materials: vec![material],
        textures,
        camera: Some(camera),
        lights: vec![sun(to_light)],
        background: SKY,
        ..Default::default()
    };
    Ok(scene)
}

#[cfg(test)]
mod tests {
    use std::collections::HashMap;

    use super::*;

    /// Every edge is shared by exactly two triangles: the displaced sphere is still closed.
    #[test]
    fn the_surface_is_closed_and_the_colour_follows_the_height() {
        let s = bumpy("bumpy-sphere", &BumpyParams { subdiv: 3, ..Default::default() }).unwrap();
        s.validate().unwrap();
        let m = &s.meshes[0];
        let mut edges: HashMap<(u32, u32), u32> = HashMap::new();
        for t in &m.indices {
            for (a, b) in [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])] {
                *edges.entry((a.min(b), a.max(b))).or_default() += 1;
            }
        }
        assert!(edges.values().all(|&n| n == 2));
        // The highest vertex is greener than the lowest, which is redder.
        let r = |i: usize| m.positions[i].length();
        let hi = (0..m.positions.len()).max_by(|&a, &b| r(a).total_cmp(&r(b))).unwrap();
        let lo = (0..m.positions.len()).min_by(|&a, &b| r(a).total_cmp(&r(b))).unwrap();
        let colour = |i: usize| s.material_sample(0, m.uvs[i]).albedo;
        let (top, bottom) = (colour(hi), colour(lo));
        assert!(top.y > top.x && bottom.x > bottom.y * 2.0, "{top} {bottom}");
        assert!(r(hi) > 1.0 && r(lo) < 1.0 && r(hi) - r(lo) <= 2.0 * 0.1 + 1e-6);
        // Outward normals.
        assert!(m.positions.iter().zip(&m.normals).all(|(p, n)| p.dot(*n) > 0.0));
    }

    #[test]
    fn the_specular_preset_is_grey_and_glossy_and_bad_values_are_named() {
        let s =
            bumpy("bumpy-specular", &BumpyParams { subdiv: 2, ..BumpyParams::specular() }).unwrap();
        assert!(s.textures.is_empty() && s.materials[0].is_specular());
        let bad = BumpyParams { amplitude: 0.0, ..Default::default() };
        assert!(bumpy("bumpy-sphere", &bad).unwrap_err().to_string().contains("amplitude"));
        let bad = BumpyParams { octaves: 0, ..Default::default() };
        assert!(bumpy("bumpy-sphere", &bad).unwrap_err().to_string().contains("octaves"));
        let bad = BumpyParams { specular: 2.0, ..Default::default() };
        assert!(bumpy("bumpy-sphere", &bad).unwrap_err().to_string().contains("specular"));
    }
}
