//! glTF materials to [`Material`]s: baseColorFactor (linear), baseColorTexture (sRGB, with its
//! sampler's wrap modes and `KHR_texture_transform`), alphaMode/alphaCutoff, doubleSided.
//!
//! voxlod shades with Lambert plus Blinn-Phong: a glTF metallic-roughness material becomes a
//! diffuse material of its base colour (metallic, roughness and the other maps are not used),
//! so `specular` stays zero. Images are decoded only when a base colour texture uses them.

use std::collections::HashMap;
use std::io;
use std::path::Path;
use std::sync::Arc;

use ::gltf::json;
use glam::{Mat3, Vec2, Vec3, Vec4};
use json::validation::Checked;

use super::accessor::Data;
use super::buffers::read_uri;
use super::parse::err;
use crate::{AlphaMode, Material, Result, Sampler, Texture, TextureRef, WrapMode};

/// How a material's base colour texture maps a primitive's texture coordinates.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(super) struct UvMapping {
    /// The `TEXCOORD_n` set the texture reads, when the material has a texture.
    pub set: Option<u32>,
    /// `KHR_texture_transform` as an affine map of texture coordinates.
    pub transform: Option<Mat3>,
}

impl UvMapping {
    /// Applies the texture transform to one texture coordinate.
    pub fn apply(&self, uv: Vec2) -> Vec2 {
        self.transform.map_or(uv, |m| m.transform_point2(uv))
    }
}

/// Converted materials and textures, and each material's texture-coordinate mapping.
pub(super) struct Materials {
    /// One per glTF material.
    pub materials: Vec<Material>,
    /// One per glTF texture used as a base colour texture.
    pub textures: Vec<Texture>,
    /// Parallel to `materials`.
    pub uv: Vec<UvMapping>,
}

fn wrap(mode: &Checked<json::texture::WrappingMode>) -> WrapMode {
    use json::texture::WrappingMode as W;
    match mode {
        Checked::Valid(W::ClampToEdge) => WrapMode::ClampToEdge,
        Checked::Valid(W::MirroredRepeat) => WrapMode::MirroredRepeat,
        _ => WrapMode::Repeat,
    }
}

/// The spec's `translation * rotation * scale` texture-coordinate matrix.
fn texture_transform(t: &json::extensions::texture::TextureTransform) -> Option<Mat3> {
    let (o, r, s) = (Vec2::from_array(t.offset.0), t.rotation.0, Vec2::from_array(t.scale.0));
    let (sin, cos) = r.sin_cos();
    let rotation = Mat3::from_cols(Vec3::new(cos, sin, 0.0), Vec3::new(-sin, cos, 0.0), Vec3::Z);
    let m = Mat3::from_translation(o) * rotation * Mat3::from_scale(s);
    m.is_finite().then_some(m)
}

/// A decoded image: width, height and RGBA8 texels (shared by the textures using it).
type Decoded = (u32, u32, Arc<[[u8; 4]]>);

/// Decodes `images[i]` to RGBA8.
fn decode_image(
    data: &Data,
    i: usize,
    resolve: &mut dyn FnMut(&Path) -> io::Result<Vec<u8>>,
) -> Result<Decoded> {
    let element = format!("images[{i}]");
    let image = &data.root.images[i];
    let bytes = match (&image.uri, image.buffer_view) {
        (Some(uri), _) => {
            let base = data.path.parent().unwrap_or(Path::new(""));
            read_uri(uri, base, resolve).map_err(|e| err(data.path, &element, e))?
        }
        (None, Some(v)) => data.view(v.value())?.0.to_vec(),
        (None, None) => return Err(err(data.path, &element, "has neither uri nor bufferView")),
    };
    let img = image::load_from_memory(&bytes)
        .map_err(|e| err(data.path, &element, format!("cannot decode: {e}")))?;
    let img = img.into_rgba8();
    let (w, h) = img.dimensions();
    let texels: Vec<[u8; 4]> =
        img.into_raw().chunks_exact(4).map(|c| [c[0], c[1], c[2], c[3]]).collect();
    Ok((w, h, Arc::from(texels)))
}

/// Converts every material, decoding the images of base colour textures.
pub(super) fn materials(
    data: &Data,
    resolve: &mut dyn FnMut(&Path) -> io::Result<Vec<u8>>,
) -> Result<Materials> {
    let root = data.root;
    let mut out = Materials { materials: Vec::new(), textures: Vec::new(), uv: Vec::new() };
    let mut by_texture: HashMap<usize, usize> = HashMap::new();
    let mut images: HashMap<usize, Decoded> = HashMap::new();
    for (i, m) in root.materials.iter().enumerate() {
        let element = format!("materials[{i}]");
        let factor = Vec4::from_array(m.pbr_metallic_roughness.base_color_factor.0);
        if !factor.is_finite() {
            return Err(err(
                data.path,
                &element,
                format!("baseColorFactor {factor} is not finite"),
            ));
        }
        let mut uv = UvMapping::default();
        let mut texture = None;
        if let Some(info) = &m.pbr_metallic_roughness.base_color_texture {
            let t = info.index.value();
            let transform = info.extensions.as_ref().and_then(|e| e.texture_transform.as_ref());
            uv.set = Some(transform.and_then(|t| t.tex_coord).unwrap_or(info.tex_coord));
            if let Some(tt) = transform {
                uv.transform = Some(texture_transform(tt).ok_or_else(|| {
                    err(
                        data.path,
                        &element,
                        "KHR_texture_transform of baseColorTexture is not finite",
                    )
                })?);
            }
            let index = match by_texture.get(&t) {
                Some(&k) => k,
                None => {
                    let tex = &root.textures[t];
                    let src = tex.source.value();
                    let (width, height, texels) = match images.entry(src) {
                        std::collections::hash_map::Entry::Occupied(e) => e.get().clone(),
                        std::collections::hash_map::Entry::Vacant(e) => {
                            e.insert(decode_image(data, src, resolve)?).clone()
                        }
                    };
                    let sampler = tex.sampler.map(|s| &root.samplers[s.value()]);
                    let name = tex.name.clone().or_else(|| root.images[src].name.clone());
                    out.textures.push(Texture {
                        name: name.unwrap_or_else(|| format!("textures[{t}]")),
                        width,
                        height,
                        texels,
                        srgb: true,
                        sampler: Sampler {
                            wrap_u: sampler.map_or(WrapMode::Repeat, |s| wrap(&s.wrap_s)),
                            wrap_v: sampler.map_or(WrapMode::Repeat, |s| wrap(&s.wrap_t)),
                        },
                    });
                    by_texture.insert(t, out.textures.len() - 1);
                    out.textures.len() - 1
                }
            };
            texture = Some(TextureRef { texture: index });
        }
        let alpha_mode = match m.alpha_mode {
            Checked::Valid(json::material::AlphaMode::Mask) => {
                let cutoff = m.alpha_cutoff.as_ref().map_or(0.5, |c| c.0);
                if !cutoff.is_finite() {
                    return Err(err(
                        data.path,
                        &element,
                        format!("alphaCutoff {cutoff} is not finite"),
                    ));
                }
                AlphaMode::Mask { cutoff }
            }
            Checked::Valid(json::material::AlphaMode::Blend) => AlphaMode::Blend,
            _ => AlphaMode::Opaque,
        };
        out.materials.push(Material {
            name: m.name.clone().unwrap_or_else(|| element.clone()),
            base_color: factor,
            base_color_texture: texture,
            specular: Vec3::ZERO,
            shininess: 0.0,
            double_sided: m.double_sided,
            alpha_mode,
        });
        out.uv.push(uv);
    }
    Ok(out)
}

/// The glTF default material (for primitives without one): white, opaque, single-sided.
pub(super) fn default_material() -> Material {
    Material { name: "default".into(), base_color: Vec4::ONE, ..Material::default() }
}
