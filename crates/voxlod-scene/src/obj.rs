//! OBJ + MTL loader (tobj).

use std::path::Path;

use crate::{Error, Result, Scene};

/// Loads an OBJ file (and its MTL) into a world-space scene.
pub fn load(path: &Path) -> Result<Scene> {
    Err(Error::UnsupportedFormat { path: path.to_owned() })
}
