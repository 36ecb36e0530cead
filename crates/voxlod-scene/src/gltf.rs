//! glTF 2.0 loader (.gltf and .glb), on gltf-json's document model with voxlod's own data
//! access, so that every malformed input is an [`Error::Gltf`](crate::Error::Gltf) naming the file and the element
//! (`nodes[3]`, `accessors[7]`, `buffers[0]`…), never a panic.
//!
//! What is loaded:
//! - the default scene's node hierarchy (else the first scene's; a file without scenes loads
//!   every root node), flattened into [`Mesh`]es, one per (node, primitive); node transforms
//!   read in `f64` from the JSON's digits and composed in `f64`, positions transformed in `f64`
//!   (accessors themselves are `f32`, as the format defines them); normals by the inverse
//!   transpose, winding flipped under mirroring transforms;
//! - re-centred: [`Scene::origin`] is the re-centring origin of the `f64` bounds of every
//!   instanced vertex ([`voxlod_format::origin::recentring_origin`]; zero for a model that reaches
//!   near the world origin), subtracted in `f64` from positions and the camera; node matrices
//!   are moved into the same local frame (roots, and the translation keys that animate them), so
//!   posed meshes stay consistent with the rest pose. A model placed at 10⁷ by a node
//!   translation loads to the same `f32` positions as at the origin, to within one unit in the
//!   last place;
//! - every primitive of mode TRIANGLES, TRIANGLE_STRIP or TRIANGLE_FAN (points and lines are
//!   skipped and counted in [`LoadReport`]); morph targets at the default weights; skinned
//!   meshes at the rest pose (joint world × inverse bind matrix), with their [`SkinBinding`]
//!   (JOINTS_0/WEIGHTS_0) kept;
//! - materials: baseColorFactor, baseColorTexture (sRGB; sampler wrap modes;
//!   `KHR_texture_transform` applied to the texture coordinates of the set it names),
//!   alphaMode/alphaCutoff, doubleSided; the texture coordinate set a base colour texture reads
//!   must exist. Metallic-roughness parameters are not used: voxlod shades glTF materials as
//!   diffuse (Lambert) with their base colour;
//! - [`Scene::nodes`], [`Scene::skins`], [`Scene::animations`] for the dynamic pipeline, and the
//!   first perspective camera of the scene. `KHR_lights_punctual` is not read (the workspace
//!   does not enable that gltf feature).
//!
//! What is checked before anything is read: the GLB container, JSON deserialization (the
//! failing element is located), gltf-json's validation of every index and enum (a POSITION
//! accessor may lack min/max), a node graph that is a forest (no cycle, one parent), buffers
//! present and long enough, data URIs that decode, every buffer view and accessor inside its
//! buffer, accessor types and component types per attribute, indices in range, finite values.
//!
//! [`SkinBinding`]: crate::mesh::SkinBinding

mod accessor;
mod buffers;
mod material;
mod nodes;
mod parse;
mod primitive;

use std::io;
use std::path::Path;

use glam::{DMat4, DVec3};

use crate::{Mesh, Result, Scene};

/// What the glTF loader skipped, converted or repaired.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct LoadReport {
    /// POINTS primitives, skipped.
    pub points_skipped: usize,
    /// LINES, LINE_LOOP and LINE_STRIP primitives, skipped.
    pub lines_skipped: usize,
    /// TRIANGLE_STRIP and TRIANGLE_FAN primitives, converted to triangle lists.
    pub strips_and_fans_converted: usize,
    /// Morph targets applied at a non-zero default weight (per instance).
    pub morph_targets_applied: usize,
    /// Vertices whose normal was computed (area-weighted): the primitive has no NORMAL, or the
    /// transformed normal had zero length.
    pub normals_computed: usize,
    /// Orthographic cameras passed over when choosing the scene's camera.
    pub orthographic_cameras_skipped: usize,
}

/// Loads a `.gltf` or `.glb` file, its buffers and its base colour textures.
pub fn load(path: &Path) -> Result<Scene> {
    load_with_report(path).map(|(scene, _)| scene)
}

/// [`load`], also returning what was skipped or converted.
pub fn load_with_report(path: &Path) -> Result<(Scene, LoadReport)> {
    let bytes = crate::error::read_file(path)?;
    load_from_bytes(path, &bytes, |p| std::fs::read(p))
}

/// Loads glTF or GLB bytes: `path` names them in errors and is the base relative URIs are
/// resolved against; `resolve` returns the bytes of an external buffer or image given its
/// path (data URIs and the GLB binary chunk need no resolver).
///
/// ```
/// # use std::path::Path;
/// let gltf = r#"{"asset": {"version": "2.0"}, "scenes": [{"nodes": [0]}], "nodes": [{"mesh": 0}],
///   "meshes": [{"primitives": [{"attributes": {"POSITION": 0}}]}],
///   "accessors": [{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3"}],
///   "bufferViews": [{"buffer": 0, "byteLength": 36}],
///   "buffers": [{"byteLength": 36, "uri": "tri.bin"}]}"#;
/// let floats: [f32; 9] = [0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0];
/// let bin: Vec<u8> = floats.iter().flat_map(|f| f.to_le_bytes()).collect();
/// let resolve = |p: &Path| match p.to_str() {
///     Some("mem/tri.bin") => Ok(bin.clone()),
///     _ => Err(std::io::ErrorKind::NotFound.into()),
/// };
/// let path = Path::new("mem/tri.gltf");
/// let (scene, _) = voxlod_scene::gltf::load_from_bytes(path, gltf.as_bytes(), resolve)?;
/// assert_eq!(scene.triangle_count(), 1);
/// # Ok::<(), voxlod_scene::Error>(())
/// ```
pub fn load_from_bytes(
    path: &Path,
    bytes: &[u8],
    mut resolve: impl FnMut(&Path) -> io::Result<Vec<u8>>,
) -> Result<(Scene, LoadReport)> {
    let (json_bytes, bin) = parse::split_glb(path, bytes)?;
    let (root, raw) = parse::deserialize(path, json_bytes)?;
    parse::validate(path, &root)?;
    let parents = parse::node_parents(path, &root)?;
    let buffers = buffers::load_buffers(path, &root, bin, &mut resolve)?;
    let data = accessor::Data { path, root: &root, buffers: &buffers };

    let (mut nodes, world) = nodes::nodes(path, &root, &raw, &parents)?;
    let order = nodes::scene_nodes(&root, &parents);
    let mut mats = material::materials(&data, &mut resolve)?;
    let skins = nodes::skins(&data)?;
    let joint_mats: Vec<Vec<DMat4>> = skins
        .iter()
        .map(|s| {
            s.joints
                .iter()
                .zip(&s.inverse_bind_matrices)
                .map(|(&j, ibm)| world[j] * ibm.as_dmat4())
                .collect()
        })
        .collect();
    let mut animations = nodes::animations(&data)?;
    let mut report = LoadReport::default();

    let mut built: Vec<primitive::Built> = Vec::new();
    let mut default_material = None;
    for &n in &order {
        let Some(m) = root.nodes[n].mesh.map(|m| m.value()) else { continue };
        let skin = root.nodes[n].skin.map(|s| s.value());
        let inst = primitive::Instance {
            node: n,
            world: world[n],
            skin: skin.map(|s| (s, &joint_mats[s][..])),
        };
        for (p, prim) in root.meshes[m].primitives.iter().enumerate() {
            let material = match prim.material {
                Some(i) => i.value(),
                None => *default_material.get_or_insert_with(|| {
                    mats.materials.push(material::default_material());
                    mats.uv.push(material::UvMapping::default());
                    mats.materials.len() - 1
                }),
            };
            let uv = mats.uv[material];
            if let Some(b) = primitive::mesh(&data, (m, p), &inst, material, &uv, &mut report)? {
                built.push(b);
            }
        }
    }
    if built.is_empty() {
        let element = match root.scene.map(|s| s.value()).or((!root.scenes.is_empty()).then_some(0))
        {
            Some(s) => format!("scenes[{s}]"),
            None => "nodes".to_owned(),
        };
        let reason = format!(
            "no triangles to load ({} points and {} line primitives skipped)",
            report.points_skipped, report.lines_skipped
        );
        return Err(parse::err(path, element, reason));
    }
    // Re-centre: the scene's origin from the f64 bounds of every instanced vertex, subtracted
    // in f64 from positions, the camera and the node hierarchy.
    let (lo, hi) = built
        .iter()
        .flat_map(|b| &b.world)
        .fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(lo, hi), &p| (lo.min(p), hi.max(p)));
    let origin = voxlod_format::origin::recentring_origin(lo, hi).unwrap_or(DVec3::ZERO);
    let meshes: Vec<Mesh> = built
        .into_iter()
        .map(|b| {
            let mut mesh = b.mesh;
            mesh.positions = b.world.iter().map(|&w| (w - origin).as_vec3()).collect();
            mesh
        })
        .collect();
    let (camera, orthographic) = nodes::camera(path, &root, &order, &world, origin)?;
    report.orthographic_cameras_skipped = orthographic;
    nodes::recentre(&mut nodes, &world, &mut animations, origin);
    let name = path.file_stem().map_or_else(|| "gltf".into(), |s| s.to_string_lossy().into_owned());
    let scene = Scene {
        name,
        origin,
        meshes,
        materials: mats.materials,
        textures: mats.textures,
        camera,
        nodes,
        skins,
        animations,
        ..Default::default()
    };
    scene.validate()?;
    Ok((scene, report))
}

#[cfg(test)]
mod tests;
