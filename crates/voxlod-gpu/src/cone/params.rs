//! The `#[repr(C)]` mirrors of the cone kernel's WGSL structs (node payloads, uniform,
//! shading points, results), checked against the WGSL by naga reflection, and the uniform's
//! constants computed on the host as voxlod-cone computes them.

use voxlod_cone::TraceOptions;
use voxlod_cone::tracer::hemisphere_directions;

use super::{BIG, ConeQuery, GpuConeOctree};

/// An isotropic node payload as the kernel reads it (mirrors WGSL `Payload` of
/// `isotropic.wgsl`). 16 bytes.
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
pub struct GpuRadiance {
    /// Radiance × opacity (zero for AO-only payloads).
    pub radiance_alpha: [f32; 3],
    /// Opacity.
    pub opacity: f32,
}

/// A directional node payload as the kernel reads it (mirrors WGSL `Payload` of
/// `directional.wgsl`): 48 bytes, of which 8 are padding keeping each `vec3` on 16 bytes.
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
pub struct GpuDirectionalRadiance {
    /// Radiance × opacity.
    pub radiance_alpha: [f32; 3],
    /// Isotropic opacity.
    pub opacity: f32,
    /// Opacity along +x, +y, +z.
    pub plus: [f32; 3],
    /// Padding.
    pub pad0: f32,
    /// Opacity along −x, −y, −z.
    pub minus: [f32; 3],
    /// Padding.
    pub pad1: f32,
}

/// The kernel's parameters (mirrors WGSL `Params`; see there for the fields).
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
pub struct GpuConeParams {
    /// Grid origin, voxel size.
    pub grid: [f32; 4],
    /// Width, point count, query bits, diffuse cones.
    pub size: [u32; 4],
    /// Depth, finest dense level, first row, rows.
    pub tree: [u32; 4],
    /// start_voxels, step_factor, opacity_cutoff, normal offset (world).
    pub march: [f32; 4],
    /// Diffuse 2·tan(θ/2), max march (voxels), AO-only max march (voxels), AO radius (voxels).
    pub limits: [f32; 4],
    /// 1/n, unused ×3.
    pub extra: [f32; 4],
}

/// One shading point as the kernel reads it (mirrors WGSL `Point`).
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
pub struct GpuPoint {
    /// World position.
    pub position: [f32; 3],
    /// Glossiness, clamped to \[0, 1\] (NaN → 0).
    pub glossiness: f32,
    /// Normal (normalized by the kernel).
    pub normal: [f32; 3],
    /// 1: position and normal usable; 2: `to_viewer` usable.
    pub flags: u32,
    /// Direction toward the viewer (normalized by the kernel).
    pub to_viewer: [f32; 3],
    /// Padding.
    pub pad: u32,
}

/// What the kernel writes per point (mirrors WGSL `Shade`).
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
pub struct GpuShade {
    /// `E/π` (rgb) and AO (w).
    pub diffuse_ao: [f32; 4],
    /// Specular radiance (rgb) and opacity (w).
    pub specular: [f32; 4],
    /// Samples of the diffuse cones, of the specular cone, unused ×2.
    pub steps: [u32; 4],
}

/// The parameters, every constant computed on the host exactly as voxlod-cone
/// computes it (same `f32` expressions).
pub(super) fn params(
    tree: &GpuConeOctree,
    o: &TraceOptions,
    query: ConeQuery,
    width: u32,
    count: u32,
) -> GpuConeParams {
    let voxel = tree.grid.voxel_size as f32;
    let finite = |x: f32| if x.is_finite() { x } else { BIG };
    // cone.rs: `2·tan(θ/2)` of the aperture clamped to [0, π], at least 0.
    let aperture = o.diffuse_aperture_deg.to_radians();
    let two_tan = 2.0 * (0.5 * aperture.clamp(0.0, std::f32::consts::PI)).tan().max(0.0);
    // tracer.rs: the AO-only march's end, then cone.rs's division by the voxel.
    let ao_max = (o.ao_radius + o.normal_offset_voxels * voxel).min(o.max_distance);
    let origin = tree.grid.origin.as_vec3();
    GpuConeParams {
        grid: origin.extend(voxel).to_array(),
        size: [width, count, query.bits(), o.diffuse_cones],
        tree: [tree.depth, tree.first_dense, 0, 0],
        march: [o.start_voxels, o.step_factor, o.opacity_cutoff, o.normal_offset_voxels * voxel],
        limits: [
            two_tan,
            finite(o.max_distance / voxel),
            finite(ao_max / voxel),
            o.ao_radius / voxel,
        ],
        extra: [1.0 / hemisphere_directions(o.diffuse_cones).len() as f32, 0.0, 0.0, 0.0],
    }
}

#[cfg(test)]
mod tests {
    use std::mem::offset_of;

    use voxlod_cone::RadiancePayload;

    use super::*;
    use crate::cone::source;
    use crate::layout::{assert_flat_octree_mirrors, assert_mirrors};

    #[test]
    fn cone_types_mirror_their_wgsl() {
        let iso = source(false);
        let dir = source(true);
        type P = GpuConeParams;
        for src in [&iso, &dir] {
            assert_mirrors(
                src,
                "Params",
                size_of::<P>(),
                &[
                    ("grid", offset_of!(P, grid)),
                    ("size", offset_of!(P, size)),
                    ("tree", offset_of!(P, tree)),
                    ("march", offset_of!(P, march)),
                    ("limits", offset_of!(P, limits)),
                    ("extra", offset_of!(P, extra)),
                ],
            );
            assert_mirrors(
                src,
                "Point",
                size_of::<GpuPoint>(),
                &[
                    ("position", offset_of!(GpuPoint, position)),
                    ("glossiness", offset_of!(GpuPoint, glossiness)),
                    ("normal", offset_of!(GpuPoint, normal)),
                    ("flags", offset_of!(GpuPoint, flags)),
                    ("to_viewer", offset_of!(GpuPoint, to_viewer)),
                    ("pad", offset_of!(GpuPoint, pad)),
                ],
            );
            assert_mirrors(
                src,
                "Shade",
                size_of::<GpuShade>(),
                &[
                    ("diffuse_ao", offset_of!(GpuShade, diffuse_ao)),
                    ("specular", offset_of!(GpuShade, specular)),
                    ("steps", offset_of!(GpuShade, steps)),
                ],
            );
            assert_flat_octree_mirrors(src, ["Level", "Node", "Tile"]);
        }
        type R = GpuRadiance;
        assert_mirrors(
            &iso,
            "Payload",
            size_of::<R>(),
            &[
                ("radiance_alpha", offset_of!(R, radiance_alpha)),
                ("opacity", offset_of!(R, opacity)),
            ],
        );
        type D = GpuDirectionalRadiance;
        assert_mirrors(
            &dir,
            "Payload",
            size_of::<D>(),
            &[
                ("radiance_alpha", offset_of!(D, radiance_alpha)),
                ("opacity", offset_of!(D, opacity)),
                ("plus", offset_of!(D, plus)),
                ("pad0", offset_of!(D, pad0)),
                ("minus", offset_of!(D, minus)),
                ("pad1", offset_of!(D, pad1)),
            ],
        );
        // The CPU payloads carry what the mirrors carry: RadiancePayload is 16 bytes of f32.
        assert_eq!(size_of::<RadiancePayload>(), size_of::<GpuRadiance>());
    }
}
