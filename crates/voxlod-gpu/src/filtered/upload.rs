//! Uploads: record grids (Averages, \[VJK21\], the baseline's opaque voxels) checked as the
//! CPU renderer checks them, decoded on the host by voxlod-format's own decoders, and laid out
//! behind the brick look-up ([`GpuRecords`]).

use glam::Vec3;
use voxlod_cpu::appearance::averages::{AveragesGrid, AveragesNormal};
use voxlod_cpu::appearance::{AppearanceGrid, RecordAppearance, record_material};
use voxlod_cpu::render::baseline::BaselineVoxel;
use voxlod_cpu::render::filtered::FrameCache;
use voxlod_format::records::{AverageRecord, SggxRecord, SpecularRecord};
use voxlod_format::{BrickMap, GridSpec};
use voxlod_scene::MaterialSample;

use super::{FilteredKernel, GpuBrick, GpuRecord, RecordKind, brick_lookup, voxels};
use crate::{Error, Result};

/// A record grid uploaded to one device.
pub struct GpuRecords {
    pub(super) kind: RecordKind,
    pub(super) grid: GridSpec,
    pub(super) table: wgpu::Buffer,
    pub(super) bricks: wgpu::Buffer,
    pub(super) slots: wgpu::Buffer,
    pub(super) records: wgpu::Buffer,
    /// Virtual-mesh and Adaptive grids: the buffers of the per-voxel passes.
    pub(super) voxels: Option<voxels::VoxelBuffers>,
    /// Averages grids: shade with the mean normal as stored instead of flipping it toward
    /// the viewer ([`AveragesNormal::AsStored`]; bit 4 of the kernel's flags).
    pub(super) averages_as_stored: bool,
}

impl GpuRecords {
    /// Which records these are.
    pub fn kind(&self) -> RecordKind {
        self.kind
    }
}

/// Records with a linear albedo (both record kinds of the kernel).
pub trait HasColor {
    /// Linear albedo.
    fn color(&self) -> Vec3;
}

impl HasColor for AverageRecord {
    fn color(&self) -> Vec3 {
        AverageRecord::color(self)
    }
}

impl HasColor for SggxRecord {
    fn color(&self) -> Vec3 {
        SggxRecord::color(self)
    }
}

impl GpuRecord {
    /// An Averages record as the kernel reads it, with the material `m` its voxel's colour and
    /// specular side record give ([`record_material`]).
    pub(super) fn averages(r: &AverageRecord, m: &MaterialSample) -> Self {
        Self {
            a: m.albedo.extend(r.opacity()).to_array(),
            b: r.normal().extend(0.0).to_array(),
            c: [0.0, 0.0, 0.0, m.specular.x],
            d: [0.0, 0.0, 0.0, m.shininess],
        }
    }

    /// A \[VJK21\] (SGGX) record as the kernel reads it, with its material `m`.
    pub(super) fn vjk21(r: &SggxRecord, m: &MaterialSample) -> Self {
        let s = r.matrix();
        Self {
            a: m.albedo.extend(r.sigma_t()).to_array(),
            b: s.x_axis.extend(r.gamma()).to_array(),
            c: s.y_axis.extend(m.specular.x).to_array(),
            d: s.z_axis.extend(m.shininess).to_array(),
        }
    }
}

/// Checks that `specular`, if any, has one side record per voxel with a record.
pub(super) fn check_specular(specular: Option<&[SpecularRecord]>, voxels: usize) -> Result<()> {
    match specular {
        Some(s) if s.len() != voxels => Err(Error::Cpu(voxlod_cpu::Error::InvalidParameter {
            name: "specular records",
            value: s.len().to_string(),
            reason: format!("one per voxel with a record: {voxels}"),
        })),
        _ => Ok(()),
    }
}

impl FilteredKernel<'_> {
    /// Uploads `app` after the CPU renderer's checks on it (a [`FrameCache`] is built over its
    /// own records and dropped: invalid grid, inconsistent records or side records give the
    /// CPU's errors).
    pub fn upload_averages(&self, app: &AppearanceGrid<AverageRecord>) -> Result<GpuRecords> {
        self.upload(app, RecordKind::Averages, GpuRecord::averages)
    }

    /// Uploads an Averages grid with its normal rule ([`AveragesGrid::normal`]: flipped toward
    /// the viewer, or as stored, both mirrored by the kernel), with the checks of
    /// [`FilteredKernel::upload_averages`].
    pub fn upload_averages_grid(&self, app: &AveragesGrid) -> Result<GpuRecords> {
        let mut records = self.upload_averages(&app.grid)?;
        records.averages_as_stored = app.normal == AveragesNormal::AsStored;
        Ok(records)
    }

    /// Uploads a \[VJK21\] (SGGX) grid, with the checks of [`FilteredKernel::upload_averages`].
    pub fn upload_vjk21(&self, app: &AppearanceGrid<SggxRecord>) -> Result<GpuRecords> {
        self.upload(app, RecordKind::Vjk21, GpuRecord::vjk21)
    }

    fn upload<R>(
        &self,
        app: &AppearanceGrid<R>,
        kind: RecordKind,
        decode: impl Fn(&R, &MaterialSample) -> GpuRecord,
    ) -> Result<GpuRecords>
    where
        R: RecordAppearance<Params = ()> + HasColor,
    {
        drop(FrameCache::with_layout(app, &app.records)?);
        check_specular(app.specular.as_deref(), app.records.len())?;
        let records: Vec<GpuRecord> = app
            .records
            .values()
            .iter()
            .enumerate()
            .map(|(i, r)| {
                decode(r, &record_material(r.color(), app.specular.as_ref().map(|s| &s[i])))
            })
            .collect();
        self.record_buffers(kind, app.grid, brick_lookup(&app.records)?, records)
    }

    /// Uploads the baseline renderer's voxels (opaque cubes of one colour) over `grid`, with
    /// the checks [`voxlod_cpu::render::baseline::render`] makes on them (a valid grid, a brick
    /// map of the grid's size). Render with [`FilteredKernel::render_baseline`].
    pub fn upload_baseline(
        &self,
        grid: &GridSpec,
        voxels: &BrickMap<BaselineVoxel>,
    ) -> Result<GpuRecords> {
        grid.validate().map_err(voxlod_cpu::Error::from)?;
        if voxels.dims() != grid.dims {
            return Err(Error::Cpu(voxlod_cpu::Error::InvalidParameter {
                name: "voxels",
                value: format!("brick map of {} voxels", voxels.dims()),
                reason: format!("the grid has {} voxels", grid.dims),
            }));
        }
        let records = voxels
            .values()
            .iter()
            .map(|v| GpuRecord { a: v.albedo().extend(1.0).to_array(), ..Default::default() })
            .collect();
        self.record_buffers(RecordKind::Baseline, *grid, brick_lookup(voxels)?, records)
    }

    /// The buffers of a brick look-up ([`brick_lookup`]) and of `records` laid out as its
    /// values (the per-voxel pass buffers are added by the virtual-mesh and Adaptive uploads).
    pub(super) fn record_buffers(
        &self,
        kind: RecordKind,
        grid: GridSpec,
        (table, bricks, slots): (Vec<u32>, Vec<GpuBrick>, Vec<u32>),
        records: Vec<GpuRecord>,
    ) -> Result<GpuRecords> {
        let ctx = self.ctx;
        Ok(GpuRecords {
            kind,
            grid,
            table: ctx.storage_array("brick table", &table)?,
            bricks: ctx.storage_array("brick masks", &bricks)?,
            slots: ctx.storage_array("record slots", &slots)?,
            records: ctx.storage_array("filtered records", &records)?,
            voxels: None,
            averages_as_stored: false,
        })
    }
}
