//! The octree-build kernels' parameters, the `#[repr(C)]` mirror of the WGSL
//! `Params` every kernel reads, checked (with voxlod-octree's flat-layout types, which the
//! kernels share) against the WGSL by naga reflection.

/// The kernels' parameters (mirrors WGSL `Params`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
pub struct GpuOctreeParams {
    /// Invocations (or items) of the dispatch.
    pub n: u32,
    /// The level built (mark, allocate, link) or filtered (prefilter).
    pub level: u32,
    /// The finest dense level.
    pub first_dense: u32,
    /// Kernel-specific: fill's first node, allocate's flagged-parent count.
    pub extra: u32,
}

#[cfg(test)]
mod tests {
    use std::mem::offset_of;

    use voxlod_octree::AveragePayload;

    use super::*;
    use crate::layout::{assert_flat_octree_mirrors, assert_mirrors};
    use crate::octree::KERNELS;

    #[test]
    fn octree_types_mirror_their_wgsl() {
        for (_, src) in KERNELS {
            assert_flat_octree_mirrors(src, ["GpuLevel", "GpuNode", "GpuTile"]);
            assert_mirrors(
                src,
                "Average",
                size_of::<AveragePayload>(),
                &[
                    ("color_alpha", offset_of!(AveragePayload, color_alpha)),
                    ("normal_alpha", offset_of!(AveragePayload, normal_alpha)),
                    ("opacity", offset_of!(AveragePayload, opacity)),
                ],
            );
            assert_mirrors(
                src,
                "Params",
                size_of::<GpuOctreeParams>(),
                &[
                    ("n", offset_of!(GpuOctreeParams, n)),
                    ("level", offset_of!(GpuOctreeParams, level)),
                    ("first_dense", offset_of!(GpuOctreeParams, first_dense)),
                    ("extra", offset_of!(GpuOctreeParams, extra)),
                ],
            );
        }
    }
}
