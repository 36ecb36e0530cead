//! Light injection on the device: the kernel's source (the cone kernel's sampler and march
//! with `inject.wgsl`), the payload conversion to the cone kernel's layout, and
//! [`DynamicKernels::inject`].

use voxlod_cone::{Light, Shadows};
use voxlod_format::GridSpec;
use voxlod_octree::AveragePayload;

use crate::cone::{GpuConeOctree, GpuConeParams};
use crate::octree::GpuOctree;
use crate::{Error, Result};

use super::{CONVERT, DynamicKernels, GpuDynamicParams, GpuInjectParams, GpuLeaves};

/// The injection kernel's source: the cone kernel's isotropic payload, the shared octree walk
/// and the cone kernel's functions (the sampler and `march`, without its entry point), then
/// `inject.wgsl`.
pub fn inject_source() -> String {
    let cone = crate::cone::WGSL;
    let functions = cone.find("@compute").map_or(cone, |at| &cone[..at]);
    format!(
        "{}\n{}\n{}\n{functions}\n{}",
        crate::cone::ISOTROPIC_WGSL,
        crate::MORTON_WGSL,
        crate::OCTREE_WALK_WGSL,
        include_str!("inject.wgsl")
    )
}

impl<'a> DynamicKernels<'a> {
    /// Converts `n` payloads of the Averages layout to the cone kernel's isotropic layout:
    /// opacity only, or (`radiance`) the colour words as radiance.
    pub(super) fn convert(
        &self,
        average: &wgpu::Buffer,
        n: u64,
        radiance: bool,
    ) -> Result<wgpu::Buffer> {
        let ctx = self.ctx;
        let out = ctx.storage_zeroed("cone payloads", n.max(1) * 16)?;
        let mut keep = Vec::new();
        let mut encoder = ctx.device().create_command_encoder(&Default::default());
        let p = GpuDynamicParams { n: n as u32, extra: u32::from(radiance), ..Default::default() };
        self.run(&mut encoder, CONVERT, n, p, &[(1, average), (2, &out)], &mut keep)?;
        ctx.submit("converting octree payloads", encoder)?;
        Ok(out)
    }

    fn inject_pipeline(&self) -> Result<&wgpu::ComputePipeline> {
        if let Some(p) = self.inject.get() {
            return Ok(p);
        }
        let p = self.ctx.pipeline("dynamic inject", &inject_source())?;
        Ok(self.inject.get_or_init(|| p))
    }

    /// The injected radiance of every leaf of `tree` (built from `leaves`), with the rules of
    /// voxlod-cone's `inject` (module docs, kernel 7), in the Averages layout. Errors on an
    /// invalid light or shadow parameter (voxlod-cone's), or a per-leaf visibility list
    /// ([`Shadows::PerLeaf`] is a CPU-side input: not supported here).
    pub fn inject(
        &self,
        grid: &GridSpec,
        tree: &GpuOctree<'a>,
        leaves: &GpuLeaves,
        light: &Light,
        shadows: &Shadows,
    ) -> Result<wgpu::Buffer> {
        let ctx = self.ctx;
        let (march, offset, step) = match *shadows {
            Shadows::None => (false, 0.0, 0.5),
            Shadows::March { offset_voxels, step_factor } => {
                let check = |ok: bool, name, v: f32, reason| {
                    if ok {
                        Ok(())
                    } else {
                        Err(voxlod_cone::Error::InvalidParameter {
                            name,
                            value: v.to_string(),
                            reason,
                        })
                    }
                };
                check(
                    offset_voxels.is_finite() && offset_voxels >= 0.0,
                    "offset_voxels",
                    offset_voxels,
                    "finite and >= 0",
                )?;
                check(
                    (0.05..=4.0).contains(&step_factor),
                    "shadow step_factor",
                    step_factor,
                    "in [0.05, 4]",
                )?;
                (true, offset_voxels, step_factor)
            }
            Shadows::PerLeaf(_) => {
                return Err(Error::Unsupported {
                    what: "per-leaf shadow visibilities in the GPU injection",
                });
            }
        };
        let (point, a, b) = match *light {
            Light::Directional { to_light, irradiance } => {
                if !(to_light.is_finite() && to_light.length() > 0.0) {
                    return Err(voxlod_cone::Error::InvalidParameter {
                        name: "to_light",
                        value: to_light.length().to_string(),
                        reason: "a finite non-zero direction",
                    }
                    .into());
                }
                (0.0, to_light, irradiance)
            }
            Light::Point { position, intensity } => (1.0, position, intensity),
        };
        if !(b.is_finite() && b.min_element() >= 0.0 && a.is_finite()) {
            return Err(voxlod_cone::Error::InvalidParameter {
                name: "light",
                value: format!("{a} / {b}"),
                reason: "finite, and >= 0 per channel",
            }
            .into());
        }
        let n = leaves.count;
        let out =
            ctx.storage_zeroed("injected radiance", n.max(1) * size_of::<AveragePayload>() as u64)?;
        if n == 0 {
            return Ok(out);
        }
        let geometry = tree
            .payload
            .as_ref()
            .ok_or(Error::Unsupported { what: "an octree without payloads" })?;
        let medium = self.convert(geometry, tree.node_count, false)?;
        let cone_tree = GpuConeOctree::from_device(
            ctx,
            &tree.levels,
            tree.nodes.clone(),
            tree.tiles.clone(),
            tree.tile_count,
            medium,
            *grid,
            tree.depth,
            tree.first_dense,
        )?;
        let cone = GpuConeParams {
            grid: grid.origin.as_vec3().extend(grid.voxel_size as f32).to_array(),
            size: [0; 4],
            tree: [tree.depth, tree.first_dense, 0, 0],
            march: [0.0, step, 0.999, 0.0],
            limits: [0.0; 4],
            extra: [0.0; 4],
        };
        let ip = GpuInjectParams {
            light_a: a.extend(point).to_array(),
            light_b: b.extend(if march { 1.0 } else { 0.0 }).to_array(),
            shadow: [offset, 0.0, 0.0, 0.0],
            counts: [n as u32, 0, 0, 0],
        };
        let pipeline = self.inject_pipeline()?;
        let ip_buf = ctx.uniform("inject params", bytemuck::bytes_of(&ip))?;
        let mut keep = vec![ip_buf.clone()];
        let mut encoder = ctx.device().create_command_encoder(&Default::default());
        let (levels, nodes, tiles, payload) = cone_tree.buffers();
        self.dispatch(
            &mut encoder,
            (pipeline, "dynamic inject"),
            n,
            bytemuck::bytes_of(&cone),
            &[
                (1, levels),
                (2, nodes),
                (3, tiles),
                (4, payload),
                (8, &ip_buf),
                (9, &leaves.coords),
                (10, &leaves.payload),
                (11, &out),
            ],
            &mut keep,
        )?;
        ctx.submit("injecting light", encoder)?;
        Ok(out)
    }
}
