//! The filtered renderer for **virtual mesh + opacity subgrid** grids (Brito, Poulin and Teichrieb
//! 2023, §3.3–3.4; [`VirtualMeshGrid`]) and **Adaptive** grids ([`AdaptiveGrid`]: each voxel an
//! Averages, \[VJK21\] or virtual-mesh record), the mirror of
//! [`voxlod_cpu::render::filtered::render`] over them: the same camera rays, DDA, compositing,
//! shadow rays and shading as the single-pass kernel of [the parent module](super), with
//! `vmesh.wgsl` porting [`voxlod_cpu::appearance::virtual_mesh::shade_record`] (the
//! projected-area-weighted faces, the fixed Hammersley barycentric samples of distribution faces,
//! the fallback, ours or the authors' unshaded one) and [`voxlod_cpu::appearance::subgrid::directional_opacity`] (both rules, Lines
//! and Circles), times
//! [`projected_area_ratio`](voxlod_cpu::appearance::virtual_mesh::projected_area_ratio) when
//! [`VirtualMeshParams::projected_area`] is on. No random numbers are drawn: the CPU's virtual-mesh
//! shading samples fixed barycentric points (`barycentric_point`) and its Lines rule a fixed
//! pattern, so both backends evaluate the same points in the same order.
//!
//! # Data on the GPU
//! The brick look-up of the parent module; the virtual-mesh records in their frozen 136-byte layout
//! ([`GpuVirtualMesh`]: the record's bytes as 34 words, decoded in the shader, plus the voxel's
//! specular level and exponent), the sRGB and semi-axis decoders as 512-entry tables made by
//! voxlod-format's own decoders (the shader then decodes bit-identically to the host); Averages and
//! \[VJK21\] records of an Adaptive grid decoded on the host as in the single-pass kernel. Per
//! voxel a [`GpuVoxel`] (grid coordinates and the tag: kind in the top 2 bits, index into its
//! kind's array below) and, per frame, 32 bytes of cached values.
//!
//! # Kernel (what a real GPU sees)
//! A virtual-mesh voxel costs far more than the others to evaluate: up to 8 faces × 16 samples of
//! the shading function, and 32 lines × 27 slab overlaps (or 16 pixels × 27 lens areas) for one
//! directional opacity. Evaluating per hit, as the single-pass kernel does, would repeat that for
//! each of the up to 4 × pixels camera rays reaching a voxel, and the light opacity for every
//! shadow-ray step. So a frame is three dispatches:
//! 1. `light_pass`, one invocation per voxel (workgroups of 64): the voxel's opacity for the
//!    direction the light travels at its centre;
//! 2. `view_pass`, one invocation per voxel: its shadow ray (reading pass 1's opacities), its
//!    radiance and its opacity toward the eye;
//! 3. `composite`, one invocation per pixel in 8×8 workgroups: the 4 camera rays composite
//!    the cached values.
//!
//! Each value is a function of the voxel alone, so it equals what the CPU caches lazily for the
//! voxels its rays reach (the CPU reference row of the suite checks that its cache equals per-ray
//! evaluation). The passes evaluate every voxel, visible or not: on a real GPU that is one coherent
//! pass over a flat array (neighbouring invocations are neighbouring voxels in Morton order, so
//! their shadow rays cross the same bricks), and the visible voxels of a surface grid are a large
//! share of all (a camera ray composites ~2–4 voxels and the 4 rays of a pixel share most of them,
//! so at image size ≈ grid size per-hit evaluation does more work). Divergence: the record kind
//! switches per voxel in an Adaptive grid (a warp of mixed kinds runs each branch), and the virtual
//! mesh's loops are bounded (8 faces, ≤ [`MAX_SAMPLES_PER_FACE`] samples, 32 lines, 27 cells) but
//! their trip counts differ between records (visible faces, distribution flags, early-out of Lines
//! on opaque cells). Memory per virtual-mesh record read is 144 bytes, read once per pass and kept
//! in registers. Expected on a real GPU: the view pass dominates (shadow walks and the shading
//! samples); the composite pass is the single-pass kernel's walk with no evaluation. On lavapipe, a
//! CPU implementation, timings are CPU timings of the GPU path, never GPU speed.
//!
//! # Agreement with the CPU
//! As for the single-pass kernel, plus: WGSL's `sqrt`, `acos` (Circles) and division are within a
//! few ULP, so a barycentric sample normal, a lens area or a slab crossing can differ in the last
//! bits. A Lines crossing that lands within an ULP of a sub-cell boundary can add or drop a
//! sub-cell (a step of `1/32` of that cell's opacity at most, per line); everything else moves a
//! radiance by ~10⁻⁶ relative. The equivalence suite states the bound.

//!
//! # Layout of the module
//! `upload` checks and lays out virtual-mesh and Adaptive grids, `passes` compiles the three
//! passes and records them; this file holds the records' mirrors and the decoder tables.
//!
//! [`VirtualMeshGrid`]: voxlod_cpu::appearance::virtual_mesh::VirtualMeshGrid
//! [`AdaptiveGrid`]: voxlod_cpu::appearance::adaptive::AdaptiveGrid
//! [`VirtualMeshParams::projected_area`]: voxlod_cpu::appearance::virtual_mesh::VirtualMeshParams::projected_area

use glam::Vec3;
use voxlod_cpu::appearance::record_material;
use voxlod_format::records::quant::srgb_to_linear_table;
use voxlod_format::records::{SCALE_RANGE, SpecularRecord, VirtualMeshRecord};

mod passes;
mod upload;

pub(super) use passes::Passes;

/// The WGSL source of the per-voxel passes: shading, the single-pass renderer (its
/// parameters, DDA, look-up and \[VJK21\] code), the virtual mesh, then the passes.
pub const WGSL: &str = concat!(
    include_str!("../../shading.wgsl"),
    include_str!("../filtered.wgsl"),
    include_str!("../../subgrid.wgsl"),
    include_str!("vmesh.wgsl"),
    include_str!("voxels.wgsl"),
);

/// Most shading samples per distribution face the kernel takes (the CPU's default is 16):
/// a bound on the shading loop of one voxel.
pub const MAX_SAMPLES_PER_FACE: u32 = 1024;

/// A virtual-mesh record as the kernel reads it (mirrors WGSL `VmeshRecord`): the frozen
/// [`VirtualMeshRecord`]'s 136 bytes as 34 little-endian words, and the voxel's specular
/// level and exponent (0 and 1 without specular records, as `record_material` gives them).
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
pub struct GpuVirtualMesh {
    /// The record's bytes.
    pub bytes: [u32; 34],
    /// Specular level, Blinn-Phong exponent.
    pub specular: [f32; 2],
}

impl Default for GpuVirtualMesh {
    fn default() -> Self {
        bytemuck::Zeroable::zeroed()
    }
}

impl GpuVirtualMesh {
    /// The record with the voxel's specular side record, if any.
    pub fn new(record: &VirtualMeshRecord, specular: Option<&SpecularRecord>) -> Self {
        let mut bytes = [0u32; 34];
        // The bytes as they are: the GPU reads its words little-endian, byte `b` of the
        // record at bits `8·(b % 4)` of word `b / 4`.
        bytemuck::bytes_of_mut(&mut bytes).copy_from_slice(bytemuck::bytes_of(record));
        let m = record_material(Vec3::ZERO, specular);
        Self { bytes, specular: [m.specular.x, m.shininess] }
    }
}

/// One voxel with a record (mirrors the WGSL `vec4<u32>` of `voxels`): grid coordinates, and its
/// tag (kind in bits 30–31 as [`AdaptiveRef`](voxlod_format::records::AdaptiveRef), index into the
/// kernel's array of that kind).
pub type GpuVoxel = [u32; 4];

/// The decoder tables: sRGB8 → linear (256), then [`SCALE_RANGE`] codes → semi-axes (256).
pub fn decode_tables() -> [f32; 512] {
    let srgb = srgb_to_linear_table();
    std::array::from_fn(|i| if i < 256 { srgb[i] } else { SCALE_RANGE.decode((i - 256) as u8) })
}

/// The buffers of a virtual-mesh or Adaptive grid beyond the brick look-up.
pub(super) struct VoxelBuffers {
    /// `Params.vmesh`: rule, samples per face, projected area, voxel count.
    pub params: [u32; 4],
    tables: wgpu::Buffer,
    voxels: wgpu::Buffer,
    vmesh: wgpu::Buffer,
}

/// Bytes of the per-frame cache: two `vec4<f32>` per voxel.
fn cache_bytes(params: &[u32; 4]) -> u64 {
    params[3] as u64 * 32
}

#[cfg(test)]
mod tests {
    use std::mem::offset_of;

    use super::*;
    use crate::layout::assert_mirrors;

    #[test]
    fn voxel_pass_types_mirror_their_wgsl() {
        assert_mirrors(
            WGSL,
            "VmeshRecord",
            size_of::<GpuVirtualMesh>(),
            &[
                ("bytes", offset_of!(GpuVirtualMesh, bytes)),
                ("specular", offset_of!(GpuVirtualMesh, specular)),
            ],
        );
        // The arrays the kernel indexes: 144-byte records (a multiple of the WGSL alignment
        // of 8, so the array stride is the size), 16-byte voxels.
        assert_eq!(size_of::<GpuVirtualMesh>() % 8, 0);
        assert_eq!(size_of::<GpuVoxel>(), 16);
    }

    #[test]
    fn records_upload_in_their_frozen_byte_order() {
        let mut r = VirtualMeshRecord::default();
        r.axes[0] = [1, -2, 3];
        r.opacity[26] = 0xab;
        r.distribution = 0x5a;
        let g = GpuVirtualMesh::new(&r, Some(&SpecularRecord::new(0.5, 32.0)));
        let byte = |b: usize| (g.bytes[b / 4] >> (8 * (b % 4))) & 0xff;
        assert_eq!((byte(0), byte(1), byte(2)), (1, 0xfe, 3));
        assert_eq!((byte(108), byte(135)), (0x5a, 0xab));
        assert!((g.specular[0] - 0.5).abs() < 0.003 && (g.specular[1] / 32.0 - 1.0).abs() < 0.02);
        let plain = GpuVirtualMesh::new(&r, None);
        assert_eq!(plain.specular, [0.0, 1.0]);
        let t = decode_tables();
        assert_eq!((t[0], t[255], t[256], t[257]), (0.0, 1.0, 0.0, SCALE_RANGE.decode(1)));
    }
}
