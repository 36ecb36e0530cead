//! Voxel cone tracing from shading points on the GPU (the diffuse, specular and AO cones of
//! Yalçıner and Sahillioğlu 2020, §4.5), the mirror of voxlod-cone's [`ConeTracer`]: per shading
//! point, ambient occlusion and diffuse indirect light `E/π` from the same `n` cosine-distributed
//! cones ([`ConeTracer::ao_and_diffuse`]), and the specular cone along the mirror direction with
//! its aperture from the glossiness ([`ConeTracer::specular`]). The radiance octree is uploaded as
//! voxlod-octree's flat layout ([`FlatOctree`]: one level table, one node array, the sparse levels'
//! tiles with their +x, +y, +z links) plus one payload per node, and sampled quadrilinearly in WGSL
//! exactly as [`Octree::sample_at_level`] does: trilinear within a level (the lower corner found by
//! a descent from the finest dense level, the seven others by the flat neighbour rule), linear
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
//!
//! # Layout of the module
//! `params` holds the `#[repr(C)]` mirrors of the kernel's WGSL structs and the uniform's
//! host-side constants, `medium` the payload conversions ([`GpuMedium`]), `points` the
//! shading inputs and results with the CPU reference of one point; this file uploads the
//! octree and dispatches the kernel.
//!
//! [`ConeTracer`]: voxlod_cone::ConeTracer
//! [`ConeTracer::ao_and_diffuse`]: voxlod_cone::ConeTracer::ao_and_diffuse
//! [`ConeTracer::specular`]: voxlod_cone::ConeTracer::specular
//! [`ConeMedium`]: voxlod_cone::ConeMedium
//! [`RadiancePayload`]: voxlod_cone::RadiancePayload
//! [`AveragePayload`]: voxlod_octree::AveragePayload

use std::cell::OnceCell;

use glam::Vec3;
use voxlod_cone::TraceOptions;
use voxlod_cone::tracer::hemisphere_directions;
use voxlod_octree::{FlatOctree, GpuLevel, GpuNode, GpuTile, Octree};

use crate::{Context, Result};

mod medium;
mod params;
mod points;

pub use medium::GpuMedium;
pub use params::{GpuConeParams, GpuDirectionalRadiance, GpuPoint, GpuRadiance, GpuShade};
pub use points::{ConeQuery, ConeShade, ShadingPoint, reference};

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
    format!("{payload}\n{}\n{}\n{WGSL}", crate::MORTON_WGSL, crate::OCTREE_WALK_WGSL)
}

/// Shading points per dispatch, at most (whole rows; a bound on a dispatch's duration).
pub const POINTS_PER_DISPATCH: u64 = 1 << 18;

/// Stands for an infinite distance in the kernel (WGSL leaves infinities indeterminate).
const BIG: f32 = 3.0e38;

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
    /// An isotropic octree already on the device in the flat layout — built by voxlod-gpu's
    /// octree kernels, its payloads in the kernel's isotropic layout ([`GpuRadiance`], one per
    /// node): the host's level table, the node and tile buffers (`tile_count` tiles; none is
    /// fine) and the payloads.
    #[allow(clippy::too_many_arguments)]
    pub fn from_device(
        ctx: &Context,
        levels: &[GpuLevel],
        nodes: wgpu::Buffer,
        tiles: wgpu::Buffer,
        tile_count: u64,
        payload: wgpu::Buffer,
        grid: voxlod_format::GridSpec,
        depth: u32,
        first_dense: u32,
    ) -> Result<Self> {
        let tiles = if tile_count == 0 {
            let none = [GpuTile { links: [voxlod_octree::NONE; 3] }];
            ctx.storage_init("octree tiles", bytemuck::cast_slice(&none))?
        } else {
            tiles
        };
        let node_count = levels.iter().map(|l| l.count as usize).sum();
        Ok(Self {
            levels: ctx.storage_init("octree levels", bytemuck::cast_slice(levels))?,
            nodes,
            tiles,
            payload,
            grid,
            depth,
            first_dense,
            directional: false,
            node_count,
        })
    }

    /// Nodes uploaded (all levels).
    pub fn node_count(&self) -> usize {
        self.node_count
    }

    /// The level table, node, tile and payload buffers (bindings 1–4 of the kernel).
    pub(crate) fn buffers(&self) -> (&wgpu::Buffer, &wgpu::Buffer, &wgpu::Buffer, &wgpu::Buffer) {
        (&self.levels, &self.nodes, &self.tiles, &self.payload)
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
        let params = params::params(tree, options, query, width, count as u32);
        let rows_per = (self.points_per_dispatch / width as u64).clamp(1, height as u64) as u32;
        let mut first = 0;
        while first < height {
            let rows = rows_per.min(height - first);
            let p = GpuConeParams { tree: [params.tree[0], params.tree[1], first, rows], ..params };
            let uniform = ctx.uniform("cone params", bytemuck::bytes_of(&p))?;
            let buffers = [
                &uniform,
                &tree.levels,
                &tree.nodes,
                &tree.tiles,
                &tree.payload,
                &dirs_buf,
                &points_buf,
                &shades,
            ];
            let workgroups = ctx.image_dispatch("cone-tracing dispatch", width, rows)?;
            ctx.dispatch("tracing cones", pipeline, &buffers, workgroups)?;
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
}
