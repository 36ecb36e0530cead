//! Uploads of virtual-mesh and Adaptive grids: the CPU renderer's checks, the records laid
//! out per kind behind the brick look-up, each voxel's coordinates and tag, the decoder
//! tables.

use voxlod_cpu::appearance::adaptive::AdaptiveGrid;
use voxlod_cpu::appearance::subgrid::DirectionalRule;
use voxlod_cpu::appearance::virtual_mesh::{
    FaceSampling, ShadingFallback, VirtualMeshGrid, VirtualMeshParams,
};
use voxlod_cpu::appearance::{AppearanceGrid, record_material};
use voxlod_cpu::render::filtered::FrameCache;
use voxlod_format::records::{AdaptiveRef, Kind};
use voxlod_format::{BrickMap, GridSpec};

use super::super::upload::check_specular;
use super::super::{FilteredKernel, GpuRecord, GpuRecords, RecordKind, brick_lookup};
use super::{
    GpuVirtualMesh, GpuVoxel, MAX_SAMPLES_PER_FACE, VoxelBuffers, cache_bytes, decode_tables,
};
use crate::{Error, Result};

/// `Params.vmesh` words for `p` (the voxel count is filled in by the upload), or an error for
/// a sample count the kernel does not take, or for a choice it has no code for (the authors'
/// directional-opacity rule, random face sampling: [`Error::Unsupported`] naming the
/// parameter). The third word holds flags: 1 projected-area scaling, 2 the unshaded fallback.
fn vmesh_words(p: VirtualMeshParams) -> Result<[u32; 4]> {
    if p.sampling != FaceSampling::Stratified {
        return Err(Error::Unsupported {
            what: "VirtualMeshParams::sampling other than FaceSampling::Stratified (the \
                   authors' random face samples) in the GPU filtered renderer",
        });
    }
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
        DirectionalRule::Authors => {
            return Err(Error::Unsupported {
                what: "VirtualMeshParams::rule = DirectionalRule::Authors (the authors' \
                       directional opacity) in the GPU filtered renderer",
            });
        }
    };
    let unshaded = p.fallback == ShadingFallback::Unshaded;
    let flags = u32::from(p.projected_area) | u32::from(unshaded) << 1;
    Ok([rule, p.samples_per_face, flags, 0])
}

fn invalid(name: &'static str, value: String, reason: String) -> Error {
    Error::Cpu(voxlod_cpu::Error::InvalidParameter { name, value, reason })
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
                    let r = &averages[k];
                    a.records.push(GpuRecord::averages(r, &record_material(r.color(), s)));
                }
                Kind::Sggx => {
                    a.push(c, Kind::Sggx, a.records.len())?;
                    let r = &sggx[k];
                    a.records.push(GpuRecord::vjk21(r, &record_material(r.color(), s)));
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
        a: Arrays,
    ) -> Result<GpuRecords> {
        let lookup = brick_lookup(map)?;
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
        let mut records = self.record_buffers(kind, grid, lookup, a.records)?;
        records.voxels = Some(VoxelBuffers {
            params,
            tables: ctx.uniform("decoder tables", &tables_bytes)?,
            voxels: ctx.storage_array("voxel coordinates and tags", &a.voxels)?,
            vmesh: ctx.storage_array("virtual-mesh records", &a.vmesh)?,
        });
        Ok(records)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

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

    /// The authors' choices: the unshaded fallback is flag 2; their opacity rule and random
    /// face samples have no kernel and are refused by name.
    #[test]
    fn authors_choices_are_flags_or_refused_by_name() {
        let p = VirtualMeshParams { fallback: ShadingFallback::Unshaded, ..Default::default() };
        assert_eq!(vmesh_words(p).unwrap(), [0, 16, 2, 0]);
        let p = VirtualMeshParams { rule: DirectionalRule::Authors, ..Default::default() };
        let e = vmesh_words(p).unwrap_err();
        assert!(matches!(e, Error::Unsupported { what } if what.contains("rule")), "{e}");
        let p = VirtualMeshParams { sampling: FaceSampling::authors(1), ..Default::default() };
        let e = vmesh_words(p).unwrap_err();
        assert!(matches!(e, Error::Unsupported { what } if what.contains("sampling")), "{e}");
    }
}
