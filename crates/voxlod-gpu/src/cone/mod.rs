//! Kernel 5: voxel cone tracing from shading points on the GPU, the mirror of voxlod-cone's
//! [`ConeTracer`]: per shading point, ambient occlusion and diffuse indirect light `E/π` from
//! the same `n` cosine-distributed cones ([`ConeTracer::ao_and_diffuse`]), and the specular
//! cone along the mirror direction with its aperture from the glossiness
//! ([`ConeTracer::specular`]). The radiance octree is uploaded as voxlod-octree's flat layout
//! ([`FlatOctree`]: one level table, one node array, the sparse levels' tiles with their +x,
//! +y, +z links) plus one payload per node, and sampled quadrilinearly in WGSL exactly as
//! [`Octree::sample_at_level`] does: trilinear within a level (the lower corner found by a
//! descent from the finest dense level, the seven others by the flat neighbour rule), linear
//! between two levels.
//!
//! # What it covers
//! Every [`ConeMedium`] voxlod-cone builds or traces for AO: [`RadiancePayload`] and
//! `Directional<RadiancePayload>` (six directional opacities, blended by `dir²` as
//! [`voxlod_octree::Directional::opacity_along`]), and [`AveragePayload`] /
//! `Directional<AveragePayload>` (opacity only: no radiance, for AO) — the [`GpuMedium`]
//! implementations. [`TraceOptions`] are validated by [`TraceOptions::validate`], so bad
//! options get voxlod-cone's error word for word ([`crate::Error::Cone`]); an octree with
//! more nodes than a `u32` indexes gets voxlod-octree's [`voxlod_octree::Error::TooManyNodes`].
//! Shading inputs are per pixel and not errors, as on the CPU: a non-finite position or
//! normal, or a zero normal, gives AO 1 and no radiance; a zero or non-finite `to_viewer` no
//! specular; a NaN glossiness is 0. [`ConeQuery`] chooses what is traced: one march per
//! diffuse cone serves AO and diffuse light together (and, as on the CPU, such a march stops
//! at the AO radius, not at `max_distance`, when AO is asked for).
//!
//! # Kernel (what a real GPU sees)
//! One invocation per shading point in 8×8 workgroups over the G-buffer (a tile of
//! neighbouring pixels: their positions and normals are close, so their cones read the same
//! octree nodes — the coarse levels especially — and share cache lines). Each invocation
//! marches its cones one after the other; a march's length depends on the opacity it meets,
//! so invocations of a workgroup diverge where some cones stop early (at a wall) and others
//! cross open space; misses (flag 0) return at once. Memory traffic per sample is at most two
//! levels × (descent + 8 corners), mostly in the dense top levels for wide cones. A frame is
//! split into dispatches of at most [`POINTS_PER_DISPATCH`] shading points (whole rows) to
//! bound a dispatch's duration (desktop watchdogs). Expected on a real GPU: bound by
//! dependent loads (pointer chasing in the sparse levels) rather than arithmetic; narrow
//! specular cones, which read the fine sparse levels, cost the most per sample.
//!
//! # Agreement with the CPU (the equivalence suite's bound)
//! The WGSL follows the CPU's arithmetic in its order (dot products `x + y + z`, products left
//! to right, `normalize` as `v·(1/|v|)`, the diffuse apertures' `tan` and the direction set
//! computed on the host by voxlod-cone's own code). What differs: world → grid coordinates in
//! `f32` (the CPU goes through `f64`), WGSL's `log2`, `exp2`, `pow` and `tan` (the specular
//! aperture), which Vulkan bounds only to a few ULP or 2⁻²¹ absolute, and a compiler's fused
//! multiply-adds. The march is continuous in these values except where a sample count changes:
//! a step landing within rounding of the end of the march (`max_distance`, the AO radius
//! test) or of the opacity cutoff adds or drops one sample. So most points agree to ~1e-6 and
//! a few may differ by one sample's contribution; the suite bounds the difference per point
//! with the fraction of points that must meet it.

use std::cell::OnceCell;

use glam::Vec3;
use voxlod_cone::tracer::hemisphere_directions;
use voxlod_cone::{ConeMedium, ConeTracer, RadiancePayload, TraceOptions};
use voxlod_cpu::render::ground_truth::GBuffer;
use voxlod_octree::{AveragePayload, Directional, FlatOctree, GpuLevel, GpuNode, GpuTile, Octree};

use crate::raycast::entry;
use crate::{Context, Result};

/// The march, sampling and tracer (the payload comes first: [`ISOTROPIC_WGSL`] or
/// [`DIRECTIONAL_WGSL`]).
pub const WGSL: &str = include_str!("cone.wgsl");
/// The isotropic payload's WGSL (struct and accessors).
pub const ISOTROPIC_WGSL: &str = include_str!("isotropic.wgsl");
/// The directional payload's WGSL.
pub const DIRECTIONAL_WGSL: &str = include_str!("directional.wgsl");

/// The kernel's whole source for a payload kind.
pub fn source(directional: bool) -> String {
    let payload = if directional { DIRECTIONAL_WGSL } else { ISOTROPIC_WGSL };
    format!("{payload}\n{WGSL}")
}

/// Shading points per dispatch, at most (whole rows; a bound on a dispatch's duration).
pub const POINTS_PER_DISPATCH: u64 = 1 << 18;

/// Stands for an infinite distance in the kernel (WGSL leaves infinities indeterminate).
const BIG: f32 = 3.0e38;

/// An isotropic node payload as the kernel reads it (mirrors WGSL `Payload` of
/// `isotropic.wgsl`). 16 bytes.
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
pub struct GpuRadiance {
    /// Radiance × opacity (zero for AO-only payloads).
    pub radiance_alpha: [f32; 3],
    /// Opacity.
    pub opacity: f32,
}

/// A directional node payload as the kernel reads it (mirrors WGSL `Payload` of
/// `directional.wgsl`): 48 bytes, of which 8 are padding keeping each `vec3` on 16 bytes.
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
pub struct GpuDirectionalRadiance {
    /// Radiance × opacity.
    pub radiance_alpha: [f32; 3],
    /// Isotropic opacity.
    pub opacity: f32,
    /// Opacity along +x, +y, +z.
    pub plus: [f32; 3],
    /// Padding.
    pub pad0: f32,
    /// Opacity along −x, −y, −z.
    pub minus: [f32; 3],
    /// Padding.
    pub pad1: f32,
}

/// A payload the kernel can march through (see the module docs for the list).
pub trait GpuMedium: ConeMedium {
    /// Whether it carries six directional opacities.
    const DIRECTIONAL: bool;
    /// The payloads as the kernel's buffer.
    fn gpu_bytes(payload: &[Self]) -> Vec<u8>;
}

fn isotropic(radiance_alpha: [f32; 3], opacity: f32) -> GpuRadiance {
    GpuRadiance { radiance_alpha, opacity }
}

fn directional(radiance_alpha: [f32; 3], opacity: f32, o: &[f32; 6]) -> GpuDirectionalRadiance {
    GpuDirectionalRadiance {
        radiance_alpha,
        opacity,
        plus: [o[0], o[2], o[4]],
        pad0: 0.0,
        minus: [o[1], o[3], o[5]],
        pad1: 0.0,
    }
}

impl GpuMedium for RadiancePayload {
    const DIRECTIONAL: bool = false;
    fn gpu_bytes(payload: &[Self]) -> Vec<u8> {
        let v: Vec<GpuRadiance> =
            payload.iter().map(|p| isotropic(p.radiance_alpha, p.opacity)).collect();
        bytemuck::cast_slice(&v).to_vec()
    }
}

impl GpuMedium for AveragePayload {
    const DIRECTIONAL: bool = false;
    fn gpu_bytes(payload: &[Self]) -> Vec<u8> {
        let v: Vec<GpuRadiance> = payload.iter().map(|p| isotropic([0.0; 3], p.opacity)).collect();
        bytemuck::cast_slice(&v).to_vec()
    }
}

impl GpuMedium for Directional<RadiancePayload> {
    const DIRECTIONAL: bool = true;
    fn gpu_bytes(payload: &[Self]) -> Vec<u8> {
        let v: Vec<GpuDirectionalRadiance> = payload
            .iter()
            .map(|p| directional(p.inner.radiance_alpha, p.inner.opacity, &p.opacity))
            .collect();
        bytemuck::cast_slice(&v).to_vec()
    }
}

impl GpuMedium for Directional<AveragePayload> {
    const DIRECTIONAL: bool = true;
    fn gpu_bytes(payload: &[Self]) -> Vec<u8> {
        let v: Vec<GpuDirectionalRadiance> =
            payload.iter().map(|p| directional([0.0; 3], p.inner.opacity, &p.opacity)).collect();
        bytemuck::cast_slice(&v).to_vec()
    }
}

/// The kernel's parameters (mirrors WGSL `Params`; see there for the fields).
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
pub struct GpuConeParams {
    /// Grid origin, voxel size.
    pub grid: [f32; 4],
    /// Width, point count, query bits, diffuse cones.
    pub size: [u32; 4],
    /// Depth, finest dense level, first row, rows.
    pub tree: [u32; 4],
    /// start_voxels, step_factor, opacity_cutoff, normal offset (world).
    pub march: [f32; 4],
    /// Diffuse 2·tan(θ/2), max march (voxels), AO-only max march (voxels), AO radius (voxels).
    pub limits: [f32; 4],
    /// 1/n, unused ×3.
    pub extra: [f32; 4],
}

/// One shading point as the kernel reads it (mirrors WGSL `Point`).
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
pub struct GpuPoint {
    /// World position.
    pub position: [f32; 3],
    /// Glossiness, clamped to \[0, 1\] (NaN → 0).
    pub glossiness: f32,
    /// Normal (normalized by the kernel).
    pub normal: [f32; 3],
    /// 1: position and normal usable; 2: `to_viewer` usable.
    pub flags: u32,
    /// Direction toward the viewer (normalized by the kernel).
    pub to_viewer: [f32; 3],
    /// Padding.
    pub pad: u32,
}

/// What the kernel writes per point (mirrors WGSL `Shade`).
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
pub struct GpuShade {
    /// `E/π` (rgb) and AO (w).
    pub diffuse_ao: [f32; 4],
    /// Specular radiance (rgb) and opacity (w).
    pub specular: [f32; 4],
    /// Samples of the diffuse cones, of the specular cone, unused ×2.
    pub steps: [u32; 4],
}

/// A shading point: what a G-buffer texel gives the tracer.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ShadingPoint {
    /// World position.
    pub position: Vec3,
    /// Surface normal (need not be unit; zero or non-finite: no cones).
    pub normal: Vec3,
    /// Direction toward the viewer, for the specular cone (need not be unit).
    pub to_viewer: Vec3,
    /// Glossiness in \[0, 1\] (clamped; NaN → 0) for the specular aperture.
    pub glossiness: f32,
}

impl ShadingPoint {
    /// The shading points of a G-buffer seen from `eye`, with one glossiness for all: a miss
    /// (triangle `u32::MAX`) gets a zero normal, so no cones (AO 1, no radiance), as
    /// `voxlod cone` treats misses.
    pub fn from_gbuffer(gb: &GBuffer, eye: Vec3, glossiness: f32) -> Vec<Self> {
        gb.texels
            .iter()
            .map(|t| {
                if t.triangle == u32::MAX {
                    ShadingPoint::default()
                } else {
                    ShadingPoint {
                        position: t.position,
                        normal: t.normal,
                        to_viewer: eye - t.position,
                        glossiness,
                    }
                }
            })
            .collect()
    }

    fn gpu(&self) -> GpuPoint {
        let ok = self.position.is_finite() && self.normal.try_normalize().is_some();
        let view = self.to_viewer.try_normalize().is_some();
        let g = if self.glossiness.is_nan() { 0.0 } else { self.glossiness.clamp(0.0, 1.0) };
        let keep = |v: Vec3, k: bool| if k { v.to_array() } else { [0.0; 3] };
        GpuPoint {
            position: keep(self.position, ok),
            glossiness: g,
            normal: keep(self.normal, ok),
            flags: u32::from(ok) | if view { 2 } else { 0 },
            to_viewer: keep(self.to_viewer, view),
            pad: 0,
        }
    }
}

/// Which cones to trace.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ConeQuery {
    /// Ambient occlusion from the diffuse cones.
    pub ambient_occlusion: bool,
    /// Diffuse indirect light `E/π` from the same cones.
    pub diffuse: bool,
    /// The specular cone.
    pub specular: bool,
}

impl ConeQuery {
    /// Everything.
    pub const ALL: Self = Self { ambient_occlusion: true, diffuse: true, specular: true };
    fn bits(self) -> u32 {
        u32::from(self.ambient_occlusion)
            | if self.diffuse { 2 } else { 0 }
            | if self.specular { 4 } else { 0 }
    }
}

/// What one shading point gathered.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ConeShade {
    /// Ambient occlusion in \[0, 1\] (1 when not asked for, or no cones).
    pub ao: f32,
    /// `E/π` from the diffuse cones (what their marches gathered, also when only AO is asked
    /// for, as [`ConeTracer::ao_and_diffuse`] returns it).
    pub diffuse: Vec3,
    /// Radiance along the specular cone (zero when not asked for).
    pub specular: Vec3,
    /// The specular cone's accumulated opacity.
    pub specular_opacity: f32,
    /// Octree samples of the diffuse cones.
    pub diffuse_steps: u32,
    /// Octree samples of the specular cone.
    pub specular_steps: u32,
}

/// The CPU reference of one shading point: exactly what the kernel computes, through
/// [`ConeTracer`] ([`ConeTracer::ao_and_diffuse`] when AO or diffuse is asked for,
/// [`ConeTracer::specular`] when specular is).
pub fn reference<M: ConeMedium>(
    tracer: &ConeTracer<'_, M>,
    point: &ShadingPoint,
    query: ConeQuery,
) -> ConeShade {
    let mut out = ConeShade { ao: 1.0, ..ConeShade::default() };
    let (p, n) = (point.position, point.normal);
    if query.ambient_occlusion || query.diffuse {
        let (ao, e, steps) = tracer.ao_and_diffuse(p, n, query.ambient_occlusion, query.diffuse);
        (out.ao, out.diffuse, out.diffuse_steps) = (ao, e, steps);
    }
    if query.specular {
        let r = tracer.specular(p, n, point.to_viewer, point.glossiness);
        (out.specular, out.specular_opacity, out.specular_steps) = (r.radiance, r.opacity, r.steps);
    }
    out
}

/// A radiance (or opacity) octree uploaded for the kernel.
pub struct GpuConeOctree {
    levels: wgpu::Buffer,
    nodes: wgpu::Buffer,
    tiles: wgpu::Buffer,
    payload: wgpu::Buffer,
    grid: voxlod_format::GridSpec,
    depth: u32,
    first_dense: u32,
    directional: bool,
    node_count: usize,
}

impl GpuConeOctree {
    /// Nodes uploaded (all levels).
    pub fn node_count(&self) -> usize {
        self.node_count
    }
    /// Whether the payload carries directional opacities.
    pub fn is_directional(&self) -> bool {
        self.directional
    }
}

/// The cone-tracing kernel on one [`Context`] (its two payload variants compiled on first
/// use).
pub struct ConeKernel<'a> {
    ctx: &'a Context,
    pipelines: [OnceCell<wgpu::ComputePipeline>; 2],
    points_per_dispatch: u64,
}

impl<'a> ConeKernel<'a> {
    /// The kernel (compiled when first used).
    pub fn new(ctx: &'a Context) -> Self {
        Self {
            ctx,
            pipelines: [OnceCell::new(), OnceCell::new()],
            points_per_dispatch: POINTS_PER_DISPATCH,
        }
    }

    /// Sets the most shading points per dispatch (whole rows, at least one row): results do
    /// not depend on it.
    pub fn with_points_per_dispatch(mut self, points: u64) -> Self {
        self.points_per_dispatch = points.max(1);
        self
    }

    fn pipeline(&self, directional: bool) -> Result<&wgpu::ComputePipeline> {
        let cell = &self.pipelines[usize::from(directional)];
        if let Some(p) = cell.get() {
            return Ok(p);
        }
        let p = self.ctx.pipeline("cone tracing", &source(directional))?;
        Ok(cell.get_or_init(|| p))
    }

    /// Uploads `tree` in the flat layout ([`FlatOctree::from_octree`]).
    pub fn upload<M: GpuMedium>(&self, tree: &Octree<M>) -> Result<GpuConeOctree> {
        let flat = FlatOctree::from_octree(tree).map_err(voxlod_cone::Error::from)?;
        let ctx = self.ctx;
        let levels: &[GpuLevel] = &flat.levels;
        let nodes: &[GpuNode] = &flat.nodes;
        // A binding holds at least one element: an octree without sparse levels has no tiles.
        let none = [GpuTile { links: [voxlod_octree::NONE; 3] }];
        let tiles: &[GpuTile] = if flat.tiles.is_empty() { &none } else { &flat.tiles };
        Ok(GpuConeOctree {
            levels: ctx.storage_init("octree levels", bytemuck::cast_slice(levels))?,
            nodes: ctx.storage_init("octree nodes", bytemuck::cast_slice(nodes))?,
            tiles: ctx.storage_init("octree tiles", bytemuck::cast_slice(tiles))?,
            payload: ctx.storage_init("octree payloads", &M::gpu_bytes(&flat.payload))?,
            grid: *tree.grid(),
            depth: tree.depth(),
            first_dense: tree.first_dense(),
            directional: M::DIRECTIONAL,
            node_count: flat.nodes.len(),
        })
    }

    /// Traces `query` from every point of `points`, laid out as an image `width` points wide
    /// (rows of 8×8 workgroups; the last row may be partial): per point what [`reference()`]
    /// computes on the CPU. Errors: `options` outside their ranges (voxlod-cone's error), a
    /// zero `width` with points, and the device's limits.
    pub fn trace(
        &self,
        tree: &GpuConeOctree,
        options: &TraceOptions,
        query: ConeQuery,
        points: &[ShadingPoint],
        width: u32,
    ) -> Result<Vec<ConeShade>> {
        options.validate()?;
        if points.is_empty() {
            return Ok(Vec::new());
        }
        if width == 0 {
            return Err(voxlod_cone::Error::InvalidParameter {
                name: "width",
                value: "0".into(),
                reason: "at least one shading point per row",
            }
            .into());
        }
        let ctx = self.ctx;
        let count = points.len() as u64;
        if count > u32::MAX as u64 {
            return Err(crate::Error::TooLarge {
                what: "shading points",
                requested: count,
                limit: u32::MAX as u64,
            });
        }
        let height = count.div_ceil(width as u64) as u32;
        ctx.image_dispatch("cone-tracing image edge (workgroups of 8 points)", width, height)?;
        let pipeline = self.pipeline(tree.directional)?;
        let gpu_points: Vec<GpuPoint> = points.iter().map(ShadingPoint::gpu).collect();
        let points_buf = ctx.storage_init("shading points", bytemuck::cast_slice(&gpu_points))?;
        let out_bytes = count * size_of::<GpuShade>() as u64;
        let shades = ctx.storage_zeroed("cone shades", out_bytes)?;
        let dirs: Vec<[f32; 4]> = hemisphere_directions(options.diffuse_cones)
            .iter()
            .map(|d| d.extend(0.0).to_array())
            .collect();
        let dirs_buf = ctx.storage_init("diffuse directions", bytemuck::cast_slice(&dirs))?;
        let params = self.params(tree, options, query, width, count as u32);
        let layout = pipeline.get_bind_group_layout(0);
        let rows_per = (self.points_per_dispatch / width as u64).clamp(1, height as u64) as u32;
        let mut first = 0;
        while first < height {
            let rows = rows_per.min(height - first);
            let p = GpuConeParams { tree: [params.tree[0], params.tree[1], first, rows], ..params };
            let uniform = ctx.uniform("cone params", bytemuck::bytes_of(&p))?;
            let bind = ctx.guarded("binding cone-tracing buffers", || {
                ctx.device().create_bind_group(&wgpu::BindGroupDescriptor {
                    label: Some("cone tracing"),
                    layout: &layout,
                    entries: &[
                        entry(0, &uniform),
                        entry(1, &tree.levels),
                        entry(2, &tree.nodes),
                        entry(3, &tree.tiles),
                        entry(4, &tree.payload),
                        entry(5, &dirs_buf),
                        entry(6, &points_buf),
                        entry(7, &shades),
                    ],
                })
            })?;
            let (lx, ly) = ctx.image_dispatch("cone-tracing dispatch", width, rows)?;
            let mut encoder = ctx.device().create_command_encoder(&Default::default());
            {
                let mut pass = encoder.begin_compute_pass(&Default::default());
                pass.set_pipeline(pipeline);
                pass.set_bind_group(0, &bind, &[]);
                pass.dispatch_workgroups(lx, ly, 1);
            }
            ctx.submit("tracing cones", encoder)?;
            first += rows;
        }
        let raw = ctx.read(&shades, out_bytes)?;
        let shades: Vec<GpuShade> = bytemuck::pod_collect_to_vec(&raw);
        Ok(shades
            .iter()
            .map(|s| ConeShade {
                ao: s.diffuse_ao[3],
                diffuse: Vec3::from_slice(&s.diffuse_ao[..3]),
                specular: Vec3::from_slice(&s.specular[..3]),
                specular_opacity: s.specular[3],
                diffuse_steps: s.steps[0],
                specular_steps: s.steps[1],
            })
            .collect())
    }

    /// The parameters, every constant computed on the host exactly as voxlod-cone
    /// computes it (same `f32` expressions).
    fn params(
        &self,
        tree: &GpuConeOctree,
        o: &TraceOptions,
        query: ConeQuery,
        width: u32,
        count: u32,
    ) -> GpuConeParams {
        let voxel = tree.grid.voxel_size as f32;
        let finite = |x: f32| if x.is_finite() { x } else { BIG };
        // cone.rs: `2·tan(θ/2)` of the aperture clamped to [0, π], at least 0.
        let aperture = o.diffuse_aperture_deg.to_radians();
        let two_tan = 2.0 * (0.5 * aperture.clamp(0.0, std::f32::consts::PI)).tan().max(0.0);
        // tracer.rs: the AO-only march's end, then cone.rs's division by the voxel.
        let ao_max = (o.ao_radius + o.normal_offset_voxels * voxel).min(o.max_distance);
        let origin = tree.grid.origin.as_vec3();
        GpuConeParams {
            grid: origin.extend(voxel).to_array(),
            size: [width, count, query.bits(), o.diffuse_cones],
            tree: [tree.depth, tree.first_dense, 0, 0],
            march: [
                o.start_voxels,
                o.step_factor,
                o.opacity_cutoff,
                o.normal_offset_voxels * voxel,
            ],
            limits: [
                two_tan,
                finite(o.max_distance / voxel),
                finite(ao_max / voxel),
                o.ao_radius / voxel,
            ],
            extra: [1.0 / hemisphere_directions(o.diffuse_cones).len() as f32, 0.0, 0.0, 0.0],
        }
    }
}

#[cfg(test)]
mod tests {
    use std::mem::offset_of;

    use super::*;
    use crate::layout::assert_mirrors;

    #[test]
    fn cone_types_mirror_their_wgsl() {
        let iso = source(false);
        let dir = source(true);
        type P = GpuConeParams;
        for src in [&iso, &dir] {
            assert_mirrors(
                src,
                "Params",
                size_of::<P>(),
                &[
                    ("grid", offset_of!(P, grid)),
                    ("size", offset_of!(P, size)),
                    ("tree", offset_of!(P, tree)),
                    ("march", offset_of!(P, march)),
                    ("limits", offset_of!(P, limits)),
                    ("extra", offset_of!(P, extra)),
                ],
            );
            assert_mirrors(
                src,
                "Point",
                size_of::<GpuPoint>(),
                &[
                    ("position", offset_of!(GpuPoint, position)),
                    ("glossiness", offset_of!(GpuPoint, glossiness)),
                    ("normal", offset_of!(GpuPoint, normal)),
                    ("flags", offset_of!(GpuPoint, flags)),
                    ("to_viewer", offset_of!(GpuPoint, to_viewer)),
                    ("pad", offset_of!(GpuPoint, pad)),
                ],
            );
            assert_mirrors(
                src,
                "Shade",
                size_of::<GpuShade>(),
                &[
                    ("diffuse_ao", offset_of!(GpuShade, diffuse_ao)),
                    ("specular", offset_of!(GpuShade, specular)),
                    ("steps", offset_of!(GpuShade, steps)),
                ],
            );
            assert_mirrors(
                src,
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
            assert_mirrors(
                src,
                "Node",
                size_of::<GpuNode>(),
                &[("child", offset_of!(GpuNode, child)), ("mask", offset_of!(GpuNode, mask))],
            );
            assert_mirrors(src, "Tile", size_of::<GpuTile>(), &[("links", 0)]);
        }
        type R = GpuRadiance;
        assert_mirrors(
            &iso,
            "Payload",
            size_of::<R>(),
            &[
                ("radiance_alpha", offset_of!(R, radiance_alpha)),
                ("opacity", offset_of!(R, opacity)),
            ],
        );
        type D = GpuDirectionalRadiance;
        assert_mirrors(
            &dir,
            "Payload",
            size_of::<D>(),
            &[
                ("radiance_alpha", offset_of!(D, radiance_alpha)),
                ("opacity", offset_of!(D, opacity)),
                ("plus", offset_of!(D, plus)),
                ("pad0", offset_of!(D, pad0)),
                ("minus", offset_of!(D, minus)),
                ("pad1", offset_of!(D, pad1)),
            ],
        );
        // The CPU payloads carry what the mirrors carry: RadiancePayload is 16 bytes of f32.
        assert_eq!(size_of::<RadiancePayload>(), size_of::<GpuRadiance>());
    }

    #[test]
    fn directional_opacities_are_regrouped_plus_then_minus() {
        let d = directional([1.0, 2.0, 3.0], 0.5, &[0.1, 0.2, 0.3, 0.4, 0.5, 0.6]);
        assert_eq!((d.plus, d.minus), ([0.1, 0.3, 0.5], [0.2, 0.4, 0.6]));
    }

    #[test]
    fn unusable_shading_inputs_are_flagged_not_uploaded() {
        let good = ShadingPoint {
            position: Vec3::ONE,
            normal: Vec3::Y * 3.0,
            to_viewer: Vec3::Z,
            glossiness: f32::NAN,
        };
        let g = good.gpu();
        assert_eq!((g.flags, g.glossiness), (3, 0.0));
        let nan = ShadingPoint { position: Vec3::NAN, ..good }.gpu();
        assert_eq!((nan.flags, nan.position), (2, [0.0; 3]));
        let zero = ShadingPoint { normal: Vec3::ZERO, to_viewer: Vec3::ZERO, ..good }.gpu();
        assert_eq!(zero.flags, 0);
        assert_eq!(ShadingPoint { glossiness: 7.0, ..good }.gpu().glossiness, 1.0);
    }
}
