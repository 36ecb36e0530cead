//! The `#[repr(C)]` mirrors of the filtered renderer's WGSL structs (uniform, bricks,
//! decoded records), checked against the WGSL by naga reflection, and a frame's uniform.

use glam::{UVec3, Vec3};
use voxlod_cpu::render::filtered::Options;
use voxlod_format::BRICK_EDGE;
use voxlod_scene::{Camera, Light};

use super::GpuRecords;
use crate::light_words;

/// The kernel's uniform parameters (mirrors WGSL `Params`).
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
pub struct GpuFilteredParams {
    /// Camera eye (world).
    pub eye: [f32; 4],
    /// Eye in grid coordinates, computed as the CPU's DDA does (`f64`, then `f32`); `w` =
    /// voxels per world unit.
    pub eye_grid: [f32; 4],
    /// Unit view direction.
    pub forward: [f32; 4],
    /// Right vector scaled by tan(fov/2)·aspect.
    pub right: [f32; 4],
    /// Up vector scaled by tan(fov/2).
    pub up: [f32; 4],
    /// Background colour (linear RGB).
    pub background: [f32; 4],
    /// Ambient term of the shading function.
    pub ambient: [f32; 4],
    /// Directional light: unit direction toward it; point light: its position.
    pub light_a: [f32; 4],
    /// Directional light: irradiance; point light: intensity.
    pub light_b: [f32; 4],
    /// Grid origin (`f32`); `w` = voxel size.
    pub grid: [f32; 4],
    /// Grid dimensions; `w` = flags (1: shadows, 2: point light, 4: Averages normal as stored).
    pub dims: [u32; 4],
    /// Width, height, the DDA step bound, 0.
    pub size: [u32; 4],
    /// Bricks per axis, 0.
    pub brick_dims: [u32; 4],
    /// Virtual-mesh and Adaptive grids ([`voxels`](super::voxels)): directional-opacity rule (0
    /// Lines, 1 Circles), shading samples per distribution face, flags (1 projected-area scaling,
    /// 2 the unshaded fallback), and
    /// the number of voxels with a record. Zero for the other kinds.
    pub vmesh: [u32; 4],
}

/// One allocated brick (mirrors WGSL `Brick`).
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
pub struct GpuBrick {
    /// Occupancy, bit `x + 8y + 64z` of the brick's 512 (word = bit / 32).
    pub mask: [u32; 16],
    /// Rank (index into the slot array) of the first occupied voxel of each word.
    pub before: [u32; 16],
}

/// A record decoded for the kernel (mirrors WGSL `Record`). Averages: `a` = (albedo,
/// opacity), `b` = (mean normal, 0); \[VJK21\]: `a` = (albedo, σ), `b.w` = γ, and the SGGX
/// matrix's columns in `b`, `c`, `d` (`xyz`). Both: `c.w` = specular level, `d.w` = shininess
/// (as `record_material` gives them).
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
pub struct GpuRecord {
    /// Albedo, opacity or σ.
    pub a: [f32; 4],
    /// Normal or first matrix column; γ.
    pub b: [f32; 4],
    /// Second matrix column; specular level.
    pub c: [f32; 4],
    /// Third matrix column; shininess.
    pub d: [f32; 4],
}

/// Which records a [`GpuRecords`] holds (the kernel's `size.w`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RecordKind {
    /// [`AverageRecord`](voxlod_format::records::AverageRecord): alpha compositing, one normal.
    Averages = 0,
    /// [`SggxRecord`](voxlod_format::records::SggxRecord): \[VJK21\] transmittance, SGGX shading.
    Vjk21 = 1,
    /// [`BaselineVoxel`](voxlod_cpu::render::baseline::BaselineVoxel): opaque cubes of one
    /// colour, the baseline renderer ([`voxlod_cpu::render::baseline`]).
    Baseline = 2,
    /// [`VirtualMeshGrid`](voxlod_cpu::appearance::virtual_mesh::VirtualMeshGrid): virtual mesh +
    /// opacity subgrid, rendered by the per-voxel passes of [`voxels`](super::voxels).
    VirtualMesh = 3,
    /// [`AdaptiveGrid`](voxlod_cpu::appearance::adaptive::AdaptiveGrid): each voxel one of
    /// the three, rendered by the per-voxel passes of [`voxels`](super::voxels).
    Adaptive = 4,
}

/// The kernel's parameters for a frame (inputs already checked by `check_frame`).
pub(super) fn frame_params(
    app: &GpuRecords,
    camera: &Camera,
    light: &Light,
    background: Vec3,
    options: &Options,
) -> GpuFilteredParams {
    let Options { width, height, ambient, shadows, .. } = *options;
    let frame = camera.frame(width, height);
    let grid = app.grid;
    let eye_grid = ((camera.eye.as_dvec3() - grid.origin) / grid.voxel_size).as_vec3();
    let (point, la, lb) = light_words(light);
    let dims: UVec3 = grid.dims;
    let brick_dims = (dims + BRICK_EDGE - 1) / BRICK_EDGE;
    let steps = dims.x.saturating_add(dims.y).saturating_add(dims.z).saturating_add(3);
    GpuFilteredParams {
        eye: camera.eye.extend(0.0).to_array(),
        eye_grid: eye_grid.extend((1.0 / grid.voxel_size) as f32).to_array(),
        forward: frame.forward.extend(0.0).to_array(),
        right: frame.right.extend(0.0).to_array(),
        up: frame.up.extend(0.0).to_array(),
        background: background.extend(0.0).to_array(),
        ambient: ambient.extend(0.0).to_array(),
        light_a: la.extend(0.0).to_array(),
        light_b: lb.extend(0.0).to_array(),
        grid: grid.origin.as_vec3().extend(grid.voxel_size as f32).to_array(),
        dims: dims
            .extend(
                u32::from(shadows)
                    | if point { 2 } else { 0 }
                    | if app.averages_as_stored { 4 } else { 0 },
            )
            .to_array(),
        size: [width, height, steps, app.kind as u32],
        brick_dims: brick_dims.extend(0).to_array(),
        vmesh: app.voxels.as_ref().map_or([0; 4], |v| v.params),
    }
}

#[cfg(test)]
mod tests {
    use std::mem::offset_of;

    use super::*;
    use crate::filtered::WGSL;
    use crate::layout::assert_mirrors;

    #[test]
    fn filtered_types_mirror_their_wgsl() {
        type P = GpuFilteredParams;
        assert_mirrors(
            WGSL,
            "Params",
            size_of::<P>(),
            &[
                ("eye", offset_of!(P, eye)),
                ("eye_grid", offset_of!(P, eye_grid)),
                ("forward", offset_of!(P, forward)),
                ("right", offset_of!(P, right)),
                ("up", offset_of!(P, up)),
                ("background", offset_of!(P, background)),
                ("ambient", offset_of!(P, ambient)),
                ("light_a", offset_of!(P, light_a)),
                ("light_b", offset_of!(P, light_b)),
                ("grid", offset_of!(P, grid)),
                ("dims", offset_of!(P, dims)),
                ("size", offset_of!(P, size)),
                ("brick_dims", offset_of!(P, brick_dims)),
                ("vmesh", offset_of!(P, vmesh)),
            ],
        );
        assert_mirrors(
            WGSL,
            "Brick",
            size_of::<GpuBrick>(),
            &[("mask", offset_of!(GpuBrick, mask)), ("before", offset_of!(GpuBrick, before))],
        );
        assert_mirrors(
            WGSL,
            "Record",
            size_of::<GpuRecord>(),
            &[
                ("a", offset_of!(GpuRecord, a)),
                ("b", offset_of!(GpuRecord, b)),
                ("c", offset_of!(GpuRecord, c)),
                ("d", offset_of!(GpuRecord, d)),
            ],
        );
    }
}
