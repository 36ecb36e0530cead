//! [`Material`]: base colour (factor × optional texture), Blinn-Phong specular, sidedness and
//! alpha mode; [`MaterialSample`] is what the shading function reads at a surface point.

use glam::{Vec2, Vec3, Vec4};

use crate::Texture;

/// How a material's alpha is used (glTF `alphaMode`).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub enum AlphaMode {
    /// Alpha ignored: fully opaque.
    #[default]
    Opaque,
    /// Alpha-tested: a surface point exists where alpha ≥ `cutoff`.
    Mask {
        /// The cutoff, 0.5 by default in glTF.
        cutoff: f32,
    },
    /// Alpha-blended. voxlod treats alpha as fractional coverage.
    Blend,
}

/// A texture bound to a material slot.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct TextureRef {
    /// Index into [`crate::Scene::textures`].
    pub texture: usize,
}

/// A surface material.
#[derive(Clone, Debug, PartialEq)]
pub struct Material {
    /// Name, for messages.
    pub name: String,
    /// Linear RGBA base colour factor (glTF baseColorFactor; OBJ `Kd` and `d`).
    pub base_color: Vec4,
    /// Base colour texture, multiplied with `base_color`.
    pub base_color_texture: Option<TextureRef>,
    /// Linear Blinn-Phong specular colour (OBJ `Ks`); zero means purely diffuse.
    pub specular: Vec3,
    /// Blinn-Phong exponent (OBJ `Ns`), ≥ 0.
    pub shininess: f32,
    /// Whether both faces are front faces (glTF doubleSided; leaves).
    pub double_sided: bool,
    /// Alpha mode.
    pub alpha_mode: AlphaMode,
}

impl Default for Material {
    fn default() -> Self {
        Self {
            name: "default".into(),
            base_color: Vec4::new(0.8, 0.8, 0.8, 1.0),
            base_color_texture: None,
            specular: Vec3::ZERO,
            shininess: 0.0,
            double_sided: false,
            alpha_mode: AlphaMode::Opaque,
        }
    }
}

/// A material evaluated at one surface point: what [`shade`](../../voxlod_cpu/shading/fn.shade.html)
/// reads.
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
pub struct MaterialSample {
    /// Linear diffuse albedo.
    pub albedo: Vec3,
    /// Coverage in [0, 1] after the alpha mode (0 or 1 for Mask, 1 for Opaque).
    pub alpha: f32,
    /// Linear specular colour.
    pub specular: Vec3,
    /// Blinn-Phong exponent.
    pub shininess: f32,
}

impl Material {
    /// A diffuse material of one linear colour.
    pub fn diffuse(name: &str, color: Vec3) -> Self {
        Self { name: name.into(), base_color: color.extend(1.0), ..Default::default() }
    }

    /// Whether the material has a specular lobe.
    pub fn is_specular(&self) -> bool {
        self.specular.max_element() > 0.0
    }

    /// Evaluates the material at texture coordinate `uv`. `textures` is the scene's texture
    /// list; a dangling texture index (rejected by [`crate::Scene::validate`]) reads as white.
    pub fn sample(&self, textures: &[Texture], uv: Vec2) -> MaterialSample {
        let mut color = self.base_color;
        if let Some(t) = self.base_color_texture.and_then(|r| textures.get(r.texture)) {
            color *= t.sample(uv);
        }
        let alpha = match self.alpha_mode {
            AlphaMode::Opaque => 1.0,
            AlphaMode::Mask { cutoff } => {
                if color.w >= cutoff {
                    1.0
                } else {
                    0.0
                }
            }
            AlphaMode::Blend => color.w.clamp(0.0, 1.0),
        };
        MaterialSample {
            albedo: color.truncate().clamp(Vec3::ZERO, Vec3::ONE),
            alpha,
            specular: self.specular.max(Vec3::ZERO),
            shininess: self.shininess.max(0.0),
        }
    }
}
