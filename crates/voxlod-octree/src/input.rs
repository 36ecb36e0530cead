//! What every octree build checks first, whichever backend runs it: the plan of levels (depth
//! and finest dense level) for a grid, and the voxels' Morton codes (inside the grid, strictly
//! increasing), so that every build reports the same error for the same bad input.

use glam::UVec3;
use rayon::prelude::*;
use voxlod_format::morton;

use crate::octree::{BuildOptions, MAX_DENSE_LOG2, MAX_DEPTH};
use crate::{Error, Result};

/// Depth and finest dense level `(depth, first_dense)` of the octree over a grid of `dims`
/// (the input checks every build shares, public so that other backends report the same errors).
pub fn plan(dims: UVec3, options: &BuildOptions) -> Result<(u32, u32)> {
    let needed = dims.max_element().next_power_of_two().trailing_zeros();
    let depth = options.depth.unwrap_or(needed);
    if depth > MAX_DEPTH {
        return Err(Error::TooDeep { requested: depth, max: MAX_DEPTH });
    }
    if depth < needed {
        return Err(Error::GridDoesNotFit { dims, depth, res: 1 << depth });
    }
    if options.dense_log2 > MAX_DENSE_LOG2 {
        return Err(Error::DenseTooLarge {
            requested_log2: options.dense_log2,
            res: 1u64 << options.dense_log2.min(63),
            max_log2: MAX_DENSE_LOG2,
        });
    }
    Ok((depth, depth - options.dense_log2.min(depth)))
}

/// What is wrong with voxel `code` after `prev` (outside the grid, repeated, out of order), if
/// anything.
pub(crate) fn code_problem(dims: UVec3, code: u64, prev: Option<u64>) -> Option<Error> {
    let coord = morton::decode(code);
    if code >> 63 != 0 || !coord.cmplt(dims).all() {
        return Some(Error::OutOfBounds { coord, dims });
    }
    let prev = prev?;
    if prev == code {
        return Some(Error::DuplicateVoxel { coord });
    }
    (prev > code).then_some(Error::OutOfOrder { coord, code })
}

/// Whether every one of the `n` codes `code(i)` lies inside `dims` (whose components are
/// positive) and is greater than the one before, and `extra(i)` holds: a parallel pass without
/// decoding (a coordinate is below a bound iff its interleaved bits, masked out of the code,
/// are below the bound's interleaved bits). The error itself is found by [`code_problem`] only
/// when this fails.
pub(crate) fn all_codes_ok(
    dims: UVec3,
    n: usize,
    code: impl Fn(usize) -> u64 + Sync,
    extra: impl Fn(usize) -> bool + Sync,
) -> bool {
    let limit: [u64; 3] = std::array::from_fn(|a| {
        let mut c = UVec3::ZERO;
        c[a] = dims[a].saturating_sub(1);
        morton::encode(c)
    });
    let inside = |c: u64| {
        (c & morton::AXIS_BITS[0] <= limit[0])
            & (c & morton::AXIS_BITS[1] <= limit[1])
            & (c & morton::AXIS_BITS[2] <= limit[2])
    };
    // Chunks checked without early exit inside (branch-free), in parallel.
    dims.min_element() > 0
        && (0..n.div_ceil(CHECK_LEN)).into_par_iter().all(|chunk| {
            let (lo, hi) = (chunk * CHECK_LEN, ((chunk + 1) * CHECK_LEN).min(n));
            let mut prev = if lo == 0 { None } else { Some(code(lo - 1)) };
            (lo..hi).fold(true, |ok, i| {
                let c = code(i);
                let ordered = prev.is_none_or(|p| p < c);
                prev = Some(c);
                ok & inside(c) & ordered & extra(i)
            })
        })
}

/// Items per rayon task of the input check (a few nanoseconds each).
const CHECK_LEN: usize = 1 << 15;
