//! glTF 2.0 loader (.gltf and .glb).

use std::path::Path;

use crate::{Error, Result, Scene};

/// Loads a glTF 2.0 file into a world-space scene.
pub fn load(path: &Path) -> Result<Scene> {
    Err(Error::UnsupportedFormat { path: path.to_owned() })
}
