//! Reading `.vox`: the chunks, the models, the palette and the scene graph, each checked as it
//! is read.

use std::collections::HashMap;
use std::path::Path;

use glam::{IVec3, UVec3};

use super::{IDENTITY_ROTATION, MAGIC, MAX_VERSION, MODEL_EDGE, VoxFile, VoxInstance, VoxModel};
use crate::{Error, Result};

/// Deepest scene graph followed (MagicaVoxel nests groups a few levels deep).
const MAX_GRAPH_DEPTH: usize = 64;
/// Most shape instances a scene graph may place (groups may share children, so a small file
/// could otherwise name exponentially many).
const MAX_INSTANCES: usize = 1 << 20;

/// A scene-graph node.
enum Node {
    Transform { child: i32, translation: IVec3 },
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
    let mut palette = [[0u8; 4]; 256];
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
                for e in 0..255 {
                    palette[e + 1].copy_from_slice(&b[4 * e..4 * e + 4]);
                }
            }
            b"nTRN" => {
                let node = c.i32("node id")?;
                c.dict()?;
                let child = c.i32("child id")?;
                let _reserved = c.i32("reserved id")?;
                let _layer = c.i32("layer id")?;
                let frames = c.count("frame count", 4)?;
                let mut translation = IVec3::ZERO;
                for f in 0..frames {
                    let at = c.pos;
                    for (key, value) in c.dict()? {
                        match key.as_str() {
                            "_t" if f == 0 => {
                                translation = parse_translation(&value)
                                    .ok_or_else(|| bad(at, format!("translation {value:?}")))?
                            }
                            "_r" if f == 0
                                && value.trim().parse::<u8>().ok() != Some(IDENTITY_ROTATION) =>
                            {
                                return Err(Error::Unsupported {
                                    path: path.to_owned(),
                                    format: "vox",
                                    offset: at as u64,
                                    feature: format!("rotation {value:?} of transform node {node}"),
                                });
                            }
                            _ => {}
                        }
                    }
                }
                insert(&mut nodes, node, pos, Node::Transform { child, translation }, path)?;
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
            .map(|model| VoxInstance { model, translation: IVec3::ZERO })
            .collect()
    } else {
        let mut out = Vec::new();
        walk(&nodes, 0, IVec3::ZERO, 0, models.len(), &mut out, path)?;
        out
    };
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

fn parse_translation(s: &str) -> Option<IVec3> {
    let v: Vec<i32> = s.split_ascii_whitespace().map(|x| x.parse().ok()).collect::<Option<_>>()?;
    (v.len() == 3).then(|| IVec3::new(v[0], v[1], v[2]))
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

fn walk(
    nodes: &HashMap<i32, (usize, Node)>,
    id: i32,
    t: IVec3,
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
        Node::Transform { child, translation } => {
            let sum = t.as_i64vec3() + translation.as_i64vec3();
            if sum.abs().max_element() > i32::MAX as i64 {
                return Err(malformed(
                    path,
                    *at,
                    format!("translations overflow i32 at node {id}"),
                ));
            }
            let sum = sum.as_ivec3();
            walk(nodes, *child, sum, depth + 1, model_count, out, path)
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
                out.push(VoxInstance { model: m as u32, translation: t });
            }
            Ok(())
        }
    }
}
