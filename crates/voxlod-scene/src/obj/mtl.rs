//! MTL materials to [`Material`]s, and `map_Kd` diffuse textures (with their `-clamp`, `-o` and
//! `-s` options) to [`Texture`]s.
//!
//! Colour conventions, as most offline renderers read MTL (pbrt, Mitsuba, Blender's importer):
//! `Kd` and `Ks` are **linear** RGB reflectances, used as given; `map_Kd` images are
//! **sRGB**-encoded and multiply `Kd` (the MTL specification's rule). A texture without `Kd`
//! gets `Kd = 1`, so that the texture is not darkened; a material with neither gets 0.8.

use std::collections::HashMap;
use std::io;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use glam::{DVec3, Vec2, Vec3};

use crate::{AlphaMode, Error, Material, Result, Sampler, Texture, TextureRef, WrapMode};

/// A `map_Kd` statement: file name and the options voxlod honours.
#[derive(Clone, Debug, PartialEq)]
pub(super) struct TextureMap {
    /// The file name as written, relative to the MTL's directory.
    pub file: String,
    /// `-clamp on`: clamp instead of repeating.
    pub clamp: bool,
    /// `-o u v`: added to texture coordinates after scaling.
    pub offset: Vec2,
    /// `-s u v`: multiplies texture coordinates.
    pub scale: Vec2,
}

impl TextureMap {
    /// Maps an OBJ texture coordinate (origin bottom-left) to voxlod's convention (origin
    /// top-left, v down), applying `-s` and `-o` first.
    pub fn apply(&self, uv: Vec2) -> Vec2 {
        let t = uv * self.scale + self.offset;
        Vec2::new(t.x, 1.0 - t.y)
    }
}

/// Parses the value of a `map_Kd` statement: options, then the file name (which may contain
/// spaces). Unknown options are skipped with their documented number of arguments.
pub(super) fn parse_map(value: &str) -> std::result::Result<TextureMap, String> {
    let mut words = value.split_whitespace().peekable();
    let mut map =
        TextureMap { file: String::new(), clamp: false, offset: Vec2::ZERO, scale: Vec2::ONE };
    while let Some(&w) = words.peek() {
        let args = match w {
            "-clamp" | "-blendu" | "-blendv" | "-bm" | "-boost" | "-cc" | "-imfchan"
            | "-texres" | "-type" => 1,
            "-mm" => 2,
            "-o" | "-s" | "-t" => 3,
            _ => break,
        };
        words.next();
        let mut nums = Vec::new();
        for k in 0..args {
            let Some(&a) = words.peek() else { break };
            match a.parse::<f32>() {
                Ok(x) if x.is_finite() => nums.push(x),
                Ok(_) => return Err(format!("option {w}: {a} is not finite")),
                Err(_) if w == "-clamp" => {
                    map.clamp = a == "on";
                    if a != "on" && a != "off" {
                        return Err(format!("option -clamp {a}: expected on or off"));
                    }
                }
                Err(_) if k > 0 && matches!(w, "-o" | "-s" | "-t") => break,
                Err(_) if matches!(w, "-blendu" | "-blendv" | "-cc" | "-imfchan" | "-type") => {}
                Err(_) => return Err(format!("option {w}: '{a}' is not a number")),
            }
            words.next();
        }
        let v = |d: f32| {
            Vec2::new(nums.first().copied().unwrap_or(d), nums.get(1).copied().unwrap_or(d))
        };
        match w {
            "-o" => map.offset = v(0.0),
            "-s" => map.scale = v(1.0),
            _ => {}
        }
    }
    map.file = words.collect::<Vec<_>>().join(" ").replace('\\', "/");
    if map.file.is_empty() {
        return Err("no file name".into());
    }
    Ok(map)
}

/// MTL materials converted to voxlod's.
pub(super) struct Converted {
    /// One material per MTL material, in tobj's order.
    pub materials: Vec<Material>,
    /// The diffuse textures, each decoded once per (file, clamp) pair.
    pub textures: Vec<Texture>,
    /// Each material's `map_Kd` statement, which maps its meshes' texture coordinates.
    pub maps: Vec<Option<TextureMap>>,
}

/// Converts the materials of one or more MTL files, loading diffuse textures through
/// `resolve`. `sources[i]` is the MTL file material `i` came from: texture paths are relative
/// to its directory, and errors name it.
pub(super) fn convert(
    materials: &[tobj::Material],
    sources: &[PathBuf],
    resolve: &mut dyn FnMut(&Path) -> io::Result<Vec<u8>>,
) -> Result<Converted> {
    let mut out = Converted { materials: Vec::new(), textures: Vec::new(), maps: Vec::new() };
    let mut cache: HashMap<(PathBuf, bool), usize> = HashMap::new();
    for (m, mtl) in materials.iter().zip(sources) {
        let err = |reason: String| Error::Obj {
            path: mtl.clone(),
            reason: format!("material '{}': {reason}", m.name),
        };
        let map = m
            .diffuse_texture
            .as_deref()
            .map(|v| parse_map(v).map_err(|e| err(format!("map_Kd '{v}': {e}"))))
            .transpose()?;
        let texture = match &map {
            None => None,
            Some(map) => {
                let file = mtl.parent().unwrap_or(Path::new("")).join(&map.file);
                let key = (file.clone(), map.clamp);
                let index = match cache.get(&key) {
                    Some(&i) => i,
                    None => {
                        let bytes = resolve(&file)
                            .map_err(|e| err(format!("map_Kd texture {}: {e}", file.display())))?;
                        let texture = decode_texture(&bytes, &map.file, map.clamp)
                            .map_err(|e| err(format!("map_Kd texture {}: {e}", file.display())))?;
                        out.textures.push(texture);
                        cache.insert(key, out.textures.len() - 1);
                        out.textures.len() - 1
                    }
                };
                Some(TextureRef { texture: index })
            }
        };
        let default_kd = if texture.is_some() { 1.0 } else { 0.8 };
        // tobj reads MTL values in f64 (the loader enables its `use_f64` for positions).
        let vec3 = |v: [f64; 3]| DVec3::from_array(v).as_vec3();
        let kd = m.diffuse.map_or(Vec3::splat(default_kd), vec3);
        let tr = m.unknown_param.get("Tr").and_then(|t| t.trim().parse::<f64>().ok());
        let alpha = m.dissolve.or(tr.map(|t| 1.0 - t)).unwrap_or(1.0).clamp(0.0, 1.0) as f32;
        let lit = !matches!(m.illumination_model, Some(0 | 1));
        let specular = if lit { m.specular.map_or(Vec3::ZERO, vec3) } else { Vec3::ZERO };
        out.materials.push(Material {
            name: m.name.clone(),
            base_color: kd.max(Vec3::ZERO).extend(alpha),
            base_color_texture: texture,
            specular: specular.max(Vec3::ZERO),
            shininess: m.shininess.unwrap_or(0.0).max(0.0) as f32,
            double_sided: false,
            alpha_mode: if alpha < 1.0 { AlphaMode::Blend } else { AlphaMode::Opaque },
        });
        out.maps.push(map);
    }
    Ok(out)
}

/// Decodes a PNG or JPEG into an sRGB texture.
pub(super) fn decode_texture(
    bytes: &[u8],
    name: &str,
    clamp: bool,
) -> std::result::Result<Texture, String> {
    let img = image::load_from_memory(bytes).map_err(|e| e.to_string())?.into_rgba8();
    let (width, height) = img.dimensions();
    let texels: Vec<[u8; 4]> =
        img.into_raw().chunks_exact(4).map(|c| [c[0], c[1], c[2], c[3]]).collect();
    let wrap = if clamp { WrapMode::ClampToEdge } else { WrapMode::Repeat };
    Ok(Texture {
        name: name.to_owned(),
        width,
        height,
        texels: Arc::from(texels),
        srgb: true,
        sampler: Sampler { wrap_u: wrap, wrap_v: wrap },
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn map_options() {
        let m = parse_map("-clamp on -s 2 3 1 -o 0.5 -blendu off my tex.png").unwrap();
        assert_eq!(m.file, "my tex.png");
        assert!(m.clamp);
        assert_eq!((m.scale, m.offset), (Vec2::new(2.0, 3.0), Vec2::new(0.5, 0.0)));
        // (0.25, 0.25) scaled, offset, then v flipped.
        assert_eq!(m.apply(Vec2::splat(0.25)), Vec2::new(1.0, 0.25));
        assert_eq!(parse_map("tex\\wood.jpg").unwrap().file, "tex/wood.jpg");
        assert!(parse_map("-s 1 1 1").unwrap_err().contains("no file name"));
        assert!(parse_map("-clamp maybe a.png").unwrap_err().contains("-clamp maybe"));
        assert!(parse_map("-mm x 1 a.png").unwrap_err().contains("'x' is not a number"));
    }

    fn material(f: impl FnOnce(&mut tobj::Material)) -> tobj::Material {
        let mut m = tobj::Material { name: "m".into(), ..Default::default() };
        f(&mut m);
        m
    }

    #[test]
    fn colours_alpha_and_specular() {
        let mats = [
            material(|m| {
                m.diffuse = Some([0.2, 0.4, 0.6]);
                m.specular = Some([0.5; 3]);
                m.shininess = Some(64.0);
                m.dissolve = Some(0.25);
            }),
            material(|m| {
                m.specular = Some([0.5; 3]);
                m.illumination_model = Some(1);
                m.unknown_param.insert("Tr".into(), "0.75".into());
            }),
        ];
        let src = vec![PathBuf::from("a.mtl"); 2];
        let c = convert(&mats, &src, &mut |_| unreachable!()).unwrap();
        let [a, b] = &c.materials[..] else { panic!() };
        assert_eq!(a.base_color, glam::Vec4::new(0.2, 0.4, 0.6, 0.25));
        assert_eq!(
            (a.specular, a.shininess, a.alpha_mode),
            (Vec3::splat(0.5), 64.0, AlphaMode::Blend)
        );
        // illum 1 means no highlight; Tr is 1 − d; no Kd and no texture gives 0.8.
        assert_eq!(b.specular, Vec3::ZERO);
        assert_eq!(b.base_color, glam::Vec4::new(0.8, 0.8, 0.8, 0.25));
    }

    #[test]
    fn missing_or_broken_texture_names_mtl_and_texture() {
        let mats = [material(|m| m.diffuse_texture = Some("-clamp on wood.png".into()))];
        let src = [PathBuf::from("dir/a.mtl")];
        let err = convert(&mats, &src, &mut |_| Err(io::ErrorKind::NotFound.into()))
            .err()
            .unwrap()
            .to_string();
        assert!(
            err.contains("dir/a.mtl") && err.contains("dir/wood.png") && err.contains("'m'"),
            "{err}"
        );
        let err =
            convert(&mats, &src, &mut |_| Ok(b"not an image".to_vec())).err().unwrap().to_string();
        assert!(err.contains("dir/a.mtl") && err.contains("wood.png"), "{err}");
    }
}
