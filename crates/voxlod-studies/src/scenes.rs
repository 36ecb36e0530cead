//! Scene specs: a path to an `.obj`/`.gltf`/`.glb` file, or `builtin:NAME[?KEY=VALUE&…]`.
//!
//! Builtins are the procedural scenes of [`voxlod_scene::procedural`] (with parameters) and the
//! real models embedded in this binary from `assets/` (no parameters): nothing is downloaded.

use std::io;
use std::path::Path;

use voxlod_scene::{Error, Result, Scene, gltf, obj, procedural};

/// Prefix that marks a builtin scene in a spec.
pub const BUILTIN_PREFIX: &str = "builtin:";

struct Embedded {
    name: &'static str,
    description: &'static str,
    file: &'static str,
    bytes: &'static [u8],
}

/// Real models compiled into the binary (each with its licence next to it in `assets/`).
const EMBEDDED: &[Embedded] = &[
    Embedded {
        name: "bunny",
        description: "the Stanford bunny (npm package `bunny`), 3 674 triangles, closed",
        file: "assets/bunny/bunny.obj",
        bytes: include_bytes!("../../../assets/bunny/bunny.obj"),
    },
    Embedded {
        name: "engine",
        description: "Khronos glTF sample 2CylinderEngine, 121 496 triangles, 82 nodes",
        file: "assets/2CylinderEngine/2CylinderEngine.glb",
        bytes: include_bytes!("../../../assets/2CylinderEngine/2CylinderEngine.glb"),
    },
    Embedded {
        name: "box-textured",
        description: "Khronos glTF sample BoxTextured, 12 triangles, one texture",
        file: "assets/BoxTextured/BoxTextured.glb",
        bytes: include_bytes!("../../../assets/BoxTextured/BoxTextured.glb"),
    },
];

/// All builtin scenes: `(name, description)`, embedded models first.
pub fn builtin_names() -> Vec<(&'static str, &'static str)> {
    EMBEDDED
        .iter()
        .map(|e| (e.name, e.description))
        .chain(procedural::builtin_names().iter().copied())
        .collect()
}

/// Loads the scene a spec names (see the module docs) and validates it.
///
/// ```
/// let bunny = voxlod_studies::scenes::load("builtin:bunny").unwrap();
/// assert_eq!(bunny.triangle_count(), 3674);
/// let err = voxlod_studies::scenes::load("builtin:bunny?seed=3").unwrap_err();
/// assert!(err.to_string().contains("seed"));
/// ```
pub fn load(spec: &str) -> Result<Scene> {
    let scene = match spec.strip_prefix(BUILTIN_PREFIX) {
        Some(rest) => load_builtin(rest)?,
        None => Scene::load(Path::new(spec))?,
    };
    scene.validate()?;
    Ok(scene)
}

fn load_builtin(spec: &str) -> Result<Scene> {
    let (name, params) = procedural::parse_spec(spec)?;
    let Some(e) = EMBEDDED.iter().find(|e| e.name == name) else {
        return procedural::builtin(name, &params);
    };
    if let Some((key, value)) = params.first() {
        return Err(Error::InvalidParameter {
            name: format!("{name}.{key}"),
            value: (*value).into(),
            reason: "embedded models take no parameters".into(),
        });
    }
    let path = Path::new(e.file);
    let no_files = |p: &Path| -> io::Result<Vec<u8>> {
        Err(io::Error::new(io::ErrorKind::NotFound, format!("{} is not embedded", p.display())))
    };
    let mut scene = if e.file.ends_with(".obj") {
        obj::load_from_bytes(path, e.bytes, no_files)?.0
    } else {
        gltf::load_from_bytes(path, e.bytes, no_files)?.0
    };
    scene.name = e.name.into();
    Ok(scene)
}

/// A scene's light in voxlod-cone's terms (the same light, for injection and shadow cones).
pub fn cone_light(l: voxlod_scene::Light) -> voxlod_cone::Light {
    match l {
        voxlod_scene::Light::Directional { to_light, irradiance } => {
            voxlod_cone::Light::Directional { to_light, irradiance }
        }
        voxlod_scene::Light::Point { position, intensity } => {
            voxlod_cone::Light::Point { position, intensity }
        }
    }
}
