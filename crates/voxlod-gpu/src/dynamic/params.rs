//! The `#[repr(C)]` mirrors of the dynamic kernels' WGSL parameter structs, checked against
//! the WGSL by naga reflection in the module's tests.

/// The kernels' parameters, bound as read-only storage (mirrors WGSL `Params` of
/// `common.wgsl`). 32 bytes.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
pub struct GpuDynamicParams {
    /// Invocations of the dispatch.
    pub n: u32,
    /// 0 nearest, 1 8-neighbour.
    pub filter_mode: u32,
    /// `log2` of the brick table's resolution per axis.
    pub brick_log2: u32,
    /// Kernel-specific: 1 for the static pass of `mark` and `accumulate`, the compact pass of
    /// `compact`, the radiance conversion of `convert`.
    pub extra: u32,
    /// The world grid's dimensions.
    pub dims: [u32; 3],
    /// The occupancy threshold in 2⁻¹⁸ voxel (at least 1).
    pub min_weight: u32,
}

/// One object's frame as the transform reads it (mirrors WGSL `Object`). 32 bytes.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
pub struct GpuObject {
    /// The anchor cell.
    pub anchor: [i32; 3],
    /// Index of its first matrix.
    pub first_matrix: u32,
    /// 1 if skinned.
    pub skinned: u32,
    /// 1 if entirely outside (not transformed).
    pub outside: u32,
    /// Padding.
    pub pad: [u32; 2],
}

/// The injection kernel's own parameters (mirrors WGSL `InjectParams`). 64 bytes.
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
pub struct GpuInjectParams {
    /// Direction toward a directional light or a point light's position; w: 1 for a point.
    pub light_a: [f32; 4],
    /// Irradiance or intensity; w: 1 to march shadows.
    pub light_b: [f32; 4],
    /// Shadow ray offset in voxels; unused ×3.
    pub shadow: [f32; 4],
    /// Leaves; unused ×3.
    pub counts: [u32; 4],
}
