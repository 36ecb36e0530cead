//! Slicemaps by rasterization on the GPU: a wgpu **render** pipeline (vertex and fragment
//! stages) whose fragment stage sets its slice bits with `atomicOr` into a storage buffer, the
//! mirror of [`voxlod_cpu::voxelize::slicemap`] (Eisemann and Décoret 2006).
//!
//! # Contract
//! The host prepares the triangles exactly as the CPU reference does
//! ([`voxlod_cpu::voxelize::slicemap::prepare`]: view transform, near and guard-band clipping,
//! window coordinates snapped to `1/256` pixel), so bad input gets the reference's errors.
//! - **Standard coverage** is the hardware rasterizer's: the vertex stage hands it the snapped
//!   positions bit for bit (a power-of-two render target makes the viewport transform exact,
//!   see `slicemap.wgsl`), and it decides pixel centres with its own fixed-point edge
//!   functions and tie rule. The reference reproduces Vulkan's rule (8 sub-pixel bits, the
//!   top-left rule), so the **columns covered agree exactly**; the equivalence suite checks it.
//! - **Conservative coverage** has no hardware path here: wgpu exposes it as the native feature
//!   `CONSERVATIVE_RASTERIZATION`, which lavapipe does not offer, and the hardware rule would
//!   not give the depth range a fragment needs anyway. It is emulated: each triangle is drawn
//!   as its pixel-aligned bounding quad (6 vertices pulled from the triangle buffer), and the
//!   fragment stage decides in exact 64-bit integer arithmetic (emulated on 32-bit words)
//!   whether the pixel's closed square meets the triangle, then computes the triangle's depth
//!   range over the square from the same candidates as the reference. Coverage is exact.
//! - **Depth**: the fragment stage evaluates `q` at the pixel centre (or the candidates) from
//!   the triangle's plane in the reference's order of operations, in `f32`; the rasterizer's
//!   own interpolation is not used. A slice bit can differ from the reference only where the
//!   driver rounds differently (fused multiply-adds, division): fragments within about `1e-6`
//!   of a slice boundary in normalized depth. The equivalence suite allows differences only
//!   at fragments within `1e-5` of a boundary, counts them, and requires them below 0.1 %.
//! - **Local slicing** is two passes of the same pipeline: the first takes the per-column
//!   minimum and maximum of `d = z − near` with `atomicMin`/`atomicMax` on its `f32` bits
//!   (`d ≥ 0`, so integer order is float order), the second slices each column over them.
//!
//! # Requirements and limits
//! Storage buffers written from the fragment stage and read from the vertex stage
//! (`DownlevelFlags::FRAGMENT_WRITABLE_STORAGE`, `VERTEX_STORAGE`; lavapipe has both), else
//! [`Error::Unsupported`], and four storage buffers per shader stage (the parameters, the
//! triangles, the bits, the column ranges; `max_storage_buffers_per_shader_stage`, else
//! [`Error::TooLarge`]). The parameters are a read-only storage buffer rather than a uniform,
//! as in every voxlod-gpu kernel. The render target is `P × P` with `P` the power of two at least the
//! map's larger side plus 4 guard pixels (an `R8Unorm` target that is never written: WebGPU
//! needs an attachment); `P` over `max_texture_dimension_2d` is [`Error::TooLarge`]. The bits
//! (`layers × width × height × ⌈slices/32⌉` words) must fit one storage binding
//! ([`Error::BufferTooLarge`] otherwise: 128 MiB on lavapipe, e.g. 1024² columns × 512 slices
//! × 2 layers); triangles are drawn in batches that each fit one binding.

use voxlod_cpu::voxelize::slicemap::{
    self as cpu, Coverage, Options, SliceCamera, SliceTriangle, Slicemap, Slicing,
};
use voxlod_scene::Geometry;

use crate::{Context, Error, Result};

pub mod query;

/// The WGSL source of the render pipeline.
pub const WGSL: &str = include_str!("slicemap.wgsl");

/// Pixels between the render target's corner and the map (WGSL `GUARD`): the host's guard band
/// ([`cpu::camera::GUARD_PIXELS`]) fits in it, so no vertex leaves the viewport.
pub const GUARD: u32 = 2;

/// The pipeline's parameters, bound as a read-only storage buffer (mirrors WGSL `Params`).
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
pub struct GpuSliceParams {
    /// Map width in columns.
    pub width: u32,
    /// Map height in columns.
    pub height: u32,
    /// Side `P` of the square render target (a power of two).
    pub target_side: u32,
    /// Slices per column.
    pub slices: u32,
    /// Words per column and layer.
    pub words: u32,
    /// Bit 0 perspective, bit 1 local slicing, bit 2 front/back layers.
    pub mode: u32,
    /// 0: depth-range pass, 1: slice pass.
    pub pass_kind: u32,
    /// `near` as `f32`.
    pub near: f32,
    /// `far − near` as the reference computes it ([`Slicemap::depth_span`]).
    pub span: f32,
    /// Padding to 16 bytes.
    pub pad0: u32,
    /// Padding.
    pub pad1: u32,
    /// Padding.
    pub pad2: u32,
}

/// The side of the square render target for a map of `width × height` columns: the smallest
/// power of two holding the map and its guard pixels on both sides.
pub fn target_side(width: u32, height: u32) -> u32 {
    (width.max(height) + 2 * GUARD).next_power_of_two()
}

fn layout_entry(
    binding: u32,
    visibility: wgpu::ShaderStages,
    ty: wgpu::BufferBindingType,
) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility,
        ty: wgpu::BindingType::Buffer { ty, has_dynamic_offset: false, min_binding_size: None },
        count: None,
    }
}

/// The slicemap render pipelines (standard and conservative), compiled for one [`Context`].
pub struct SlicemapRenderer<'a> {
    ctx: &'a Context,
    layout: wgpu::BindGroupLayout,
    standard: wgpu::RenderPipeline,
    conservative: wgpu::RenderPipeline,
    batch: usize,
}

impl<'a> SlicemapRenderer<'a> {
    /// Checks the adapter's capabilities (module docs) and compiles both pipelines.
    pub fn new(ctx: &'a Context) -> Result<Self> {
        let flags = ctx.downlevel().flags;
        for (flag, what) in [
            (
                wgpu::DownlevelFlags::FRAGMENT_WRITABLE_STORAGE,
                "slicemaps need storage buffers written from the fragment stage \
                 (DownlevelFlags::FRAGMENT_WRITABLE_STORAGE), which this adapter lacks",
            ),
            (
                wgpu::DownlevelFlags::VERTEX_STORAGE,
                "slicemaps need storage buffers read from the vertex stage \
                 (DownlevelFlags::VERTEX_STORAGE), which this adapter lacks",
            ),
        ] {
            if !flags.contains(flag) {
                return Err(Error::Unsupported { what });
            }
        }
        let have = ctx.limits().max_storage_buffers_per_shader_stage;
        if have < 4 {
            return Err(Error::TooLarge {
                what: "storage buffers per shader stage of the slicemap pipeline \
                       (device limit max_storage_buffers_per_shader_stage)",
                requested: 4,
                limit: have as u64,
            });
        }
        use wgpu::BufferBindingType::Storage;
        // Writable storage only in the fragment stage (vertex-stage writes are a native
        // feature).
        let (both, fragment) = (wgpu::ShaderStages::VERTEX_FRAGMENT, wgpu::ShaderStages::FRAGMENT);
        let entries = [
            layout_entry(0, both, Storage { read_only: true }),
            layout_entry(1, both, Storage { read_only: true }),
            layout_entry(2, fragment, Storage { read_only: false }),
            layout_entry(3, fragment, Storage { read_only: false }),
        ];
        let device = ctx.device();
        let (layout, standard, conservative) =
            ctx.guarded("compiling the slicemap pipelines", || {
                let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                    label: Some("slicemap"),
                    entries: &entries,
                });
                let pipeline_layout =
                    device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                        label: Some("slicemap"),
                        bind_group_layouts: &[Some(&layout)],
                        immediate_size: 0,
                    });
                let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
                    label: Some("slicemap"),
                    source: wgpu::ShaderSource::Wgsl(WGSL.into()),
                });
                let pipeline = |vs: &str, fs: &str| {
                    device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                        label: Some("slicemap"),
                        layout: Some(&pipeline_layout),
                        vertex: wgpu::VertexState {
                            module: &module,
                            entry_point: Some(vs),
                            compilation_options: Default::default(),
                            buffers: &[],
                        },
                        primitive: wgpu::PrimitiveState {
                            topology: wgpu::PrimitiveTopology::TriangleList,
                            cull_mode: None,
                            ..Default::default()
                        },
                        depth_stencil: None,
                        multisample: wgpu::MultisampleState::default(),
                        fragment: Some(wgpu::FragmentState {
                            module: &module,
                            entry_point: Some(fs),
                            compilation_options: Default::default(),
                            targets: &[Some(wgpu::ColorTargetState {
                                format: wgpu::TextureFormat::R8Unorm,
                                blend: None,
                                write_mask: wgpu::ColorWrites::empty(),
                            })],
                        }),
                        multiview_mask: None,
                        cache: None,
                    })
                };
                let standard = pipeline("vs_standard", "fs_standard");
                let conservative = pipeline("vs_conservative", "fs_conservative");
                (layout, standard, conservative)
            })?;
        let record = size_of::<SliceTriangle>() as u64;
        let batch = (ctx.limits().max_storage_buffer_binding_size / record).clamp(1, 1 << 24);
        Ok(Self { ctx, layout, standard, conservative, batch: batch as usize })
    }

    /// Draws at most `triangles` (≥ 1) records per draw call (default: as many as one storage
    /// binding holds, up to 2^24): smaller draws for drivers that time out on long ones, and
    /// for testing the batching.
    pub fn with_batch(mut self, triangles: usize) -> Self {
        self.batch = triangles.clamp(1, self.batch);
        self
    }

    /// Rasterizes `geometry` into the slicemap of `camera` on the GPU (module docs); the same
    /// errors as [`cpu::build`] for bad input.
    pub fn build(
        &self,
        geometry: &Geometry,
        camera: &SliceCamera,
        options: &Options,
    ) -> Result<Slicemap> {
        options.validate(camera)?;
        let prepared = cpu::prepare(geometry, camera)?;
        self.build_prepared(&prepared.triangles, camera, options)
    }

    /// [`SlicemapRenderer::build`] from records already prepared for `camera`.
    pub fn build_prepared(
        &self,
        triangles: &[SliceTriangle],
        camera: &SliceCamera,
        options: &Options,
    ) -> Result<Slicemap> {
        options.validate(camera)?;
        let ctx = self.ctx;
        let (width, height) = (camera.width, camera.height);
        let side = target_side(width, height);
        let max_side = ctx.limits().max_texture_dimension_2d;
        if side > max_side {
            return Err(Error::TooLarge {
                what: "slicemap render target side (device limit max_texture_dimension_2d)",
                requested: side as u64,
                limit: max_side as u64,
            });
        }
        let mut map = Slicemap::empty(*camera, *options);
        let columns = width as u64 * height as u64;
        let bit_bytes = map.bits.len() as u64 * 4;
        let local = options.slicing == Slicing::Local;
        // Uniform slicing reads no ranges: one placeholder entry.
        let range_entries = if local { columns } else { 1 };
        let range_bytes = range_entries * 8;
        ctx.check_storage("the slicemap bits", bit_bytes)?;
        ctx.check_storage("the slicemap column ranges", range_bytes)?;
        let mode = camera.is_perspective() as u32
            | (local as u32) << 1
            | ((options.faces.layers() == 2) as u32) << 2;
        let base = GpuSliceParams {
            width,
            height,
            target_side: side,
            slices: options.slices,
            words: options.words(),
            mode,
            pass_kind: 1,
            near: camera.near as f32,
            span: map.depth_span(),
            ..Default::default()
        };
        let bits = ctx.storage_zeroed("slicemap bits", bit_bytes)?;
        let init: Vec<[u32; 2]> = vec![[f32::INFINITY.to_bits(), 0]; range_entries as usize];
        let ranges = ctx.storage_init("slicemap ranges", bytemuck::cast_slice(&init))?;
        let target = ctx.guarded("allocating the slicemap render target", || {
            ctx.device().create_texture(&wgpu::TextureDescriptor {
                label: Some("slicemap target (never written)"),
                size: wgpu::Extent3d { width: side, height: side, depth_or_array_layers: 1 },
                mip_level_count: 1,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D2,
                format: wgpu::TextureFormat::R8Unorm,
                usage: wgpu::TextureUsages::RENDER_ATTACHMENT,
                view_formats: &[],
            })
        })?;
        let view = target.create_view(&Default::default());
        let (pipeline, per_tri) = match options.coverage {
            Coverage::Standard => (&self.standard, 3u32),
            Coverage::Conservative => (&self.conservative, 6u32),
        };
        let mut batches = Vec::new();
        for chunk in triangles.chunks(self.batch) {
            batches.push((
                ctx.storage_init("slicemap triangles", bytemuck::cast_slice(chunk))?,
                chunk.len(),
            ));
        }
        let mut encoder = ctx.device().create_command_encoder(&Default::default());
        let mut keep = Vec::new();
        let passes: &[u32] = if local { &[0, 1] } else { &[1] };
        for &pass_kind in passes {
            let params = GpuSliceParams { pass_kind, ..base };
            let params = ctx.uniform("slicemap params", bytemuck::bytes_of(&params))?;
            let mut groups = Vec::new();
            for (tris, count) in &batches {
                let bind = ctx.guarded("binding slicemap buffers", || {
                    ctx.device().create_bind_group(&wgpu::BindGroupDescriptor {
                        label: Some("slicemap"),
                        layout: &self.layout,
                        entries: &[
                            entry(0, &params),
                            entry(1, tris),
                            entry(2, &bits),
                            entry(3, &ranges),
                        ],
                    })
                })?;
                groups.push((bind, *count as u32));
            }
            {
                let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                    label: Some("slicemap"),
                    color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                        view: &view,
                        depth_slice: None,
                        resolve_target: None,
                        ops: wgpu::Operations {
                            load: wgpu::LoadOp::Clear(wgpu::Color::BLACK),
                            store: wgpu::StoreOp::Discard,
                        },
                    })],
                    depth_stencil_attachment: None,
                    timestamp_writes: None,
                    occlusion_query_set: None,
                    multiview_mask: None,
                });
                pass.set_pipeline(pipeline);
                pass.set_viewport(0.0, 0.0, side as f32, side as f32, 0.0, 1.0);
                pass.set_scissor_rect(GUARD, GUARD, width, height);
                for (bind, count) in &groups {
                    if *count > 0 {
                        pass.set_bind_group(0, bind, &[]);
                        pass.draw(0..count * per_tri, 0..1);
                    }
                }
            }
            keep.push((params, groups));
        }
        ctx.submit("rasterizing a slicemap", encoder)?;
        map.bits = bytemuck::cast_slice(&ctx.read(&bits, bit_bytes)?).to_vec();
        if local {
            let r: Vec<[u32; 2]> = bytemuck::cast_slice(&ctx.read(&ranges, range_bytes)?).to_vec();
            map.ranges = Some(
                r.into_iter().map(|[lo, hi]| [f32::from_bits(lo), f32::from_bits(hi)]).collect(),
            );
        }
        drop(keep);
        Ok(map)
    }
}

fn entry(binding: u32, buffer: &wgpu::Buffer) -> wgpu::BindGroupEntry<'_> {
    wgpu::BindGroupEntry { binding, resource: buffer.as_entire_binding() }
}

#[cfg(test)]
mod tests {
    use std::mem::offset_of;

    use super::*;
    use crate::layout::assert_mirrors;

    #[test]
    fn slicemap_types_mirror_their_wgsl() {
        let fields = [
            ("x0", offset_of!(SliceTriangle, x0)),
            ("y0", offset_of!(SliceTriangle, y0)),
            ("x1", offset_of!(SliceTriangle, x1)),
            ("y1", offset_of!(SliceTriangle, y1)),
            ("x2", offset_of!(SliceTriangle, x2)),
            ("y2", offset_of!(SliceTriangle, y2)),
            ("q0", offset_of!(SliceTriangle, q0)),
            ("q1", offset_of!(SliceTriangle, q1)),
            ("q2", offset_of!(SliceTriangle, q2)),
            ("dqdx", offset_of!(SliceTriangle, dqdx)),
            ("dqdy", offset_of!(SliceTriangle, dqdy)),
            ("flags", offset_of!(SliceTriangle, flags)),
            ("id", offset_of!(SliceTriangle, id)),
        ];
        assert_mirrors(WGSL, "SliceTri", size_of::<SliceTriangle>(), &fields);
        let params = [
            ("width", offset_of!(GpuSliceParams, width)),
            ("height", offset_of!(GpuSliceParams, height)),
            ("target_side", offset_of!(GpuSliceParams, target_side)),
            ("slices", offset_of!(GpuSliceParams, slices)),
            ("words", offset_of!(GpuSliceParams, words)),
            ("mode", offset_of!(GpuSliceParams, mode)),
            ("pass_kind", offset_of!(GpuSliceParams, pass_kind)),
            ("near", offset_of!(GpuSliceParams, near)),
            ("span", offset_of!(GpuSliceParams, span)),
            ("pad0", offset_of!(GpuSliceParams, pad0)),
            ("pad1", offset_of!(GpuSliceParams, pad1)),
            ("pad2", offset_of!(GpuSliceParams, pad2)),
        ];
        assert_mirrors(WGSL, "Params", size_of::<GpuSliceParams>(), &params);
    }

    #[test]
    fn the_render_target_holds_the_map_and_its_guard_pixels() {
        assert_eq!(target_side(1, 1), 8);
        assert_eq!(target_side(60, 4), 64);
        assert_eq!(target_side(61, 4), 128);
        assert_eq!(target_side(4096, 4096), 8192);
    }
}
