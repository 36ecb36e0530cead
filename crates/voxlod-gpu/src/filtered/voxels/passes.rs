//! The three passes of a virtual-mesh or Adaptive frame: their shared bind-group layout and
//! pipelines (compiled on first use), and the frame's recording (light pass, view pass,
//! composite) into one submission.

use voxlod_scene::Image;

use super::super::{FilteredKernel, GpuFilteredParams, GpuRecords, read_image};
use super::{VoxelBuffers, WGSL, cache_bytes};
use crate::context::record_pass;
use crate::{Context, Error, Result};

/// The three pipelines and their shared bind group layout.
pub(in crate::filtered) struct Passes {
    layout: wgpu::BindGroupLayout,
    light: wgpu::ComputePipeline,
    view: wgpu::ComputePipeline,
    composite: wgpu::ComputePipeline,
}

fn layout_entry(binding: u32, ty: wgpu::BufferBindingType) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::COMPUTE,
        ty: wgpu::BindingType::Buffer { ty, has_dynamic_offset: false, min_binding_size: None },
        count: None,
    }
}

/// Storage buffers the passes bind at once (one layout for the three), the parameters included
/// (see [`Context::uniform`]).
const STORAGE_BUFFERS: u32 = 9;

impl Passes {
    fn new(ctx: &Context) -> Result<Self> {
        let have = ctx.limits().max_storage_buffers_per_shader_stage;
        if have < STORAGE_BUFFERS {
            return Err(Error::TooLarge {
                what: "storage buffers per shader stage of the virtual-mesh/Adaptive renderer \
                       (device limit max_storage_buffers_per_shader_stage)",
                requested: STORAGE_BUFFERS as u64,
                limit: have as u64,
            });
        }
        use wgpu::BufferBindingType::{Storage, Uniform};
        let ro = Storage { read_only: true };
        let rw = Storage { read_only: false };
        let entries = [
            layout_entry(0, ro),
            layout_entry(1, ro),
            layout_entry(2, ro),
            layout_entry(3, ro),
            layout_entry(4, ro),
            layout_entry(5, rw),
            layout_entry(6, Uniform),
            layout_entry(7, ro),
            layout_entry(8, ro),
            layout_entry(9, rw),
        ];
        let device = ctx.device();
        let (layout, pipeline_layout) = ctx.guarded("creating the voxel passes' layout", || {
            let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                label: Some("filtered voxel passes"),
                entries: &entries,
            });
            let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                label: Some("filtered voxel passes"),
                bind_group_layouts: &[Some(&layout)],
                immediate_size: 0,
            });
            (layout, pipeline_layout)
        })?;
        let mut p = ctx.pipelines(
            "filtered voxel passes",
            WGSL,
            &["light_pass", "view_pass", "composite"],
            &pipeline_layout,
        )?;
        let composite = p.pop().expect("three pipelines");
        let view = p.pop().expect("three pipelines");
        let light = p.pop().expect("three pipelines");
        Ok(Self { layout, light, view, composite })
    }
}

impl FilteredKernel<'_> {
    fn passes(&self) -> Result<&Passes> {
        if let Some(p) = self.passes.get() {
            return Ok(p);
        }
        let p = Passes::new(self.ctx)?;
        Ok(self.passes.get_or_init(|| p))
    }

    /// Renders a virtual-mesh or Adaptive grid: the three passes (module docs).
    pub(in crate::filtered) fn render_voxels(
        &self,
        app: &GpuRecords,
        v: &VoxelBuffers,
        params: &GpuFilteredParams,
        (lx, ly): (u32, u32),
    ) -> Result<Image> {
        let ctx = self.ctx;
        let passes = self.passes()?;
        let [width, height, ..] = params.size;
        let count = v.params[3] as u64;
        let (vx, vy) =
            ctx.dispatch_size("voxel passes (workgroups of 64 voxels)", count.div_ceil(64))?;
        let bytes = width as u64 * height as u64 * 16;
        let out = ctx.storage_zeroed("filtered image", bytes)?;
        let cache =
            ctx.storage_zeroed("per-voxel cache of the voxel passes", cache_bytes(&v.params))?;
        let uniform = ctx.uniform("filtered params", bytemuck::bytes_of(params))?;
        let buffers = [
            &uniform,
            &app.table,
            &app.bricks,
            &app.slots,
            &app.records,
            &out,
            &v.tables,
            &v.voxels,
            &v.vmesh,
            &cache,
        ];
        let bind = ctx.bind_group("binding the voxel passes' buffers", &passes.layout, &buffers)?;
        let mut encoder = ctx.device().create_command_encoder(&Default::default());
        // Separate passes: each reads what the previous one wrote.
        for (name, pipeline, workgroups) in [
            ("light pass", &passes.light, (vx, vy)),
            ("view pass", &passes.view, (vx, vy)),
            ("composite", &passes.composite, (lx, ly)),
        ] {
            record_pass(&mut encoder, name, pipeline, &bind, workgroups);
        }
        ctx.submit("rendering virtual-mesh/Adaptive records", encoder)?;
        read_image(ctx, &out, width, height)
    }
}
