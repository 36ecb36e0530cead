//! The volume on the device ([`GpuVolume`]): its buffers, the upload of a CPU-built volume
//! (for the march alone) and the readback as the CPU's metavoxels.

use glam::{Vec3, Vec4};
use voxlod_cpu::volume::{Attenuation, BuildStats, Metavoxel, StageTimes, Volume, VolumeSpec};

use super::VolumeKernels;
use crate::{Error, Result};

/// A volume on the device: kept metavoxels (slots, in key order), their voxels (`M³` per
/// slot, RGB + extinction; albedo before propagation, lit radiance after), light at the top of
/// each voxel column and the occupied boxes.
pub struct GpuVolume {
    /// The shape.
    pub spec: VolumeSpec,
    /// The attenuation it was lit with (`None`: filled, not lit yet).
    pub attenuation: Option<Attenuation>,
    /// Metavoxel coordinate per slot.
    pub coords: Vec<[u32; 3]>,
    /// Particles binned into each slot.
    pub particles: Vec<usize>,
    /// Box of the voxels the fill wrote per slot (as [`Metavoxel::occupied`]).
    pub occupied: Vec<[[u32; 3]; 2]>,
    /// Whether an emission buffer is live (some kept bin holds an emissive particle).
    pub emissive: bool,
    /// Counts (as the CPU's).
    pub stats: BuildStats,
    /// Wall-clock per stage, host side (submission and readback included).
    pub times: StageTimes,
    pub(super) voxels: wgpu::Buffer,
    pub(super) emission: wgpu::Buffer,
    pub(super) boxes: wgpu::Buffer,
    pub(super) light_top: Option<wgpu::Buffer>,
}

impl GpuVolume {
    /// Device bytes of the volume: voxels, emission, light at the column tops, boxes.
    pub fn bytes(&self) -> u64 {
        self.voxels.size()
            + self.emission.size()
            + self.boxes.size()
            + self.light_top.as_ref().map_or(0, |b| b.size())
    }
}

impl std::fmt::Debug for GpuVolume {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("GpuVolume")
            .field("spec", &self.spec)
            .field("attenuation", &self.attenuation)
            .field("kept", &self.coords.len())
            .field("stats", &self.stats)
            .finish()
    }
}

impl VolumeKernels<'_> {
    /// Uploads a CPU-built volume (for the march alone).
    pub fn upload(&self, volume: &Volume) -> Result<GpuVolume> {
        let ctx = self.ctx;
        let mvs = &volume.metavoxels;
        let voxels: Vec<Vec4> = mvs.iter().flat_map(|mv| mv.voxels.iter().copied()).collect();
        let light: Vec<f32> = mvs.iter().flat_map(|mv| mv.light_top.iter().copied()).collect();
        let boxes: Vec<u32> = mvs.iter().flat_map(|mv| mv.occupied.concat()).collect();
        Ok(GpuVolume {
            spec: volume.spec,
            attenuation: Some(volume.attenuation),
            coords: mvs.iter().map(|mv| mv.coord).collect(),
            particles: mvs.iter().map(|mv| mv.particles).collect(),
            occupied: mvs.iter().map(|mv| mv.occupied).collect(),
            emissive: false,
            stats: volume.stats,
            times: volume.times,
            voxels: ctx.storage_array("volume voxels", &voxels)?,
            emission: ctx.storage_zeroed("volume emission", 16)?,
            boxes: ctx.storage_init("volume boxes", bytemuck::cast_slice(&boxes))?,
            light_top: Some(ctx.storage_init("volume light", bytemuck::cast_slice(&light))?),
        })
    }

    /// Reads the volume back: per slot its metavoxel (voxels, light at the column tops — all
    /// 1 before propagation, as the CPU fill leaves them — and occupied box) and, before
    /// propagation, its emission when the fill wrote any.
    pub fn read(&self, volume: &GpuVolume) -> Result<Vec<(Metavoxel, Option<Vec<Vec3>>)>> {
        let ctx = self.ctx;
        let m = volume.spec.metavoxel_edge as usize;
        let (m2, m3) = (m * m, m * m * m);
        let kept = volume.coords.len();
        if kept == 0 {
            return Ok(Vec::new());
        }
        let voxels: Vec<Vec4> =
            bytemuck::pod_collect_to_vec(&ctx.read(&volume.voxels, (kept * m3 * 16) as u64)?);
        let light: Vec<f32> = match &volume.light_top {
            Some(b) => bytemuck::pod_collect_to_vec(&ctx.read(b, (kept * m2 * 4) as u64)?),
            None => vec![1.0; kept * m2],
        };
        let emission: Option<Vec<Vec4>> = if volume.emissive && volume.attenuation.is_none() {
            Some(bytemuck::pod_collect_to_vec(
                &ctx.read(&volume.emission, (kept * m3 * 16) as u64)?,
            ))
        } else {
            None
        };
        Ok((0..kept)
            .map(|s| {
                let e = emission.as_ref().map(|e| {
                    e[s * m3..(s + 1) * m3].iter().map(|v| v.truncate()).collect::<Vec<Vec3>>()
                });
                let e = e.filter(|e| e.iter().any(|v| *v != Vec3::ZERO));
                (
                    Metavoxel {
                        coord: volume.coords[s],
                        particles: volume.particles[s],
                        voxels: voxels[s * m3..(s + 1) * m3].to_vec(),
                        light_top: light[s * m2..(s + 1) * m2].to_vec(),
                        occupied: volume.occupied[s],
                    },
                    e,
                )
            })
            .collect())
    }

    /// Reads a lit volume back as the CPU's [`Volume`] (for the volume's shadow on the mesh,
    /// [`Volume::transmittance_to_light`], and for comparisons). Errors before propagation.
    pub fn read_volume(&self, volume: &GpuVolume) -> Result<Volume> {
        let Some(attenuation) = volume.attenuation else {
            return Err(Error::Unsupported {
                what: "reading a volume that was not lit back as a Volume (propagate it first)",
            });
        };
        let metavoxels = self.read(volume)?.into_iter().map(|(mv, _)| mv).collect();
        Ok(Volume::from_parts(volume.spec, attenuation, metavoxels, volume.stats, volume.times)?)
    }
}
