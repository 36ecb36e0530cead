//! MagicaVoxel `.vox` export and import: occupancy with a 255-colour palette, so a voxelized
//! scene opens in MagicaVoxel and the many tools that read its files.
//!
//! The format (ephtracy's "MagicaVoxel .vox File Format" and its scene-graph extension, both in
//! the `ephtracy/voxel-model` repository): the magic `VOX `, a version `i32` (150), then a RIFF
//! style `MAIN` chunk whose children are the chunks below. Every chunk is an id (4 ASCII
//! bytes), its content length `N` (`i32`), its children's length `M` (`i32`), the content and the
//! children; integers are little-endian.
//!
//! | chunk | content |
//! |---|---|
//! | `SIZE` | a model's size x, y, z (`i32`×3, each 1–256); z is up |
//! | `XYZI` | its voxel count `n` (`i32`), then `n` × (x, y, z, colour index) bytes; index 1–255 |
//! | `nTRN` | transform node: id, attributes (DICT), child id, reserved −1, layer id, frame count 1, frame DICT (`_t`: translation `"x y z"` of the model's centre, `_r`: rotation byte) |
//! | `nGRP` | group node: id, attributes, child count, child ids |
//! | `nSHP` | shape node: id, attributes, model count 1, model id, model attributes |
//! | `RGBA` | 256 × RGBA bytes: entry `e` is colour index `e + 1` |
//!
//! A DICT is an `i32` pair count and, per pair, two STRINGs (`i32` length, bytes).
//!
//! # Export
//! - **Axes.** MagicaVoxel is z-up, voxlod y-up; both are right-handed. Voxel `(i, j, k)` of
//!   a grid of dims `(X, Y, Z)` becomes MagicaVoxel voxel `(i, Z − 1 − k, j)` (the usual y-up
//!   to z-up rotation), in a scene of `(X, Z, Y)` voxels centred on the origin in x and y and
//!   standing on z = 0.
//! - **Models.** A model holds at most 256³ voxels, so the scene is cut into 256³ tiles; each
//!   tile holding a voxel becomes one model (`SIZE` + `XYZI`), placed by its own transform node
//!   under one group: root `nTRN` (id 0) → `nGRP` (id 1) → per model `nTRN` (id 2 + 2m) →
//!   `nSHP` (id 3 + 2m). Model sizes are rounded up to even numbers (≤ 256) so that the centre
//!   each translation anchors is a whole voxel and no reader has to guess a rounding.
//! - **Colours.** The palette is built from the voxels' colours by [`Palette::quantize`]
//!   (median cut refined by k-means in sRGB8, see [`palette`]); its error is returned.
//! - **World placement.** The file stores whole voxels only: the grid's origin and voxel size
//!   are not kept.
//!
//! # Refused
//! An empty map (MagicaVoxel needs a model) and output beyond the format's `i32` chunk lengths
//! (over 2³¹ bytes, about 5·10⁸ voxels) are [`Error::Unrepresentable`].
//!
//! # Import
//! [`read`] keeps the models, the palette and the placement of each shape node. Transforms are
//! composed down the scene graph as affine maps (a parent's rotation `Rp` and translation `tp`
//! applied to a child's `R`, `t`: `Rp·R`, `tp + Rp·t`); rotations are MagicaVoxel's signed
//! permutation bytes ([`VoxRotation`]), reflections included; an `_r` that is not one is
//! [`Error::Malformed`], naming the node. A voxel lands where
//! [`rotation::place`] puts it: its centre, relative to the model's pivot `⌊size/2⌋`, rotated
//! and translated. Unknown chunks (materials, layers, cameras) are skipped; models without a
//! scene graph sit centred on the origin; a file without an `RGBA` chunk gets MagicaVoxel's
//! default palette ([`default_palette`]). [`VoxFile::to_brick_map`] gives back voxlod's axes and
//! a brick map of colour indices.

pub mod palette;
mod read;
pub mod rotation;
#[cfg(test)]
mod tests;

use std::collections::HashMap;
use std::path::Path;

use glam::{IVec3, UVec3};

pub use palette::{LLOYD_ITERATIONS, MAX_COLORS, Palette, PaletteError};
pub use read::{decode, default_palette, read};
pub use rotation::VoxRotation;

use crate::{BrickMap, Error, Result};

/// The magic bytes that open every `.vox` file.
pub const MAGIC: [u8; 4] = *b"VOX ";
/// The version written.
pub const VERSION: i32 = 150;
/// Newest version read (MagicaVoxel 0.99.7 writes 200).
pub const MAX_VERSION: i32 = 200;
/// Largest model edge, in voxels.
pub const MODEL_EDGE: u32 = 256;
/// The rotation byte of the identity (`_r`): rows pick x, y, z, all signs positive.
pub const IDENTITY_ROTATION: u8 = 0b0000_0100;

/// One model: its size and its voxels `(x, y, z, colour index)`.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct VoxModel {
    /// Size in voxels (MagicaVoxel axes, z up).
    pub size: UVec3,
    /// Voxels: coordinates inside `size`, colour index 1–255.
    pub voxels: Vec<[u8; 4]>,
}

/// A model placed in the scene by a shape node.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct VoxInstance {
    /// Index into [`VoxFile::models`].
    pub model: u32,
    /// Rotation about the model's pivot (the product of the transform nodes above it).
    pub rotation: VoxRotation,
    /// Translation of the model's pivot (the transform nodes above it, composed).
    pub translation: IVec3,
}

/// A decoded `.vox` file.
#[derive(Clone, Debug, PartialEq)]
pub struct VoxFile {
    /// The version in the header.
    pub version: i32,
    /// The models, in file order.
    pub models: Vec<VoxModel>,
    /// Where each model is shown (one per shape node; one per model without a scene graph).
    pub instances: Vec<VoxInstance>,
    /// RGBA of colour index `i` at `palette[i]`; `palette[0]` (empty) is zero. MagicaVoxel's
    /// default palette ([`default_palette`]) when the file has no `RGBA` chunk.
    pub palette: [[u8; 4]; 256],
}

impl VoxFile {
    /// Every voxel of every instance: its MagicaVoxel world coordinate ([`rotation::place`];
    /// without rotation, the model's minimum corner `translation − ⌊size/2⌋` plus its
    /// coordinate) and colour index.
    pub fn world_voxels(&self) -> impl Iterator<Item = (IVec3, u8)> + '_ {
        self.instances.iter().flat_map(move |inst| {
            let model = &self.models[inst.model as usize];
            model.voxels.iter().map(move |v| {
                let p = UVec3::new(v[0] as u32, v[1] as u32, v[2] as u32);
                (rotation::place(p, model.size, inst.rotation, inst.translation), v[3])
            })
        })
    }

    /// The voxels in voxlod's axes (y up; see the [module docs](self)) as a brick map of colour
    /// indices over their bounding box, with that box's minimum corner in whole voxels.
    ///
    /// Errors: no voxel ([`Error::InvalidGrid`]); two instances setting the same voxel
    /// ([`Error::DuplicateVoxel`]); a box wider than [`GridSpec::MAX_DIM`](crate::GridSpec::MAX_DIM).
    pub fn to_brick_map(&self) -> Result<(IVec3, BrickMap<u8>)> {
        let voxels: Vec<(IVec3, u8)> =
            self.world_voxels().map(|(w, c)| (IVec3::new(w.x, w.z, -1 - w.y), c)).collect();
        let Some(first) = voxels.first() else {
            return Err(Error::InvalidGrid { reason: "the .vox file holds no voxel".into() });
        };
        let (mut lo, mut hi) = (first.0, first.0);
        for (p, _) in &voxels {
            lo = lo.min(*p);
            hi = hi.max(*p);
        }
        let dims = (hi - lo + IVec3::ONE).as_uvec3();
        let map =
            BrickMap::from_voxels(dims, voxels.into_iter().map(|(p, c)| ((p - lo).as_uvec3(), c)))?;
        Ok((lo, map))
    }
}

/// What an export wrote.
#[derive(Clone, Debug, PartialEq)]
pub struct VoxExport {
    /// The file's bytes.
    pub bytes: Vec<u8>,
    /// Models (non-empty 256³ tiles).
    pub models: usize,
    /// The palette and its error.
    pub palette: Palette,
}

/// The `.vox` bytes of `map`'s voxels, coloured by `color` (sRGB8; see the [module docs](self)).
///
/// ```
/// use glam::UVec3;
/// use voxlod_format::{BrickMap, vox};
/// let map = BrickMap::from_voxels(UVec3::new(4, 2, 3), [(UVec3::new(3, 1, 2), [200u8, 30, 30])])
///     .unwrap();
/// let export = vox::encode(&map, |&c| c).unwrap();
/// assert_eq!((export.models, export.palette.colors.as_slice()), (1, &[[200, 30, 30]][..]));
/// let file = vox::decode(&export.bytes, std::path::Path::new("<memory>")).unwrap();
/// let (_, back) = file.to_brick_map().unwrap();
/// assert_eq!(back.len(), 1);
/// assert_eq!(file.palette[1], [200, 30, 30, 255]);
/// ```
pub fn encode<T>(map: &BrickMap<T>, color: impl Fn(&T) -> [u8; 3]) -> Result<VoxExport> {
    if map.is_empty() {
        return Err(Error::Unrepresentable {
            format: "vox",
            what: "an empty grid".into(),
            reason: "a .vox file needs at least one voxel in one model".into(),
        });
    }
    let palette = Palette::quantize(map.values().iter().map(&color));
    let d = map.dims();
    // MagicaVoxel axes: (i, Z − 1 − k, j); the scene is centred in x and y.
    let vdims = UVec3::new(d.x, d.z, d.y);
    let centre = IVec3::new((vdims.x / 2) as i32, (vdims.y / 2) as i32, 0);
    let mut tiles: HashMap<UVec3, Vec<[u8; 4]>> = HashMap::new();
    for (c, value) in map.iter() {
        let g = UVec3::new(c.x, d.z - 1 - c.z, c.y);
        let local = g % MODEL_EDGE;
        let index = palette.index_of(color(value));
        tiles.entry(g / MODEL_EDGE).or_default().push([
            local.x as u8,
            local.y as u8,
            local.z as u8,
            index,
        ]);
    }
    let mut tiles: Vec<(UVec3, Vec<[u8; 4]>)> = tiles.into_iter().collect();
    tiles.sort_unstable_by_key(|(t, _)| (t.z, t.y, t.x));

    let mut models = Vec::new();
    let mut graph = Vec::new();
    let n = tiles.len();
    let group_children: Vec<i32> = (0..n as i32).map(|m| 2 + 2 * m).collect();
    chunk(&mut graph, b"nTRN", &transform_node(0, 1, -1, None));
    chunk(&mut graph, b"nGRP", &group_node(1, &group_children));
    for (m, (tile, mut voxels)) in tiles.into_iter().enumerate() {
        voxels.sort_unstable_by_key(|v| (v[2], v[1], v[0]));
        let origin = tile * MODEL_EDGE;
        let extent = (vdims - origin).min(UVec3::splat(MODEL_EDGE));
        let size = (extent + 1) / 2 * 2;
        let mut content = Vec::with_capacity(12);
        for s in size.to_array() {
            content.extend_from_slice(&(s as i32).to_le_bytes());
        }
        chunk(&mut models, b"SIZE", &content);
        let mut content = Vec::with_capacity(4 + 4 * voxels.len());
        content.extend_from_slice(&(voxels.len() as i32).to_le_bytes());
        for v in &voxels {
            content.extend_from_slice(v);
        }
        chunk(&mut models, b"XYZI", &content);
        let t = origin.as_ivec3() + (size / 2).as_ivec3() - centre;
        let m = m as i32;
        chunk(&mut graph, b"nTRN", &transform_node(2 + 2 * m, 3 + 2 * m, 0, Some(t)));
        chunk(&mut graph, b"nSHP", &shape_node(3 + 2 * m, m));
    }
    let mut rgba = Vec::with_capacity(1024);
    for e in 0..256 {
        match palette.colors.get(e) {
            Some(c) => rgba.extend_from_slice(&[c[0], c[1], c[2], 255]),
            None => rgba.extend_from_slice(&[0; 4]),
        }
    }
    let children = models.len() as u64 + graph.len() as u64 + 12 + rgba.len() as u64;
    if children > i32::MAX as u64 {
        return Err(Error::Unrepresentable {
            format: "vox",
            what: format!("{} voxels in {n} models ({children} bytes of chunks)", map.len()),
            reason: "the MAIN chunk's length is an i32: at most 2³¹ − 1 bytes".into(),
        });
    }
    let mut bytes = Vec::with_capacity(20 + children as usize);
    bytes.extend_from_slice(&MAGIC);
    bytes.extend_from_slice(&VERSION.to_le_bytes());
    bytes.extend_from_slice(b"MAIN");
    bytes.extend_from_slice(&0i32.to_le_bytes());
    bytes.extend_from_slice(&(children as i32).to_le_bytes());
    bytes.extend_from_slice(&models);
    bytes.extend_from_slice(&graph);
    chunk(&mut bytes, b"RGBA", &rgba);
    Ok(VoxExport { bytes, models: n, palette })
}

/// Writes `map`'s voxels as a `.vox` file, atomically (see [`encode`]); returns the export
/// (with the palette's error).
pub fn write<T>(
    path: impl AsRef<Path>,
    map: &BrickMap<T>,
    color: impl Fn(&T) -> [u8; 3],
) -> Result<VoxExport> {
    let export = encode(map, color)?;
    crate::io::write_bytes_atomic(path.as_ref(), &export.bytes)?;
    Ok(export)
}

fn chunk(out: &mut Vec<u8>, id: &[u8; 4], content: &[u8]) {
    out.extend_from_slice(id);
    out.extend_from_slice(&(content.len() as i32).to_le_bytes());
    out.extend_from_slice(&0i32.to_le_bytes());
    out.extend_from_slice(content);
}

fn string(out: &mut Vec<u8>, s: &str) {
    out.extend_from_slice(&(s.len() as i32).to_le_bytes());
    out.extend_from_slice(s.as_bytes());
}

fn dict(out: &mut Vec<u8>, pairs: &[(&str, &str)]) {
    out.extend_from_slice(&(pairs.len() as i32).to_le_bytes());
    for (k, v) in pairs {
        string(out, k);
        string(out, v);
    }
}

fn transform_node(id: i32, child: i32, layer: i32, t: Option<IVec3>) -> Vec<u8> {
    let mut c = Vec::new();
    c.extend_from_slice(&id.to_le_bytes());
    dict(&mut c, &[]);
    for x in [child, -1, layer, 1] {
        c.extend_from_slice(&x.to_le_bytes());
    }
    match t {
        Some(t) => dict(&mut c, &[("_t", &format!("{} {} {}", t.x, t.y, t.z))]),
        None => dict(&mut c, &[]),
    }
    c
}

fn group_node(id: i32, children: &[i32]) -> Vec<u8> {
    let mut c = Vec::new();
    c.extend_from_slice(&id.to_le_bytes());
    dict(&mut c, &[]);
    c.extend_from_slice(&(children.len() as i32).to_le_bytes());
    for x in children {
        c.extend_from_slice(&x.to_le_bytes());
    }
    c
}

fn shape_node(id: i32, model: i32) -> Vec<u8> {
    let mut c = Vec::new();
    c.extend_from_slice(&id.to_le_bytes());
    dict(&mut c, &[]);
    c.extend_from_slice(&1i32.to_le_bytes());
    c.extend_from_slice(&model.to_le_bytes());
    dict(&mut c, &[]);
    c
}
