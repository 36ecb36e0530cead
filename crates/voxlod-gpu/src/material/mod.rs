//! Materials and textures on the GPU: [`WGSL`] is voxlod-scene's [`Material::sample`] and
//! [`Texture::sample`] in WGSL (`material.wgsl`), for every kernel that evaluates a surface
//! (the ground truth and the per-voxel precompute), and [`GpuMaterials`]
//! the buffers it reads: one [`GpuMaterial`] per material, a descriptor table (the two 8-bit
//! decode tables, then one [`GpuTextureDesc`] per texture: offset, width, height, sRGB and
//! wrap flags) and every texture's RGBA8 texels in one `u32` array.
//!
//! # Agreement with the CPU
//! Decoding is bit for bit: the sRGB table is voxlod's own ([`srgb_to_linear_table`]) and the
//! linear one holds the CPU's `c as f32 / 255.0` (WGSL's division and `unpack4x8unorm` are
//! not correctly rounded). Addressing is bit for bit for every |uv| < 2^23: the CPU computes
//! `x = uv·size − 0.5` in f64, takes its floor and `(x − x0) as f32`; the kernel redoes that
//! with 64-bit integers on `u32` pairs (the f64 rounding of `x` included), then wraps
//! (repeat, clamp, mirrored repeat) the same way. The bilinear weights combine the texels as
//! glam's `lerp` does, `a·(1 − s) + b·s`, which a GPU compiler may fuse into a
//! multiply-add: a sample differs from the CPU's by at most a few ULP, which
//! [`MaterialKernel`] lets the equivalence suite measure on each adapter. An alpha that lands
//! within those ULP of a mask cutoff, or of a blend test's random number, can flip.
//!
//! # Limits
//! A texture edge above [`MAX_TEXTURE_EDGE`] texels is refused ([`Error::TooLarge`]: the
//! exact addressing multiplies a 24-bit significand by the edge in 39 bits and reduces
//! modulo twice the edge in 16); all texels together must fit one storage binding (checked
//! against the device's `max_storage_buffer_binding_size` with the numbers, by
//! [`Context::storage_init`]).
//!
//! On a real GPU a sample is four dependent loads of 4 bytes (the texels, usually in one or
//! two cache lines) and ~100 integer operations for the exact addressing: small next to a BVH
//! traversal; neighbouring rays read neighbouring texels.
//!
//! [`Material::sample`]: voxlod_scene::Material::sample
//! [`Texture::sample`]: voxlod_scene::Texture::sample
//! [`srgb_to_linear_table`]: voxlod_format::records::quant::srgb_to_linear_table

use glam::{Vec2, Vec4};
use voxlod_format::records::quant::srgb_to_linear_table;
use voxlod_scene::{AlphaMode, Scene, WrapMode};

use crate::{Context, Error, Result};

/// The WGSL of materials and textures (needs the includer's `materials`, `textures` and
/// `texels` bindings, see the file's header).
pub const WGSL: &str = include_str!("material.wgsl");

/// The test kernel: [`WGSL`] with an entry point evaluating materials at given UVs.
pub const PROBE_WGSL: &str = concat!(include_str!("material.wgsl"), include_str!("probe.wgsl"));

/// The longest texture edge the kernels address exactly.
pub const MAX_TEXTURE_EDGE: u32 = 1 << 15;

/// A material as the kernels read it (mirrors WGSL `Material`).
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
pub struct GpuMaterial {
    /// Linear RGBA base colour factor.
    pub base_color: [f32; 4],
    /// Specular colour clamped to ≥ 0; `w` = shininess clamped to ≥ 0 (as `Material::sample`).
    pub specular: [f32; 4],
    /// Texture index + 1; 0 for none (or a dangling index, which the CPU reads as white).
    pub texture: u32,
    /// 0 opaque, 1 mask, 2 blend.
    pub alpha_mode: u32,
    /// The mask cutoff (0 otherwise).
    pub cutoff: f32,
    /// 1 if double-sided.
    pub double_sided: u32,
}

/// A texture's entry in the descriptor table (mirrors WGSL `TextureDesc`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
pub struct GpuTextureDesc {
    /// Index of its first texel in the texel array.
    pub offset: u32,
    /// Width in texels.
    pub width: u32,
    /// Height in texels.
    pub height: u32,
    /// Bit 0: sRGB colour; bits 1..3: wrap u; bits 3..5: wrap v (0 repeat, 1 clamp, 2 mirror).
    pub flags: u32,
}

/// The host-side contents of the three material buffers.
#[derive(Clone, Debug, PartialEq)]
pub struct GpuMaterials {
    /// One per scene material.
    pub materials: Vec<GpuMaterial>,
    /// The descriptor table's bytes: sRGB decode table, unorm decode table (256 `f32` each),
    /// then one [`GpuTextureDesc`] per texture (WGSL `Textures`).
    pub table: Vec<u8>,
    /// Every texture's RGBA8 texels, `r` in the low byte.
    pub texels: Vec<u32>,
}

fn wrap_code(w: WrapMode) -> u32 {
    match w {
        WrapMode::Repeat => 0,
        WrapMode::ClampToEdge => 1,
        WrapMode::MirroredRepeat => 2,
    }
}

/// The material buffers of `scene`; [`Error::TooLarge`] for a texture edge over
/// [`MAX_TEXTURE_EDGE`] or more texels than a `u32` indexes.
pub fn gpu_materials(scene: &Scene) -> Result<GpuMaterials> {
    let materials = scene
        .materials
        .iter()
        .map(|m| {
            let (alpha_mode, cutoff) = match m.alpha_mode {
                AlphaMode::Opaque => (0, 0.0),
                AlphaMode::Mask { cutoff } => (1, cutoff),
                AlphaMode::Blend => (2, 0.0),
            };
            let texture = m
                .base_color_texture
                .filter(|r| r.texture < scene.textures.len())
                .map_or(0, |r| r.texture as u32 + 1);
            // The CPU clamps specular and shininess in `Material::sample`, independent of uv.
            let s = m.sample(&[], Vec2::ZERO);
            GpuMaterial {
                base_color: m.base_color.to_array(),
                specular: s.specular.extend(s.shininess).to_array(),
                texture,
                alpha_mode,
                cutoff,
                double_sided: u32::from(m.double_sided),
            }
        })
        .collect();
    let mut table: Vec<u8> = Vec::new();
    table.extend_from_slice(bytemuck::cast_slice(srgb_to_linear_table()));
    let unorm: Vec<f32> = (0..256).map(|c| c as f32 / 255.0).collect();
    table.extend_from_slice(bytemuck::cast_slice(&unorm));
    let mut texels: Vec<u32> = Vec::new();
    for t in &scene.textures {
        if t.width.max(t.height) > MAX_TEXTURE_EDGE {
            return Err(Error::TooLarge {
                what: "texture edge in texels (exact GPU texture addressing)",
                requested: t.width.max(t.height) as u64,
                limit: MAX_TEXTURE_EDGE as u64,
            });
        }
        let offset = texels.len() as u64;
        if offset + t.texels.len() as u64 > u32::MAX as u64 {
            return Err(Error::TooLarge {
                what: "texels of all textures",
                requested: offset + t.texels.len() as u64,
                limit: u32::MAX as u64,
            });
        }
        let flags =
            u32::from(t.srgb) | wrap_code(t.sampler.wrap_u) << 1 | wrap_code(t.sampler.wrap_v) << 3;
        let desc =
            GpuTextureDesc { offset: offset as u32, width: t.width, height: t.height, flags };
        table.extend_from_slice(bytemuck::bytes_of(&desc));
        texels.extend(t.texels.iter().map(|&c| u32::from_le_bytes(c)));
    }
    if scene.textures.is_empty() {
        // WGSL's runtime-sized `descs` needs at least one element in the binding.
        table.extend_from_slice(bytemuck::bytes_of(&GpuTextureDesc::default()));
    }
    Ok(GpuMaterials { materials, table, texels })
}

/// The material buffers on one device.
pub struct MaterialBuffers {
    /// `array<Material>`.
    pub materials: wgpu::Buffer,
    /// `Textures` (decode tables and descriptors).
    pub textures: wgpu::Buffer,
    /// `array<u32>` of texels.
    pub texels: wgpu::Buffer,
}

impl GpuMaterials {
    /// Uploads the three buffers (each checked against the device's storage limits: an error
    /// with the numbers when the texels do not fit one binding).
    pub fn upload(&self, ctx: &Context) -> Result<MaterialBuffers> {
        Ok(MaterialBuffers {
            materials: ctx.storage_init("materials", bytemuck::cast_slice(&self.materials))?,
            textures: ctx.storage_init("texture descriptors", &self.table)?,
            texels: ctx.storage_init("texture texels", bytemuck::cast_slice(&self.texels))?,
        })
    }
}

/// The test kernel's parameters (mirrors WGSL `Params` of `probe.wgsl`).
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
pub struct GpuProbeParams {
    /// `x` = number of queries.
    pub counts: [u32; 4],
}

/// One answer of [`MaterialKernel::eval`]: the material's texture sample (white when
/// untextured) and its [`voxlod_scene::MaterialSample`]'s `(albedo, alpha)`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MaterialProbe {
    /// `Texture::sample(uv)` of the material's texture.
    pub texture: Vec4,
    /// Albedo (xyz) and alpha (w).
    pub sample: Vec4,
}

/// Materials evaluated on the GPU at given UVs, for the equivalence suite.
pub struct MaterialKernel<'a> {
    ctx: &'a Context,
    pipeline: wgpu::ComputePipeline,
}

impl<'a> MaterialKernel<'a> {
    /// Compiles the kernel.
    pub fn new(ctx: &'a Context) -> Result<Self> {
        Ok(Self { ctx, pipeline: ctx.pipeline("material probe", PROBE_WGSL)? })
    }

    /// Evaluates material `m` of `scene` at `uv` for every `(m, uv)` of `queries`
    /// ([`Error::TooLarge`] for a material index out of range: nothing is read out of bounds).
    pub fn eval(&self, scene: &Scene, queries: &[(u32, Vec2)]) -> Result<Vec<MaterialProbe>> {
        let ctx = self.ctx;
        if queries.is_empty() {
            return Ok(Vec::new());
        }
        if let Some(&(m, _)) = queries.iter().find(|q| q.0 as usize >= scene.materials.len()) {
            return Err(Error::TooLarge {
                what: "material index",
                requested: m as u64,
                limit: scene.materials.len().saturating_sub(1) as u64,
            });
        }
        let n = queries.len() as u64;
        if n > (u32::MAX / 2) as u64 {
            return Err(Error::TooLarge {
                what: "material queries",
                requested: n,
                limit: (u32::MAX / 2) as u64,
            });
        }
        let buffers = gpu_materials(scene)?.upload(ctx)?;
        let q: Vec<[f32; 4]> =
            queries.iter().map(|&(m, uv)| [uv.x, uv.y, f32::from_bits(m), 0.0]).collect();
        let params = GpuProbeParams { counts: [n as u32, 0, 0, 0] };
        let uniform = ctx.uniform("material probe params", bytemuck::bytes_of(&params))?;
        let input = ctx.storage_init("material queries", bytemuck::cast_slice(&q))?;
        let bytes = n * 32;
        let output = ctx.storage_zeroed("material results", bytes)?;
        let (x, y) = ctx.dispatch_size("material probe workgroups", n.div_ceil(64))?;
        let bound =
            [&uniform, &buffers.materials, &buffers.textures, &buffers.texels, &input, &output];
        ctx.dispatch("evaluating materials", &self.pipeline, &bound, (x, y))?;
        let raw = ctx.read(&output, bytes)?;
        let out: &[[f32; 4]] = bytemuck::cast_slice(&raw);
        Ok(out
            .chunks_exact(2)
            .map(|c| MaterialProbe {
                texture: Vec4::from_array(c[0]),
                sample: Vec4::from_array(c[1]),
            })
            .collect())
    }
}

#[cfg(test)]
mod tests {
    use std::mem::offset_of;
    use std::sync::Arc;

    use voxlod_scene::{Material, Sampler, Texture, TextureRef};

    use super::*;
    use crate::layout::assert_mirrors;

    #[test]
    fn material_types_mirror_their_wgsl() {
        // material.wgsl alone does not resolve (the includer declares its bindings).
        type M = GpuMaterial;
        assert_mirrors(
            PROBE_WGSL,
            "Material",
            size_of::<M>(),
            &[
                ("base_color", offset_of!(M, base_color)),
                ("specular", offset_of!(M, specular)),
                ("texture", offset_of!(M, texture)),
                ("alpha_mode", offset_of!(M, alpha_mode)),
                ("cutoff", offset_of!(M, cutoff)),
                ("double_sided", offset_of!(M, double_sided)),
            ],
        );
        type D = GpuTextureDesc;
        assert_mirrors(
            PROBE_WGSL,
            "TextureDesc",
            size_of::<D>(),
            &[
                ("offset", offset_of!(D, offset)),
                ("width", offset_of!(D, width)),
                ("height", offset_of!(D, height)),
                ("flags", offset_of!(D, flags)),
            ],
        );
        assert_mirrors(
            PROBE_WGSL,
            "Params",
            size_of::<GpuProbeParams>(),
            &[("counts", offset_of!(GpuProbeParams, counts))],
        );
    }

    fn texture(width: u32, height: u32) -> Texture {
        Texture {
            name: "t".into(),
            width,
            height,
            texels: Arc::from(vec![[1u8, 2, 3, 4]; (width * height) as usize]),
            srgb: true,
            sampler: Sampler { wrap_u: WrapMode::MirroredRepeat, wrap_v: WrapMode::ClampToEdge },
        }
    }

    #[test]
    fn buffers_hold_the_tables_descriptors_and_texels() {
        let mut scene = Scene {
            materials: vec![
                Material::default(),
                Material {
                    base_color_texture: Some(TextureRef { texture: 1 }),
                    alpha_mode: AlphaMode::Mask { cutoff: 0.25 },
                    double_sided: true,
                    shininess: -3.0,
                    ..Material::default()
                },
            ],
            textures: vec![texture(2, 3), texture(4, 1)],
            ..Default::default()
        };
        let g = gpu_materials(&scene).unwrap();
        assert_eq!(g.materials[0].texture, 0);
        assert_eq!(g.materials[0].alpha_mode, 0);
        let m = g.materials[1];
        assert_eq!((m.texture, m.alpha_mode, m.cutoff, m.double_sided), (2, 1, 0.25, 1));
        assert_eq!(m.specular[3], 0.0, "shininess clamped as Material::sample does");
        assert_eq!(g.texels.len(), 10);
        assert_eq!(g.texels[0], 0x0403_0201);
        let descs: &[GpuTextureDesc] = bytemuck::cast_slice(&g.table[2048..]);
        assert_eq!(
            descs[1],
            GpuTextureDesc { offset: 6, width: 4, height: 1, flags: 1 | 2 << 1 | 1 << 3 }
        );
        let tables: &[f32] = bytemuck::cast_slice(&g.table[..2048]);
        assert_eq!(tables[..256], srgb_to_linear_table()[..]);
        assert_eq!(tables[256 + 51].to_bits(), (51.0f32 / 255.0).to_bits());
        // A dangling texture index reads as untextured, as on the CPU.
        scene.materials[1].base_color_texture = Some(TextureRef { texture: 7 });
        assert_eq!(gpu_materials(&scene).unwrap().materials[1].texture, 0);
        // An edge over the exact-addressing limit is refused with the numbers.
        scene.textures[0] = texture(MAX_TEXTURE_EDGE + 1, 1);
        let err = gpu_materials(&scene).unwrap_err().to_string();
        assert!(err.contains("32769") && err.contains("32768"), "{err}");
    }
}
