//! The error type of voxlod-gpu.

/// Result alias of this crate.
pub type Result<T, E = Error> = std::result::Result<T, E>;

/// Everything that can go wrong on the GPU path.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// Bad input, reported exactly as the CPU reference reports it (the GPU path validates
    /// through the same host-side code: snapping, culling, BVH build).
    #[error(transparent)]
    Cpu(#[from] voxlod_cpu::Error),
    /// Bad octree input, reported exactly as voxlod-octree's CPU builds report it.
    #[error(transparent)]
    Octree(#[from] voxlod_octree::Error),
    /// Bad cone-tracing options or an octree the flat layout cannot index, reported exactly as
    /// voxlod-cone reports them.
    #[error(transparent)]
    Cone(#[from] voxlod_cone::Error),
    /// No wgpu adapter at all.
    #[error(
        "no GPU adapter found (wgpu enumerated none on Vulkan, Metal or DX12; on Linux without a GPU, \
         install Mesa's lavapipe: apt-get install mesa-vulkan-drivers)"
    )]
    NoAdapter,
    /// `VOXLOD_ADAPTER` (or an explicit selector) matched no adapter.
    #[error("no adapter matches {selector:?}; found: {available}")]
    AdapterNotFound {
        /// The selector: an index or a substring of the adapter name.
        selector: String,
        /// The adapters found, one per line.
        available: String,
    },
    /// The adapter refused to create a device.
    #[error("adapter {adapter:?} could not create a device: {message}")]
    RequestDevice {
        /// Adapter name.
        adapter: String,
        /// wgpu's message.
        message: String,
    },
    /// A buffer larger than the device allows.
    #[error(
        "{what} needs a buffer of {bytes} bytes, over the device limit of {limit} bytes ({limit_name}) on {adapter:?}"
    )]
    BufferTooLarge {
        /// What the buffer holds.
        what: &'static str,
        /// Requested size.
        bytes: u64,
        /// The limit.
        limit: u64,
        /// Which wgpu limit.
        limit_name: &'static str,
        /// Adapter name.
        adapter: String,
    },
    /// A request that exceeds what the kernel can index (e.g. a grid over 2^32 voxels).
    #[error("{what}: {requested} is over the kernel's limit of {limit}")]
    TooLarge {
        /// What was requested.
        what: &'static str,
        /// The requested amount.
        requested: u64,
        /// The most the kernel handles.
        limit: u64,
    },
    /// A request this backend has no kernel for.
    #[error("not supported on the GPU backend: {what}")]
    Unsupported {
        /// What was requested.
        what: &'static str,
    },
    /// The device ran out of memory (allocation or dispatch).
    #[error("GPU out of memory on {adapter:?} while {during}: {message}")]
    OutOfMemory {
        /// Adapter name.
        adapter: String,
        /// What was being done.
        during: &'static str,
        /// wgpu's message.
        message: String,
    },
    /// wgpu reported a validation or internal error (a bug in this crate, or a driver bug).
    #[error("GPU error on {adapter:?} while {during}: {message}")]
    Device {
        /// Adapter name.
        adapter: String,
        /// What was being done.
        during: &'static str,
        /// wgpu's message.
        message: String,
    },
    /// The device was lost (driver reset, GPU removed, timeout detection).
    #[error("GPU device {adapter:?} lost while {during}: {message}")]
    DeviceLost {
        /// Adapter name.
        adapter: String,
        /// What was being done.
        during: &'static str,
        /// The reason the driver gave.
        message: String,
    },
    /// The GPU did not finish within the timeout.
    #[error("GPU work on {adapter:?} did not finish within {seconds} s while {during}")]
    Timeout {
        /// Adapter name.
        adapter: String,
        /// What was being done.
        during: &'static str,
        /// The timeout.
        seconds: u64,
    },
}
