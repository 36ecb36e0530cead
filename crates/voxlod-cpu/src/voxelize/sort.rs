//! Sorting the (Morton code, triangle) keys of a voxelization: a most-significant-digit bucket
//! sort. The keys' top bits are the top bits of the voxel's Morton code, i.e. which cell of a
//! coarse octree level it lies in; one sequential scatter from the emission buffers into those
//! buckets (a cache-friendly number of write heads, and no separate concatenation copy), then
//! the small buckets are sorted in parallel, each inside the cache.
//!
//! A parallel comparison sort of the concatenated keys is the alternative; on the 1.2 M-triangle
//! forest of `benches/voxelize.rs` it costs more than rasterizing the triangles.

use rayon::prelude::*;

/// A sort key packing a voxel's Morton code above a triangle id (`tri_bits` low bits), so that
/// sorting keys groups pairs by voxel in Morton order, triangles ascending within a voxel.
pub trait Key: Copy + Default + Ord + Send + Sync {
    /// Packs a pair.
    fn pack(code: u64, tri: u32, tri_bits: u32) -> Self;
    /// The voxel's Morton code.
    fn code(self, tri_bits: u32) -> u64;
    /// The triangle id.
    fn tri(self, tri_bits: u32) -> u32;
}

impl Key for u64 {
    #[inline]
    fn pack(code: u64, tri: u32, tri_bits: u32) -> Self {
        code << tri_bits | tri as u64
    }
    #[inline]
    fn code(self, tri_bits: u32) -> u64 {
        self >> tri_bits
    }
    #[inline]
    fn tri(self, tri_bits: u32) -> u32 {
        (self & ((1u64 << tri_bits) - 1)) as u32
    }
}

impl Key for u128 {
    #[inline]
    fn pack(code: u64, tri: u32, _: u32) -> Self {
        (code as u128) << 32 | tri as u128
    }
    #[inline]
    fn code(self, _: u32) -> u64 {
        (self >> 32) as u64
    }
    #[inline]
    fn tri(self, _: u32) -> u32 {
        self as u32
    }
}

/// Most buckets used: 2^16 write heads (the scatter's cursors and their cache lines stay in L2).
const MAX_BUCKET_BITS: u32 = 16;
/// Target keys per bucket.
const KEYS_PER_BUCKET: usize = 256;

/// Sorts the concatenation of `chunks`, whose keys hold Morton codes of `code_bits` bits above
/// `tri_bits` triangle bits.
pub fn bucket_sort<K: Key>(chunks: Vec<Vec<K>>, code_bits: u32, tri_bits: u32) -> Vec<K> {
    let total: usize = chunks.iter().map(Vec::len).sum();
    let wanted = (total / KEYS_PER_BUCKET).max(1).next_power_of_two().trailing_zeros();
    let bits = wanted.min(MAX_BUCKET_BITS).min(code_bits);
    let shift = code_bits - bits;
    let bucket = |k: K| (k.code(tri_bits) >> shift) as usize;
    let buckets = 1usize << bits;
    // Histogram: one per rayon job, summed.
    let counts = chunks
        .par_iter()
        .fold(
            || vec![0usize; buckets],
            |mut h, chunk| {
                for &k in chunk {
                    h[bucket(k)] += 1;
                }
                h
            },
        )
        .reduce(
            || vec![0usize; buckets],
            |mut a, b| {
                a.iter_mut().zip(&b).for_each(|(x, y)| *x += y);
                a
            },
        );
    let mut cursor = Vec::with_capacity(buckets);
    let mut start = 0;
    for &c in &counts {
        cursor.push(start);
        start += c;
    }
    let mut out = vec![K::default(); total];
    for chunk in chunks {
        for k in chunk {
            let b = bucket(k);
            out[cursor[b]] = k;
            cursor[b] += 1;
        }
    }
    // Split the output into its buckets and sort them in parallel.
    let mut slices = Vec::with_capacity(buckets);
    let mut rest = out.as_mut_slice();
    for &c in &counts {
        let (head, tail) = rest.split_at_mut(c);
        if c > 1 {
            slices.push(head);
        }
        rest = tail;
    }
    slices.par_iter_mut().with_min_len(64).for_each(|s| s.sort_unstable());
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        #[test]
        fn equals_a_plain_sort(
            chunks in proptest::collection::vec(proptest::collection::vec(0u64..1 << 20, 0..400), 0..12),
            tri_bits in 0u32..8,
        ) {
            let code_bits = 20 - tri_bits;
            let mut expected: Vec<u64> = chunks.concat();
            expected.sort_unstable();
            prop_assert_eq!(bucket_sort(chunks.clone(), code_bits, tri_bits), expected.clone());
            let wide: Vec<Vec<u128>> = chunks
                .iter()
                .map(|c| c.iter().map(|&k| u128::pack(k >> tri_bits, (k & ((1 << tri_bits) - 1)) as u32, 0)).collect())
                .collect();
            let mut expected: Vec<u128> = wide.concat();
            expected.sort_unstable();
            prop_assert_eq!(bucket_sort(wide, code_bits, 0), expected);
        }
    }
}
