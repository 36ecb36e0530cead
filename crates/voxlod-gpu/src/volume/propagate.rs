//! Light propagation (McNabb 2015, Listing 5.2) on the GPU: the voxel columns and the mesh's
//! shadow depths (cast by the GPU ray caster) prepared on the host, one dispatch over the
//! voxel columns, the volume lit in place.

use voxlod_cpu::volume::{BuildSettings, VolumeSpec};

use super::params::{GpuPropagateParams, attenuation_id};
use super::{GpuVolume, VolumeKernels, WORKGROUP};
use crate::Result;
use crate::raycast::{GpuBvh, GpuRay, RayCaster};

impl VolumeKernels<'_> {
    /// Per voxel column of the kept metavoxel columns, the depth (voxels from the volume's
    /// top) of the first mesh hit: the CPU's `scene_shadow_depths`, its two rays per column
    /// cast by the GPU ray caster ([`RayCaster`]).
    fn shadow_depths(
        &self,
        spec: &VolumeSpec,
        columns: &[[u32; 2]],
        blocker: &GpuBvh,
    ) -> Result<Vec<f32>> {
        let m = spec.metavoxel_edge;
        let f = &spec.frame;
        let depth = spec.voxels_per_axis() as f32 * f.voxel_size;
        let mut up = Vec::with_capacity(columns.len() * (m * m) as usize);
        let mut down = Vec::with_capacity(up.capacity());
        for &[i, j] in columns {
            for idx in 0..m * m {
                let (a, b) = (idx % m, idx / m);
                let q = glam::Vec2::new((i * m + a) as f32 + 0.5, (j * m + b) as f32 + 0.5);
                let top = f.to_world(q.extend(0.0));
                up.push(GpuRay::new(top, -f.w, 0.0, f32::INFINITY));
                down.push(GpuRay::new(top, f.w, 0.0, depth));
            }
        }
        let caster = RayCaster::new(self.ctx)?;
        let up = caster.intersect(blocker, &up)?;
        let down = caster.intersect(blocker, &down)?;
        Ok(up
            .iter()
            .zip(&down)
            .map(|(u, d)| match (u.hit(), d.hit()) {
                (Some(_), _) => f32::NEG_INFINITY,
                (None, Some(h)) => h.t / f.voxel_size,
                (None, None) => f32::INFINITY,
            })
            .collect())
    }

    /// Light propagation (Listing 5.2) on the GPU: the CPU's
    /// [`voxlod_cpu::volume::propagate::propagate`] over the filled `volume`, in place.
    /// `blocker` (the mesh's BVH on this device) casts the scene's shadow on the volume.
    pub fn propagate(
        &self,
        volume: &mut GpuVolume,
        settings: &BuildSettings,
        blocker: Option<&GpuBvh>,
    ) -> Result<()> {
        let ctx = self.ctx;
        let spec = volume.spec;
        let m = spec.metavoxel_edge;
        let m2 = (m * m) as u64;
        let kept = volume.coords.len() as u64;
        let mut columns: Vec<[u32; 4]> = Vec::new();
        let mut heads: Vec<[u32; 2]> = Vec::new();
        for (s, c) in volume.coords.iter().enumerate() {
            match columns.last_mut() {
                Some(col) if heads.last() == Some(&[c[0], c[1]]) => col[1] += 1,
                _ => {
                    columns.push([s as u32, 1, 0, 0]);
                    heads.push([c[0], c[1]]);
                }
            }
        }
        let light_bytes = kept * m2 * 4;
        let light_top = ctx.storage_zeroed("volume light", light_bytes)?;
        if !columns.is_empty() {
            let items = columns.len() as u64 * m2;
            let shadow = match blocker {
                Some(bvh) => self.shadow_depths(&spec, &heads, bvh)?,
                None => vec![f32::INFINITY; items as usize],
            };
            let direct = settings.irradiance / std::f32::consts::PI;
            let params = GpuPropagateParams {
                dims: [
                    m,
                    columns.len() as u32,
                    attenuation_id(settings.attenuation),
                    volume.emissive as u32,
                ],
                direct: direct.extend(spec.frame.voxel_size).to_array(),
                ambient: settings.ambient.extend(0.0).to_array(),
            };
            let slots: Vec<[u32; 4]> =
                volume.coords.iter().map(|c| [c[0], c[1], c[2], 0]).collect();
            let uniform = ctx.uniform("propagation params", bytemuck::bytes_of(&params))?;
            let col_buf =
                ctx.storage_init("propagation columns", bytemuck::cast_slice(&columns))?;
            let slot_buf = ctx.storage_init("propagation slots", bytemuck::cast_slice(&slots))?;
            let shadow_buf =
                ctx.storage_init("propagation shadow", bytemuck::cast_slice(&shadow))?;
            let wg = ctx.dispatch_size("propagation workgroups", items.div_ceil(WORKGROUP))?;
            self.ctx.dispatch(
                "propagating light",
                &self.propagate,
                &[
                    &uniform,
                    &col_buf,
                    &slot_buf,
                    &volume.boxes,
                    &volume.emission,
                    &shadow_buf,
                    &volume.voxels,
                    &light_top,
                ],
                wg,
            )?;
        }
        volume.light_top = Some(light_top);
        volume.attenuation = Some(settings.attenuation);
        Ok(())
    }
}
