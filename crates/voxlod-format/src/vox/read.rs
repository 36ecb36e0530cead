//! Reading `.vox`: the chunks, the models, the palette and the scene graph, each checked as it
//! is read.

use std::collections::HashMap;
use std::path::Path;

use glam::{IVec3, UVec3};

use super::{MAGIC, MAX_VERSION, MODEL_EDGE, VoxFile, VoxInstance, VoxModel, VoxRotation};
use crate::{Error, Result};

/// Deepest scene graph followed (MagicaVoxel nests groups a few levels deep).
const MAX_GRAPH_DEPTH: usize = 64;
/// Most shape instances a scene graph may place (groups may share children, so a small file
/// could otherwise name exponentially many).
const MAX_INSTANCES: usize = 1 << 20;
/// Largest translation component kept (composed down the graph): 2³⁰ voxels, far beyond any
/// grid voxlod builds, so that placing a voxel never overflows `i32`.
const MAX_TRANSLATION: i64 = 1 << 30;

/// A scene-graph node.
enum Node {
    Transform { child: i32, rotation: VoxRotation, translation: IVec3 },
    Group { children: Vec<i32> },
    Shape { models: Vec<i32> },
}

/// A bounds-checked little-endian cursor over one chunk's content.
struct Cursor<'a> {
    bytes: &'a [u8],
    pos: usize,
    end: usize,
    path: &'a Path,
}

impl Cursor<'_> {
    fn bad(&self, at: usize, reason: impl Into<String>) -> Error {
        malformed(self.path, at, reason)
    }
    fn take(&mut self, n: usize, what: &str) -> Result<&[u8]> {
        if self.end - self.pos < n {
            return Err(self.bad(self.pos, format!("{what} runs past the end of its chunk")));
        }
        let s = &self.bytes[self.pos..self.pos + n];
        self.pos += n;
        Ok(s)
    }
    fn i32(&mut self, what: &str) -> Result<i32> {
        let b = self.take(4, what)?;
        Ok(i32::from_le_bytes([b[0], b[1], b[2], b[3]]))
    }
    fn count(&mut self, what: &str, item_bytes: usize) -> Result<usize> {
        let at = self.pos;
        let n = self.i32(what)?;
        if n < 0 || (n as usize).saturating_mul(item_bytes) > self.end - self.pos {
            return Err(self.bad(at, format!("{what} {n} does not fit in its chunk")));
        }
        Ok(n as usize)
    }
    fn string(&mut self) -> Result<String> {
        let n = self.count("string length", 1)?;
        let at = self.pos;
        let b = self.take(n, "string")?;
        String::from_utf8(b.to_vec()).map_err(|_| self.bad(at, "a string is not UTF-8"))
    }
    fn dict(&mut self) -> Result<Vec<(String, String)>> {
        let n = self.count("dictionary size", 8)?;
        (0..n).map(|_| Ok((self.string()?, self.string()?))).collect()
    }
}

/// Decodes `.vox` bytes; `path` only names the source in errors.
pub fn decode(bytes: &[u8], path: &Path) -> Result<VoxFile> {
    let bad = |at: usize, reason: String| malformed(path, at, reason);
    if bytes.len() < 20 {
        return Err(bad(bytes.len(), format!("truncated: {} bytes", bytes.len())));
    }
    if bytes[0..4] != MAGIC {
        return Err(bad(0, "not a MagicaVoxel file: it does not start with `VOX `".into()));
    }
    let le = |o: usize| i32::from_le_bytes([bytes[o], bytes[o + 1], bytes[o + 2], bytes[o + 3]]);
    let version = le(4);
    if version > MAX_VERSION {
        return Err(Error::UnsupportedVersion {
            path: path.to_owned(),
            format: "vox",
            found: version as u32,
            supported: MAX_VERSION as u32,
        });
    }
    if version < 1 {
        return Err(bad(4, format!("version {version}")));
    }
    if &bytes[8..12] != b"MAIN" {
        return Err(bad(8, "the first chunk is not MAIN".into()));
    }
    let (n, m) = (le(12), le(16));
    if n < 0 || m < 0 || 20 + n as u64 + m as u64 != bytes.len() as u64 {
        return Err(bad(
            12,
            format!(
                "MAIN holds {n} + {m} bytes but the file has {} after its header",
                bytes.len() - 20
            ),
        ));
    }
    let mut pos = 20 + n as usize;
    let mut sizes: Vec<(usize, UVec3)> = Vec::new();
    let mut models = Vec::new();
    let mut palette = None;
    let mut nodes: HashMap<i32, (usize, Node)> = HashMap::new();
    while pos < bytes.len() {
        if bytes.len() - pos < 12 {
            return Err(bad(pos, "truncated chunk header".into()));
        }
        let id: [u8; 4] = bytes[pos..pos + 4].try_into().expect("4 bytes");
        let (n, m) = (le(pos + 4), le(pos + 8));
        let start = pos + 12;
        if n < 0 || m < 0 || (n as u64 + m as u64) > (bytes.len() - start) as u64 {
            return Err(bad(pos + 4, format!("chunk {} overruns the file", show(&id))));
        }
        let end = start + n as usize;
        let mut c = Cursor { bytes, pos: start, end, path };
        match &id {
            b"SIZE" => {
                let mut s = [0u32; 3];
                for (axis, v) in s.iter_mut().enumerate() {
                    let x = c.i32("model size")?;
                    if !(1..=MODEL_EDGE as i32).contains(&x) {
                        return Err(bad(start + 4 * axis, format!("model size {x} (1 to 256)")));
                    }
                    *v = x as u32;
                }
                if sizes.len() != models.len() {
                    return Err(bad(pos, "a SIZE chunk without its XYZI chunk".into()));
                }
                sizes.push((pos, UVec3::from_array(s)));
            }
            b"XYZI" => {
                let Some(&(_, size)) = sizes.get(models.len()) else {
                    return Err(bad(pos, "an XYZI chunk without a SIZE chunk before it".into()));
                };
                let count = c.count("voxel count", 4)?;
                let mut voxels = Vec::with_capacity(count);
                for i in 0..count {
                    let at = c.pos;
                    let v: [u8; 4] = c.take(4, "voxel")?.try_into().expect("4 bytes");
                    if UVec3::new(v[0] as u32, v[1] as u32, v[2] as u32).cmpge(size).any() {
                        return Err(bad(
                            at,
                            format!("voxel {i} at {:?} outside a model of {size}", &v[..3]),
                        ));
                    }
                    if v[3] == 0 {
                        return Err(bad(at + 3, format!("voxel {i} has colour index 0 (empty)")));
                    }
                    voxels.push(v);
                }
                models.push(VoxModel { size, voxels });
            }
            b"RGBA" => {
                let b = c.take(1024, "palette")?;
                let mut p = [[0u8; 4]; 256];
                for e in 0..255 {
                    p[e + 1].copy_from_slice(&b[4 * e..4 * e + 4]);
                }
                palette = Some(p);
            }
            b"nTRN" => {
                let node = c.i32("node id")?;
                c.dict()?;
                let child = c.i32("child id")?;
                let _reserved = c.i32("reserved id")?;
                let _layer = c.i32("layer id")?;
                let frames = c.count("frame count", 4)?;
                let mut translation = IVec3::ZERO;
                let mut rotation = VoxRotation::IDENTITY;
                // Animation frames after the first are not shown by a still scene: skipped.
                for f in 0..frames {
                    let at = c.pos;
                    for (key, value) in c.dict()? {
                        match key.as_str() {
                            "_t" if f == 0 => {
                                translation = parse_translation(&value).ok_or_else(|| {
                                    bad(at, format!("translation {value:?} of node {node}"))
                                })?
                            }
                            "_r" if f == 0 => {
                                rotation = value
                                    .trim()
                                    .parse::<u8>()
                                    .ok()
                                    .and_then(VoxRotation::from_byte)
                                    .ok_or_else(|| {
                                        bad(
                                            at,
                                            format!(
                                                "rotation {value:?} of node {node} is not a \
                                                 signed permutation byte"
                                            ),
                                        )
                                    })?
                            }
                            _ => {}
                        }
                    }
                }
                let transform = Node::Transform { child, rotation, translation };
                insert(&mut nodes, node, pos, transform, path)?;
            }
            b"nGRP" => {
                let node = c.i32("node id")?;
                c.dict()?;
                let n = c.count("child count", 4)?;
                let children = (0..n).map(|_| c.i32("child id")).collect::<Result<_>>()?;
                insert(&mut nodes, node, pos, Node::Group { children }, path)?;
            }
            b"nSHP" => {
                let node = c.i32("node id")?;
                c.dict()?;
                let n = c.count("model count", 8)?;
                let mut ids = Vec::with_capacity(n);
                for _ in 0..n {
                    ids.push(c.i32("model id")?);
                    c.dict()?;
                }
                insert(&mut nodes, node, pos, Node::Shape { models: ids }, path)?;
            }
            _ => {} // PACK, MATL, MATT, LAYR, rOBJ, rCAM, NOTE, IMAP, ...: not needed
        }
        pos = end + m as usize;
    }
    if sizes.len() != models.len() {
        return Err(bad(sizes[models.len()].0, "a SIZE chunk without its XYZI chunk".into()));
    }
    let instances = if nodes.is_empty() {
        (0..models.len() as u32)
            .map(|model| VoxInstance {
                model,
                rotation: VoxRotation::IDENTITY,
                translation: IVec3::ZERO,
            })
            .collect()
    } else {
        let mut out = Vec::new();
        let root = Placement { rotation: VoxRotation::IDENTITY, translation: IVec3::ZERO };
        walk(&nodes, 0, root, 0, models.len(), &mut out, path)?;
        out
    };
    let palette = palette.unwrap_or_else(default_palette);
    Ok(VoxFile { version, models, instances, palette })
}

/// Reads a `.vox` file (see [`decode`]).
pub fn read(path: impl AsRef<Path>) -> Result<VoxFile> {
    let path = path.as_ref();
    decode(&crate::io::read_bytes(path)?, path)
}

fn malformed(path: &Path, offset: usize, reason: impl Into<String>) -> Error {
    Error::Malformed {
        path: path.to_owned(),
        format: "vox",
        offset: offset as u64,
        reason: reason.into(),
    }
}

fn show(id: &[u8; 4]) -> String {
    id.iter().map(|&b| if b.is_ascii_graphic() || b == b' ' { b as char } else { '?' }).collect()
}

/// `"x y z"`, each within ±[`MAX_TRANSLATION`].
fn parse_translation(s: &str) -> Option<IVec3> {
    let v: Vec<i32> = s.split_ascii_whitespace().map(|x| x.parse().ok()).collect::<Option<_>>()?;
    let fits = v.iter().all(|c| (*c as i64).abs() <= MAX_TRANSLATION);
    (v.len() == 3 && fits).then(|| IVec3::new(v[0], v[1], v[2]))
}

fn insert(
    nodes: &mut HashMap<i32, (usize, Node)>,
    id: i32,
    at: usize,
    node: Node,
    path: &Path,
) -> Result<()> {
    if nodes.insert(id, (at, node)).is_some() {
        return Err(malformed(path, at, format!("scene-graph node {id} defined twice")));
    }
    Ok(())
}

/// MagicaVoxel's default palette, which applies when a file has no `RGBA` chunk (entry 0,
/// empty, is zero). As the format's specification lists it: entries 1–215 are the 6×6×6 cube of
/// the levels FF, CC, 99, 66, 33, 00 without black, blue changing fastest, then red; then ten
/// shades each of red, green, blue and grey (EE, DD, BB, AA, 88, 77, 55, 44, 22, 11). All
/// opaque.
///
/// ```
/// let p = voxlod_format::vox::default_palette();
/// assert_eq!((p[0], p[1], p[2]), ([0; 4], [255, 255, 255, 255], [255, 255, 204, 255]));
/// assert_eq!(p[255], [0x11, 0x11, 0x11, 255]);
/// ```
pub fn default_palette() -> [[u8; 4]; 256] {
    const CUBE: [u8; 6] = [0xFF, 0xCC, 0x99, 0x66, 0x33, 0x00];
    const RAMP: [u8; 10] = [0xEE, 0xDD, 0xBB, 0xAA, 0x88, 0x77, 0x55, 0x44, 0x22, 0x11];
    let mut p = [[0u8; 4]; 256];
    let mut i = 1;
    for r in CUBE {
        for g in CUBE {
            for b in CUBE {
                if (r, g, b) != (0, 0, 0) {
                    p[i] = [r, g, b, 255];
                    i += 1;
                }
            }
        }
    }
    for channel in [Some(0), Some(1), Some(2), None] {
        for v in RAMP {
            p[i] = match channel {
                Some(c) => {
                    let mut rgba = [0, 0, 0, 255];
                    rgba[c] = v;
                    rgba
                }
                None => [v, v, v, 255],
            };
            i += 1;
        }
    }
    debug_assert_eq!(i, 256);
    p
}

/// The rotation and translation composed from the root down to a node.
#[derive(Clone, Copy)]
struct Placement {
    rotation: VoxRotation,
    translation: IVec3,
}

fn walk(
    nodes: &HashMap<i32, (usize, Node)>,
    id: i32,
    t: Placement,
    depth: usize,
    model_count: usize,
    out: &mut Vec<VoxInstance>,
    path: &Path,
) -> Result<()> {
    let Some((at, node)) = nodes.get(&id) else {
        return Err(malformed(path, 8, format!("scene graph refers to missing node {id}")));
    };
    if depth > MAX_GRAPH_DEPTH {
        return Err(malformed(
            path,
            *at,
            format!("scene graph deeper than {MAX_GRAPH_DEPTH} (a cycle?)"),
        ));
    }
    match node {
        Node::Transform { child, rotation, translation } => {
            // The parent's affine map applied to this node's: R = Rp·R, t = tp + Rp·t.
            let sum = t.translation.as_i64vec3() + t.rotation.apply(*translation).as_i64vec3();
            if sum.abs().max_element() > MAX_TRANSLATION {
                return Err(malformed(
                    path,
                    *at,
                    format!("translation {sum} at node {id} is beyond ±2³⁰ voxels"),
                ));
            }
            let placed = Placement {
                rotation: t.rotation.then_inner(*rotation),
                translation: sum.as_ivec3(),
            };
            walk(nodes, *child, placed, depth + 1, model_count, out, path)
        }
        Node::Group { children } => {
            for &c in children {
                walk(nodes, c, t, depth + 1, model_count, out, path)?;
            }
            Ok(())
        }
        Node::Shape { models } => {
            for &m in models {
                if m < 0 || m as usize >= model_count {
                    return Err(malformed(
                        path,
                        *at,
                        format!("shape node {id} refers to model {m} of {model_count}"),
                    ));
                }
                if out.len() >= MAX_INSTANCES {
                    return Err(malformed(path, *at, format!("more than {MAX_INSTANCES} shapes")));
                }
                out.push(VoxInstance {
                    model: m as u32,
                    rotation: t.rotation,
                    translation: t.translation,
                });
            }
            Ok(())
        }
    }
}
