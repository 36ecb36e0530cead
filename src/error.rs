//! The error type of the `voxlod` facade: any error of the layered crates.

/// An error from any voxlod crate, with its source kept for the cause chain.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// From voxlod-scene (loading, validating, procedural parameters).
    #[error(transparent)]
    Scene(#[from] voxlod_scene::Error),
    /// From voxlod-format (grids, containers).
    #[error(transparent)]
    Format(#[from] voxlod_format::Error),
    /// From voxlod-cpu (voxelizers, renderers).
    #[error(transparent)]
    Cpu(#[from] voxlod_cpu::Error),
    /// From voxlod-eval (metrics, reports).
    #[error(transparent)]
    Eval(#[from] voxlod_eval::Error),
    /// From voxlod-gpu (adapter, kernels), when the GPU backend was asked for.
    #[error(transparent)]
    Gpu(#[from] voxlod_gpu::Error),
    /// A scene the GPU backend cannot render (e.g. textures over the device's storage limits).
    #[error("scene '{scene}' cannot be rendered on the GPU backend")]
    GpuScene {
        /// The scene's spec.
        scene: String,
        /// Why.
        #[source]
        source: voxlod_gpu::Error,
    },
}
