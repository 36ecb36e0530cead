//! The error type of voxlod-scene.

use std::path::PathBuf;

/// Result alias of this crate.
pub type Result<T, E = Error> = std::result::Result<T, E>;

/// Everything that can go wrong loading, building or validating a scene. Each variant names the
/// file and the element at fault.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// A file could not be read or written.
    #[error("{op} {path}: {source}")]
    Io {
        /// What was being done.
        op: &'static str,
        /// The file.
        path: PathBuf,
        /// The underlying error.
        #[source]
        source: std::io::Error,
    },
    /// An OBJ or MTL file is malformed.
    #[error("{path}: {reason}")]
    Obj {
        /// The file.
        path: PathBuf,
        /// What is wrong, with the line or element where known.
        reason: String,
    },
    /// A glTF file is malformed or refers to something that does not exist.
    #[error("{path}: {element}: {reason}")]
    Gltf {
        /// The file.
        path: PathBuf,
        /// The element at fault, e.g. `nodes[3]`, `accessors[7]`, `buffers[0]`.
        element: String,
        /// What is wrong.
        reason: String,
    },
    /// An image could not be decoded or encoded.
    #[error("{path}: image: {reason}")]
    Image {
        /// The file (or where the image was embedded).
        path: PathBuf,
        /// What is wrong.
        reason: String,
    },
    /// A vertex attribute holds NaN or infinity.
    #[error("mesh '{mesh}': {attribute} of vertex {vertex} is not finite: {value:?}")]
    NonFinite {
        /// The mesh's name.
        mesh: String,
        /// Which attribute ("position", "normal", "uv").
        attribute: &'static str,
        /// Vertex index within the mesh.
        vertex: usize,
        /// The offending value.
        value: [f32; 3],
    },
    /// A triangle refers to a vertex that does not exist.
    #[error(
        "mesh '{mesh}': triangle {triangle} refers to vertex {index}, but the mesh has {vertex_count} vertices"
    )]
    IndexOutOfRange {
        /// The mesh's name.
        mesh: String,
        /// Triangle index within the mesh.
        triangle: usize,
        /// The offending vertex index.
        index: u32,
        /// Number of vertices in the mesh.
        vertex_count: usize,
    },
    /// A reference to a material, texture or other element that does not exist.
    #[error("{what} {index} does not exist ({count} defined), referenced by {by}")]
    DanglingReference {
        /// The kind of element ("material", "texture").
        what: &'static str,
        /// The index referenced.
        index: usize,
        /// How many exist.
        count: usize,
        /// Who referenced it.
        by: String,
    },
    /// A mesh's attribute arrays disagree in length.
    #[error("mesh '{mesh}': {attribute} has {found} entries for {expected} vertices")]
    AttributeLength {
        /// The mesh's name.
        mesh: String,
        /// Which attribute.
        attribute: &'static str,
        /// Entries found.
        found: usize,
        /// Entries expected.
        expected: usize,
    },
    /// The scene has no triangles (or no finite extent) where some were required.
    #[error("scene '{scene}' is empty: {reason}")]
    EmptyScene {
        /// The scene's name.
        scene: String,
        /// Why it counts as empty.
        reason: String,
    },
    /// A parameter (of a camera, light, procedural scene…) is out of its valid range.
    #[error("invalid {name} = {value}: {reason}")]
    InvalidParameter {
        /// The parameter.
        name: String,
        /// Its value, as given.
        value: String,
        /// The valid range or why it is wrong.
        reason: String,
    },
    /// A particle of a procedural volume has a non-finite or out-of-range field.
    #[error("particle {index}: {field} = {value}: {reason}")]
    InvalidParticle {
        /// Index of the particle in its system.
        index: usize,
        /// The field at fault (`center`, `radius`, `density`…).
        field: &'static str,
        /// Its value, as given.
        value: String,
        /// The valid range.
        reason: &'static str,
    },
    /// An animation cannot be evaluated: a morph-weights channel, a channel on a node that does
    /// not exist or is given by a matrix, keys that do not match their values, a non-finite
    /// time, a rotation that interpolates to zero.
    #[error("animation '{animation}', channel {channel} (node {node}): {reason}")]
    Animation {
        /// The animation's name.
        animation: String,
        /// The channel's index in the animation.
        channel: usize,
        /// The node it targets.
        node: usize,
        /// What is wrong.
        reason: String,
    },
    /// A file type this crate does not load.
    #[error("{path}: unsupported scene file (expected .obj, .gltf or .glb)")]
    UnsupportedFormat {
        /// The file.
        path: PathBuf,
    },
}

/// Reads a whole file, naming it in the error.
pub(crate) fn read_file(path: &std::path::Path) -> Result<Vec<u8>> {
    std::fs::read(path).map_err(|source| Error::Io { op: "reading", path: path.to_owned(), source })
}
