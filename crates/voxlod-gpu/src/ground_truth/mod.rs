//! Kernel 3: the ground-truth renderer on the GPU, the mirror of
//! [`voxlod_cpu::render::ground_truth::render`]: `spp` stratified, jittered camera rays per
//! pixel through the CWBVH of [`crate::raycast`], each hit shaded with the interpolated
//! shading normal (flipped toward the viewer on double-sided materials), one shadow ray from
//! voxlod-cpu's offset origin, and the one shading function (`shading.wgsl`, a port of
//! [`voxlod_cpu::shading::shade`]); a miss adds the background; the samples are averaged with
//! equal weights (a box filter). The random numbers are voxlod-cpu's
//! ([`crate::random`]: the same PCG3D counters, equal bit for bit), so both backends send the
//! same rays up to float rounding.
//!
//! # What it covers (partial)
//! Opaque, untextured materials (base colour, Blinn-Phong specular, double-sided), directional
//! and point lights, shadows, ambient: every material of the builtin scenes except the
//! alpha-masked textured leaves of `forest` (`alpha=false` gives its untextured leaves). A
//! scene with a base-colour texture or an alpha mode other than opaque is refused with
//! [`Error::Unsupported`], never rendered differently. The pixel-centre G-buffer is produced
//! as on the CPU (voxlod-cpu's [`GTexel`], the same `#[repr(C)]` type, mirrored in WGSL), by
//! the last dispatch.
//!
//! # Kernel (what a real GPU sees)
//! One invocation per pixel in 8×8 workgroups: neighbouring camera rays are coherent, so they
//! walk the same BVH nodes and share cache lines; shadow rays toward one light are coherent
//! too. Each dispatch covers a range of samples of every pixel (at most
//! [`RAYS_PER_DISPATCH`] camera rays in all) and adds them in sample order to a running sum per
//! pixel, which bounds a dispatch's duration (watchdogs kill long dispatches on desktop GPUs)
//! and keeps the CPU's summation order. Expected on a real GPU: the cost of the closest-hit
//! traversal times (1 + shadow rays), divergence growing only at silhouettes and shadow edges.
//!
//! # Agreement with the CPU (the equivalence suite's bound)
//! The rays agree up to float rounding (WGSL's division and `normalize` are accurate to a few
//! ULP, and a compiler may fuse multiply-adds), so a sample whose camera ray grazes a triangle
//! edge, or whose shadow ray grazes a blocker's edge, may hit on one backend and miss on the
//! other; every other sample agrees to about 1e-6 relative. The suite compares 8-bit sRGB
//! images with a per-pixel bound and the fraction of pixels that must meet it.

use glam::{Vec3, Vec4};
use voxlod_cpu::raycast::Bvh;
use voxlod_cpu::render::ground_truth::{
    GBuffer, GTexel, GroundTruth, Options, check_options, validate,
};
use voxlod_cpu::render::sampling::Streams;
use voxlod_scene::{AlphaMode, Camera, Geometry, Image, Light, Scene};

use crate::raycast::{GpuBvh, entry, upload_bvh};
use crate::{Context, Error, Result, light_words};

/// The WGSL source of the kernel: RNG, shading, BVH traversal, then the renderer.
pub const WGSL: &str = concat!(
    include_str!("../random/random.wgsl"),
    include_str!("../shading.wgsl"),
    include_str!("../bvh.wgsl"),
    include_str!("ground_truth.wgsl")
);

/// Camera rays per dispatch, at most (a bound on a dispatch's duration on real GPUs).
pub const RAYS_PER_DISPATCH: u64 = 1 << 20;

/// The kernel's uniform parameters (mirrors WGSL `Params`).
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
    /// Width, height, samples per pixel, flags (1: shadows, 2: point light).
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
}

/// A material as the kernel evaluates it (mirrors WGSL `Material`).
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
pub struct GpuMaterial {
    /// Linear albedo, clamped to \[0, 1\]; `w` = 1 if double-sided.
    pub albedo: [f32; 4],
    /// Specular colour; `w` = shininess.
    pub specular: [f32; 4],
}

/// The materials of `scene` for the kernel, or [`Error::Unsupported`] for a textured or
/// non-opaque material (see the module docs).
pub fn gpu_materials(scene: &Scene) -> Result<Vec<GpuMaterial>> {
    scene
        .materials
        .iter()
        .enumerate()
        .map(|(i, m)| {
            if m.base_color_texture.is_some() || m.alpha_mode != AlphaMode::Opaque {
                return Err(Error::Unsupported {
                    what: "textured or alpha-masked/blended materials in the ground-truth \
                           kernel (opaque untextured materials only)",
                });
            }
            // The CPU's own evaluation (clamping included); UV is irrelevant untextured.
            let s = scene.material_sample(i as u32, glam::Vec2::ZERO);
            let flag = if m.double_sided { 1.0 } else { 0.0 };
            Ok(GpuMaterial {
                albedo: s.albedo.extend(flag).to_array(),
                specular: s.specular.extend(s.shininess).to_array(),
            })
        })
        .collect()
}

/// The per-triangle shading data of `geometry` (validated by the caller: indices in range).
pub fn gpu_shade_tris(geometry: &Geometry) -> Vec<GpuShadeTri> {
    (0..geometry.triangle_count())
        .map(|t| {
            let [a, b, c] = geometry.triangle(t);
            let [i, j, k] = geometry.indices[t].map(|i| i as usize);
            let n = |v: usize| geometry.normals[v].extend(0.0).to_array();
            GpuShadeTri {
                p0: a.extend(f32::from_bits(geometry.materials[t])).to_array(),
                p1: b.extend(0.0).to_array(),
                p2: c.extend(0.0).to_array(),
                n0: n(i),
                n1: n(j),
                n2: n(k),
            }
        })
        .collect()
}

/// A scene uploaded to one device for the ground-truth kernel.
pub struct GpuScene {
    bvh: GpuBvh,
    shade_tris: wgpu::Buffer,
    materials: wgpu::Buffer,
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
    /// checks on them ([`validate`], with a trivially valid camera and options), and refuses
    /// materials the kernel does not cover.
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
            materials: ctx.storage_init("materials", bytemuck::cast_slice(&materials))?,
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
        let flags = u32::from(shadows) | if point { 2 } else { 0 };
        let per_dispatch = (self.rays_per_dispatch / pixels).clamp(1, spp as u64) as u32;
        let layout = self.pipeline.get_bind_group_layout(0);
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
            let bind = ctx.guarded("binding ground-truth buffers", || {
                ctx.device().create_bind_group(&wgpu::BindGroupDescriptor {
                    label: Some("ground truth"),
                    layout: &layout,
                    entries: &[
                        entry(0, &uniform),
                        entry(1, &scene.bvh.nodes),
                        entry(2, &scene.bvh.tris),
                        entry(3, &scene.shade_tris),
                        entry(4, &scene.materials),
                        entry(5, &sums),
                        entry(6, &gbuffer),
                    ],
                })
            })?;
            let mut encoder = ctx.device().create_command_encoder(&Default::default());
            {
                let mut pass = encoder.begin_compute_pass(&Default::default());
                pass.set_pipeline(&self.pipeline);
                pass.set_bind_group(0, &bind, &[]);
                pass.dispatch_workgroups(lx, ly, 1);
            }
            ctx.submit("rendering the ground truth", encoder)?;
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
            gbuffer: GBuffer { width, height, texels },
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
        assert_mirrors(
            WGSL,
            "ShadeTri",
            size_of::<GpuShadeTri>(),
            &[
                ("p0", offset_of!(GpuShadeTri, p0)),
                ("p1", offset_of!(GpuShadeTri, p1)),
                ("p2", offset_of!(GpuShadeTri, p2)),
                ("n0", offset_of!(GpuShadeTri, n0)),
                ("n1", offset_of!(GpuShadeTri, n1)),
                ("n2", offset_of!(GpuShadeTri, n2)),
            ],
        );
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
        assert_mirrors(
            WGSL,
            "Material",
            size_of::<GpuMaterial>(),
            &[
                ("albedo", offset_of!(GpuMaterial, albedo)),
                ("specular", offset_of!(GpuMaterial, specular)),
            ],
        );
    }

    #[test]
    fn textured_and_alpha_materials_are_refused_not_approximated() {
        use voxlod_scene::{Material, TextureRef};
        let mut scene = Scene { materials: vec![Material::default()], ..Default::default() };
        assert_eq!(gpu_materials(&scene).unwrap().len(), 1);
        scene.materials[0].alpha_mode = AlphaMode::Blend;
        assert!(matches!(gpu_materials(&scene), Err(Error::Unsupported { .. })));
        scene.materials[0].alpha_mode = AlphaMode::Opaque;
        scene.materials[0].base_color_texture = Some(TextureRef { texture: 0 });
        assert!(matches!(gpu_materials(&scene), Err(Error::Unsupported { .. })));
    }
}
