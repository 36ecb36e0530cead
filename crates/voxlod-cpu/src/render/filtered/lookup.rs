//! The voxel look-up of the filtered renderer: which voxels have a record, and which record.
//!
//! The brick map (Morton order, what the DDA's brick look-ups and the bounds read) is mirrored
//! by one [`LinearBrick`] per brick whose occupancy mask is in linear order
//! (`x + 8y + 64z` within the brick) with per-word prefix counts, so the test a walk makes at
//! every voxel it visits is a shift and a mask, and the record index of an occupied voxel one
//! popcount away — instead of a Morton encoding per visited voxel.

use glam::UVec3;
use voxlod_format::{BRICK_EDGE, BrickMap, Result, morton};

use crate::render::bricks::{BrickLookup, BrickMasks, DenseBricks, Occupancy};

/// Where one brick's records start: per word of its [`BrickMasks::voxels`], the set bits in
/// the words before it, and the index in `records` of the brick's first voxel.
#[derive(Clone, Copy, Debug, Default)]
struct Ranks {
    before: [u16; 8],
    first: u32,
}

/// The voxels with a record: a brick map (for brick look-ups and iteration), its dense brick
/// table when one fits, each brick's linear-order occupancy ([`BrickMasks`], what the DDA's
/// [`next_occupied_voxel`](crate::render::dda::Dda::next_occupied_voxel) reads) and each
/// voxel's record index.
pub(super) struct VoxelLookup {
    pub map: BrickMap<()>,
    pub dense: Option<DenseBricks>,
    masks: Vec<BrickMasks>,
    ranks: Vec<Ranks>,
    records: Vec<u32>,
}

/// The position of local voxel `l` (each coordinate in `0..8`) in a brick's linear order.
#[inline(always)]
fn linear(l: UVec3) -> u32 {
    l.x | l.y << 3 | l.z << 6
}

impl VoxelLookup {
    /// The look-up of `found`: `(Morton code, record index)` in strictly increasing code order.
    pub fn new(dims: UVec3, found: &[(u64, u32)]) -> Result<Self> {
        let map = BrickMap::from_morton_sorted(dims, found.iter().map(|&(c, _)| (c, ())))?;
        let dense = DenseBricks::new(&map);
        let mut masks = Vec::with_capacity(map.bricks().len());
        let mut ranks = Vec::with_capacity(map.bricks().len());
        let mut records = vec![0u32; found.len()];
        let mut rest = found;
        let mut local = Vec::new();
        for h in map.bricks() {
            let (mine, next) = rest.split_at(h.count() as usize);
            rest = next;
            local.clear();
            local.extend(
                mine.iter().map(|&(code, record)| (morton::decode(code) % BRICK_EDGE, record)),
            );
            local.sort_unstable_by_key(|&(l, _)| linear(l));
            for (rank, &(_, record)) in local.iter().enumerate() {
                records[h.first as usize + rank] = record;
            }
            let m = BrickMasks::from_local(local.iter().map(|&(l, _)| l));
            let mut r = Ranks { first: h.first, ..Default::default() };
            let mut count = 0u16;
            for w in 0..8 {
                r.before[w] = count;
                count += m.voxels[w].count_ones() as u16;
            }
            masks.push(m);
            ranks.push(r);
        }
        Ok(Self { map, dense, masks, ranks, records })
    }

    /// The occupancy the DDA walks with: `bricks` (the dense table or the map) and the masks.
    #[inline(always)]
    pub fn occupancy<'a, L: BrickLookup>(&'a self, bricks: &'a L) -> Occupancy<'a, L> {
        Occupancy { bricks, masks: &self.masks }
    }

    /// The record index of `voxel`, which lies in brick number `brick` of the map (as
    /// [`crate::render::dda::DdaVoxel::brick`] reports it), if the voxel has one.
    #[inline(always)]
    pub fn record(&self, brick: u32, voxel: UVec3) -> Option<usize> {
        self.record_linear(brick, linear(voxel % BRICK_EDGE))
    }

    /// [`VoxelLookup::record`] of the voxel at linear index `i = x + 8y + 64z` (`i < 512`) in
    /// brick number `brick`.
    #[inline(always)]
    pub fn record_linear(&self, brick: u32, i: u32) -> Option<usize> {
        let (m, r) = (self.masks.get(brick as usize)?, &self.ranks[brick as usize]);
        let (z, bit) = ((i >> 6) as usize & 7, i & 63);
        let word = m.voxels[z];
        if word >> bit & 1 == 0 {
            return None;
        }
        let rank = r.first + r.before[z] as u32 + (word & ((1 << bit) - 1)).count_ones();
        Some(self.records[rank as usize] as usize)
    }

    /// The occupancy masks of brick number `brick` (an index the brick look-ups return).
    #[inline(always)]
    pub fn masks(&self, brick: u32) -> &BrickMasks {
        &self.masks[brick as usize]
    }

    /// Heap bytes held.
    pub fn memory_bytes(&self) -> usize {
        self.map.memory_bytes()
            + self.dense.as_ref().map_or(0, DenseBricks::memory_bytes)
            + self.masks.capacity() * size_of::<BrickMasks>()
            + self.ranks.capacity() * size_of::<Ranks>()
            + self.records.capacity() * size_of::<u32>()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::random::rand_u32;

    #[test]
    fn records_are_found_by_linear_masks_as_by_the_brick_map() {
        let dims = UVec3::new(40, 17, 25);
        let mut found: Vec<(u64, u32)> = (0..900u32)
            .map(|i| {
                let r = |k| rand_u32(i, 9, k);
                let c = UVec3::new(r(0) % dims.x, r(1) % dims.y, r(2) % dims.z);
                (morton::encode(c), r(3))
            })
            .collect();
        found.sort_unstable_by_key(|f| f.0);
        found.dedup_by_key(|f| f.0);
        let lookup = VoxelLookup::new(dims, &found).unwrap();
        let reference: BrickMap<u32> = BrickMap::from_morton_sorted(dims, found.clone()).unwrap();
        let mut hits = 0;
        for x in 0..dims.x {
            for y in 0..dims.y {
                for z in 0..dims.z {
                    let c = UVec3::new(x, y, z);
                    let got = lookup
                        .map
                        .brick_index(c / BRICK_EDGE)
                        .and_then(|b| lookup.record(b as u32, c));
                    assert_eq!(got, reference.get(c).map(|&r| r as usize), "{c}");
                    hits += got.is_some() as usize;
                }
            }
        }
        assert_eq!(hits, found.len());
        assert_eq!(lookup.record(u32::MAX, UVec3::ZERO), None);
    }
}
