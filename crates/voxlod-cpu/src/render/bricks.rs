//! Brick and voxel look-ups for the DDA: the [`BrickLookup`] trait (which bricks exist), a
//! dense brick table ([`DenseBricks`]) that answers in one load instead of a hash probe, and
//! [`voxel_index`], the occupied-voxel test inside a brick.

use glam::UVec3;
use voxlod_format::{BRICK_EDGE, BrickMap, morton};

/// Which 8³ bricks of a grid are allocated.
pub trait BrickLookup {
    /// Index of the brick at brick coordinate `brick` (voxel coordinate / 8) in the brick map's
    /// brick list, or `None` when it is not allocated or outside the grid.
    fn brick_index(&self, brick: UVec3) -> Option<u32>;
}

impl<T> BrickLookup for BrickMap<T> {
    #[inline]
    fn brick_index(&self, brick: UVec3) -> Option<u32> {
        BrickMap::brick_index(self, brick).map(|i| i as u32)
    }
}

/// A dense table of brick indices over the grid's brick dimensions, 4 bytes per brick
/// position (1/128 byte per voxel of the bounding box): a DDA step looks a brick up with one
/// load. [`DenseBricks::new`] declines grids whose table would exceed
/// [`DenseBricks::MAX_ENTRIES`]; use the [`BrickMap`] itself (hashed) there.
#[derive(Clone, Debug)]
pub struct DenseBricks {
    dims: UVec3,
    index: Vec<u32>,
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
        for (i, h) in map.bricks().iter().enumerate() {
            let b = morton::decode(h.morton);
            index[Self::offset(dims, b)] = i as u32;
        }
        Some(Self { dims, index })
    }

    #[inline(always)]
    fn offset(dims: UVec3, b: UVec3) -> usize {
        (b.x as usize) + dims.x as usize * (b.y as usize + dims.y as usize * b.z as usize)
    }

    /// Heap bytes held.
    pub fn memory_bytes(&self) -> usize {
        self.index.capacity() * size_of::<u32>()
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
        assert_eq!(dense.memory_bytes(), 5 * 2 * 3 * 4);
        for x in 0..6 {
            for y in 0..3 {
                for z in 0..4 {
                    let b = UVec3::new(x, y, z);
                    assert_eq!(dense.brick_index(b), BrickLookup::brick_index(&map, b), "{b}");
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
