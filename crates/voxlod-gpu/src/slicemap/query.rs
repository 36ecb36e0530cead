//! The slicemap's queries on the GPU (compute): occupied slices in front of located points and
//! inner voxels per column, the mirrors of [`voxlod_cpu::voxelize::slicemap::query`] with
//! `countOneBits`, `firstTrailingBit` and shifts on the column words. Both are integer functions
//! of the bits and of the point's slice, which the GPU computes from the point's `f32` depth in
//! the reference's order of operations: counts are exact except for a point within rounding of
//! a slice boundary.

use voxlod_cpu::voxelize::slicemap::query::Located;
use voxlod_cpu::voxelize::slicemap::{Faces, Slicemap};

use crate::{Context, Error, Result};

/// The WGSL source of the query kernels.
pub const WGSL: &str = include_str!("query.wgsl");

/// The kernels' parameters, bound as a read-only storage buffer (mirrors WGSL `QueryParams`).
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
pub struct GpuQueryParams {
    /// Map width.
    pub width: u32,
    /// Map height.
    pub height: u32,
    /// Slices per column.
    pub slices: u32,
    /// Words per column and layer.
    pub words: u32,
    /// Bit 0: local slicing; bit 1: local columns end at their farthest fragment.
    pub mode: u32,
    /// Queries (occluder kernel).
    pub count: u32,
    /// `far − near` in `f32` ([`Slicemap::depth_span`]).
    pub span: f32,
    /// Padding.
    pub pad: u32,
}

/// One located point as the kernel reads it (mirrors WGSL `Query`).
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
pub struct GpuQuery {
    /// `y·width + x`, or `u32::MAX` for a point outside the map.
    pub column: u32,
    /// Depth `d = z − near`.
    pub d: f32,
}

/// The query kernels, compiled for one [`Context`].
pub struct SlicemapQueries<'a> {
    ctx: &'a Context,
    layout: wgpu::BindGroupLayout,
    occluders: wgpu::ComputePipeline,
    inner: wgpu::ComputePipeline,
}

impl<'a> SlicemapQueries<'a> {
    /// Compiles the kernels.
    pub fn new(ctx: &'a Context) -> Result<Self> {
        use wgpu::BufferBindingType::Storage;
        let ro = Storage { read_only: true };
        let entry = |binding, ty| wgpu::BindGroupLayoutEntry {
            binding,
            visibility: wgpu::ShaderStages::COMPUTE,
            ty: wgpu::BindingType::Buffer { ty, has_dynamic_offset: false, min_binding_size: None },
            count: None,
        };
        let entries = [
            entry(0, ro),
            entry(1, ro),
            entry(2, ro),
            entry(3, ro),
            entry(4, Storage { read_only: false }),
        ];
        let device = ctx.device();
        let (layout, pipeline_layout) =
            ctx.guarded("creating the slicemap query layout", || {
                let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                    label: Some("slicemap queries"),
                    entries: &entries,
                });
                let pipeline_layout =
                    device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                        label: Some("slicemap queries"),
                        bind_group_layouts: &[Some(&layout)],
                        immediate_size: 0,
                    });
                (layout, pipeline_layout)
            })?;
        let mut p = ctx.pipelines(
            "slicemap queries",
            WGSL,
            &["occluders", "inner_voxels"],
            &pipeline_layout,
        )?;
        let inner = p.pop().expect("two pipelines");
        let occluders = p.pop().expect("two pipelines");
        Ok(Self { ctx, layout, occluders, inner })
    }

    fn params(map: &Slicemap, count: u32) -> GpuQueryParams {
        let local = map.ranges.is_some() as u32;
        GpuQueryParams {
            width: map.camera.width,
            height: map.camera.height,
            slices: map.options.slices,
            words: map.words(),
            mode: local | local << 1,
            count,
            span: map.depth_span(),
            pad: 0,
        }
    }

    fn run(
        &self,
        pipeline: &wgpu::ComputePipeline,
        map: &Slicemap,
        queries: &[GpuQuery],
        items: u64,
    ) -> Result<Vec<u32>> {
        let ctx = self.ctx;
        let params = Self::params(map, queries.len() as u32);
        let params_buffer = ctx.uniform("slicemap query params", bytemuck::bytes_of(&params))?;
        let bits = ctx.storage_init("slicemap bits", bytemuck::cast_slice(&map.bits))?;
        let ranges: Vec<[f32; 2]> = map.ranges.clone().unwrap_or_else(|| vec![[0.0; 2]]);
        let ranges = ctx.storage_init("slicemap ranges", bytemuck::cast_slice(&ranges))?;
        let query = if queries.is_empty() { &[GpuQuery::default()][..] } else { queries };
        let query = ctx.storage_init("slicemap queries", bytemuck::cast_slice(query))?;
        let out_bytes = items.max(1) * 4;
        let out = ctx.storage_zeroed("slicemap query results", out_bytes)?;
        let (x, y) = ctx.dispatch_size("slicemap query workgroups", items.div_ceil(64))?;
        let layout = &self.layout;
        let bind = ctx.guarded("binding slicemap query buffers", || {
            ctx.device().create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("slicemap query"),
                layout,
                entries: &[
                    wgpu::BindGroupEntry {
                        binding: 0,
                        resource: params_buffer.as_entire_binding(),
                    },
                    wgpu::BindGroupEntry { binding: 1, resource: bits.as_entire_binding() },
                    wgpu::BindGroupEntry { binding: 2, resource: ranges.as_entire_binding() },
                    wgpu::BindGroupEntry { binding: 3, resource: query.as_entire_binding() },
                    wgpu::BindGroupEntry { binding: 4, resource: out.as_entire_binding() },
                ],
            })
        })?;
        let mut encoder = ctx.device().create_command_encoder(&Default::default());
        {
            let mut pass = encoder.begin_compute_pass(&Default::default());
            pass.set_pipeline(pipeline);
            pass.set_bind_group(0, &bind, &[]);
            pass.dispatch_workgroups(x, y, 1);
        }
        ctx.submit("querying a slicemap", encoder)?;
        let mut v: Vec<u32> = bytemuck::cast_slice(&ctx.read(&out, out_bytes)?).to_vec();
        v.truncate(items as usize);
        Ok(v)
    }

    /// Occupied slices of layer 0 in front of each located point (`None` for points outside
    /// the map), as [`Slicemap::count_nearer`].
    pub fn occluders(
        &self,
        map: &Slicemap,
        points: &[Option<Located>],
    ) -> Result<Vec<Option<u32>>> {
        if points.len() as u64 >= u32::MAX as u64 {
            return Err(Error::TooLarge {
                what: "slicemap queries",
                requested: points.len() as u64,
                limit: u32::MAX as u64 - 1,
            });
        }
        let w = map.camera.width;
        let queries: Vec<GpuQuery> = points
            .iter()
            .map(|p| match p {
                Some(l) => GpuQuery { column: l.y * w + l.x, d: l.d },
                None => GpuQuery { column: u32::MAX, d: 0.0 },
            })
            .collect();
        let out = self.run(&self.occluders, map, &queries, queries.len() as u64)?;
        Ok(out.into_iter().map(|n| (n != u32::MAX).then_some(n)).collect())
    }

    /// Inner voxels of every column (row-major), as [`Slicemap::inner_voxels`]; the map must
    /// have front and back layers.
    pub fn inner_voxels(&self, map: &Slicemap) -> Result<Vec<u32>> {
        if map.options.faces != Faces::Split {
            return Err(Error::Unsupported {
                what: "inner voxels of a slicemap without front and back layers (Faces::Split)",
            });
        }
        let columns = map.camera.width as u64 * map.camera.height as u64;
        self.run(&self.inner, map, &[], columns)
    }
}

#[cfg(test)]
mod tests {
    use std::mem::offset_of;

    use super::*;
    use crate::layout::assert_mirrors;

    #[test]
    fn query_types_mirror_their_wgsl() {
        assert_mirrors(
            WGSL,
            "QueryParams",
            size_of::<GpuQueryParams>(),
            &[
                ("width", offset_of!(GpuQueryParams, width)),
                ("height", offset_of!(GpuQueryParams, height)),
                ("slices", offset_of!(GpuQueryParams, slices)),
                ("words", offset_of!(GpuQueryParams, words)),
                ("mode", offset_of!(GpuQueryParams, mode)),
                ("count", offset_of!(GpuQueryParams, count)),
                ("span", offset_of!(GpuQueryParams, span)),
                ("pad", offset_of!(GpuQueryParams, pad)),
            ],
        );
        assert_mirrors(
            WGSL,
            "Query",
            size_of::<GpuQuery>(),
            &[("column", offset_of!(GpuQuery, column)), ("d", offset_of!(GpuQuery, d))],
        );
    }
}
