//! Differential cone tracing with coverage masks (Heitz and Neyret 2012) on the GPU: the mirror
//! of voxlod-cone's [`DifferentialRenderer`] over an octree of [`MicrosurfacePayload`], shaded
//! by [`shade_element`] (voxlod-cpu's `shade` with the element's visible colours, convolved
//! exponent and the ambient term on `ā(v)`), and a probe of its `f32` Smith functions
//! ([`DifferentialKernel::probe`]) for the stability check against `f64`.
//!
//! # Kernel (what a real GPU sees)
//! One invocation per pixel in 8×8 workgroups: its cone's elements one after the other (each a
//! quadrilinear read of 88-byte payloads: two levels × (descent + 8 corners)), the mask table
//! (256² × 16 bytes = 1 MiB, read once per element that meets a plane) and, for elements that
//! add coverage, the local illumination (two Λ: a 24-term series or a 30-term continued
//! fraction each) and a shadow cone (the same march without shading). The octree is uploaded
//! in voxlod-octree's flat layout ([`FlatOctree`]); payloads as 22 `f32` per node. Invocations
//! of a workgroup diverge where some cones stop at a surface and others cross open space or
//! graze a silhouette (the expensive case: several partial elements). A frame is split into
//! dispatches of at most [`PIXELS_PER_DISPATCH`] pixels (whole rows).
//!
//! # Agreement with the CPU (the equivalence suite's bound)
//! Every step follows the CPU's arithmetic in its order. What differs: world positions in
//! `f32` (the CPU goes through `f64`), WGSL's `exp`, `log2`, `atan2`, `sqrt` and `pow` (a few
//! ULP in Vulkan), and a compiler's fused multiply-adds. The march is continuous in these
//! except where a discrete choice flips: a mask-table cell (θ or v on a cell boundary moves a
//! few of the 128 rays), an element count (a step landing within rounding of the march's end),
//! a shadow cache decision. So most pixels agree to rounding, and a few by a few rays' share of
//! one element's radiance; the suite bounds the difference per pixel on 8-bit sRGB with the
//! fraction of pixels that must meet it.

use std::cell::OnceCell;

use glam::Vec3;
use voxlod_cone::differential::mask::MaskTable;
use voxlod_cone::{DifferentialRenderer, Light, SurfaceShadeInput};
use voxlod_cpu::shading::shade;
use voxlod_octree::{FlatOctree, GpuLevel, GpuNode, GpuTile, MicrosurfacePayload, Octree};
use voxlod_scene::{Image, LightSample, MaterialSample};

use crate::{Context, Result};

/// Smith's model in `f32` (prepended to the kernels).
pub const SMITH_WGSL: &str = include_str!("smith.wgsl");
/// The renderer (after `smith.wgsl` and `shading.wgsl`).
pub const WGSL: &str = include_str!("differential.wgsl");
/// The Λ / erfc probe (after `smith.wgsl`).
pub const PROBE_WGSL: &str = include_str!("probe.wgsl");

/// The renderer's whole source.
pub fn source() -> String {
    format!(
        "{SMITH_WGSL}\n{}\n{}\n{}\n{WGSL}",
        include_str!("../shading.wgsl"),
        crate::MORTON_WGSL,
        crate::OCTREE_WALK_WGSL
    )
}

/// The probe's whole source.
pub fn probe_source() -> String {
    format!("{SMITH_WGSL}\n{PROBE_WGSL}")
}

/// Pixels per dispatch, at most (whole rows; a bound on a dispatch's duration).
pub const PIXELS_PER_DISPATCH: u64 = 1 << 16;

/// Stands for an infinite distance in the kernel.
const BIG: f32 = 3.0e38;

/// The reference shader of an element (what the kernel computes): [`shade`] with the visible
/// colour `ā(v, l)`, the element's specular level and convolved exponent, its shading normal,
/// the light at its position and the visibility `V̄(l)·V_shadow`, plus `ā(v)·ambient`.
pub fn shade_element(s: &SurfaceShadeInput, light: &Light, ambient: Vec3) -> Vec3 {
    let il = &s.illumination;
    let m = MaterialSample {
        albedo: il.albedo,
        alpha: 1.0,
        specular: Vec3::splat(il.specular),
        shininess: il.exponent,
    };
    let sample = match light.at(s.position) {
        Some((to_light, irradiance, distance)) => LightSample { to_light, distance, irradiance },
        None => LightSample { to_light: Vec3::ZERO, distance: 0.0, irradiance: Vec3::ZERO },
    };
    shade(&m, il.normal, s.to_viewer, &sample, s.visibility, Vec3::ZERO)
        + il.ambient_albedo * ambient
}

/// The CPU reference of a frame: [`DifferentialRenderer::render`] with [`shade_element`], as
/// an [`Image`] (linear RGBA) and the element counts (primary, shaded, shadow).
pub fn reference(renderer: &DifferentialRenderer, ambient: Vec3) -> (Image, [u64; 3]) {
    let light = *renderer.light();
    let img = renderer.render(&|s: &SurfaceShadeInput| shade_element(s, &light, ambient));
    let mut out = Image::new(img.width, img.height, glam::Vec4::ZERO);
    out.pixels.copy_from_slice(&img.pixels);
    (out, [img.elements, img.shaded, img.shadow_elements])
}

/// The kernel's parameters, bound as a read-only storage buffer (mirrors WGSL `Params`; see
/// there for the fields).
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
pub struct GpuDifferentialParams {
    /// Forward, footprint per voxel.
    pub forward: [f32; 4],
    /// Scaled right, circle-of-confusion factor.
    pub right: [f32; 4],
    /// Scaled up, focus distance (voxels).
    pub up: [f32; 4],
    /// Eye in grid coordinates, longest march (voxels).
    pub origin: [f32; 4],
    /// Grid origin, voxel size.
    pub grid: [f32; 4],
    /// Light direction or position, 1 for a point light.
    pub light_a: [f32; 4],
    /// Irradiance or intensity, 1 for shadows.
    pub light_b: [f32; 4],
    /// Ambient, element factor.
    pub ambient: [f32; 4],
    /// Background, 1 for alpha blending.
    pub background: [f32; 4],
    /// Width, height, first row, rows.
    pub size: [u32; 4],
    /// Depth, finest dense level, unused ×2.
    pub tree: [u32; 4],
}

/// One pixel as the kernel writes it (mirrors WGSL `Pixel`).
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
pub struct GpuPixel {
    /// Linear RGBA.
    pub rgba: [f32; 4],
    /// Elements, shaded elements, shadow elements, unused.
    pub counts: [u32; 4],
}

/// A [`MicrosurfacePayload`] octree uploaded for the kernel.
pub struct GpuMicrosurfaceOctree {
    levels: wgpu::Buffer,
    nodes: wgpu::Buffer,
    tiles: wgpu::Buffer,
    payload: wgpu::Buffer,
    depth: u32,
    first_dense: u32,
    node_count: usize,
}

impl GpuMicrosurfaceOctree {
    /// Nodes uploaded (all levels).
    pub fn node_count(&self) -> usize {
        self.node_count
    }
}

/// The kernel on one [`Context`]: the renderer and the probe, compiled on first use, and the
/// mask table uploaded once.
pub struct DifferentialKernel<'a> {
    ctx: &'a Context,
    pipeline: OnceCell<wgpu::ComputePipeline>,
    probe: OnceCell<wgpu::ComputePipeline>,
    masks: OnceCell<wgpu::Buffer>,
    pixels_per_dispatch: u64,
}

impl<'a> DifferentialKernel<'a> {
    /// The kernel (compiled when first used).
    pub fn new(ctx: &'a Context) -> Self {
        Self {
            ctx,
            pipeline: OnceCell::new(),
            probe: OnceCell::new(),
            masks: OnceCell::new(),
            pixels_per_dispatch: PIXELS_PER_DISPATCH,
        }
    }

    /// Sets the most pixels per dispatch (whole rows, at least one): results do not depend on
    /// it.
    pub fn with_pixels_per_dispatch(mut self, pixels: u64) -> Self {
        self.pixels_per_dispatch = pixels.max(1);
        self
    }

    fn pipeline(&self) -> Result<&wgpu::ComputePipeline> {
        if let Some(p) = self.pipeline.get() {
            return Ok(p);
        }
        let p = self.ctx.pipeline("differential cone tracing", &source())?;
        Ok(self.pipeline.get_or_init(|| p))
    }

    fn masks(&self) -> Result<&wgpu::Buffer> {
        if let Some(b) = self.masks.get() {
            return Ok(b);
        }
        let table = MaskTable::get().masks();
        let b = self.ctx.storage_init("coverage mask table", bytemuck::cast_slice(table))?;
        Ok(self.masks.get_or_init(|| b))
    }

    /// Uploads `tree` in the flat layout ([`FlatOctree::from_octree`]).
    pub fn upload(&self, tree: &Octree<MicrosurfacePayload>) -> Result<GpuMicrosurfaceOctree> {
        let flat = FlatOctree::from_octree(tree).map_err(voxlod_cone::Error::from)?;
        let ctx = self.ctx;
        let levels: &[GpuLevel] = &flat.levels;
        let nodes: &[GpuNode] = &flat.nodes;
        // A binding holds at least one element: an octree without sparse levels has no tiles.
        let none = [GpuTile { links: [voxlod_octree::NONE; 3] }];
        let tiles: &[GpuTile] = if flat.tiles.is_empty() { &none } else { &flat.tiles };
        Ok(GpuMicrosurfaceOctree {
            levels: ctx.storage_array("octree levels", levels)?,
            nodes: ctx.storage_array("octree nodes", nodes)?,
            tiles: ctx.storage_array("octree tiles", tiles)?,
            payload: ctx
                .storage_init("microsurface payloads", bytemuck::cast_slice(&flat.payload))?,
            depth: tree.depth(),
            first_dense: tree.first_dense(),
            node_count: flat.nodes.len(),
        })
    }

    /// Renders `renderer`'s frame from the uploaded copy of its octree: what [`reference()`]
    /// computes on the CPU (same image up to the suite's bound), and the element counts.
    pub fn render(
        &self,
        tree: &GpuMicrosurfaceOctree,
        renderer: &DifferentialRenderer,
        ambient: Vec3,
    ) -> Result<(Image, [u64; 3])> {
        let ctx = self.ctx;
        let cam = renderer.camera();
        let (width, height) = (cam.width, cam.height);
        ctx.image_dispatch("differential image edge (workgroups of 8 pixels)", width, height)?;
        let pipeline = self.pipeline()?;
        let masks = self.masks()?;
        let count = width as u64 * height as u64;
        let out_bytes = count * size_of::<GpuPixel>() as u64;
        let out = ctx.storage_zeroed("differential pixels", out_bytes)?;
        let params = Self::params(tree, renderer, ambient);
        let rows_per = (self.pixels_per_dispatch / width as u64).clamp(1, height as u64) as u32;
        let mut first = 0;
        while first < height {
            let rows = rows_per.min(height - first);
            let p = GpuDifferentialParams { size: [width, height, first, rows], ..params };
            let p_buffer = ctx.uniform("differential params", bytemuck::bytes_of(&p))?;
            let buffers =
                [&p_buffer, &tree.levels, &tree.nodes, &tree.tiles, &tree.payload, masks, &out];
            let workgroups = ctx.image_dispatch("differential dispatch", width, rows)?;
            ctx.dispatch("differential cone tracing", pipeline, &buffers, workgroups)?;
            first += rows;
        }
        let raw = ctx.read(&out, out_bytes)?;
        let px: Vec<GpuPixel> = bytemuck::pod_collect_to_vec(&raw);
        let mut img = Image::new(width, height, glam::Vec4::ZERO);
        let mut counts = [0u64; 3];
        for (dst, p) in img.pixels.iter_mut().zip(&px) {
            *dst = glam::Vec4::from(p.rgba);
            for (total, &c) in counts.iter_mut().zip(&p.counts) {
                *total += c as u64;
            }
        }
        Ok((img, counts))
    }

    /// The parameters, from the renderer's own set-up ([`DifferentialRenderer::
    /// frame_constants`]).
    fn params(
        tree: &GpuMicrosurfaceOctree,
        r: &DifferentialRenderer,
        ambient: Vec3,
    ) -> GpuDifferentialParams {
        let c = r.frame_constants();
        let grid = r.tree().grid();
        let o = r.options();
        let finite = |x: f32| if x.is_finite() { x } else { BIG };
        let (light_a, light_b) = match *r.light() {
            Light::Directional { to_light, irradiance } => {
                (to_light.normalize().extend(0.0), irradiance)
            }
            Light::Point { position, intensity } => (position.extend(1.0), intensity),
        };
        let blend = o.compositing == voxlod_cone::Compositing::AlphaBlending;
        GpuDifferentialParams {
            forward: c.forward.extend(c.spread).to_array(),
            right: c.right.extend(c.coc).to_array(),
            up: c.up.extend(c.focus).to_array(),
            origin: c.origin.extend(finite(c.max_t)).to_array(),
            grid: grid.origin.as_vec3().extend(grid.voxel_size as f32).to_array(),
            light_a: light_a.to_array(),
            light_b: light_b.extend(if o.shadows { 1.0 } else { 0.0 }).to_array(),
            ambient: ambient.extend(o.element_factor).to_array(),
            background: o.background.extend(if blend { 1.0 } else { 0.0 }).to_array(),
            size: [0; 4],
            tree: [tree.depth, tree.first_dense, 0, 0],
        }
    }

    /// Smith's Λ (from `cos θ`, `sin θ`, `σ`) and `erfc(x)` evaluated by the kernel's `f32`
    /// functions on the GPU, one pair per input `[cos θ, sin θ, σ, x]`.
    pub fn probe(&self, inputs: &[[f32; 4]]) -> Result<Vec<[f32; 2]>> {
        if inputs.is_empty() {
            return Ok(Vec::new());
        }
        let ctx = self.ctx;
        let pipeline = match self.probe.get() {
            Some(p) => p,
            None => {
                let p = ctx.pipeline("Smith probe", &probe_source())?;
                self.probe.get_or_init(|| p)
            }
        };
        let input = ctx.storage_init("probe inputs", bytemuck::cast_slice(inputs))?;
        let bytes = inputs.len() as u64 * 8;
        let out = ctx.storage_zeroed("probe outputs", bytes)?;
        let workgroups = ctx.dispatch_size("Smith probe", (inputs.len() as u64).div_ceil(64))?;
        ctx.dispatch("Smith probe", pipeline, &[&input, &out], workgroups)?;
        Ok(bytemuck::pod_collect_to_vec(&ctx.read(&out, bytes)?))
    }
}

#[cfg(test)]
mod tests {
    use std::mem::offset_of;

    use super::*;
    use crate::layout::assert_mirrors;

    #[test]
    fn differential_types_mirror_their_wgsl() {
        let src = source();
        type P = GpuDifferentialParams;
        assert_mirrors(
            &src,
            "Params",
            size_of::<P>(),
            &[
                ("forward", offset_of!(P, forward)),
                ("right", offset_of!(P, right)),
                ("up", offset_of!(P, up)),
                ("origin", offset_of!(P, origin)),
                ("grid", offset_of!(P, grid)),
                ("light_a", offset_of!(P, light_a)),
                ("light_b", offset_of!(P, light_b)),
                ("ambient", offset_of!(P, ambient)),
                ("background", offset_of!(P, background)),
                ("size", offset_of!(P, size)),
                ("tree", offset_of!(P, tree)),
            ],
        );
        assert_mirrors(
            &src,
            "Pixel",
            size_of::<GpuPixel>(),
            &[("rgba", offset_of!(GpuPixel, rgba)), ("counts", offset_of!(GpuPixel, counts))],
        );
        assert_mirrors(
            &src,
            "Level",
            size_of::<GpuLevel>(),
            &[
                ("first", offset_of!(GpuLevel, first)),
                ("count", offset_of!(GpuLevel, count)),
                ("res_log2", offset_of!(GpuLevel, res_log2)),
                ("dense", offset_of!(GpuLevel, dense)),
                ("first_tile", offset_of!(GpuLevel, first_tile)),
            ],
        );
        // The payload is read as 22 f32 per node in field order (indices in the WGSL).
        type M = MicrosurfacePayload;
        assert_eq!(size_of::<M>(), 22 * 4);
        let offsets = [
            offset_of!(M, coverage),
            offset_of!(M, centroid),
            offset_of!(M, normal),
            offset_of!(M, normal_moments),
            offset_of!(M, height_variance),
            offset_of!(M, albedo),
            offset_of!(M, albedo_slope),
            offset_of!(M, specular),
            offset_of!(M, roughness),
        ];
        assert_eq!(offsets.map(|o| o / 4), [0, 1, 4, 7, 13, 14, 17, 20, 21]);
        assert!(src.contains("const FIELDS: u32 = 22u;"));
        let probe = probe_source();
        assert!(crate::layout::wgsl_struct(&probe, "Params").is_none());
    }
}
