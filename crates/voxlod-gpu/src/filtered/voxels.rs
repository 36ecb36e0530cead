//! Kernel 4 (second part): the filtered renderer for **virtual mesh + opacity subgrid** grids
//! ([`VirtualMeshGrid`]) and **Adaptive** grids ([`AdaptiveGrid`]: each voxel an Averages,
//! \[VJK21\] or virtual-mesh record), the mirror of [`voxlod_cpu::render::filtered::render`]
//! over them: the same camera rays, DDA, compositing, shadow rays and shading as the first
//! part (see [the parent module](super)), with `vmesh.wgsl` porting
//! [`voxlod_cpu::appearance::vmesh::shade_record`] (the projected-area-weighted faces, the
//! fixed Hammersley barycentric samples of distribution faces, the fallback) and
//! [`voxlod_cpu::appearance::subgrid::directional_opacity`] (both rules, Lines and Circles),
//! times [`projected_area_ratio`](voxlod_cpu::appearance::vmesh::projected_area_ratio) when
//! [`VirtualMeshParams::projected_area`] is on. No random numbers are drawn: the CPU's
//! virtual-mesh shading samples fixed barycentric points (`barycentric_point`) and its Lines
//! rule a fixed pattern, so both backends evaluate the same points in the same order.
//!
//! # Data on the GPU
//! The brick look-up of the parent module; the virtual-mesh records in their frozen 136-byte
//! layout ([`GpuVirtualMesh`]: the record's bytes as 34 words, decoded in the shader, plus
//! the voxel's specular level and exponent), the sRGB and semi-axis decoders as 512-entry
//! tables made by voxlod-format's own decoders (the shader then decodes bit-identically to
//! the host); Averages and \[VJK21\] records of an Adaptive grid decoded on the host as in the
//! first part. Per voxel a [`GpuVoxel`] (grid coordinates and the tag: kind in the top 2 bits,
//! index into its kind's array below) and, per frame, 32 bytes of cached values.
//!
//! # Kernel (what a real GPU sees)
//! A virtual-mesh voxel costs far more than the others to evaluate: up to 8 faces × 16
//! samples of the shading function, and 32 lines × 27 slab overlaps (or 16 pixels × 27 lens
//! areas) for one directional opacity. Evaluating per hit, as the first part does, would
//! repeat that for each of the up to 4 × pixels camera rays reaching a voxel, and the light
//! opacity for every shadow-ray step. So a frame is three dispatches:
//! 1. `light_pass`, one invocation per voxel (workgroups of 64): the voxel's opacity for the
//!    direction the light travels at its centre;
//! 2. `view_pass`, one invocation per voxel: its shadow ray (reading pass 1's opacities), its
//!    radiance and its opacity toward the eye;
//! 3. `composite`, one invocation per pixel in 8×8 workgroups: the 4 camera rays composite
//!    the cached values.
//!
//! Each value is a function of the voxel alone, so it equals what the CPU caches lazily for
//! the voxels its rays reach (the CPU reference row of the suite checks that its cache equals
//! per-ray evaluation). The passes evaluate every voxel, visible or not: on a real GPU that is
//! one coherent pass over a flat array (neighbouring invocations are neighbouring voxels in
//! Morton order, so their shadow rays cross the same bricks), and the visible voxels of a
//! surface grid are a large share of all (a camera ray composites ~2–4 voxels and the 4 rays
//! of a pixel share most of them, so at image size ≈ grid size per-hit evaluation does more
//! work). Divergence: the record kind switches per voxel in an Adaptive grid (a warp of mixed
//! kinds runs each branch), and the virtual mesh's loops are bounded (8 faces, ≤
//! [`MAX_SAMPLES_PER_FACE`] samples, 32 lines, 27 cells) but their trip counts differ between
//! records (visible faces, distribution flags, early-out of Lines on opaque cells). Memory
//! per virtual-mesh record read is 144 bytes, read once per pass and kept in registers.
//! Expected on a real GPU: the view pass dominates (shadow walks and the shading samples);
//! the composite pass is the first part's walk with no evaluation. Measured figures on
//! lavapipe are CPU timings of the GPU path, never GPU speed (README).
//!
//! # Agreement with the CPU
//! As for the first part, plus: WGSL's `sqrt`, `acos` (Circles) and division are within a
//! few ULP, so a barycentric sample normal, a lens area or a slab crossing can differ in the
//! last bits. A Lines crossing that lands within an ULP of a sub-cell boundary can add or
//! drop a sub-cell (a step of `1/32` of that cell's opacity at most, per line); everything
//! else moves a radiance by ~10⁻⁶ relative. The equivalence suite states the bound.

use glam::Vec3;
use voxlod_cpu::appearance::adaptive::AdaptiveGrid;
use voxlod_cpu::appearance::subgrid::DirectionalRule;
use voxlod_cpu::appearance::vmesh::{VirtualMeshGrid, VirtualMeshParams};
use voxlod_cpu::appearance::{AppearanceGrid, record_material};
use voxlod_cpu::render::filtered::FrameCache;
use voxlod_format::records::quant::srgb_to_linear_table;
use voxlod_format::records::{
    AdaptiveRef, AverageRecord, Kind, SCALE_RANGE, SggxRecord, SpecularRecord, VirtualMeshRecord,
};
use voxlod_format::{BrickMap, GridSpec};
use voxlod_scene::Image;

use super::{
    FilteredKernel, GpuFilteredParams, GpuRecord, GpuRecords, RecordKind, brick_lookup, non_empty,
    read_image,
};
use crate::raycast::entry;
use crate::{Context, Error, Result};

/// The WGSL source of the per-voxel passes: shading, the first part's renderer (its
/// parameters, DDA, look-up and \[VJK21\] code), the virtual mesh, then the passes.
pub const WGSL: &str = concat!(
    include_str!("../shading.wgsl"),
    include_str!("filtered.wgsl"),
    include_str!("../subgrid.wgsl"),
    include_str!("vmesh.wgsl"),
    include_str!("voxels.wgsl"),
);

/// Most shading samples per distribution face the kernel takes (the CPU's default is 16):
/// a bound on the shading loop of one voxel.
pub const MAX_SAMPLES_PER_FACE: u32 = 1024;

/// A virtual-mesh record as the kernel reads it (mirrors WGSL `VmeshRecord`): the frozen
/// [`VirtualMeshRecord`]'s 136 bytes as 34 little-endian words, and the voxel's specular
/// level and exponent (0 and 1 without specular records, as `record_material` gives them).
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
pub struct GpuVirtualMesh {
    /// The record's bytes.
    pub bytes: [u32; 34],
    /// Specular level, Blinn-Phong exponent.
    pub specular: [f32; 2],
}

impl Default for GpuVirtualMesh {
    fn default() -> Self {
        bytemuck::Zeroable::zeroed()
    }
}

impl GpuVirtualMesh {
    /// The record with the voxel's specular side record, if any.
    pub fn new(record: &VirtualMeshRecord, specular: Option<&SpecularRecord>) -> Self {
        let mut bytes = [0u32; 34];
        // The bytes as they are: the GPU reads its words little-endian, byte `b` of the
        // record at bits `8·(b % 4)` of word `b / 4`.
        bytemuck::bytes_of_mut(&mut bytes).copy_from_slice(bytemuck::bytes_of(record));
        let m = record_material(Vec3::ZERO, specular);
        Self { bytes, specular: [m.specular.x, m.shininess] }
    }
}

/// One voxel with a record (mirrors the WGSL `vec4<u32>` of `voxels`): grid coordinates, and
/// its tag (kind in bits 30–31 as [`AdaptiveRef`], index into the kernel's array of that kind).
pub type GpuVoxel = [u32; 4];

/// The decoder tables: sRGB8 → linear (256), then [`SCALE_RANGE`] codes → semi-axes (256).
pub fn decode_tables() -> [f32; 512] {
    let srgb = srgb_to_linear_table();
    std::array::from_fn(|i| if i < 256 { srgb[i] } else { SCALE_RANGE.decode((i - 256) as u8) })
}

/// The buffers of a virtual-mesh or Adaptive grid beyond the brick look-up.
pub(super) struct VoxelBuffers {
    /// `Params.vmesh`: rule, samples per face, projected area, voxel count.
    pub params: [u32; 4],
    tables: wgpu::Buffer,
    voxels: wgpu::Buffer,
    vmesh: wgpu::Buffer,
}

/// The three pipelines and their shared bind group layout.
pub(super) struct Passes {
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

/// `Params.vmesh` words for `p` (the voxel count is filled in by the upload), or an error for
/// a sample count the kernel does not take.
fn vmesh_words(p: VirtualMeshParams) -> Result<[u32; 4]> {
    if p.samples_per_face > MAX_SAMPLES_PER_FACE {
        return Err(Error::TooLarge {
            what: "VirtualMeshParams::samples_per_face on the GPU (shading samples per face)",
            requested: p.samples_per_face as u64,
            limit: MAX_SAMPLES_PER_FACE as u64,
        });
    }
    let rule = match p.rule {
        DirectionalRule::Lines => 0,
        DirectionalRule::Circles => 1,
    };
    Ok([rule, p.samples_per_face, u32::from(p.projected_area), 0])
}

fn invalid(name: &'static str, value: String, reason: String) -> Error {
    Error::Cpu(voxlod_cpu::Error::InvalidParameter { name, value, reason })
}

/// Checks that `specular`, if any, has one record per voxel.
fn check_specular(specular: Option<&[SpecularRecord]>, voxels: usize) -> Result<()> {
    match specular {
        Some(s) if s.len() != voxels => Err(invalid(
            "specular records",
            s.len().to_string(),
            format!("one per voxel with a record: {voxels}"),
        )),
        _ => Ok(()),
    }
}

/// The host-side arrays of a grid for the passes.
#[derive(Default)]
struct Arrays {
    voxels: Vec<GpuVoxel>,
    records: Vec<GpuRecord>,
    vmesh: Vec<GpuVirtualMesh>,
}

impl Arrays {
    /// Adds voxel `c` with kind `kind` at `index` of the kind's kernel array.
    fn push(&mut self, c: glam::UVec3, kind: Kind, index: usize) -> Result<()> {
        let tag = u32::try_from(index).ok().and_then(|i| AdaptiveRef::new(kind, i)).ok_or(
            Error::TooLarge {
                what: "records of one kind in a virtual-mesh/Adaptive grid on the GPU",
                requested: index as u64 + 1,
                limit: AdaptiveRef::MAX_INDEX as u64 + 1,
            },
        )?;
        self.voxels.push([c.x, c.y, c.z, tag.0]);
        Ok(())
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

    /// Uploads a virtual-mesh grid (its records, specular side records and parameters, the
    /// projected-area variant included), after the CPU renderer's checks on it: invalid grid,
    /// inconsistent records or side records give the CPU's errors; more than
    /// [`MAX_SAMPLES_PER_FACE`] shading samples per face, or a grid over the device's buffer
    /// limits, an error naming it.
    pub fn upload_virtual_mesh(&self, grid: &VirtualMeshGrid) -> Result<GpuRecords> {
        let params = vmesh_words(grid.params())?;
        let AppearanceGrid { records, specular, .. } = &grid.grid;
        drop(FrameCache::with_layout(grid, records)?);
        check_specular(specular.as_deref(), records.len())?;
        let mut a = Arrays::default();
        for (i, (c, r)) in records.iter().enumerate() {
            a.push(c, Kind::VirtualMesh, i)?;
            a.vmesh.push(GpuVirtualMesh::new(r, specular.as_ref().map(|s| &s[i])));
        }
        self.voxel_buffers(RecordKind::VirtualMesh, grid.grid.grid, records, params, a)
    }

    /// Uploads an Adaptive grid (each voxel's record of its kind, its specular side record,
    /// the virtual-mesh parameters), with the checks of
    /// [`FilteredKernel::upload_virtual_mesh`]; a tag pointing past its kind's records is an
    /// error naming the voxel.
    pub fn upload_adaptive(&self, grid: &AdaptiveGrid) -> Result<GpuRecords> {
        use voxlod_cpu::appearance::Appearance;
        let params = vmesh_words(grid.vmesh_params())?;
        let refs = grid.refs();
        drop(FrameCache::with_layout(grid, refs)?);
        let specular = grid.specular_records();
        check_specular(specular, refs.len())?;
        let (averages, sggx, vmesh) =
            (grid.average_records(), grid.sggx_records(), grid.vmesh_records());
        let mut a = Arrays::default();
        for (i, (c, tag)) in refs.iter().enumerate() {
            let s = specular.map(|s| &s[i]);
            let k = tag.index() as usize;
            let (len, name) = match tag.kind() {
                Kind::Average => (averages.len(), "Averages"),
                Kind::Sggx => (sggx.len(), "[VJK21]"),
                Kind::VirtualMesh => (vmesh.len(), "virtual-mesh"),
            };
            if k >= len {
                return Err(invalid(
                    "adaptive tag",
                    format!("voxel {c}: {name} record {k}"),
                    format!("the grid has {len} {name} records"),
                ));
            }
            match tag.kind() {
                Kind::Average => {
                    a.push(c, Kind::Average, a.records.len())?;
                    a.records.push(average_record(&averages[k], s));
                }
                Kind::Sggx => {
                    a.push(c, Kind::Sggx, a.records.len())?;
                    a.records.push(sggx_record(&sggx[k], s));
                }
                Kind::VirtualMesh => {
                    a.push(c, Kind::VirtualMesh, a.vmesh.len())?;
                    a.vmesh.push(GpuVirtualMesh::new(&vmesh[k], s));
                }
            }
        }
        self.voxel_buffers(RecordKind::Adaptive, *grid.grid(), refs, params, a)
    }

    fn voxel_buffers<T>(
        &self,
        kind: RecordKind,
        grid: GridSpec,
        map: &BrickMap<T>,
        mut params: [u32; 4],
        mut a: Arrays,
    ) -> Result<GpuRecords> {
        let (mut table, mut bricks, mut slots) = brick_lookup(map)?;
        params[3] = u32::try_from(a.voxels.len()).map_err(|_| Error::TooLarge {
            what: "voxels with a record in a virtual-mesh/Adaptive grid on the GPU",
            requested: a.voxels.len() as u64,
            limit: u32::MAX as u64,
        })?;
        // The per-frame cache the render allocates: checked now, so an oversized grid is
        // refused at upload.
        self.ctx.check_storage("per-voxel cache of the voxel passes", cache_bytes(&params))?;
        let ctx = self.ctx;
        let tables = decode_tables();
        let mut tables_bytes = bytemuck::bytes_of(&tables).to_vec();
        tables_bytes.resize(2048, 0);
        Ok(GpuRecords {
            kind,
            grid,
            table: ctx.storage_init("brick table", non_empty(&mut table))?,
            bricks: ctx.storage_init("brick masks", non_empty(&mut bricks))?,
            slots: ctx.storage_init("record slots", non_empty(&mut slots))?,
            records: ctx.storage_init("Averages/[VJK21] records", non_empty(&mut a.records))?,
            voxels: Some(VoxelBuffers {
                params,
                tables: ctx.uniform("decoder tables", &tables_bytes)?,
                voxels: ctx.storage_init("voxel coordinates and tags", non_empty(&mut a.voxels))?,
                vmesh: ctx.storage_init("virtual-mesh records", non_empty(&mut a.vmesh))?,
            }),
        })
    }

    /// Renders a virtual-mesh or Adaptive grid: the three passes (module docs).
    pub(super) fn render_voxels(
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
        let bind = ctx.guarded("binding the voxel passes' buffers", || {
            ctx.device().create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("filtered voxel passes"),
                layout: &passes.layout,
                entries: &[
                    entry(0, &uniform),
                    entry(1, &app.table),
                    entry(2, &app.bricks),
                    entry(3, &app.slots),
                    entry(4, &app.records),
                    entry(5, &out),
                    entry(6, &v.tables),
                    entry(7, &v.voxels),
                    entry(8, &v.vmesh),
                    entry(9, &cache),
                ],
            })
        })?;
        let mut encoder = ctx.device().create_command_encoder(&Default::default());
        // Separate passes: each reads what the previous one wrote.
        for (pipeline, (x, y)) in
            [(&passes.light, (vx, vy)), (&passes.view, (vx, vy)), (&passes.composite, (lx, ly))]
        {
            let mut pass = encoder.begin_compute_pass(&Default::default());
            pass.set_pipeline(pipeline);
            pass.set_bind_group(0, &bind, &[]);
            pass.dispatch_workgroups(x, y, 1);
        }
        ctx.submit("rendering virtual-mesh/Adaptive records", encoder)?;
        read_image(ctx, &out, width, height)
    }
}

/// Bytes of the per-frame cache: two `vec4<f32>` per voxel.
fn cache_bytes(params: &[u32; 4]) -> u64 {
    params[3] as u64 * 32
}

/// An Averages record decoded as the first part decodes it.
fn average_record(r: &AverageRecord, s: Option<&SpecularRecord>) -> GpuRecord {
    let m = record_material(r.color(), s);
    GpuRecord {
        a: m.albedo.extend(r.opacity()).to_array(),
        b: r.normal().extend(0.0).to_array(),
        c: [0.0, 0.0, 0.0, m.specular.x],
        d: [0.0, 0.0, 0.0, m.shininess],
    }
}

/// A \[VJK21\] record decoded as the first part decodes it.
fn sggx_record(r: &SggxRecord, s: Option<&SpecularRecord>) -> GpuRecord {
    let m = record_material(r.color(), s);
    let x = r.matrix();
    GpuRecord {
        a: m.albedo.extend(r.sigma_t()).to_array(),
        b: x.x_axis.extend(r.gamma()).to_array(),
        c: x.y_axis.extend(m.specular.x).to_array(),
        d: x.z_axis.extend(m.shininess).to_array(),
    }
}

#[cfg(test)]
mod tests {
    use std::mem::offset_of;

    use super::*;
    use crate::layout::assert_mirrors;

    #[test]
    fn voxel_pass_types_mirror_their_wgsl() {
        assert_mirrors(
            WGSL,
            "VmeshRecord",
            size_of::<GpuVirtualMesh>(),
            &[
                ("bytes", offset_of!(GpuVirtualMesh, bytes)),
                ("specular", offset_of!(GpuVirtualMesh, specular)),
            ],
        );
        // The arrays the kernel indexes: 144-byte records (a multiple of the WGSL alignment
        // of 8, so the array stride is the size), 16-byte voxels.
        assert_eq!(size_of::<GpuVirtualMesh>() % 8, 0);
        assert_eq!(size_of::<GpuVoxel>(), 16);
    }

    #[test]
    fn records_upload_in_their_frozen_byte_order() {
        let mut r = VirtualMeshRecord::default();
        r.axes[0] = [1, -2, 3];
        r.opacity[26] = 0xab;
        r.distribution = 0x5a;
        let g = GpuVirtualMesh::new(&r, Some(&SpecularRecord::new(0.5, 32.0)));
        let byte = |b: usize| (g.bytes[b / 4] >> (8 * (b % 4))) & 0xff;
        assert_eq!((byte(0), byte(1), byte(2)), (1, 0xfe, 3));
        assert_eq!((byte(108), byte(135)), (0x5a, 0xab));
        assert!((g.specular[0] - 0.5).abs() < 0.003 && (g.specular[1] / 32.0 - 1.0).abs() < 0.02);
        let plain = GpuVirtualMesh::new(&r, None);
        assert_eq!(plain.specular, [0.0, 1.0]);
        let t = decode_tables();
        assert_eq!((t[0], t[255], t[256], t[257]), (0.0, 1.0, 0.0, SCALE_RANGE.decode(1)));
    }

    #[test]
    fn sample_counts_over_the_bound_are_refused_by_name() {
        let p =
            VirtualMeshParams { samples_per_face: MAX_SAMPLES_PER_FACE + 1, ..Default::default() };
        let e = vmesh_words(p).unwrap_err().to_string();
        assert!(e.contains("samples_per_face") && e.contains("1025"), "{e}");
        let p = VirtualMeshParams {
            rule: DirectionalRule::Circles,
            projected_area: true,
            ..Default::default()
        };
        assert_eq!(vmesh_words(p).unwrap(), [1, 16, 1, 0]);
    }
}
