//! [`VoxelCache`]: one object's voxels in its own space, built once (module rules in
//! [`super`]), and its `.vxl` form.
//!
//! # File
//! A cache is a `.vxl` file (voxlod-format's container, unchanged): the object grid, and one
//! record per voxel in Morton order — `AverageRecord` (tag `AVG1`) for a rigid object,
//! `SkinnedRecord` (tag `SKV1`) for a skinned one — with these metadata keys:
//! `voxlod.cache` (the cache layout's version, [`CACHE_VERSION`]), `object` (name), `scale`
//! (the object-to-world scale, `f64` in Rust's shortest round-trip form), and for skinned
//! objects `skin` (index of the scene's skin) and `joints` (its joint count). Reading checks
//! the version, every key, the grid's size limit and every voxel's skin (weights summing to
//! 255, joints below the count), each failure an [`Error::InvalidCache`] naming the file.

use std::path::Path;

use glam::UVec3;
use voxlod_format::records::{AverageRecord, SkinnedRecord, VoxelSkin};
use voxlod_format::{BrickMap, GridSpec, VxlRecord, vxl};

use crate::{Error, Result};

/// Most voxels per axis of a cache: positions pack 10 bits per axis.
pub const MAX_CACHE_DIM: u32 = 1 << 10;

/// Version of the cache layout in `.vxl` metadata (key `voxlod.cache`).
pub const CACHE_VERSION: u32 = 1;

/// `x | y << 10 | z << 20`, or `None` if a coordinate is ≥ [`MAX_CACHE_DIM`].
#[inline]
pub fn pack_position(c: UVec3) -> Option<u32> {
    c.cmplt(UVec3::splat(MAX_CACHE_DIM)).all().then_some(c.x | c.y << 10 | c.z << 20)
}

/// The coordinates of a packed position (the top two bits are ignored).
#[inline]
pub fn unpack_position(p: u32) -> UVec3 {
    UVec3::new(p & 1023, (p >> 10) & 1023, (p >> 20) & 1023)
}

/// A skinned cache's influences.
#[derive(Clone, Debug, PartialEq)]
pub struct CacheSkin {
    /// Index of the skin in its scene.
    pub skin: usize,
    /// Joints of that skin (every voxel's joint indices are below it).
    pub joint_count: u32,
    /// One per cached voxel, same order as [`VoxelCache::positions`].
    pub voxels: Vec<VoxelSkin>,
}

/// One object's voxels in its own space (module docs of [`super`]).
#[derive(Clone, Debug, PartialEq)]
pub struct VoxelCache {
    /// The object's name, for messages.
    pub name: String,
    /// The object grid: origin at the corner of the object's bounds in object space, the
    /// object-space voxel edge, at most [`MAX_CACHE_DIM`] voxels per axis.
    pub grid: GridSpec,
    /// The object-to-world scale the cache was built for: a cached voxel spans
    /// `grid.voxel_size · scale` world units.
    pub scale: f64,
    /// Packed positions ([`pack_position`]), in Morton order.
    pub positions: Vec<u32>,
    /// Averages record per voxel (object-space normal).
    pub records: Vec<AverageRecord>,
    /// Influences per voxel of a skinned object; `None` for a rigid one.
    pub skin: Option<CacheSkin>,
}

impl VoxelCache {
    /// A rigid object's cache from its voxels' records (any voxel count, grid checked).
    pub fn rigid(
        name: &str,
        grid: GridSpec,
        scale: f64,
        map: &BrickMap<AverageRecord>,
    ) -> Result<Self> {
        let cache = Self {
            name: name.into(),
            grid,
            scale,
            positions: positions(name, &grid, map)?,
            records: map.values().to_vec(),
            skin: None,
        };
        cache.validate()?;
        Ok(cache)
    }

    /// A skinned object's cache from its voxels' records and influences.
    pub fn skinned(
        name: &str,
        grid: GridSpec,
        scale: f64,
        skin: usize,
        joint_count: u32,
        map: &BrickMap<SkinnedRecord>,
    ) -> Result<Self> {
        let cache = Self {
            name: name.into(),
            grid,
            scale,
            positions: positions(name, &grid, map)?,
            records: map.values().iter().map(|r| r.average).collect(),
            skin: Some(CacheSkin {
                skin,
                joint_count,
                voxels: map.values().iter().map(|r| r.skin).collect(),
            }),
        };
        cache.validate()?;
        Ok(cache)
    }

    /// Cached voxels.
    pub fn len(&self) -> usize {
        self.positions.len()
    }

    /// Whether the cache holds no voxel.
    pub fn is_empty(&self) -> bool {
        self.positions.is_empty()
    }

    /// Bytes per cached voxel: 4 (position) + 8 (record), + 8 (skin) for a skinned object.
    pub fn bytes_per_voxel(&self) -> usize {
        4 + size_of::<AverageRecord>() + self.skin.as_ref().map_or(0, |_| size_of::<VoxelSkin>())
    }

    /// Heap bytes of the cache's arrays.
    pub fn memory_bytes(&self) -> usize {
        self.positions.capacity() * 4
            + self.records.capacity() * size_of::<AverageRecord>()
            + self.skin.as_ref().map_or(0, |s| s.voxels.capacity() * size_of::<VoxelSkin>())
    }

    fn invalid(&self, reason: String) -> Error {
        Error::InvalidCache { object: self.name.clone(), reason }
    }

    /// Checks the grid (valid, at most [`MAX_CACHE_DIM`] per axis), the scale (positive,
    /// finite), array lengths, positions inside the grid, and every skin (weights summing to
    /// 255, joints below the joint count).
    pub fn validate(&self) -> Result<()> {
        self.grid.validate()?;
        if self.grid.dims.max_element() > MAX_CACHE_DIM {
            return Err(Error::CacheTooLarge {
                object: self.name.clone(),
                dims: self.grid.dims.as_u64vec3().to_array(),
                max: MAX_CACHE_DIM,
            });
        }
        if !(self.scale.is_finite() && self.scale > 0.0) {
            return Err(self.invalid(format!("scale {} is not positive and finite", self.scale)));
        }
        if self.records.len() != self.positions.len() {
            return Err(self.invalid(format!(
                "{} records for {} positions",
                self.records.len(),
                self.positions.len()
            )));
        }
        if let Some(i) =
            self.positions.iter().position(|&p| !unpack_position(p).cmplt(self.grid.dims).all())
        {
            let c = unpack_position(self.positions[i]);
            return Err(self.invalid(format!("voxel {i} at {c} is outside the grid")));
        }
        if let Some(s) = &self.skin {
            if s.voxels.len() != self.positions.len() {
                return Err(self.invalid(format!(
                    "{} skin entries for {} voxels",
                    s.voxels.len(),
                    self.positions.len()
                )));
            }
            if s.joint_count == 0 || s.joint_count > VoxelSkin::MAX_JOINTS {
                return Err(self.invalid(format!(
                    "{} joints: a skin needs 1 ..= {} joints",
                    s.joint_count,
                    VoxelSkin::MAX_JOINTS
                )));
            }
            for (i, v) in s.voxels.iter().enumerate() {
                if !v.is_normalized() {
                    return Err(self.invalid(format!(
                        "voxel {i}: skin weights {:?} do not sum to 255",
                        v.weights
                    )));
                }
                if let Some(k) =
                    (0..4).find(|&k| v.weights[k] > 0 && v.joints[k] as u32 >= s.joint_count)
                {
                    return Err(self.invalid(format!(
                        "voxel {i}: joint {} of a skin with {} joints",
                        v.joints[k], s.joint_count
                    )));
                }
            }
        }
        Ok(())
    }

    /// The cache as `.vxl` bytes (module docs).
    pub fn encode(&self) -> Result<Vec<u8>> {
        self.validate()?;
        let coords = self.positions.iter().map(|&p| unpack_position(p));
        let mut meta = vec![
            ("voxlod.cache".to_string(), CACHE_VERSION.to_string()),
            ("object".to_string(), self.name.clone()),
            ("scale".to_string(), format!("{:?}", self.scale)),
        ];
        Ok(match &self.skin {
            None => {
                let map = BrickMap::from_voxels(
                    self.grid.dims,
                    coords.zip(self.records.iter().copied()),
                )?;
                vxl::encode(&self.grid, &map, &meta)?
            }
            Some(s) => {
                meta.push(("skin".into(), s.skin.to_string()));
                meta.push(("joints".into(), s.joint_count.to_string()));
                let records = self
                    .records
                    .iter()
                    .zip(&s.voxels)
                    .map(|(&average, &skin)| SkinnedRecord { average, skin });
                let map = BrickMap::from_voxels(self.grid.dims, coords.zip(records))?;
                vxl::encode(&self.grid, &map, &meta)?
            }
        })
    }

    /// Writes the cache as a `.vxl` file, atomically.
    pub fn write(&self, path: &Path) -> Result<()> {
        let bytes = self.encode()?;
        Ok(voxlod_format::io::write_bytes_atomic(path, &bytes)?)
    }

    /// Decodes `.vxl` bytes written by [`VoxelCache::encode`]; `path` names them in errors.
    pub fn decode(bytes: &[u8], path: &Path) -> Result<Self> {
        let info = vxl::decode_info(bytes, path)?;
        let name = path.display().to_string();
        let bad = |reason: String| Error::InvalidCache { object: name.clone(), reason };
        let key = |k: &str| {
            info.meta_value(k).ok_or_else(|| bad(format!("metadata key '{k}' is missing")))
        };
        let version = key("voxlod.cache")?;
        if version != CACHE_VERSION.to_string() {
            return Err(bad(format!(
                "cache layout version {version}; this library reads {CACHE_VERSION}"
            )));
        }
        let object = key("object")?.to_owned();
        let scale: f64 = key("scale")?
            .parse()
            .map_err(|_| bad(format!("scale '{}'", key("scale").unwrap_or(""))))?;
        if info.grid.dims.max_element() > MAX_CACHE_DIM {
            return Err(Error::CacheTooLarge {
                object,
                dims: info.grid.dims.as_u64vec3().to_array(),
                max: MAX_CACHE_DIM,
            });
        }
        if info.holds::<AverageRecord>() {
            let file = vxl::decode::<AverageRecord>(bytes, path)?;
            Self::rigid(&object, file.grid, scale, &file.map)
        } else if info.holds::<SkinnedRecord>() {
            let file = vxl::decode::<SkinnedRecord>(bytes, path)?;
            let skin: usize =
                key("skin")?.parse().map_err(|_| bad("metadata 'skin' is not an index".into()))?;
            let joints: u32 = key("joints")?
                .parse()
                .map_err(|_| bad("metadata 'joints' is not a count".into()))?;
            Self::skinned(&object, file.grid, scale, skin, joints, &file.map)
        } else {
            Err(bad(format!(
                "records of type {} ({} bytes): a cache holds {} or {}",
                vxl::tag_name(info.record_tag),
                info.record_size,
                vxl::tag_name(AverageRecord::TAG),
                vxl::tag_name(SkinnedRecord::TAG)
            )))
        }
    }

    /// Reads a cache file written by [`VoxelCache::write`].
    pub fn read(path: &Path) -> Result<Self> {
        Self::decode(&voxlod_format::io::read_bytes(path)?, path)
    }
}

/// Packed positions of a brick map's voxels (Morton order), checked against the size limit.
fn positions<T>(name: &str, grid: &GridSpec, map: &BrickMap<T>) -> Result<Vec<u32>> {
    grid.validate()?;
    if grid.dims.max_element() > MAX_CACHE_DIM {
        return Err(Error::CacheTooLarge {
            object: name.into(),
            dims: grid.dims.as_u64vec3().to_array(),
            max: MAX_CACHE_DIM,
        });
    }
    if map.dims() != grid.dims {
        return Err(Error::InvalidCache {
            object: name.into(),
            reason: format!("brick map of {} voxels in a grid of {}", map.dims(), grid.dims),
        });
    }
    Ok(map.coords().map(|c| pack_position(c).expect("inside a grid of at most 1024")).collect())
}
