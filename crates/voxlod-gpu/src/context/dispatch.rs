//! Dispatch: compiling pipelines, sizing dispatches within the device's workgroup-count limit,
//! binding buffers, and recording or submitting one compute pass. Every kernel of the crate
//! binds and dispatches through these functions.

use crate::{Context, Error, Result};

/// A bind-group entry binding all of `buffer` at `binding`.
pub fn entry(binding: u32, buffer: &wgpu::Buffer) -> wgpu::BindGroupEntry<'_> {
    wgpu::BindGroupEntry { binding, resource: buffer.as_entire_binding() }
}

/// Records one compute pass into `encoder`: `pipeline` with `bind` as group 0, dispatched
/// over `(x, y, 1)` workgroups.
pub fn record_pass(
    encoder: &mut wgpu::CommandEncoder,
    label: &str,
    pipeline: &wgpu::ComputePipeline,
    bind: &wgpu::BindGroup,
    (x, y): (u32, u32),
) {
    let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
        label: Some(label),
        timestamp_writes: None,
    });
    pass.set_pipeline(pipeline);
    pass.set_bind_group(0, bind, &[]);
    pass.dispatch_workgroups(x, y, 1);
}

impl Context {
    /// A compute pipeline from WGSL source, with its layout inferred from the shader.
    pub fn pipeline(&self, label: &'static str, wgsl: &str) -> Result<wgpu::ComputePipeline> {
        self.guarded("compiling a kernel", || {
            let module = self.device.create_shader_module(wgpu::ShaderModuleDescriptor {
                label: Some(label),
                source: wgpu::ShaderSource::Wgsl(wgsl.into()),
            });
            self.device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                label: Some(label),
                layout: None,
                module: &module,
                entry_point: Some("main"),
                compilation_options: Default::default(),
                cache: None,
            })
        })
    }

    /// Compute pipelines for the entry points `entries` of one WGSL module, sharing the
    /// explicit `layout` (one bind group for all of them).
    pub fn pipelines(
        &self,
        label: &'static str,
        wgsl: &str,
        entries: &[&str],
        layout: &wgpu::PipelineLayout,
    ) -> Result<Vec<wgpu::ComputePipeline>> {
        self.guarded("compiling a kernel", || {
            let module = self.device.create_shader_module(wgpu::ShaderModuleDescriptor {
                label: Some(label),
                source: wgpu::ShaderSource::Wgsl(wgsl.into()),
            });
            entries
                .iter()
                .map(|entry| {
                    self.device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                        label: Some(label),
                        layout: Some(layout),
                        module: &module,
                        entry_point: Some(entry),
                        compilation_options: Default::default(),
                        cache: None,
                    })
                })
                .collect()
        })
    }

    /// Splits `workgroups` into a 2D dispatch `(x, y)` within
    /// `max_compute_workgroups_per_dimension` (kernels rebuild the flat index from
    /// `num_workgroups`), or an error with the numbers.
    pub fn dispatch_size(&self, what: &'static str, workgroups: u64) -> Result<(u32, u32)> {
        let max = self.limits.max_compute_workgroups_per_dimension as u64;
        let x = workgroups.clamp(1, max);
        let y = workgroups.div_ceil(x).max(1);
        if y > max {
            return Err(Error::TooLarge { what, requested: workgroups, limit: max * max });
        }
        Ok((x as u32, y as u32))
    }

    /// The dispatch of an image kernel with one thread per pixel in 8×8 workgroups:
    /// `(⌈width/8⌉, ⌈height/8⌉)`, or an error with the numbers when an edge exceeds
    /// `max_compute_workgroups_per_dimension`.
    pub fn image_dispatch(
        &self,
        what: &'static str,
        width: u32,
        height: u32,
    ) -> Result<(u32, u32)> {
        let (x, y) = (width.div_ceil(8), height.div_ceil(8));
        let max = self.limits.max_compute_workgroups_per_dimension;
        if x.max(y) > max {
            return Err(Error::TooLarge { what, requested: x.max(y) as u64, limit: max as u64 });
        }
        Ok((x, y))
    }

    /// A bind group on `layout` with `buffers` bound whole at bindings `0, 1, 2, …` in order
    /// (the layout of every kernel but the octree build's), created inside error scopes.
    pub fn bind_group(
        &self,
        during: &'static str,
        layout: &wgpu::BindGroupLayout,
        buffers: &[&wgpu::Buffer],
    ) -> Result<wgpu::BindGroup> {
        let entries: Vec<_> = (0u32..).zip(buffers).map(|(i, b)| entry(i, b)).collect();
        self.bind_group_entries(during, layout, &entries)
    }

    /// A bind group on `layout` with each `(binding, buffer)` of `buffers` bound whole.
    pub fn bind_group_at(
        &self,
        during: &'static str,
        layout: &wgpu::BindGroupLayout,
        buffers: &[(u32, &wgpu::Buffer)],
    ) -> Result<wgpu::BindGroup> {
        let entries: Vec<_> = buffers.iter().map(|&(i, b)| entry(i, b)).collect();
        self.bind_group_entries(during, layout, &entries)
    }

    fn bind_group_entries(
        &self,
        during: &'static str,
        layout: &wgpu::BindGroupLayout,
        entries: &[wgpu::BindGroupEntry<'_>],
    ) -> Result<wgpu::BindGroup> {
        self.guarded(during, || {
            self.device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some(during),
                layout,
                entries,
            })
        })
    }

    /// Binds `buffers` at `0, 1, 2, …` of `pipeline`'s group 0, dispatches `pipeline` over
    /// `(x, y, 1)` workgroups in one compute pass, submits it and waits (with the timeout):
    /// one kernel launch, every step inside error scopes.
    pub fn dispatch(
        &self,
        during: &'static str,
        pipeline: &wgpu::ComputePipeline,
        buffers: &[&wgpu::Buffer],
        workgroups: (u32, u32),
    ) -> Result<()> {
        let bind = self.bind_group(during, &pipeline.get_bind_group_layout(0), buffers)?;
        let mut encoder = self.device.create_command_encoder(&Default::default());
        record_pass(&mut encoder, during, pipeline, &bind, workgroups);
        self.submit(during, encoder)
    }
}
