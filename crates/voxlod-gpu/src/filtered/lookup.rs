//! The brick map's look-up arrays for the kernels (as voxlod-cpu's `render/filtered/lookup.rs`
//! lays them out): the dense brick table, each brick's 512-bit occupancy mask with per-word
//! ranks, and the record index of each rank.

use voxlod_cpu::render::bricks::DenseBricks;
use voxlod_format::{BRICK_EDGE, BrickMap};

use super::GpuBrick;
use crate::{Error, Result};

/// The look-up arrays of a brick map: the dense brick table (`u32::MAX` = empty), the bricks'
/// linear masks and ranks, and the value index of each rank. Errors when the dense table
/// would exceed [`DenseBricks::MAX_ENTRIES`].
pub fn brick_lookup<T>(map: &BrickMap<T>) -> Result<(Vec<u32>, Vec<GpuBrick>, Vec<u32>)> {
    let bd = map.brick_dims();
    let entries = bd.as_u64vec3().element_product();
    if entries > DenseBricks::MAX_ENTRIES {
        return Err(Error::TooLarge {
            what: "dense brick table of the filtered renderer (brick positions)",
            requested: entries,
            limit: DenseBricks::MAX_ENTRIES,
        });
    }
    let mut table = vec![u32::MAX; entries as usize];
    let mut per_brick: Vec<Vec<(u32, u32)>> = vec![Vec::new(); map.bricks().len()];
    for (i, (c, _)) in map.iter().enumerate() {
        let b = c / BRICK_EDGE;
        let ordinal = map.brick_index(b).expect("an occupied voxel's brick is allocated");
        table[(b.x + bd.x * (b.y + bd.y * b.z)) as usize] = ordinal as u32;
        let l = c % BRICK_EDGE;
        per_brick[ordinal].push((l.x | l.y << 3 | l.z << 6, i as u32));
    }
    let mut bricks = Vec::with_capacity(per_brick.len());
    let mut slots = Vec::with_capacity(map.len());
    for mut voxels in per_brick {
        voxels.sort_unstable();
        let mut b = GpuBrick::default();
        for &(l, value) in &voxels {
            b.mask[(l >> 5) as usize] |= 1 << (l & 31);
            slots.push(value);
        }
        let mut rank = (slots.len() - voxels.len()) as u32;
        for w in 0..16 {
            b.before[w] = rank;
            rank += b.mask[w].count_ones();
        }
        bricks.push(b);
    }
    Ok((table, bricks, slots))
}

#[cfg(test)]
mod tests {
    use glam::UVec3;

    use super::*;

    /// The look-up arrays find every voxel's value index, as the brick map does, and the 2³
    /// block test finds every block holding a voxel (the WGSL `walk_next`'s rank look-up and
    /// block bits, written here in Rust over the same arrays).
    #[test]
    fn brick_lookup_finds_every_voxel() {
        let dims = UVec3::new(21, 9, 17);
        let voxels = (0..400u32).map(|i| {
            let r = |k| voxlod_cpu::random::rand_u32(i, 5, k);
            (UVec3::new(r(0) % dims.x, r(1) % dims.y, r(2) % dims.z), i)
        });
        let voxels: std::collections::HashMap<UVec3, u32> = voxels.collect();
        let map = BrickMap::from_voxels(dims, voxels).unwrap();
        let (table, bricks, slots) = brick_lookup(&map).unwrap();
        let bd = map.brick_dims();
        for x in 0..dims.x {
            for y in 0..dims.y {
                for z in 0..dims.z {
                    let c = UVec3::new(x, y, z);
                    let b = c / 8;
                    let bi = table[(b.x + bd.x * (b.y + bd.y * b.z)) as usize];
                    let got = (bi != u32::MAX)
                        .then(|| {
                            let l = c % 8;
                            let lin = l.x | l.y << 3 | l.z << 6;
                            let (w, bit) = ((lin >> 5) as usize, lin & 31);
                            let word = bricks[bi as usize].mask[w];
                            (word >> bit & 1 == 1).then(|| {
                                let below = (word & ((1u32 << bit) - 1)).count_ones();
                                slots[(bricks[bi as usize].before[w] + below) as usize] as usize
                            })
                        })
                        .flatten();
                    assert_eq!(got, map.index_of(c), "{c}");
                    if bi == u32::MAX {
                        continue;
                    }
                    // walk_next's block test: 0x303 << ((x & 6) + 16·((y >> 1) & 1)) in the
                    // words of the block's two z layers.
                    let l = c % 8;
                    let bw = ((l.y >> 2) + 4 * (l.z >> 1)) as usize;
                    let mask = &bricks[bi as usize].mask;
                    let block = (mask[bw] | mask[bw + 2]) >> ((l.x & 6) + 16 * ((l.y >> 1) & 1));
                    let lo = c / 2 * 2;
                    let occupied = (0..8).any(|k| {
                        let v = lo + UVec3::new(k & 1, k >> 1 & 1, k >> 2);
                        v.cmplt(dims).all() && map.index_of(v).is_some()
                    });
                    assert_eq!(block & 0x303 != 0, occupied, "block of {c}");
                }
            }
        }
    }
}
