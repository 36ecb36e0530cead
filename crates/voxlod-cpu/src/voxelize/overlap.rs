//! Exact triangle/voxel overlap tests on the lattice ([`super::lattice`]), in integer
//! arithmetic: the per-voxel reference that the rasterizer ([`super::raster`]), the tests and the
//! WGSL port are all checked against.
//!
//! # Tie rule
//! Voxel `(i, j, k)` is the **closed** box `[i·V, (i+1)·V] × [j·V, (j+1)·V] × [k·V, (k+1)·V]`
//! (`V` = [`VOXEL`]) and the triangle is the closed convex hull of its three snapped vertices.
//! They overlap unless some axis separates them **strictly**: a triangle touching a voxel's
//! face, edge or corner overlaps it. So a triangle lying in the plane `z = k·V` overlaps the
//! voxels of both layers `k − 1` and `k`. (The grid's half-open index convention of
//! `GridSpec` is about points; voxelization is about closed boxes, so no face is ever lost.)
//!
//! # Conservative test ([`box_overlap`])
//! The separating axis theorem with Akenine-Möller's 13 axes: the 3 box axes, the triangle
//! normal `n = e0 × e1`, and the 9 products `e_i × x̂_k`. Everything is relative to the voxel
//! centre `c` (a lattice point), with half-extent `h = V/2`.
//!
//! **Degenerate triangles.** If the snapped vertices are collinear (or coincide), `n = 0` and
//! some `e_i × x̂_k` vanish. A vanishing axis projects everything to 0 and so never separates;
//! what remains suffices: the triangle is then the segment `S` (or point) spanned by its
//! vertices, with direction `d` parallel to every nonzero `e_i`. Two convex polytopes are
//! disjoint iff they are separated along a face normal of one of them or along a cross product
//! of an edge direction of each; a segment has no face, and its only edge direction is `d`, so
//! the candidate axes are the box normals `x̂_k` and `d × x̂_k` — all of them still among the
//! 13 (`e_i × x̂_k` is a nonzero multiple of `d × x̂_k` for each nonzero `e_i`, and if
//! `d × x̂_k = 0` that axis is not needed). For a point only the box axes remain, which is the
//! point-in-closed-box test. Hence the same 13-axis code is exact for points, segments and
//! triangles, and the tests check all three.
//!
//! # 6-separating "thin" test ([`diamond_overlap`])
//! Schwarz & Seidel 2010 replace the voxel box by its inner **diamond**
//! `D = {x : ‖x − c‖₁ ≤ h}`. Any segment between two 6-adjacent voxel centres is covered by
//! their two closed diamonds, so a surface crossing it meets one of them: the voxels whose
//! diamond meets the triangle form a 6-separating voxelization. We set a voxel when all of these
//! necessary conditions for `T ∩ D ≠ ∅` hold (so the result contains that set and stays
//! 6-separating):
//! - the plane of `T` meets `D`: `|n·(c − v0)| ≤ h·‖n‖∞` (support of `D` is `h·‖n‖∞` where
//!   the box's is `h·‖n‖₁`);
//! - for **each** of the three axis-aligned projections, the projected triangle meets the
//!   projected diamond (a 2D diamond of radius `h`), tested exactly by the 2D separating axis
//!   theorem: the three projected edge normals `m` (support `h·‖m‖∞`) and the diamond's own edge
//!   normals `(1, ±1)` (support `h`); degenerate projections work as in 3D;
//! - the box axes (implied by the projections; a cheap early out).
//!
//! Schwarz & Seidel test the dominant projection only; testing all three (and the diamond's
//! axes) removes only voxels whose diamond the triangle misses. Same tie rule: touching counts.
//!
//! # Bit widths (what the WGSL port must emulate)
//! With snapped vertices `|v| ≤ 2^29` ([`super::lattice::COORD_LIMIT`]) and voxels inside a grid
//! of at most `2^20` voxels per axis (centres `0 < c < 2^28 + 2^7`):
//! | quantity | bound | type |
//! |---|---|---|
//! | `w = v − c`, edges `e` | `< 2^30` | `i32` |
//! | edge-axis projections `a·w` (2 products, sum) | `< 2^61` | `i64` |
//! | edge-axis radii `h·(|a1| + |a2|)` | `< 2^38` | `i64` |
//! | normal `n = e0 × e1` | `≤ 2^61` | `i64` |
//! | plane distance `n·w0` (3 products of 61×30 bits) | `< 2^93` | `i128` |
//! | plane radius `h·‖n‖₁` | `< 2^70` | `i128` |
//!
//! WGSL has only 32-bit integers: the port needs a 64-bit signed multiply-add built from
//! 32×32→64 partial products (`i64` rows), and a 96-bit accumulator for the plane test's three
//! 61×30-bit products (or, equivalently, an exact comparison of `n·w0` with `±h·‖n‖₁` by
//! multi-word arithmetic). Only signs and comparisons are used, never a division, so the result
//! is exact on any backend that computes these widths exactly.

use glam::{I64Vec3, IVec3};

use super::lattice::{HALF_VOXEL, VOXEL};

/// The triangle's vertices relative to the centre of `voxel`, and its edges, in `i64`.
#[inline]
fn relative(tri: &[IVec3; 3], voxel: IVec3) -> ([I64Vec3; 3], [I64Vec3; 3]) {
    let c = voxel.as_i64vec3() * VOXEL as i64 + HALF_VOXEL as i64;
    let w = tri.map(|v| v.as_i64vec3() - c);
    let e = [w[1] - w[0], w[2] - w[1], w[0] - w[2]];
    (w, e)
}

/// Whether the interval of the three projections `p` misses `[-r, r]` strictly.
#[inline]
fn separated(p: [i64; 3], r: i64) -> bool {
    p[0].min(p[1]).min(p[2]) > r || p[0].max(p[1]).max(p[2]) < -r
}

/// The triangle normal `e0 × e1` (not normalized; zero for degenerate triangles).
#[inline]
pub fn normal(tri: &[IVec3; 3]) -> I64Vec3 {
    let a = tri[0].as_i64vec3();
    (tri[1].as_i64vec3() - a).cross(tri[2].as_i64vec3() - a)
}

/// Separated along a box axis: the triangle's extent on some axis misses `[-h, h]`.
#[inline]
fn box_axes_separate(w: &[I64Vec3; 3], h: i64) -> bool {
    (0..3).any(|k| separated([w[0][k], w[1][k], w[2][k]], h))
}

/// The plane distance `n·w0` of the voxel centre (relative vertex `w0`), exactly.
#[inline]
fn plane_distance(n: I64Vec3, w0: I64Vec3) -> i128 {
    n.x as i128 * w0.x as i128 + n.y as i128 * w0.y as i128 + n.z as i128 * w0.z as i128
}

/// Conservative overlap: whether the closed triangle `tri` (snapped vertices) meets the closed
/// box of voxel `voxel` (voxel indices; the box is `voxel·VOXEL + [0, VOXEL]³`). Exact for any
/// triangle, including degenerate ones (segments and points); see the module docs for the tie
/// rule and the bit widths. Preconditions: vertices within `±COORD_LIMIT`, voxel indices within
/// `±2^21`.
pub fn box_overlap(tri: &[IVec3; 3], voxel: IVec3) -> bool {
    let h = HALF_VOXEL as i64;
    let (w, e) = relative(tri, voxel);
    if box_axes_separate(&w, h) {
        return false;
    }
    // Axes e_i × x̂_k = (0, e.z, −e.y), (−e.z, 0, e.x), (e.y, −e.x, 0): in the plane of the two
    // other axes (k1, k2) the axis is (e[k2], −e[k1]).
    for ei in e {
        for k in 0..3 {
            let (k1, k2) = ((k + 1) % 3, (k + 2) % 3);
            let (a1, a2) = (ei[k2], -ei[k1]);
            let p = w.map(|x| a1 * x[k1] + a2 * x[k2]);
            if separated(p, h * (a1.abs() + a2.abs())) {
                return false;
            }
        }
    }
    let n = e[0].cross(e[1]);
    let d = plane_distance(n, w[0]);
    let r = h as i128 * (n.x.abs() + n.y.abs() + n.z.abs()) as i128;
    -r <= d && d <= r
}

/// 6-separating ("thin") overlap: whether `tri` passes Schwarz & Seidel's diamond test for
/// `voxel` as refined in the module docs (plane meets the voxel's diamond, each axis-aligned
/// projection of the triangle meets the projected diamond). Same tie rule, widths and
/// preconditions as [`box_overlap`].
pub fn diamond_overlap(tri: &[IVec3; 3], voxel: IVec3) -> bool {
    let h = HALF_VOXEL as i64;
    let (w, e) = relative(tri, voxel);
    if box_axes_separate(&w, h) {
        return false;
    }
    for k in 0..3 {
        let (k1, k2) = ((k + 1) % 3, (k + 2) % 3);
        for ei in e {
            let (m1, m2) = (-ei[k2], ei[k1]);
            let p = w.map(|x| m1 * x[k1] + m2 * x[k2]);
            if separated(p, h * m1.abs().max(m2.abs())) {
                return false;
            }
        }
        if separated(w.map(|x| x[k1] + x[k2]), h) || separated(w.map(|x| x[k1] - x[k2]), h) {
            return false;
        }
    }
    let n = e[0].cross(e[1]);
    let d = plane_distance(n, w[0]);
    let r = h as i128 * n.x.abs().max(n.y.abs()).max(n.z.abs()) as i128;
    -r <= d && d <= r
}

#[cfg(test)]
mod tests;
