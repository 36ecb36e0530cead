//! Fill (McNabb 2015, §5.5.2) on the GPU: the per-particle radii and the bins' particle
//! lists prepared on the host, one dispatch over the voxels of the kept metavoxels, and the
//! occupied boxes read back.

use voxlod_cpu::volume::binning::{Bin, Prepared};
use voxlod_cpu::volume::{BuildStats, StageTimes, VolumeSpec};
use voxlod_scene::particles::{DisplacedSphere, DisplacementMap, FLAG_EMISSIVE};

use super::params::{GpuFillParams, GpuFrame, GpuPrep, GpuSlot};
use super::{GpuVolume, VolumeKernels, WORKGROUP};
use crate::{Error, Result};

impl VolumeKernels<'_> {
    /// Fill (§5.5.2) of the metavoxels of `bins` on the GPU: density the sum, colour the max,
    /// emission kept apart (the CPU's [`voxlod_cpu::volume::fill::fill`] per bin). `prepared` is
    /// [`Binning::prepared`](voxlod_cpu::volume::binning::Binning::prepared) of the same spheres
    /// and spec.
    pub fn fill(
        &self,
        spheres: &[DisplacedSphere],
        prepared: &[Prepared],
        map: &DisplacementMap,
        spec: &VolumeSpec,
        bins: &[Bin],
    ) -> Result<GpuVolume> {
        let ctx = self.ctx;
        if prepared.len() != spheres.len() {
            return Err(voxlod_cpu::Error::InvalidParameter {
                name: "prepared particles",
                value: format!("{} for {} spheres", prepared.len(), spheres.len()),
                reason: "must be binning::prepare of the same spheres".into(),
            }
            .into());
        }
        let m = spec.metavoxel_edge;
        let m3 = (m as u64).pow(3);
        let voxels = bins.len() as u64 * m3;
        if voxels > u32::MAX as u64 {
            return Err(Error::TooLarge {
                what: "voxels of the kept metavoxels (indexed in 32 bits)",
                requested: voxels,
                limit: u32::MAX as u64,
            });
        }
        let [n_lo, n_hi] = map.bounds();
        let preps: Vec<GpuPrep> = prepared
            .iter()
            .map(|p| {
                // The CPU fill's radii, the same f32 operations.
                let (r_lo, r_hi) = (p.inner + p.amplitude * n_lo, p.inner + p.amplitude * n_hi);
                let accept = p.inner.max(r_lo);
                GpuPrep {
                    center: p.center.extend(p.inner).to_array(),
                    radii: [p.amplitude, accept * accept, r_hi * r_hi, 0.0],
                }
            })
            .collect();
        let mut lists = Vec::new();
        let mut slots = Vec::with_capacity(bins.len());
        let mut emissive = false;
        for b in bins {
            if let Some(&bad) = b.particles.iter().find(|&&p| p as usize >= spheres.len()) {
                return Err(voxlod_cpu::Error::InvalidParameter {
                    name: "bin",
                    value: format!("particle {bad} in metavoxel {:?}", b.coord),
                    reason: format!("only {} particles", spheres.len()),
                }
                .into());
            }
            emissive |= b.particles.iter().any(|&p| spheres[p as usize].flags & FLAG_EMISSIVE != 0);
            slots.push(GpuSlot {
                coord: [b.coord[0], b.coord[1], b.coord[2], lists.len() as u32],
                range: [b.particles.len() as u32, 0, 0, 0],
            });
            lists.extend_from_slice(&b.particles);
        }
        let voxel_bytes = voxels * 16;
        ctx.check_storage("volume voxels", voxel_bytes)?;
        let emission_bytes = if emissive { voxel_bytes } else { 16 };
        ctx.check_storage("volume emission", emission_bytes)?;
        let boxes_init: Vec<u32> =
            bins.iter().flat_map(|_| [u32::MAX, u32::MAX, u32::MAX, 0, 0, 0]).collect();
        // At least one element: a binding must hold one element of its array.
        let voxel_buf = ctx.storage_zeroed("volume voxels", voxel_bytes.max(16))?;
        let emission = ctx.storage_zeroed("volume emission", emission_bytes)?;
        let boxes = ctx.storage_init("volume boxes", bytemuck::cast_slice(&boxes_init))?;
        if !bins.is_empty() {
            let params = GpuFillParams {
                dims: [m, bins.len() as u32, map.face_size(), emissive as u32],
                frame: GpuFrame::new(&spec.frame),
            };
            let uniform = ctx.uniform("fill params", bytemuck::bytes_of(&params))?;
            let sphere_buf = ctx.storage_init("fill spheres", bytemuck::cast_slice(spheres))?;
            let prep_buf = ctx.storage_init("fill particles", bytemuck::cast_slice(&preps))?;
            let slot_buf = ctx.storage_init("fill slots", bytemuck::cast_slice(&slots))?;
            let list_buf = ctx.storage_init("fill bins", bytemuck::cast_slice(&lists))?;
            let texels = ctx.storage_init("cube map", bytemuck::cast_slice(map.texels()))?;
            let wg = ctx.dispatch_size("fill workgroups", voxels.div_ceil(WORKGROUP))?;
            self.ctx.dispatch(
                "filling metavoxels",
                &self.fill,
                &[
                    &uniform,
                    &sphere_buf,
                    &prep_buf,
                    &slot_buf,
                    &list_buf,
                    &texels,
                    &voxel_buf,
                    &emission,
                    &boxes,
                ],
                wg,
            )?;
        }
        let words: Vec<u32> =
            bytemuck::pod_collect_to_vec(&ctx.read(&boxes, boxes_init.len() as u64 * 4)?);
        let occupied = words
            .chunks_exact(6)
            .map(|b| {
                if b[0] == u32::MAX {
                    [[0; 3]; 2]
                } else {
                    [[b[0], b[1], b[2]], [b[3], b[4], b[5]]]
                }
            })
            .collect();
        Ok(GpuVolume {
            spec: *spec,
            attenuation: None,
            coords: bins.iter().map(|b| b.coord).collect(),
            particles: bins.iter().map(|b| b.particles.len()).collect(),
            occupied,
            emissive,
            stats: BuildStats {
                particles: spheres.len(),
                bin_entries: lists.len(),
                occupied: bins.len(),
                kept: bins.len(),
            },
            times: StageTimes::default(),
            voxels: voxel_buf,
            emission,
            boxes,
            light_top: None,
        })
    }
}
