//! The ground-truth renderer on the GPU, the mirror of
//! [`voxlod_cpu::render::ground_truth::render`]: `spp` stratified, jittered camera rays per
//! pixel through the CWBVH of [`crate::raycast`], each hit shaded with the interpolated
//! shading normal (flipped toward the viewer on double-sided materials), one shadow ray from
//! voxlod-cpu's offset origin, and the one shading function (`shading.wgsl`, a port of
//! [`voxlod_cpu::shading::shade`]); a miss adds the background; the samples are averaged with
//! equal weights (a box filter). The random numbers are voxlod-cpu's
//! ([`crate::random`]: the same PCG3D counters, equal bit for bit), so both backends send the
//! same rays up to float rounding.
//!
//! # What it covers
//! Every material of voxlod-scene: base colour factor × base-colour texture (bilinear, wrap
//! modes, sRGB decode: [`crate::material`], bit for bit the CPU's addressing and decoding),
//! Blinn-Phong specular, double-sided, and the alpha modes as voxlod-cpu's `surface.rs` applies
//! them to camera **and** shadow rays inside the BVH walk (`bvh_alpha.wgsl`): `Mask` keeps a
//! hit where the sampled alpha reaches the cutoff, `Blend` keeps a hit on triangle `t` when
//! `rand_f32(pixel, sample, key ^ t) < alpha` with the CPU's keys (camera, shadow) and sample
//! indices (the pixel-centre ray uses `u32::MAX`), so both backends cut the same holes.
//! Directional and point lights, shadows, ambient. What is still refused with
//! [`Error::Unsupported`]: a host-side light filter ([`Options::light_filter`]). Textures must
//! fit the device's storage binding and have edges ≤ [`crate::material::MAX_TEXTURE_EDGE`]
//! (errors with the numbers). The pixel-centre G-buffer is produced as on the CPU (voxlod-cpu's
//! [`GTexel`], the same `#[repr(C)]` type, mirrored in WGSL; albedo textured), by the last
//! dispatch.
//!
//! # Kernel (what a real GPU sees)
//! One invocation per pixel in 8×8 workgroups, its rays (camera, shadow, pixel centre) cast from
//! one call site of the traversal in a loop, because drivers inline every call site (three copies
//! of the alpha-tested walk and the texture sampling would triple the shader a driver compiles):
//! neighbouring camera rays are coherent, so they walk the same BVH nodes and share cache lines;
//! shadow rays toward one light are coherent too. Each dispatch covers a range of samples of every
//! pixel (at most [`RAYS_PER_DISPATCH`] camera rays in all) and adds them in sample order to a
//! running sum per pixel, which bounds a dispatch's duration (watchdogs kill long dispatches on
//! desktop GPUs) and keeps the CPU's summation order. Expected on a real GPU: the cost of the
//! closest-hit traversal times (1 + shadow rays), divergence growing only at silhouettes and shadow
//! edges.
//!
//! # Agreement with the CPU (the equivalence suite's bound)
//! The rays agree up to float rounding (WGSL's division and `normalize` are accurate to a few
//! ULP, and a compiler may fuse multiply-adds), so a sample whose camera ray grazes a triangle
//! edge, or whose shadow ray grazes a blocker's edge, may hit on one backend and miss on the
//! other; so may a sample whose alpha lands within a few ULP of a mask cutoff or of its blend
//! test's random number (the texture lerp may be fused on the GPU); every other sample agrees
//! to about 1e-6 relative. The suite compares 8-bit sRGB
//! images with a per-pixel bound and the fraction of pixels that must meet it.

use glam::{Vec3, Vec4};
use voxlod_cpu::raycast::Bvh;
use voxlod_cpu::render::ground_truth::{
    GBuffer, GTexel, GroundTruth, Options, check_options, validate,
};
use voxlod_cpu::render::pixel_samples::Streams;
use voxlod_scene::{AlphaMode, Camera, Geometry, Image, Light, Scene};

use crate::material::{MaterialBuffers, gpu_materials};
use crate::raycast::{GpuBvh, upload_bvh};
use crate::{Context, Error, Result, light_words};

/// The WGSL source of the kernel: RNG, shading, BVH traversal, then the renderer.
pub const WGSL: &str = concat!(
    include_str!("../random/random.wgsl"),
    include_str!("../shading.wgsl"),
    include_str!("../material/material.wgsl"),
    include_str!("../bvh.wgsl"),
    include_str!("../bvh_alpha.wgsl"),
    include_str!("ground_truth.wgsl")
);

/// Camera rays per dispatch, at most (a bound on a dispatch's duration on real GPUs).
pub const RAYS_PER_DISPATCH: u64 = 1 << 20;

/// The kernel's parameters (mirrors WGSL `Params`).
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
pub struct GpuGroundTruthParams {
    /// Camera eye.
    pub eye: [f32; 4],
    /// Unit view direction.
    pub forward: [f32; 4],
    /// Right vector scaled by tan(fov/2)·aspect.
    pub right: [f32; 4],
    /// Up vector scaled by tan(fov/2).
    pub up: [f32; 4],
    /// Background colour (linear RGB).
    pub background: [f32; 4],
    /// Ambient term of the shading function.
    pub ambient: [f32; 4],
    /// Directional light: unit direction toward it; point light: its position.
    pub light_a: [f32; 4],
    /// Directional light: irradiance; point light: intensity.
    pub light_b: [f32; 4],
    /// Width, height, samples per pixel, flags (1: shadows, 2: point light, 4: a material
    /// is alpha-masked or blended, so hits go through the alpha test).
    pub size: [u32; 4],
    /// First and end sample of this dispatch.
    pub samples: [u32; 4],
    /// The random stream keys ([`Streams`]): jitter x, jitter y, alpha primary, alpha shadow.
    pub streams: [u32; 4],
}

/// A triangle's shading data, indexed by triangle id (mirrors WGSL `ShadeTri`).
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
pub struct GpuShadeTri {
    /// Vertex 0; `w` = material index (as `f32` bits).
    pub p0: [f32; 4],
    /// Vertex 1.
    pub p1: [f32; 4],
    /// Vertex 2.
    pub p2: [f32; 4],
    /// Shading normal at vertex 0.
    pub n0: [f32; 4],
    /// Shading normal at vertex 1.
    pub n1: [f32; 4],
    /// Shading normal at vertex 2.
    pub n2: [f32; 4],
    /// UVs of vertices 0 (`xy`) and 1 (`zw`).
    pub uv01: [f32; 4],
    /// UV of vertex 2 (`xy`).
    pub uv2: [f32; 4],
}

/// The per-triangle shading data of `geometry` (validated by the caller: indices in range).
pub fn gpu_shade_tris(geometry: &Geometry) -> Vec<GpuShadeTri> {
    (0..geometry.triangle_count())
        .map(|t| {
            let [a, b, c] = geometry.triangle(t);
            let [i, j, k] = geometry.indices[t].map(|i| i as usize);
            let n = |v: usize| geometry.normals[v].extend(0.0).to_array();
            let uv = |v: usize| geometry.uvs[v];
            GpuShadeTri {
                p0: a.extend(f32::from_bits(geometry.materials[t])).to_array(),
                p1: b.extend(0.0).to_array(),
                p2: c.extend(0.0).to_array(),
                n0: n(i),
                n1: n(j),
                n2: n(k),
                uv01: [uv(i).x, uv(i).y, uv(j).x, uv(j).y],
                uv2: [uv(k).x, uv(k).y, 0.0, 0.0],
            }
        })
        .collect()
}

/// A scene uploaded to one device for the ground-truth kernel.
pub struct GpuScene {
    bvh: GpuBvh,
    shade_tris: wgpu::Buffer,
    materials: MaterialBuffers,
    any_alpha: bool,
    light: Light,
    background: Vec3,
}

/// The ground-truth kernel, compiled for one [`Context`].
pub struct GroundTruthKernel<'a> {
    ctx: &'a Context,
    pipeline: wgpu::ComputePipeline,
    rays_per_dispatch: u64,
}

impl<'a> GroundTruthKernel<'a> {
    /// Compiles the kernel.
    pub fn new(ctx: &'a Context) -> Result<Self> {
        Ok(Self {
            ctx,
            pipeline: ctx.pipeline("ground truth", WGSL)?,
            rays_per_dispatch: RAYS_PER_DISPATCH,
        })
    }

    /// Sets the most camera rays per dispatch (at least one sample of every pixel per
    /// dispatch whatever the value): smaller keeps each dispatch shorter. The image does not
    /// depend on it — the samples are added in the same order — which the equivalence suite
    /// checks bit for bit.
    pub fn with_rays_per_dispatch(mut self, rays: u64) -> Self {
        self.rays_per_dispatch = rays.max(1);
        self
    }

    /// Uploads `scene` (flattened to `geometry`, with `bvh` over it) after the CPU renderer's
    /// checks on them ([`validate`], with a trivially valid camera and options), with its
    /// materials and textures ([`crate::material`]: an error with the numbers for textures
    /// over the device's storage limits or the exact-addressing edge).
    pub fn upload(&self, scene: &Scene, geometry: &Geometry, bvh: &Bvh) -> Result<GpuScene> {
        let probe = Camera::look_at(Vec3::ZERO, Vec3::Z, Vec3::Y, 40.0);
        let options = Options { width: 1, height: 1, spp: 1, ..Options::default() };
        validate(scene, geometry, bvh, &probe, &options)?;
        let materials = gpu_materials(scene)?;
        let tris = gpu_shade_tris(geometry);
        let ctx = self.ctx;
        Ok(GpuScene {
            bvh: upload_bvh(ctx, bvh, geometry)?,
            shade_tris: ctx.storage_init("shading triangles", bytemuck::cast_slice(&tris))?,
            materials: materials.upload(ctx)?,
            any_alpha: scene.materials.iter().any(|m| m.alpha_mode != AlphaMode::Opaque),
            light: scene.light().validated().map_err(voxlod_cpu::Error::from)?,
            background: scene.background,
        })
    }

    /// Renders the uploaded scene from `camera`: what
    /// [`voxlod_cpu::render::ground_truth::render`] returns (linear RGB with the background
    /// composited, alpha = coverage, and the pixel-centre G-buffer), with the same errors for
    /// bad options or camera; [`Error::Unsupported`] when `options.light_filter` is set (the
    /// kernel cannot call a host-side filter; the CPU renderer takes it).
    pub fn render(
        &self,
        scene: &GpuScene,
        camera: &Camera,
        options: &Options,
    ) -> Result<GroundTruth> {
        let ctx = self.ctx;
        let Options { width, height, spp, seed, ambient, shadows, light_filter: _ } = *options;
        // Only the option and camera checks can fail here: the scene was checked on upload.
        check(options, camera)?;
        let frame = camera.frame(width, height);
        let streams = Streams::new(seed);
        let pixels = width as u64 * height as u64;
        let (lx, ly) =
            ctx.image_dispatch("ground-truth image edge (workgroups of 8 pixels)", width, height)?;
        let bytes = pixels * 16;
        let sums = ctx.storage_zeroed("ground-truth sums", bytes)?;
        let texel_bytes = pixels * size_of::<GTexel>() as u64;
        let gbuffer = ctx.storage_zeroed("ground-truth G-buffer", texel_bytes)?;
        let (point, la, lb) = light_words(&scene.light);
        let flags =
            u32::from(shadows) | if point { 2 } else { 0 } | if scene.any_alpha { 4 } else { 0 };
        let per_dispatch = (self.rays_per_dispatch / pixels).clamp(1, spp as u64) as u32;
        let mut first = 0;
        while first < spp {
            let end = first.saturating_add(per_dispatch).min(spp);
            let params = GpuGroundTruthParams {
                eye: frame.eye.extend(0.0).to_array(),
                forward: frame.forward.extend(0.0).to_array(),
                right: frame.right.extend(0.0).to_array(),
                up: frame.up.extend(0.0).to_array(),
                background: scene.background.extend(0.0).to_array(),
                ambient: ambient.extend(0.0).to_array(),
                light_a: la.extend(0.0).to_array(),
                light_b: lb.extend(0.0).to_array(),
                size: [width, height, spp, flags],
                samples: [first, end, u32::from(end == spp), 0],
                streams: [
                    streams.jitter_x,
                    streams.jitter_y,
                    streams.alpha_primary,
                    streams.alpha_shadow,
                ],
            };
            let uniform = ctx.uniform("ground-truth params", bytemuck::bytes_of(&params))?;
            let buffers = [
                &uniform,
                &scene.bvh.nodes,
                &scene.bvh.tris,
                &scene.shade_tris,
                &scene.materials.materials,
                &sums,
                &gbuffer,
                &scene.materials.textures,
                &scene.materials.texels,
            ];
            ctx.dispatch("rendering the ground truth", &self.pipeline, &buffers, (lx, ly))?;
            first = end;
        }
        let raw = ctx.read(&sums, bytes)?;
        let sums: &[[f32; 4]] = bytemuck::cast_slice(&raw);
        // The CPU's normalization, on the host: (sum / spp, hits / spp).
        let pixels = sums
            .iter()
            .map(|s| (Vec3::new(s[0], s[1], s[2]) / spp as f32).extend(s[3] / spp as f32))
            .collect::<Vec<Vec4>>();
        let raw = ctx.read(&gbuffer, texel_bytes)?;
        let mut texels: Vec<GTexel> = bytemuck::pod_collect_to_vec(&raw);
        for (t, p) in texels.iter_mut().zip(&pixels) {
            t.coverage = p.w;
        }
        Ok(GroundTruth {
            image: Image { width, height, pixels },
            gbuffer: GBuffer { width, height, texels, eye: frame.eye },
        })
    }
}

/// The option and camera checks of the CPU renderer.
fn check(options: &Options, camera: &Camera) -> Result<()> {
    check_options(options)?;
    if options.light_filter.is_some() {
        // A host-side closure cannot run in the kernel: refuse rather than drop the shadow.
        return Err(Error::Unsupported {
            what: "a light filter (Options::light_filter) in the ground-truth kernel; render \
                   with voxlod_cpu::render::ground_truth::render",
        });
    }
    camera.validate().map_err(voxlod_cpu::Error::from)?;
    Ok(())
}

/// Asserts that [`GpuShadeTri`] matches its WGSL mirror `ShadeTri` in `source` (the ground
/// truth and the precompute read the same shading triangles).
#[cfg(test)]
pub(crate) fn assert_shade_tri_mirrors(source: &str) {
    use std::mem::offset_of;

    crate::layout::assert_mirrors(
        source,
        "ShadeTri",
        size_of::<GpuShadeTri>(),
        &[
            ("p0", offset_of!(GpuShadeTri, p0)),
            ("p1", offset_of!(GpuShadeTri, p1)),
            ("p2", offset_of!(GpuShadeTri, p2)),
            ("n0", offset_of!(GpuShadeTri, n0)),
            ("n1", offset_of!(GpuShadeTri, n1)),
            ("n2", offset_of!(GpuShadeTri, n2)),
            ("uv01", offset_of!(GpuShadeTri, uv01)),
            ("uv2", offset_of!(GpuShadeTri, uv2)),
        ],
    );
}

#[cfg(test)]
mod tests {
    use std::mem::offset_of;

    use super::*;
    use crate::layout::assert_mirrors;

    #[test]
    fn a_light_filter_is_refused_not_ignored() {
        let camera = Camera::look_at(Vec3::new(0.0, 0.0, 3.0), Vec3::ZERO, Vec3::Y, 40.0);
        let plain = Options { width: 4, height: 4, spp: 1, ..Options::default() };
        assert!(check(&plain, &camera).is_ok());
        let half = |_: Vec3| 0.5;
        let filtered = Options { light_filter: Some(&half), ..plain };
        let err = check(&filtered, &camera).unwrap_err();
        assert!(matches!(err, Error::Unsupported { .. }), "{err}");
        assert!(err.to_string().contains("light filter"), "{err}");
    }

    /// `trace_alpha` walks the BVH exactly as `trace` does: the node part of its loop is the
    /// same text (only the primitive loop, where the alpha test goes, differs).
    #[test]
    fn the_alpha_walk_is_the_plain_walk() {
        let node_walk = |src: &str, f: &str| {
            let body = &src[src.find(f).expect("the function")..];
            let start = body.find("        if (current.y & 0xff000000u) != 0u {").unwrap();
            let end = body[start..].find("    return best;").unwrap();
            body[start..start + end].to_string()
        };
        let plain = node_walk(include_str!("../bvh.wgsl"), "fn trace(");
        let alpha = node_walk(include_str!("../bvh_alpha.wgsl"), "fn trace_alpha(");
        assert!(plain.len() > 500);
        assert_eq!(plain, alpha);
    }

    #[test]
    fn ground_truth_types_mirror_their_wgsl() {
        type P = GpuGroundTruthParams;
        assert_mirrors(
            WGSL,
            "Params",
            size_of::<P>(),
            &[
                ("eye", offset_of!(P, eye)),
                ("forward", offset_of!(P, forward)),
                ("right", offset_of!(P, right)),
                ("up", offset_of!(P, up)),
                ("background", offset_of!(P, background)),
                ("ambient", offset_of!(P, ambient)),
                ("light_a", offset_of!(P, light_a)),
                ("light_b", offset_of!(P, light_b)),
                ("size", offset_of!(P, size)),
                ("samples", offset_of!(P, samples)),
                ("streams", offset_of!(P, streams)),
            ],
        );
        assert_shade_tri_mirrors(WGSL);
        assert_mirrors(
            WGSL,
            "GTexel",
            size_of::<GTexel>(),
            &[
                ("position", offset_of!(GTexel, position)),
                ("depth", offset_of!(GTexel, depth)),
                ("normal", offset_of!(GTexel, normal)),
                ("coverage", offset_of!(GTexel, coverage)),
                ("albedo", offset_of!(GTexel, albedo)),
                ("triangle", offset_of!(GTexel, triangle)),
            ],
        );
    }
}
