//! Brick and voxel look-ups for the DDA: the [`BrickLookup`] trait (which bricks exist), a
//! dense brick table ([`DenseBricks`]) that answers in one load instead of a hash probe,
//! [`voxel_index`], the occupied-voxel test inside a brick, and the [`VoxelOccupancy`] trait
//! with its per-brick [`BrickMasks`] (which voxels and which 2³ blocks of a brick are
//! occupied), with which [`Dda::next_occupied_voxel`](super::dda::Dda::next_occupied_voxel)
//! visits only occupied voxels.

use glam::{IVec3, UVec3, Vec3A};
use voxlod_format::{BRICK_EDGE, BrickMap, morton};

use super::lanes::{trunc_index, trunc_ivec3};

/// Which 8³ bricks of a grid are allocated.
pub trait BrickLookup {
    /// Index of the brick at brick coordinate `brick` (voxel coordinate / 8) in the brick map's
    /// brick list, or `None` when it is not allocated or outside the grid.
    fn brick_index(&self, brick: UVec3) -> Option<u32>;

    /// [`BrickLookup::brick_index`] of a brick coordinate held as integer-valued `f32` lanes
    /// (as the DDA holds them), which the caller has checked lies inside the grid's bricks.
    #[inline(always)]
    fn brick_index_f(&self, brick: Vec3A) -> Option<u32> {
        self.brick_index(brick.as_uvec3())
    }

    /// Whether the 2³-brick block (16³ voxels, aligned to even brick coordinates) holding
    /// `brick` — an unallocated brick inside the grid's bricks, held as integer-valued `f32`
    /// lanes — has no allocated brick at all, so that a walk may cross the whole block in one
    /// jump. `false` (the default) is always correct: the walk then steps brick by brick.
    #[inline(always)]
    fn empty_block_f(&self, brick: Vec3A) -> bool {
        let _ = brick;
        false
    }
}

/// Which voxels of an allocated 8³ brick are occupied, at two granularities: voxels and the
/// brick's 4×4×4 blocks of 2³ voxels.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct BrickMasks {
    /// Bit `x + 8y` of word `z`: voxel `(x, y, z)` of the brick (local coordinates) is occupied.
    pub voxels: [u64; 8],
    /// Bit `bx + 4by + 16bz`: block `(bx, by, bz)` (voxels `2bx..2bx+1`, …) holds an occupied
    /// voxel.
    pub blocks: u64,
}

impl BrickMasks {
    /// The masks of the voxels at local coordinates `local` (each component below 8).
    pub fn from_local(local: impl IntoIterator<Item = UVec3>) -> Self {
        let mut m = Self::default();
        for l in local {
            m.voxels[l.z as usize] |= 1 << (l.x | l.y << 3);
            m.blocks |= 1 << Self::block_bit(l);
        }
        m
    }

    /// The bit of [`BrickMasks::blocks`] for the block holding local voxel `l`.
    #[inline(always)]
    pub fn block_bit(l: UVec3) -> u32 {
        (l.x >> 1) | (l.y >> 1) << 2 | (l.z >> 1) << 4
    }

    /// Whether local voxel `l` is occupied.
    #[inline(always)]
    pub fn has_voxel(&self, l: UVec3) -> bool {
        self.voxels[l.z as usize & 7] >> (l.x | l.y << 3) & 1 != 0
    }

    /// Whether the 2³ block holding local voxel `l` has an occupied voxel.
    #[inline(always)]
    pub fn has_block(&self, l: UVec3) -> bool {
        self.blocks >> Self::block_bit(l) & 1 != 0
    }

    /// Whether the local voxel of linear index `i = x + 8y + 64z` is occupied.
    #[inline(always)]
    pub fn has_voxel_linear(&self, i: u32) -> bool {
        self.voxels[(i >> 6) as usize & 7] >> (i & 63) & 1 != 0
    }

    /// Whether the 2³ block holding the local voxel of linear index `i = x + 8y + 64z` has
    /// an occupied voxel: its bit `(x >> 1) + 4(y >> 1) + 16(z >> 1)` read off `i`'s bits.
    #[inline(always)]
    pub fn has_block_linear(&self, i: u32) -> bool {
        let bit = (i >> 1 & 0x3) | (i >> 2 & 0xc) | (i >> 3 & 0x30);
        self.blocks >> bit & 1 != 0
    }
}

/// A [`BrickLookup`] that also knows which voxels of each allocated brick are occupied.
pub trait VoxelOccupancy: BrickLookup {
    /// The masks of the brick with index `brick` (as returned by
    /// [`BrickLookup::brick_index`]).
    fn masks(&self, brick: u32) -> &BrickMasks;
}

/// A brick look-up `L` with the [`BrickMasks`] of each of its bricks, by brick index.
#[derive(Clone, Copy, Debug)]
pub struct Occupancy<'a, L> {
    /// Which bricks exist.
    pub bricks: &'a L,
    /// The masks of brick `i` at index `i`.
    pub masks: &'a [BrickMasks],
}

impl<L: BrickLookup> BrickLookup for Occupancy<'_, L> {
    #[inline(always)]
    fn brick_index(&self, brick: UVec3) -> Option<u32> {
        self.bricks.brick_index(brick)
    }

    #[inline(always)]
    fn brick_index_f(&self, brick: Vec3A) -> Option<u32> {
        self.bricks.brick_index_f(brick)
    }

    #[inline(always)]
    fn empty_block_f(&self, brick: Vec3A) -> bool {
        self.bricks.empty_block_f(brick)
    }
}

impl<L: BrickLookup> VoxelOccupancy for Occupancy<'_, L> {
    #[inline(always)]
    fn masks(&self, brick: u32) -> &BrickMasks {
        &self.masks[brick as usize]
    }
}

/// The [`BrickMasks`] of every brick of `map`, by brick index.
pub fn brick_masks<T>(map: &BrickMap<T>) -> Vec<BrickMasks> {
    let mut coords = map.coords();
    map.bricks()
        .iter()
        .map(|h| {
            BrickMasks::from_local(coords.by_ref().take(h.count() as usize).map(|c| c % BRICK_EDGE))
        })
        .collect()
}

impl<T> BrickLookup for BrickMap<T> {
    #[inline]
    fn brick_index(&self, brick: UVec3) -> Option<u32> {
        BrickMap::brick_index(self, brick).map(|i| i as u32)
    }
}

/// A dense table of brick indices over the grid's brick dimensions, 4 bytes per brick
/// position (1/128 byte per voxel of the bounding box): a DDA step looks a brick up with one
/// load. Beside it, one byte per 2³-brick block (16³ voxels) saying whether the block has an
/// allocated brick ([`BrickLookup::empty_block_f`]), so that walks cross empty blocks in one
/// jump. [`DenseBricks::new`] declines grids whose table would exceed
/// [`DenseBricks::MAX_ENTRIES`]; use the [`BrickMap`] itself (hashed) there.
#[derive(Clone, Debug)]
pub struct DenseBricks {
    dims: UVec3,
    /// `(1, x, x·y)` of `dims`, for [`BrickLookup::brick_index_f`].
    strides: Vec3A,
    index: Vec<u32>,
    /// `(1, x, x·y)` of the block dimensions `⌈dims / 2⌉`.
    block_strides: IVec3,
    /// Per 2³-brick block: 1 if it holds an allocated brick.
    blocks: Vec<u8>,
}

impl DenseBricks {
    /// Largest table built: 2²⁴ brick positions (64 MiB), a 2048³ grid.
    pub const MAX_ENTRIES: u64 = 1 << 24;

    /// The table of `map`'s bricks, or `None` if it would have more than
    /// [`DenseBricks::MAX_ENTRIES`] entries.
    pub fn new<T>(map: &BrickMap<T>) -> Option<Self> {
        let dims = map.brick_dims();
        let n = dims.as_u64vec3().element_product();
        if n > Self::MAX_ENTRIES {
            return None;
        }
        let mut index = vec![u32::MAX; n as usize];
        let block_dims = (dims + 1) / 2;
        let mut blocks = vec![0u8; block_dims.as_u64vec3().element_product() as usize];
        for (i, h) in map.bricks().iter().enumerate() {
            let b = morton::decode(h.morton);
            index[Self::offset(dims, b)] = i as u32;
            blocks[Self::offset(block_dims, b / 2)] = 1;
        }
        Some(Self {
            dims,
            strides: Vec3A::new(1.0, dims.x as f32, (dims.x * dims.y) as f32),
            index,
            block_strides: IVec3::new(1, block_dims.x as i32, (block_dims.x * block_dims.y) as i32),
            blocks,
        })
    }

    #[inline(always)]
    fn offset(dims: UVec3, b: UVec3) -> usize {
        (b.x as usize) + dims.x as usize * (b.y as usize + dims.y as usize * b.z as usize)
    }

    /// Heap bytes held.
    pub fn memory_bytes(&self) -> usize {
        self.index.capacity() * size_of::<u32>() + self.blocks.capacity()
    }
}

impl BrickLookup for DenseBricks {
    #[inline(always)]
    fn brick_index(&self, brick: UVec3) -> Option<u32> {
        if !brick.cmplt(self.dims).all() {
            return None;
        }
        let i = self.index[Self::offset(self.dims, brick)];
        (i != u32::MAX).then_some(i)
    }

    /// The offset as one dot product in `f32` (exact: below [`DenseBricks::MAX_ENTRIES`] =
    /// 2²⁴) and one conversion, instead of three. A coordinate outside the table (which the
    /// caller promised against) still reads inside it or gets `None`, never out of bounds.
    #[inline(always)]
    fn brick_index_f(&self, brick: Vec3A) -> Option<u32> {
        let offset = trunc_index(brick.dot(self.strides));
        let i = *self.index.get(offset)?;
        (i != u32::MAX).then_some(i)
    }

    /// One load: the block `⌊brick / 2⌋` (a truncation: bricks inside the grid are
    /// non-negative) and its offset in integers; outside the table reads as "not empty".
    #[inline(always)]
    fn empty_block_f(&self, brick: Vec3A) -> bool {
        let offset = trunc_ivec3(brick * 0.5).dot(self.block_strides);
        usize::try_from(offset).ok().and_then(|o| self.blocks.get(o)) == Some(&0)
    }
}

/// Index into `map.values()` of `voxel`, which lies in the brick at `brick` (an index into
/// `map.bricks()`, as [`super::dda::DdaVoxel::brick`] reports it), if the voxel is occupied.
#[inline]
pub fn voxel_index<T>(map: &BrickMap<T>, brick: u32, voxel: UVec3) -> Option<usize> {
    let header = map.bricks().get(brick as usize)?;
    let local = morton::encode(voxel % BRICK_EDGE) as u32;
    header.is_set(local).then(|| (header.first + header.rank(local)) as usize)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dense_table_agrees_with_the_brick_map() {
        let dims = UVec3::new(37, 9, 20);
        let voxels: Vec<(UVec3, u32)> = (0..200u32)
            .map(|i| {
                let r = |k| crate::random::rand_u32(i, 0, k);
                UVec3::new(r(0) % dims.x, r(1) % dims.y, r(2) % dims.z)
            })
            .collect::<std::collections::HashSet<_>>()
            .into_iter()
            .map(|c| (c, c.x * 1000 + c.y * 100 + c.z))
            .collect();
        let map = BrickMap::from_voxels(dims, voxels.iter().copied()).unwrap();
        let dense = DenseBricks::new(&map).unwrap();
        // 5 × 2 × 3 bricks of 4 bytes, 3 × 1 × 2 blocks of one byte.
        assert_eq!(dense.memory_bytes(), 5 * 2 * 3 * 4 + 3 * 2);
        for x in 0..6 {
            for y in 0..3 {
                for z in 0..4 {
                    let b = UVec3::new(x, y, z);
                    assert_eq!(dense.brick_index(b), BrickLookup::brick_index(&map, b), "{b}");
                    if b.cmplt((dims + 7) / 8).all() {
                        let got = dense.brick_index_f(b.as_vec3a());
                        assert_eq!(got, dense.brick_index(b), "{b}");
                        // The block's 8 bricks (those outside the grid have none).
                        let empty = (0..8).all(|k| {
                            let n = b / 2 * 2 + UVec3::new(k & 1, k >> 1 & 1, k >> 2);
                            dense.brick_index(n).is_none()
                        });
                        assert_eq!(dense.empty_block_f(b.as_vec3a()), empty, "{b}");
                        assert!(!BrickLookup::empty_block_f(&map, b.as_vec3a()), "the default");
                    }
                }
            }
        }
        for x in 0..dims.x {
            for y in 0..dims.y {
                for z in 0..dims.z {
                    let c = UVec3::new(x, y, z);
                    let got = dense
                        .brick_index(c / BRICK_EDGE)
                        .and_then(|b| voxel_index(&map, b, c))
                        .map(|i| map.values()[i]);
                    assert_eq!(got, map.get(c).copied(), "{c}");
                }
            }
        }
    }

    #[test]
    fn huge_grids_decline_the_dense_table() {
        let map = BrickMap::<u8>::new(UVec3::splat(1 << 20));
        assert!(DenseBricks::new(&map).is_none());
    }
}
