//! The `#[repr(C)]` mirrors of the volume kernels' WGSL structs (uniforms and per-item
//! records), each checked against its WGSL by naga reflection in the tests below, and the
//! attenuation model's word.

use voxlod_cpu::volume::{Attenuation, LightSpace};

/// The light-space frame as the kernels read it (mirrors WGSL `Frame`).
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
pub struct GpuFrame {
    /// Origin; `w` the voxel size.
    pub origin: [f32; 4],
    /// First horizontal axis.
    pub u: [f32; 4],
    /// Second horizontal axis.
    pub v: [f32; 4],
    /// Direction of propagation.
    pub w: [f32; 4],
}

impl GpuFrame {
    /// The frame of `f`.
    pub fn new(f: &LightSpace) -> Self {
        Self {
            origin: f.origin.extend(f.voxel_size).to_array(),
            u: f.u.extend(0.0).to_array(),
            v: f.v.extend(0.0).to_array(),
            w: f.w.extend(0.0).to_array(),
        }
    }
}

/// One particle with candidates, as the binning kernel reads it (mirrors WGSL `Candidate`).
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
pub struct GpuCandidate {
    /// Centre in voxel coordinates; `w` the outer radius in voxels.
    pub sphere: [f32; 4],
    /// First metavoxel of the range; `w` the first candidate's index.
    pub lo: [u32; 4],
    /// Last metavoxel of the range (inclusive); `w` unused.
    pub hi: [u32; 4],
}

/// Parameters of the binning kernel (mirrors WGSL `Params` of `binning.wgsl`).
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
pub struct GpuBinParams {
    /// Candidates, particles with candidates, `M`, unused.
    pub counts: [u32; 4],
}

/// Per particle, what the fill reads besides the sphere (mirrors WGSL `Prep`).
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
pub struct GpuPrep {
    /// Centre in voxel coordinates; `w` the inner radius in voxels.
    pub center: [f32; 4],
    /// Amplitude in voxels, accept², reject², unused.
    pub radii: [f32; 4],
}

/// One kept metavoxel for the fill (mirrors WGSL `Slot`).
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
pub struct GpuSlot {
    /// Metavoxel coordinate; `w` its first entry in the particle lists.
    pub coord: [u32; 4],
    /// `x` its number of particles.
    pub range: [u32; 4],
}

/// Parameters of the fill kernel (mirrors WGSL `Params` of `fill.wgsl`).
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
pub struct GpuFillParams {
    /// `M`, kept metavoxels, cube-map face size, 1 if some particle is emissive.
    pub dims: [u32; 4],
    /// The frame.
    pub frame: GpuFrame,
}

/// Parameters of the propagation kernel (mirrors WGSL `Params` of `propagate.wgsl`).
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
pub struct GpuPropagateParams {
    /// `M`, columns, attenuation (0 chapter, 1 Beer–Lambert, 2 exact), emission live.
    pub dims: [u32; 4],
    /// `E/π`; `w` the voxel size.
    pub direct: [f32; 4],
    /// Ambient irradiance.
    pub ambient: [f32; 4],
}

/// Parameters of the march kernel (mirrors WGSL `Params` of `march.wgsl`).
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
pub struct GpuMarchParams {
    /// Camera eye.
    pub eye: [f32; 4],
    /// Camera forward.
    pub forward: [f32; 4],
    /// Camera right (scaled).
    pub right: [f32; 4],
    /// Camera up (scaled).
    pub up: [f32; 4],
    /// Light-space frame.
    pub frame: GpuFrame,
    /// Eye in voxel coordinates; `w` the step in world units.
    pub eye_voxel: [f32; 4],
    /// Width, height, entries, `M`.
    pub dims: [u32; 4],
    /// Attenuation (0 chapter, 1 Beer–Lambert), 1 if a depth buffer is bound.
    pub mode: [u32; 4],
}

/// One metavoxel of the march's order (mirrors WGSL `Entry`).
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
pub struct GpuMarchEntry {
    /// Metavoxel box corner (voxel coordinates).
    pub base: [f32; 4],
    /// Marched box low corner.
    pub lo: [f32; 4],
    /// Marched box high corner.
    pub hi: [f32; 4],
    /// Slot, 1 for over blending.
    pub flags: [u32; 4],
}

/// The kernels' word for an attenuation model (WGSL `Params.dims.z` / `mode.x`).
pub(super) fn attenuation_id(a: Attenuation) -> u32 {
    match a {
        Attenuation::Chapter => 0,
        Attenuation::BeerLambert => 1,
        Attenuation::Exact => 2,
    }
}

#[cfg(test)]
mod tests {
    use std::mem::offset_of;

    use voxlod_scene::particles::DisplacedSphere;

    use super::*;
    use crate::layout::assert_mirrors;
    use crate::volume::{BINNING_WGSL, FILL_WGSL, MARCH_EXACT_WGSL, MARCH_WGSL, PROPAGATE_WGSL};

    #[test]
    fn sphere_mirrors_displaced_sphere() {
        type S = DisplacedSphere;
        assert_mirrors(
            FILL_WGSL,
            "Sphere",
            size_of::<S>(),
            &[
                ("center", offset_of!(S, center)),
                ("inner", offset_of!(S, inner)),
                ("color", offset_of!(S, color)),
                ("amplitude", offset_of!(S, amplitude)),
                ("color_outer", offset_of!(S, color_outer)),
                ("density", offset_of!(S, density)),
                ("rot_cos", offset_of!(S, rot_cos)),
                ("rot_sin", offset_of!(S, rot_sin)),
                ("color_mode", offset_of!(S, color_mode)),
                ("flags", offset_of!(S, flags)),
            ],
        );
    }

    #[test]
    fn kernel_records_mirror_their_wgsl() {
        assert_mirrors(
            BINNING_WGSL,
            "Candidate",
            size_of::<GpuCandidate>(),
            &[
                ("sphere", offset_of!(GpuCandidate, sphere)),
                ("lo", offset_of!(GpuCandidate, lo)),
                ("hi", offset_of!(GpuCandidate, hi)),
            ],
        );
        assert_mirrors(BINNING_WGSL, "Params", size_of::<GpuBinParams>(), &[("counts", 0)]);
        assert_mirrors(
            FILL_WGSL,
            "Frame",
            size_of::<GpuFrame>(),
            &[("origin", 0), ("u", 16), ("v", 32), ("w", 48)],
        );
        assert_mirrors(
            FILL_WGSL,
            "Params",
            size_of::<GpuFillParams>(),
            &[
                ("dims", offset_of!(GpuFillParams, dims)),
                ("frame", offset_of!(GpuFillParams, frame)),
            ],
        );
        assert_mirrors(
            FILL_WGSL,
            "Prep",
            size_of::<GpuPrep>(),
            &[("center", offset_of!(GpuPrep, center)), ("radii", offset_of!(GpuPrep, radii))],
        );
        assert_mirrors(
            FILL_WGSL,
            "Slot",
            size_of::<GpuSlot>(),
            &[("coord", offset_of!(GpuSlot, coord)), ("range", offset_of!(GpuSlot, range))],
        );
        assert_mirrors(
            PROPAGATE_WGSL,
            "Params",
            size_of::<GpuPropagateParams>(),
            &[
                ("dims", offset_of!(GpuPropagateParams, dims)),
                ("direct", offset_of!(GpuPropagateParams, direct)),
                ("ambient", offset_of!(GpuPropagateParams, ambient)),
            ],
        );
        type P = GpuMarchParams;
        let f = offset_of!(P, frame);
        // The approximate and the exact march read the same parameters.
        for wgsl in [MARCH_WGSL, MARCH_EXACT_WGSL] {
            assert_mirrors(
                wgsl,
                "Params",
                size_of::<P>(),
                &[
                    ("eye", offset_of!(P, eye)),
                    ("forward", offset_of!(P, forward)),
                    ("right", offset_of!(P, right)),
                    ("up", offset_of!(P, up)),
                    ("origin", f),
                    ("u", f + 16),
                    ("v", f + 32),
                    ("w", f + 48),
                    ("eye_voxel", offset_of!(P, eye_voxel)),
                    ("dims", offset_of!(P, dims)),
                    ("mode", offset_of!(P, mode)),
                ],
            );
        }
        assert_mirrors(
            MARCH_WGSL,
            "Entry",
            size_of::<GpuMarchEntry>(),
            &[
                ("base", offset_of!(GpuMarchEntry, base)),
                ("lo", offset_of!(GpuMarchEntry, lo)),
                ("hi", offset_of!(GpuMarchEntry, hi)),
                ("flags", offset_of!(GpuMarchEntry, flags)),
            ],
        );
    }
}
