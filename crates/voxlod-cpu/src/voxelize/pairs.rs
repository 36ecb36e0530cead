//! From triangles to the sparse result: parallel emission of (Morton code, triangle id) pairs,
//! a parallel sort, grouping into per-voxel triangle runs (CSR), and the occupancy-only paths
//! (a dense atomic bitset of 8³ bricks when the grid is small enough, sorted unique codes
//! otherwise). Every path yields voxels in global Morton order, the order of
//! [`BrickMap`](voxlod_format::BrickMap) values.

use std::sync::atomic::{AtomicU64, Ordering};

use glam::UVec3;
use rayon::prelude::*;
use voxlod_format::morton;
use voxlod_scene::Geometry;

use super::TriangleRange;
use super::lattice::{Lattice, Reach};
use super::raster::for_each_voxel;
use super::sort::{Key, bucket_sort};
use crate::{Error, Result};

/// Triangles per parallel work item.
const CHUNK: usize = 4096;

/// Bits needed to hold values `0..count`.
pub fn bits_for(count: u64) -> u32 {
    64 - count.saturating_sub(1).leading_zeros()
}

/// Bits of the Morton codes of a `dims` grid.
pub fn code_bits(dims: UVec3) -> u32 {
    3 * bits_for(dims.max_element() as u64)
}

/// Calls `f(triangle id, snapped triangle)` for every triangle whose vertices are all within
/// the lattice's range, in parallel chunks, and concatenates what each chunk's closure pushed.
/// Other triangles go through [`Lattice::triangle`]: culled, or an error (a bad index, a far
/// vertex of a triangle that may reach the grid); the error of the first such triangle is
/// returned after the pass.
pub fn par_emit<T: Send>(
    geometry: &Geometry,
    lattice: &Lattice,
    reach: Reach,
    f: impl Fn(u32, &[glam::IVec3; 3], &mut Vec<T>) + Sync,
) -> Result<Vec<T>> {
    Ok(concat(par_emit_chunks(geometry, lattice, reach, f)?))
}

/// [`par_emit`] without the final concatenation: one buffer per chunk of triangles, in order.
pub fn par_emit_chunks<T: Send>(
    geometry: &Geometry,
    lattice: &Lattice,
    reach: Reach,
    f: impl Fn(u32, &[glam::IVec3; 3], &mut Vec<T>) + Sync,
) -> Result<Vec<Vec<T>>> {
    let chunks: Vec<(Vec<T>, Option<Error>)> = geometry
        .indices
        .par_chunks(CHUNK)
        .enumerate()
        .map(|(ci, chunk)| {
            let mut out = Vec::new();
            for (j, idx) in chunk.iter().enumerate() {
                let t = ci * CHUNK + j;
                if let (Some(a), Some(b), Some(c)) =
                    (lattice.vertex(idx[0]), lattice.vertex(idx[1]), lattice.vertex(idx[2]))
                {
                    f(t as u32, &[a, b, c], &mut out);
                } else {
                    match lattice.triangle(geometry, t, reach) {
                        Ok(Some(tri)) => f(t as u32, &tri, &mut out),
                        Ok(None) => {}
                        Err(e) => return (out, Some(e)),
                    }
                }
            }
            (out, None)
        })
        .collect();
    let mut out = Vec::with_capacity(chunks.len());
    for (chunk, error) in chunks {
        if let Some(e) = error {
            return Err(e);
        }
        out.push(chunk);
    }
    Ok(out)
}

/// Concatenates in parallel (the copy of every pair is the largest memory traffic here).
fn concat<T: Send>(chunks: Vec<Vec<T>>) -> Vec<T> {
    let total = chunks.iter().map(Vec::len).sum();
    let mut out = Vec::with_capacity(total);
    out.par_extend(chunks.into_par_iter().flatten_iter());
    out
}

/// Sorted (Morton code, triangle) keys of every overlap of the surface test.
pub fn sorted_keys<K: Key>(
    geometry: &Geometry,
    lattice: &Lattice,
    thin: bool,
    tri_bits: u32,
) -> Result<Vec<K>> {
    let dims = lattice.grid().dims;
    let chunks = par_emit_chunks(geometry, lattice, Reach::Surface, |t, tri, out: &mut Vec<K>| {
        for_each_voxel(tri, thin, dims, |c| out.push(K::pack(morton::encode(c), t, tri_bits)));
    })?;
    let keys = bucket_sort(chunks, code_bits(dims), tri_bits);
    Ok(keys)
}

/// The voxels of sorted keys with their runs of triangles: `(code, range)` in Morton order,
/// ranges consecutive from 0 (so the triangle ids are the keys' low bits, in order).
pub fn runs<K: Key>(keys: &[K], tri_bits: u32) -> impl Iterator<Item = (u64, TriangleRange)> + '_ {
    let mut i = 0;
    std::iter::from_fn(move || {
        let code = keys.get(i)?.code(tri_bits);
        let first = i;
        i += 1;
        while i < keys.len() && keys[i].code(tri_bits) == code {
            i += 1;
        }
        Some((code, TriangleRange { first: first as u32, count: (i - first) as u32 }))
    })
}

/// Groups sorted keys into voxels: `(code, range into triangles)` in Morton order, and the
/// triangle ids. A voxel for which `keep(code)` is false is dropped with its triangles.
pub fn group<K: Key>(
    keys: &[K],
    tri_bits: u32,
    keep: impl Fn(u64) -> bool,
) -> (Vec<(u64, TriangleRange)>, Vec<u32>) {
    let mut voxels = Vec::new();
    let mut triangles = Vec::with_capacity(keys.len());
    let mut i = 0;
    while i < keys.len() {
        let code = keys[i].code(tri_bits);
        let mut j = i + 1;
        while j < keys.len() && keys[j].code(tri_bits) == code {
            j += 1;
        }
        if keep(code) {
            let first = triangles.len() as u32;
            triangles.extend(keys[i..j].iter().map(|k| k.tri(tri_bits)));
            voxels.push((code, TriangleRange { first, count: (j - i) as u32 }));
        }
        i = j;
    }
    (voxels, triangles)
}

/// Sorted unique Morton codes of every voxel the surface test sets (occupancy, large grids).
pub fn sorted_codes(geometry: &Geometry, lattice: &Lattice, thin: bool) -> Result<Vec<u64>> {
    let dims = lattice.grid().dims;
    let mut codes = par_emit(geometry, lattice, Reach::Surface, |_, tri, out: &mut Vec<u64>| {
        for_each_voxel(tri, thin, dims, |c| out.push(morton::encode(c)));
    })?;
    codes.par_sort_unstable();
    codes.dedup();
    Ok(codes)
}

/// A dense bitset over a grid's 8³ bricks (brick-major, Morton order inside a brick), set
/// concurrently.
pub struct BrickBits {
    bricks: UVec3,
    words: Vec<AtomicU64>,
}

/// Local Morton code of a 3-bit coordinate.
const LOCAL: [u32; 8] = [0, 1, 8, 9, 64, 65, 72, 73];

impl BrickBits {
    /// Bytes a bitset over `dims` takes.
    pub fn bytes(dims: UVec3) -> u64 {
        dims.as_u64vec3().map(|d| d.div_ceil(8)).element_product() * 64
    }

    /// An empty bitset over `dims`.
    pub fn new(dims: UVec3) -> Self {
        let bricks = (dims + 7) / 8;
        let n = bricks.as_u64vec3().element_product() as usize * 8;
        Self { bricks, words: (0..n).into_par_iter().map(|_| AtomicU64::new(0)).collect() }
    }

    /// Word index and bit of voxel `c`.
    #[inline]
    fn locate(&self, c: UVec3) -> (usize, u64) {
        let b = c / 8;
        let brick = ((b.z * self.bricks.y + b.y) * self.bricks.x + b.x) as usize;
        let local = LOCAL[(c.x & 7) as usize]
            | LOCAL[(c.y & 7) as usize] << 1
            | LOCAL[(c.z & 7) as usize] << 2;
        (brick * 8 + (local >> 6) as usize, 1 << (local & 63))
    }

    /// Sets voxel `c` (a plain load first: most voxels of dense scenes are hit many times, and
    /// a read is much cheaper than an atomic read-modify-write).
    #[inline]
    pub fn set(&self, c: UVec3) {
        let (w, bit) = self.locate(c);
        let word = &self.words[w];
        if word.load(Ordering::Relaxed) & bit == 0 {
            word.fetch_or(bit, Ordering::Relaxed);
        }
    }

    /// Morton codes of the set voxels, in Morton order.
    pub fn codes(&self) -> impl Iterator<Item = u64> + '_ {
        let bricks = self.bricks;
        let mut occupied: Vec<(u64, usize)> = (0..self.words.len() / 8)
            .into_par_iter()
            .filter(|&i| {
                self.words[i * 8..i * 8 + 8].iter().any(|w| w.load(Ordering::Relaxed) != 0)
            })
            .map(|i| {
                let i = i as u32;
                let b =
                    UVec3::new(i % bricks.x, i / bricks.x % bricks.y, i / (bricks.x * bricks.y));
                (morton::encode(b), i as usize)
            })
            .collect();
        occupied.par_sort_unstable();
        occupied.into_iter().flat_map(move |(code, i)| {
            (0..8).flat_map(move |w| {
                let mut bits = self.words[i * 8 + w].load(Ordering::Relaxed);
                std::iter::from_fn(move || {
                    (bits != 0).then(|| {
                        let local = w as u64 * 64 + bits.trailing_zeros() as u64;
                        bits &= bits - 1;
                        code << 9 | local
                    })
                })
            })
        })
    }
}

/// The dense bitset of every voxel the surface test sets (occupancy); read it back with
/// [`BrickBits::codes`].
pub fn dense_bits(geometry: &Geometry, lattice: &Lattice, thin: bool) -> Result<BrickBits> {
    let dims = lattice.grid().dims;
    let bits = BrickBits::new(dims);
    par_emit_chunks(geometry, lattice, Reach::Surface, |_, tri, _: &mut Vec<()>| {
        for_each_voxel(tri, thin, dims, |c| bits.set(c));
    })?;
    Ok(bits)
}
