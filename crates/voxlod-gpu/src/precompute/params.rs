//! The `#[repr(C)]` mirrors of the precompute kernel's WGSL structs (uniform, voxels, local
//! triangles, per-voxel and per-line results), checked against the WGSL by naga reflection.

/// The kernel's parameters (mirrors WGSL `Params`).
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
pub struct GpuPrecomputeParams {
    /// Voxels, lines per voxel, first voxel of the dispatch, flags (1: write the lines).
    pub counts: [u32; 4],
    /// First random dimension (`8·seed`), voxels in the dispatch, blend key
    /// (`blend_key(seed)`), 0.
    pub seed: [u32; 4],
}

/// One voxel (mirrors WGSL `Voxel`).
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
pub struct GpuVoxel {
    /// First entry in the triangle buffer.
    pub first: u32,
    /// Entries (non-degenerate triangles of the voxel's list, in list order).
    pub count: u32,
    /// Random id `x + X·(y + Y·z)`.
    pub id: u32,
    /// Zero.
    pub pad: u32,
}

/// A triangle of one voxel in voxel-local coordinates (mirrors WGSL `Tri`).
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
pub struct GpuLocalTri {
    /// Vertex 0; `w` = bits of the flat-axis mask (bits 0..3) and [`ALPHA_FLAG`].
    pub a: [f32; 4],
    /// Unit plane normal; `w` = offset.
    pub n: [f32; 4],
    /// Barycentric plane of vertex 1; `w` = its constant.
    pub bu: [f32; 4],
    /// Barycentric plane of vertex 2; `w` = its constant.
    pub bv: [f32; 4],
    /// World geometric normal `(b−a)×(c−a)`; `w` = bits of the triangle id.
    pub ng: [f32; 4],
}

/// Set in [`GpuLocalTri::a`]'s `w` bits when the triangle's material is not `Opaque` (its hits
/// pass the alpha test).
pub const ALPHA_FLAG: u32 = 8;

/// One voxel's results (mirrors WGSL `VoxelOut`).
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
pub struct GpuVoxelOut {
    /// Occluded lines, case-(a) lines, marked sub-cells (bit mask), lines.
    pub counts: [u32; 4],
    /// Σ albedo; `w` = Σ specular level.
    pub albedo: [f32; 4],
    /// Σ shading normal; `w` = Σ level × exponent.
    pub normal: [f32; 4],
    /// Σ n nᵀ: xx, xy, xz, yy.
    pub scatter0: [f32; 4],
    /// Σ n nᵀ: yz, zz, 0, 0.
    pub scatter1: [f32; 4],
    /// The 27 subgrid bytes (index `x + 3y + 9z`), then zeros.
    pub subgrid: [u32; 8],
}

/// One line (mirrors WGSL `LineOut`).
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
pub struct GpuLineOut {
    /// Direction; `w` = chord.
    pub dir: [f32; 4],
    /// Entry point; `w` = bits of the case (0 miss, 1 occluded without surface, 2 surface).
    pub entry: [f32; 4],
    /// Hit point; `w` = bits of the triangle id (`u32::MAX`: none).
    pub point: [f32; 4],
    /// Shading normal of a surface hit.
    pub normal: [f32; 4],
    /// Albedo of a surface hit (`Material::sample` at its UV).
    pub albedo: [f32; 4],
}

#[cfg(test)]
mod tests {
    use std::mem::offset_of;

    use super::*;
    use crate::layout::assert_mirrors;
    use crate::precompute::WGSL;

    #[test]
    fn precompute_types_mirror_their_wgsl() {
        type P = GpuPrecomputeParams;
        assert_mirrors(
            WGSL,
            "Params",
            size_of::<P>(),
            &[("counts", offset_of!(P, counts)), ("seed", offset_of!(P, seed))],
        );
        assert_mirrors(
            WGSL,
            "Voxel",
            size_of::<GpuVoxel>(),
            &[
                ("first", offset_of!(GpuVoxel, first)),
                ("count", offset_of!(GpuVoxel, count)),
                ("id", offset_of!(GpuVoxel, id)),
                ("pad", offset_of!(GpuVoxel, pad)),
            ],
        );
        type T = GpuLocalTri;
        assert_mirrors(
            WGSL,
            "Tri",
            size_of::<T>(),
            &[
                ("a", offset_of!(T, a)),
                ("n", offset_of!(T, n)),
                ("bu", offset_of!(T, bu)),
                ("bv", offset_of!(T, bv)),
                ("ng", offset_of!(T, ng)),
            ],
        );
        type O = GpuVoxelOut;
        assert_mirrors(
            WGSL,
            "VoxelOut",
            size_of::<O>(),
            &[
                ("counts", offset_of!(O, counts)),
                ("albedo", offset_of!(O, albedo)),
                ("normal", offset_of!(O, normal)),
                ("scatter0", offset_of!(O, scatter0)),
                ("scatter1", offset_of!(O, scatter1)),
                ("subgrid", offset_of!(O, subgrid)),
            ],
        );
        type L = GpuLineOut;
        assert_mirrors(
            WGSL,
            "LineOut",
            size_of::<L>(),
            &[
                ("dir", offset_of!(L, dir)),
                ("entry", offset_of!(L, entry)),
                ("point", offset_of!(L, point)),
                ("normal", offset_of!(L, normal)),
                ("albedo", offset_of!(L, albedo)),
            ],
        );
        crate::ground_truth::assert_shade_tri_mirrors(WGSL);
    }
}
