//! The error type of the studies: any error of the layered crates, or a configuration a study
//! cannot measure.

/// An error from a study: a layered crate's error (its source kept for the cause chain), or a
/// configuration that names what is wrong and what was expected.
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
    /// From voxlod-octree (build, payloads).
    #[error(transparent)]
    Octree(#[from] voxlod_octree::Error),
    /// From voxlod-cone (injection, tracing, primary renderer).
    #[error(transparent)]
    Cone(#[from] voxlod_cone::Error),
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
    /// A configuration field out of its range.
    #[error("{study} study: {field} = {value} is invalid: expected {expected}")]
    InvalidConfig {
        /// The study.
        study: &'static str,
        /// The configuration field.
        field: &'static str,
        /// The value given.
        value: String,
        /// What the field accepts.
        expected: &'static str,
    },
    /// The scene leaves the study nothing to measure (every row would agree trivially).
    #[error("{scene}: nothing to measure: {why}")]
    NothingToMeasure {
        /// The scene's spec.
        scene: String,
        /// Why.
        why: String,
    },
}
