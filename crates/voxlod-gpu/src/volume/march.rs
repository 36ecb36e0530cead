//! The eye march (McNabb 2015, Listing 5.3 and §5.5.5) on the GPU: the input checks and the
//! metavoxel sort order on the host, one dispatch per frame (the chapter's march, or the
//! exact-attenuation reference march), the image read back.

use glam::{Vec3, Vec4};
use voxlod_cpu::render::check_image_size;
use voxlod_cpu::volume::{Attenuation, MarchOptions, VolumeSpec};
use voxlod_scene::camera::CameraFrame;
use voxlod_scene::{Camera, Image};

use super::params::{GpuFrame, GpuMarchEntry, GpuMarchParams, attenuation_id};
use super::{GpuVolume, VolumeKernels};
use crate::{Error, Result};

/// The march's metavoxel order for a camera at `eye` (the CPU's `march::sort_order` on the
/// slots' coordinates): slot indices and whether each is over-blended.
pub fn sort_order(spec: &VolumeSpec, coords: &[[u32; 3]], eye: Vec3) -> Vec<(usize, bool)> {
    let q = spec.frame.to_voxel(eye) / spec.metavoxel_edge as f32;
    let e = q.floor().clamp(Vec3::splat(-1e6), Vec3::splat(1e6)).as_ivec3().as_i64vec3();
    let dist = |c: [u32; 3]| {
        (c[0] as i64 - e.x).abs() + (c[1] as i64 - e.y).abs() + (c[2] as i64 - e.z).abs()
    };
    let mut over = Vec::new();
    let mut under = Vec::new();
    for (i, &c) in coords.iter().enumerate() {
        let d = dist(c);
        if c[2] as i64 <= e.z { over.push((d, i)) } else { under.push((d, i)) }
    }
    over.sort_by(|a, b| b.0.cmp(&a.0).then(a.1.cmp(&b.1)));
    under.sort();
    over.into_iter()
        .map(|(_, i)| (i, true))
        .chain(under.into_iter().map(|(_, i)| (i, false)))
        .collect()
}

/// The march's checks of its input, with the CPU reference's errors.
pub(super) fn check_march(
    camera: &Camera,
    options: &MarchOptions,
    depth: Option<&[f32]>,
) -> Result<CameraFrame> {
    check_image_size(options.width, options.height)?;
    if !(options.step.is_finite() && options.step > 0.0) {
        return Err(voxlod_cpu::Error::InvalidParameter {
            name: "march step",
            value: options.step.to_string(),
            reason: "must be finite and > 0 voxels".into(),
        }
        .into());
    }
    camera.validate().map_err(voxlod_cpu::Error::from)?;
    let pixels = options.width as usize * options.height as usize;
    if let Some(d) = depth
        && d.len() != pixels
    {
        return Err(voxlod_cpu::Error::InvalidParameter {
            name: "depth buffer",
            value: format!("{} entries", d.len()),
            reason: format!("must have one per pixel ({pixels})"),
        }
        .into());
    }
    Ok(camera.frame(options.width, options.height))
}

impl VolumeKernels<'_> {
    /// The eye march (Listing 5.3) of a lit `volume` on the GPU: the CPU's
    /// [`voxlod_cpu::volume::march::render`] (premultiplied RGBA, rays stopping at `depth`).
    pub fn render(
        &self,
        volume: &GpuVolume,
        camera: &Camera,
        options: &MarchOptions,
        depth: Option<&[f32]>,
    ) -> Result<Image> {
        let ctx = self.ctx;
        let frame = check_march(camera, options, depth)?;
        let Some(attenuation) = volume.attenuation else {
            return Err(Error::Unsupported {
                what: "marching a volume that was not lit (propagate it first)",
            });
        };
        let spec = &volume.spec;
        let m = spec.metavoxel_edge;
        let mf = m as f32;
        let pixels = options.width as u64 * options.height as u64;
        let image_bytes = pixels * 16;
        ctx.check_storage("volume image", image_bytes)?;
        let wg = ctx.image_dispatch("volume march workgroups", options.width, options.height)?;
        let f = &spec.frame;
        let mut params = GpuMarchParams {
            eye: frame.eye.extend(0.0).to_array(),
            forward: frame.forward.extend(0.0).to_array(),
            right: frame.right.extend(0.0).to_array(),
            up: frame.up.extend(0.0).to_array(),
            frame: GpuFrame::new(f),
            eye_voxel: f.to_voxel(frame.eye).extend(options.step * f.voxel_size).to_array(),
            dims: [options.width, options.height, 0, m],
            mode: [attenuation_id(attenuation), depth.is_some() as u32, 0, 0],
        };
        let depth_buf =
            ctx.storage_init("march depth", bytemuck::cast_slice(depth.unwrap_or(&[])))?;
        let image = ctx.storage_zeroed("volume image", image_bytes)?;
        if attenuation == Attenuation::Exact {
            // The reference march: every voxel crossed, through the K³ slot index.
            let k = spec.metavoxels;
            let mut index = vec![u32::MAX; (k as usize).pow(3)];
            for (s, &c) in volume.coords.iter().enumerate() {
                index[spec.key(c) as usize] = s as u32;
            }
            params.dims[2] = k;
            params.eye_voxel[3] = 1e-4 * f.voxel_size;
            let uniform = ctx.uniform("exact march params", bytemuck::bytes_of(&params))?;
            let index_buf = ctx.storage_init("metavoxel index", bytemuck::cast_slice(&index))?;
            self.ctx.dispatch(
                "marching eye rays (exact)",
                &self.march_exact,
                &[&uniform, &index_buf, &volume.voxels, &depth_buf, &image],
                wg,
            )?;
        } else {
            let entries: Vec<GpuMarchEntry> = sort_order(spec, &volume.coords, frame.eye)
                .into_iter()
                .filter(|&(s, _)| volume.occupied[s][0][0] < volume.occupied[s][1][0])
                .map(|(s, over)| {
                    let c = volume.coords[s];
                    let base = Vec3::new(c[0] as f32, c[1] as f32, c[2] as f32) * mf;
                    let [lo, hi] = volume.occupied[s];
                    let lo =
                        (Vec3::new(lo[0] as f32, lo[1] as f32, lo[2] as f32) - 1.0).max(Vec3::ZERO);
                    let hi = (Vec3::new(hi[0] as f32, hi[1] as f32, hi[2] as f32) + 1.0)
                        .min(Vec3::splat(mf));
                    GpuMarchEntry {
                        base: base.extend(0.0).to_array(),
                        lo: (base + lo).extend(0.0).to_array(),
                        hi: (base + hi).extend(0.0).to_array(),
                        flags: [s as u32, over as u32, 0, 0],
                    }
                })
                .collect();
            params.dims[2] = entries.len() as u32;
            let uniform = ctx.uniform("march params", bytemuck::bytes_of(&params))?;
            let order = ctx.storage_array("march order", &entries)?;
            self.ctx.dispatch(
                "marching eye rays",
                &self.march,
                &[&uniform, &order, &volume.voxels, &depth_buf, &image],
                wg,
            )?;
        }
        let pixels: Vec<Vec4> = bytemuck::pod_collect_to_vec(&ctx.read(&image, image_bytes)?);
        Ok(Image { width: options.width, height: options.height, pixels })
    }
}
