//! OBJ + MTL loader: [tobj] parses, voxlod validates and triangulates.
//!
//! - Every line is checked first (module `scan`): unparsable numbers, NaN/∞ coordinates, face
//!   indices that are zero or out of range, MTL statements with missing values are errors
//!   naming the file and the line. tobj then parses the validated text.
//! - Coordinates are read in `f64` (tobj's `use_f64`) and the scene is re-centred before they
//!   are stored in `f32`: [`Scene::origin`] is the re-centring origin of the bounds of every
//!   vertex the faces use ([`voxlod_format::origin::recentring_origin`]; zero for a model that
//!   reaches near the world origin), subtracted in `f64`. A model exported at 10⁶–10⁷ loads to
//!   the same `f32` positions as at the origin, to within the digits its file holds.
//! - Faces are loaded untriangulated and triangulated here by ear clipping on the polygon's
//!   dominant plane (module `triangulate`), which is correct for concave faces; faces of one or
//!   two corners, `l` polylines and `p` points are skipped and counted in [`LoadReport`].
//! - Normals: the file's, normalized; computed area-weighted ([`Mesh::compute_normals`]) where
//!   a normal is zero-length, and for a whole mesh when some of its face corners have none.
//! - Texture coordinates are flipped to voxlod's convention (origin top-left, v down), after
//!   the `map_Kd` `-s`/`-o` options are applied. A textured material on faces without texture
//!   coordinates is an error.
//! - Materials (module `mtl`): `Kd` linear base colour, `d` (or 1 − `Tr`) alpha, `Ks`/`Ns`
//!   Blinn-Phong specular (none under `illum 0/1`), `map_Kd` sRGB diffuse texture relative to
//!   the MTL. A missing MTL or texture file is an error naming the file that refers to it; a
//!   `usemtl` of a name no library defines gets the default material and is listed in the
//!   report.
//!
//! Text is UTF-8, or else read as Latin-1 (the legacy encoding of many exporters); UTF-16 is
//! an error. A `usemtl` or `newmtl` without a name (Blender writes one for an unnamed material)
//! names the material `(unnamed)`.
//!
//! Companion files (MTL libraries, textures) are read through a resolver, so a file embedded
//! with `include_str!` loads without a file system ([`load_from_str`]).

mod mtl;
mod scan;
mod triangulate;

use std::collections::{BTreeSet, HashMap};
use std::io;
use std::path::{Path, PathBuf};

use glam::{DVec2, DVec3, Vec2, Vec3};

use crate::{Error, Material, Mesh, Result, Scene};

/// What the OBJ loader skipped or repaired. Nothing here makes the scene wrong; it says what
/// the file held that voxlod does not draw.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct LoadReport {
    /// `p` elements and faces with a single corner, skipped.
    pub points_skipped: usize,
    /// `l` elements and faces with two corners, skipped.
    pub lines_skipped: usize,
    /// Faces of four or more corners, triangulated by ear clipping.
    pub polygons_triangulated: usize,
    /// Polygon corners dropped because they were collinear with their neighbours.
    pub collinear_corners_dropped: usize,
    /// Vertices whose normal was computed (the file had none, or a zero-length one).
    pub normals_computed: usize,
    /// Meshes whose texture coordinates were dropped because only some of their face corners
    /// had one and no texture needs them.
    pub partial_uvs_dropped: usize,
    /// `usemtl` names that no MTL library defines; those faces got the default material.
    pub unknown_materials: Vec<String>,
}

/// Loads an OBJ file, its MTL libraries and their textures into a scene, re-centred.
pub fn load(path: &Path) -> Result<Scene> {
    load_with_report(path).map(|(scene, _)| scene)
}

/// [`load`], also returning what was skipped or repaired.
pub fn load_with_report(path: &Path) -> Result<(Scene, LoadReport)> {
    let bytes = crate::error::read_file(path)?;
    load_from_bytes(path, &bytes, |p| std::fs::read(p))
}

/// Loads OBJ text that is not (necessarily) a file: `path` names it in errors and is the base
/// that `mtllib` names are resolved against; `resolve` returns the bytes of a companion file
/// (an MTL library or a texture) given its path. For a file embedded in the binary:
///
/// ```
/// use std::path::Path;
/// let obj = "mtllib tri.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl red\nf 1 2 3\n";
/// let (scene, _) = voxlod_scene::obj::load_from_str(Path::new("builtin/tri.obj"), obj, |p| {
///     match p.to_str() {
///         Some("builtin/tri.mtl") => Ok(b"newmtl red\nKd 1 0 0\n".to_vec()),
///         _ => Err(std::io::ErrorKind::NotFound.into()),
///     }
/// })?;
/// assert_eq!(scene.triangle_count(), 1);
/// assert_eq!(scene.materials[0].name, "red");
/// # Ok::<(), voxlod_scene::Error>(())
/// ```
pub fn load_from_str(
    path: &Path,
    text: &str,
    resolve: impl FnMut(&Path) -> io::Result<Vec<u8>>,
) -> Result<(Scene, LoadReport)> {
    load_from_bytes(path, text.as_bytes(), resolve)
}

/// [`load_from_str`] for bytes: UTF-8 text, else read as Latin-1 (UTF-16 is an error).
pub fn load_from_bytes(
    path: &Path,
    bytes: &[u8],
    mut resolve: impl FnMut(&Path) -> io::Result<Vec<u8>>,
) -> Result<(Scene, LoadReport)> {
    let obj_err = |reason: String| Error::Obj { path: path.to_owned(), reason };
    // An error in an MTL library (or a texture it names) also names the OBJ using it.
    let via_obj = |e: Error| match e {
        Error::Obj { path: p, reason } if p != path => {
            Error::Obj { reason: format!("{reason} (library of {})", path.display()), path: p }
        }
        other => other,
    };
    let text = scan::text(path, bytes)?;
    let scan = scan::scan_obj(path, &text)?;
    let mut report = LoadReport {
        points_skipped: scan.points,
        lines_skipped: scan.polylines,
        ..Default::default()
    };

    // MTL libraries, validated and parsed once each. tobj appends a library's materials every
    // time it meets an `mtllib`, in file order; `sources` mirrors that order.
    let dir = path.parent().unwrap_or(Path::new(""));
    let mut libs: HashMap<String, (PathBuf, tobj::MTLLoadResult)> = HashMap::new();
    let mut sources = Vec::new();
    for (line, name) in &scan.mtllibs {
        if !libs.contains_key(name) {
            let mtl_path = dir.join(name.replace('\\', "/"));
            let bytes = resolve(&mtl_path).map_err(|e| {
                obj_err(format!(
                    "line {line}: mtllib '{name}': cannot read {}: {e}",
                    mtl_path.display()
                ))
            })?;
            let mtl_text = scan::text(&mtl_path, &bytes)
                .and_then(|text| scan::scan_mtl(&mtl_path, &text))
                .map_err(via_obj)?;
            let parsed = tobj::load_mtl_buf(&mut mtl_text.as_bytes()).map_err(|e| {
                via_obj(Error::Obj { path: mtl_path.clone(), reason: e.to_string() })
            })?;
            libs.insert(name.clone(), (mtl_path, Ok(parsed)));
        }
        let (mtl_path, parsed) = &libs[name];
        let count = parsed.as_ref().map_or(0, |(m, _)| m.len());
        sources.extend(std::iter::repeat_n(mtl_path.clone(), count));
    }
    let options = tobj::LoadOptions { single_index: true, ..Default::default() };
    let (models, materials) =
        tobj::load_obj_buf(&mut scan.normalized.as_bytes(), &options, |p: &Path| {
            let name = p.to_string_lossy();
            libs.get(name.as_ref()).map_or(Err(tobj::LoadError::OpenFileFailed), |(_, r)| r.clone())
        })
        .map_err(|e| obj_err(e.to_string()))?;
    let materials = materials.map_err(|e| obj_err(format!("MTL libraries: {e}")))?;
    sources.resize(materials.len(), path.to_owned());
    let mut converted = mtl::convert(&materials, &sources, &mut resolve).map_err(via_obj)?;
    let known: BTreeSet<&str> = materials.iter().map(|m| m.name.as_str()).collect();
    let unknown: BTreeSet<&String> =
        scan.usemtls.iter().filter(|u| !known.contains(u.as_str())).collect();
    report.unknown_materials = unknown.into_iter().cloned().collect();

    let stem = path.file_stem().map_or_else(|| "obj".into(), |s| s.to_string_lossy().into_owned());
    let origin = recentring_origin(&models);
    let mut default_material = None;
    let mut meshes = Vec::new();
    for model in &models {
        let material = match model.mesh.material_id {
            Some(i) => i,
            None => *default_material.get_or_insert_with(|| {
                converted.materials.push(Material::default());
                converted.maps.push(None);
                converted.materials.len() - 1
            }),
        };
        let name = format!("{stem}/{}", model.name);
        if let Some(mesh) =
            convert_mesh(&model.mesh, name, material, origin, &converted, &mut report)
                .map_err(obj_err)?
        {
            meshes.push(mesh);
        }
    }
    if meshes.is_empty() {
        return Err(obj_err(format!(
            "no triangles to load ({} points and {} polylines skipped)",
            report.points_skipped, report.lines_skipped
        )));
    }
    if default_material.is_some_and(|d| !meshes.iter().any(|m| m.material == d)) {
        converted.materials.pop();
    }
    let scene = Scene {
        name: stem,
        meshes,
        materials: converted.materials,
        textures: converted.textures,
        origin,
        ..Default::default()
    };
    scene.validate()?;
    Ok((scene, report))
}

/// The scene's origin: [`voxlod_format::origin::recentring_origin`] of the `f64` bounds of every
/// vertex tobj kept (those the faces use), or zero without vertices.
fn recentring_origin(models: &[tobj::Model]) -> DVec3 {
    let mut points = models.iter().flat_map(|m| m.mesh.positions.chunks_exact(3));
    let Some(first) = points.next().map(DVec3::from_slice) else { return DVec3::ZERO };
    let (lo, hi) =
        points.map(DVec3::from_slice).fold((first, first), |(lo, hi), p| (lo.min(p), hi.max(p)));
    voxlod_format::origin::recentring_origin(lo, hi).unwrap_or(DVec3::ZERO)
}

/// Converts one tobj mesh: positions to `f32` relative to `origin` (subtracted in `f64`),
/// triangulates its faces, fixes up normals, maps texture coordinates. `None` when it has no
/// triangles.
fn convert_mesh(
    m: &tobj::Mesh,
    name: String,
    material: usize,
    origin: DVec3,
    converted: &mtl::Converted,
    report: &mut LoadReport,
) -> std::result::Result<Option<Mesh>, String> {
    let positions: Vec<Vec3> =
        m.positions.chunks_exact(3).map(|p| (DVec3::from_slice(p) - origin).as_vec3()).collect();
    let n = positions.len();
    let arities: Vec<usize> = if m.face_arities.is_empty() {
        vec![3; m.indices.len() / 3]
    } else {
        m.face_arities.iter().map(|&a| a as usize).collect()
    };
    let mut indices = Vec::with_capacity(m.indices.len() / 3);
    let mut offset = 0;
    for (face, &k) in arities.iter().enumerate() {
        let corners = m
            .indices
            .get(offset..offset + k)
            .filter(|c| c.iter().all(|&i| (i as usize) < n))
            .ok_or_else(|| format!("object '{name}': face {face} refers to a missing vertex"))?;
        offset += k;
        match k {
            0 | 1 => report.points_skipped += 1,
            2 => report.lines_skipped += 1,
            3 => indices.push([corners[0], corners[1], corners[2]]),
            _ => {
                let points: Vec<Vec3> = corners.iter().map(|&i| positions[i as usize]).collect();
                let t = triangulate::triangulate(&points);
                indices.extend(t.triangles.iter().map(|tri| tri.map(|c| corners[c])));
                report.polygons_triangulated += 1;
                report.collinear_corners_dropped += t.dropped_corners;
            }
        }
    }
    if indices.is_empty() {
        return Ok(None);
    }
    let map = converted.maps.get(material).and_then(Option::as_ref);
    let uvs = if m.texcoords.len() == 2 * n {
        let uv = m.texcoords.chunks_exact(2).map(|t| DVec2::from_slice(t).as_vec2());
        match map {
            Some(map) => uv.map(|t| map.apply(t)).collect(),
            None => uv.map(|t| Vec2::new(t.x, 1.0 - t.y)).collect(),
        }
    } else if m.texcoords.is_empty() && map.is_none() {
        Vec::new()
    } else if map.is_some() {
        return Err(format!(
            "object '{name}': {} of {n} vertices have texture coordinates, but its material \
             is textured: every face corner needs a vt index",
            m.texcoords.len() / 2
        ));
    } else {
        report.partial_uvs_dropped += 1;
        Vec::new()
    };
    let mut mesh = Mesh { name, positions, uvs, indices, material, ..Default::default() };
    mesh.compute_normals();
    if m.normals.len() == 3 * n {
        for (computed, file) in mesh.normals.iter_mut().zip(m.normals.chunks_exact(3)) {
            match DVec3::from_slice(file).as_vec3().try_normalize() {
                Some(unit) => *computed = unit,
                None => report.normals_computed += 1,
            }
        }
    } else {
        report.normals_computed += n;
    }
    Ok(Some(mesh))
}

#[cfg(test)]
mod tests;
