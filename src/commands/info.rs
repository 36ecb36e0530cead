//! `voxlod info`: describe a voxel file, a scene file or an image.

use anyhow::{Context, Result, bail};
use serde_json::json;
use voxlod::format::{binvox, vxl};
use voxlod::scene::{Scene, Srgb8Image};

use super::print_json;
use crate::cli::InfoArgs;

/// Prints what a file holds.
pub fn info(args: InfoArgs) -> Result<()> {
    let path = &args.file;
    let ext = path.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase);
    let value = match ext.as_deref() {
        Some("vxl") => {
            let i = vxl::read_info(path)?;
            json!({
                "kind": "vxl",
                "version": i.version,
                "bytes": i.file_len,
                "dims": i.grid.dims.to_array(),
                "origin": i.grid.origin.to_array(),
                "voxel_size": i.grid.voxel_size,
                "record": vxl::tag_name(i.record_tag),
                "record_bytes": i.record_size,
                "bricks": i.brick_count,
                "voxels": i.voxel_count,
                "checksum": format!("{:#010x}", i.checksum),
                "checksum_ok": i.checksum_ok,
                "meta": i.meta.iter().map(|(k, v)| (k.clone(), json!(v))).collect::<serde_json::Map<_, _>>(),
            })
        }
        Some("binvox") => {
            let i = binvox::read_info(path)?;
            json!({
                "kind": "binvox",
                "version": i.header.version,
                "dim": i.header.dim,
                "translate": i.header.translate.to_array(),
                "scale": i.header.scale,
                "voxel_size": i.grid.voxel_size,
                "voxels": i.occupied,
            })
        }
        Some("obj" | "gltf" | "glb") => {
            let s = Scene::load(path).with_context(|| format!("loading {}", path.display()))?;
            let (lo, hi) = s.world_bounds()?;
            json!({
                "kind": "scene",
                "meshes": s.meshes.len(),
                "triangles": s.triangle_count(),
                "vertices": s.meshes.iter().map(|m| m.positions.len()).sum::<usize>(),
                "materials": s.materials.len(),
                "textures": s.textures.len(),
                "bounds_min": lo.to_array(),
                "bounds_max": hi.to_array(),
                "origin": s.origin.to_array(),
                "camera": s.camera.is_some(),
                "lights": s.lights.len(),
                "nodes": s.nodes.len(),
                "skins": s.skins.len(),
                "animations": s.animations.len(),
            })
        }
        Some("png" | "jpg" | "jpeg") => {
            let img = Srgb8Image::load(path)?;
            json!({ "kind": "image", "width": img.width, "height": img.height })
        }
        _ => bail!(
            "{}: unknown file type (expected .vxl, .binvox, .obj, .gltf, .glb, .png or .jpg)",
            path.display()
        ),
    };
    if args.json {
        return print_json("info", &value);
    }
    println!("{}", path.display());
    if let Some(map) = value.as_object() {
        for (k, v) in map {
            println!("  {k:<12} {v}");
        }
    }
    if value["checksum_ok"] == json!(false) {
        bail!("{}: the checksum does not match: the file is corrupted", path.display());
    }
    Ok(())
}
