//! The memory guard: before allocating anything large, every voxelizer validates the triangles
//! and estimates what it will hold at its peak, and refuses with
//! [`Error::OutOfMemory`](crate::Error::OutOfMemory) (dimensions, estimate, limit) when that
//! exceeds [`Options::memory_limit_bytes`](super::Options::memory_limit_bytes).
//!
//! The estimate is an upper bound of the (triangle, voxel) pairs — per triangle, the columns of
//! its bounding box in the plane of its dominant axis times the most voxels one column can hold
//! (`2 + ⌈(|n_a| + |n_b|)/|n_w|⌉` conservative, 2 thin; for zero-area triangles the bounding box,
//! at most 4 voxels per unit of extent) — priced with the bytes each stage keeps per pair and
//! per voxel. It over-estimates by about the ratio of a triangle's bounding box to its area
//! (typically 2–3×), which errs on the side of refusing rather than swapping.

use glam::{IVec3, UVec3};
use rayon::prelude::*;
use voxlod_scene::Geometry;

use super::lattice::{Lattice, Reach, voxel_span};
use super::overlap::normal;
use crate::{Error, Result};

/// Bytes held per occupied voxel at the peak of assembly: its [`super::TriangleRange`] in the
/// brick map (8) and its sorted key (8, or 16 for wide keys), which
/// `BrickMap::from_morton_sorted` consumes in place.
pub const BYTES_PER_VOXEL: u64 = 24;
/// Bytes per allocated 8³ brick: header (80) and lookup entry (~16).
pub const BYTES_PER_BRICK: u64 = 96;

/// Upper bound of the voxels `tri` overlaps in a `dims` grid (see the module docs).
pub fn pairs_bound(tri: &[IVec3; 3], thin: bool, dims: UVec3) -> u64 {
    let lo = tri[0].min(tri[1]).min(tri[2]);
    let hi = tri[0].max(tri[1]).max(tri[2]);
    let mut ext = [0u64; 3];
    let mut single = true;
    for k in 0..3 {
        let (s0, s1) = voxel_span(lo[k], hi[k]);
        single &= s0 == s1;
        let (c0, c1) = (s0.max(0) as i64, s1.min(dims[k] as i32 - 1) as i64);
        if c0 > c1 {
            return 0;
        }
        ext[k] = (c1 - c0 + 1) as u64;
    }
    let bbox = ext[0] * ext[1] * ext[2];
    if single {
        return 1;
    }
    if bbox <= 64 {
        return bbox;
    }
    let n = normal(tri).abs();
    if n.max_element() == 0 {
        return bbox.min(4 * (ext[0] + ext[1] + ext[2]));
    }
    let w = if n.z >= n.x && n.z >= n.y {
        2
    } else if n.y >= n.x {
        1
    } else {
        0
    };
    let (a, b) = ((w + 1) % 3, (w + 2) % 3);
    let depth = if thin {
        2
    } else {
        2 + (n[a] as u128 + n[b] as u128).div_ceil(n[w] as u128).min(u64::MAX as u128) as u64
    };
    (ext[a] * ext[b]).saturating_mul(depth.min(ext[w]))
}

/// What a validation pass over the triangles found.
#[derive(Clone, Copy, Debug, Default)]
pub struct Survey {
    /// Upper bound of (triangle, voxel) pairs (surface overlap).
    pub pairs: u64,
    /// Triangles that can influence the result.
    pub live: u64,
}

/// Validates every triangle (indices, far vertices; see [`Lattice::triangle`]) and bounds the
/// surface pairs. Errors name the first bad triangle.
pub fn survey(geometry: &Geometry, lattice: &Lattice, reach: Reach, thin: bool) -> Result<Survey> {
    let dims = lattice.grid().dims;
    let per_triangle = |t: usize| -> Result<Survey> {
        let idx = geometry.indices[t];
        let tri = match (lattice.vertex(idx[0]), lattice.vertex(idx[1]), lattice.vertex(idx[2])) {
            (Some(a), Some(b), Some(c)) => Some([a, b, c]),
            _ => lattice.triangle(geometry, t, reach)?,
        };
        Ok(match tri {
            Some(tri) => Survey { pairs: pairs_bound(&tri, thin, dims), live: 1 },
            None => Survey::default(),
        })
    };
    let add = |a: Survey, b: Survey| Survey {
        pairs: a.pairs.saturating_add(b.pairs),
        live: a.live + b.live,
    };
    // try_reduce keeps the error of an arbitrary failing triangle; report the first one.
    match (0..geometry.indices.len())
        .into_par_iter()
        .map(per_triangle)
        .try_reduce(Survey::default, |a, b| Ok(add(a, b)))
    {
        Ok(s) => Ok(s),
        Err(_) => {
            let first = (0..geometry.indices.len()).find_map(|t| per_triangle(t).err());
            Err(first.expect("a triangle failed"))
        }
    }
}

/// Refuses an estimate over the limit.
pub fn check(dims: UVec3, estimated_bytes: u64, limit_bytes: u64) -> Result<()> {
    if estimated_bytes > limit_bytes {
        return Err(Error::OutOfMemory { dims: dims.to_array(), estimated_bytes, limit_bytes });
    }
    Ok(())
}

/// Bytes of the occupied voxels of a result holding at most `voxels` voxels of a `dims` grid.
pub fn result_bytes(voxels: u64, dims: UVec3) -> u64 {
    let bricks = dims.as_u64vec3().map(|d| d.div_ceil(8)).element_product().min(voxels);
    voxels.saturating_mul(BYTES_PER_VOXEL).saturating_add(bricks.saturating_mul(BYTES_PER_BRICK))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::voxelize::lattice::VOXEL;
    use crate::voxelize::raster::voxels;
    use proptest::prelude::*;

    proptest! {
        #[test]
        fn bound_is_an_upper_bound(
            a in (0..12 * VOXEL, 0..12 * VOXEL, 0..12 * VOXEL),
            b in (0..12 * VOXEL, 0..12 * VOXEL, 0..12 * VOXEL),
            c in (0..12 * VOXEL, 0..12 * VOXEL, 0..12 * VOXEL),
            degenerate in any::<bool>(),
        ) {
            let (a, b) = (IVec3::from(a), IVec3::from(b));
            let tri = [a, b, if degenerate { b * 2 - a } else { IVec3::from(c) }];
            let dims = UVec3::splat(12);
            for thin in [false, true] {
                let n = voxels(&tri, thin, dims).len() as u64;
                prop_assert!(n <= pairs_bound(&tri, thin, dims), "{} > bound", n);
            }
        }
    }

    #[test]
    fn over_the_limit_is_an_error_with_the_numbers() {
        let err = check(UVec3::splat(9), 1000, 999).unwrap_err();
        assert!(matches!(err, Error::OutOfMemory { estimated_bytes: 1000, limit_bytes: 999, .. }));
        check(UVec3::splat(9), 999, 999).unwrap();
    }
}
