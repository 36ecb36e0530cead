//! Truncating conversions of the integer-valued `f32` lanes the DDA walks with (cells, bricks,
//! table offsets) to integers, in one SIMD instruction on x86-64.
//!
//! glam's `as_ivec3`/`as_uvec3` and a plain `as usize` convert lane by lane with Rust's
//! saturating casts, a dozen instructions and branches per lane on the walks' hottest paths.
//! `cvttps2dq` truncates all lanes at once and is defined for every input (NaN and values out
//! of range give `i32::MIN`), so these functions are safe for any input and equal to the casts
//! for the values the walks hold: finite integers (or truncations of finite values) of
//! magnitude below 2³¹ — grid coordinates are below 2²¹
//! ([`voxlod_format::morton::MAX_COORD`]).

use glam::{IVec3, UVec3, Vec3A};

/// `v` truncated toward zero per lane; equal to `v.as_ivec3()` for lanes in `(−2³¹, 2³¹)`.
#[inline(always)]
pub(crate) fn trunc_ivec3(v: Vec3A) -> IVec3 {
    #[cfg(target_arch = "x86_64")]
    {
        use std::arch::x86_64::{_mm_cvttps_epi32, _mm_storeu_si128};
        let mut out = [0i32; 4];
        // SAFETY: SSE2 is part of the x86-64 baseline; the store writes the 16 bytes of `out`.
        unsafe { _mm_storeu_si128(out.as_mut_ptr().cast(), _mm_cvttps_epi32(v.into())) };
        IVec3::new(out[0], out[1], out[2])
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        v.as_ivec3()
    }
}

/// `v` truncated toward zero per lane, as floats: `v.floor()` for the non-negative lanes below
/// 2³¹ the walks hold (cells and bricks inside the grid), in two instructions on x86-64 where
/// glam's SSE2 `floor` is a dozen.
#[inline(always)]
pub(crate) fn trunc_vec3a(v: Vec3A) -> Vec3A {
    #[cfg(target_arch = "x86_64")]
    {
        use std::arch::x86_64::{_mm_cvtepi32_ps, _mm_cvttps_epi32};
        // SAFETY: SSE2 is part of the x86-64 baseline.
        Vec3A::from(unsafe { _mm_cvtepi32_ps(_mm_cvttps_epi32(v.into())) })
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        v.trunc()
    }
}

/// `v` truncated per lane as unsigned; equal to `v.as_uvec3()` for lanes in `[0, 2³¹)`.
#[inline(always)]
pub(crate) fn trunc_uvec3(v: Vec3A) -> UVec3 {
    trunc_ivec3(v).as_uvec3()
}

/// `x` truncated to an index; equal to `x as usize` for `x` in `[0, 2³¹)`, and `usize::MAX`-like
/// (out of every table) for negative, huge or NaN `x`, so that a `get` with it fails.
#[inline(always)]
pub(crate) fn trunc_index(x: f32) -> usize {
    #[cfg(target_arch = "x86_64")]
    {
        use std::arch::x86_64::{_mm_cvttss_si32, _mm_set_ss};
        // SAFETY: SSE is part of the x86-64 baseline.
        let i = unsafe { _mm_cvttss_si32(_mm_set_ss(x)) };
        if i < 0 { usize::MAX } else { i as usize }
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        if x >= 0.0 { x as usize } else { usize::MAX }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn truncations_equal_the_casts_in_range_and_stay_safe_outside() {
        let values = [0.0, -0.0, 0.5, 1.0, 7.999, 8.0, -1.0, -2.5, 1048575.0, 2097152.0, 1e9];
        for &x in &values {
            for &y in &values {
                let v = Vec3A::new(x, y, -x);
                assert_eq!(trunc_ivec3(v), v.as_ivec3(), "{v}");
                if x >= 0.0 && y >= 0.0 {
                    let u = Vec3A::new(x, y, x);
                    assert_eq!(trunc_uvec3(u), u.as_uvec3(), "{u}");
                }
            }
            if x >= 0.0 {
                assert_eq!(trunc_index(x), x as usize, "{x}");
            }
        }
        for bad in [-1.0, -0.5e-3, f32::NAN, f32::INFINITY, f32::NEG_INFINITY, 3e9] {
            let i = trunc_index(bad);
            // Out of any table (or, for -0.5e-3 → 0, the cast's own answer).
            assert!(i == usize::MAX || i == 0, "{bad}: {i}");
        }
        // NaN and values out of i32's range: `i32::MIN` in every lane on x86-64 (the casts
        // would saturate), never a panic.
        #[cfg(target_arch = "x86_64")]
        for bad in [f32::NAN, f32::INFINITY, f32::NEG_INFINITY, 3e9, -3e9] {
            assert_eq!(trunc_ivec3(Vec3A::splat(bad)), IVec3::splat(i32::MIN), "{bad}");
        }
        for x in [0.0, 0.25, 0.5, 7.999, 8.0, 12.5, 1048575.5, 2097151.0] {
            let v = Vec3A::new(x, x * 0.5, x + 1.0);
            assert_eq!(trunc_vec3a(v), v.floor(), "{v}");
        }
        assert_eq!(trunc_index(-0.0005), 0);
        assert_eq!(trunc_index(-1.0), usize::MAX);
        assert_eq!(trunc_index(f32::NAN), usize::MAX);
    }
}
