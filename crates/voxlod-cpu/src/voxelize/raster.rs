//! Per-triangle voxel enumeration: the voxels of a grid that one triangle overlaps, found
//! without testing every voxel of its bounding box.
//!
//! Schwarz & Seidel's formulation of the tests of [`super::overlap`]: per triangle, each of the
//! three axis-aligned projections becomes a few linear **constraints** `a·i + b·j + c ≥ 0` over
//! voxel indices (one per projected edge, with the critical corner of the box — or the support
//! of the diamond — folded into `c`; plus the diamond's own axes in thin mode), and the plane
//! test becomes an interval of voxels along the **dominant axis** `w` (largest `|n_w|`). The
//! triangle is then scanned column by column over its bounding box in the plane of the other
//! two axes: a column passes the dominant projection's constraints, its voxel interval along
//! `w` comes from the plane (at most `2 + (|n_a| + |n_b|)/|n_w| ≤ 4` voxels in conservative
//! mode, at most 2 in thin mode, whatever the triangle's size), and each voxel of the interval
//! checks the two other projections. Work is proportional to the columns of the projected
//! bounding box plus the voxels emitted, so a ground plane across 256² columns costs 256² cheap
//! column tests, not 256³ voxel tests.
//!
//! One-sided edge constraints are equivalent to the two-sided edge axes of the reference
//! because, in 2D, two disjoint convex polygons are always separated by an edge of one of them
//! *with that polygon on the inner side* (the Minkowski difference's edges are those of the box
//! or diamond and the reversed edges of the triangle). Orientation comes from the sign of the
//! projected area `n_k`; when `n_k = 0` the projection is a segment or a point, its nonzero edges
//! point both ways along the segment and the one-sided constraints become the two-sided test
//! along the segment's normal, as required. The tests compare this enumeration with the
//! reference on every voxel of small grids.

use std::ops::{Add, Mul, Neg};

use glam::{I64Vec3, IVec3, UVec3};

use super::lattice::{HALF_VOXEL, VOXEL, voxel_span};
use super::overlap::normal;

const V: i64 = VOXEL as i64;
const H: i64 = HALF_VOXEL as i64;

/// A constraint `a·i + b·j + c ≥ 0` over the voxel indices `(i, j)` of one projection.
/// Widths: `|a|, |b| ≤ 2^38`, `|c| < 2^62`, `|value| < 2^62` for voxels in a `2^20` grid.
#[derive(Clone, Copy, Debug, Default)]
struct Constraint {
    a: i64,
    b: i64,
    c: i64,
}

/// The constraints of one projection: 3 edges, plus 4 diamond axes in thin mode.
#[derive(Clone, Copy, Debug, Default)]
struct Projection {
    constraints: [Constraint; 7],
}

impl Projection {
    /// The projection onto the plane of the coordinates `uv` picks, in which the projected
    /// triangle has signed area of sign `s` (the normal's component along the dropped axis,
    /// `≥ 0` counting as positive).
    #[inline(always)]
    fn new<const THIN: bool>(v: &[I64Vec3; 3], s: i64, uv: impl Fn(I64Vec3) -> (i64, i64)) -> Self {
        let p = v.map(&uv);
        let mut out = Projection::default();
        for i in 0..3 {
            let (e1, e2) = (p[(i + 1) % 3].0 - p[i].0, p[(i + 1) % 3].1 - p[i].1);
            // Inward edge normal of the counter-clockwise oriented projection.
            let (m1, m2) = (-s * e2, s * e1);
            let on_edge = -(m1 * p[i].0 + m2 * p[i].1);
            let support = if THIN {
                m1 * H + m2 * H + H * m1.abs().max(m2.abs())
            } else {
                (m1 * V).max(0) + (m2 * V).max(0)
            };
            out.constraints[i] = Constraint { a: m1 * V, b: m2 * V, c: on_edge + support };
        }
        if THIN {
            let sum = p.map(|q| q.0 + q.1);
            let diff = p.map(|q| q.0 - q.1);
            let (smin, smax) = (sum[0].min(sum[1]).min(sum[2]), sum[0].max(sum[1]).max(sum[2]));
            let (dmin, dmax) =
                (diff[0].min(diff[1]).min(diff[2]), diff[0].max(diff[1]).max(diff[2]));
            out.constraints[3] = Constraint { a: V, b: V, c: 3 * H - smin };
            out.constraints[4] = Constraint { a: -V, b: -V, c: smax - H };
            out.constraints[5] = Constraint { a: V, b: -V, c: H - dmin };
            out.constraints[6] = Constraint { a: -V, b: V, c: dmax + H };
        }
        out
    }

    /// Whether voxel `(i, j)` of this projection satisfies every constraint.
    #[inline(always)]
    fn passes<const THIN: bool>(&self, i: i64, j: i64) -> bool {
        let n = if THIN { 7 } else { 3 };
        self.constraints[..n].iter().all(|c| c.a * i + c.b * j + c.c >= 0)
    }
}

/// The sign convention of [`Projection::new`].
#[inline(always)]
fn orientation(n: i64) -> i64 {
    if n >= 0 { 1 } else { -1 }
}

/// The integer type of the plane test: `i64` for small triangles, `i128` otherwise.
trait Wide: Copy + Ord + Add<Output = Self> + Mul<Output = Self> + Neg<Output = Self> {
    fn of(x: i64) -> Self;
    fn div_floor(self, d: Self) -> Self;
    fn saturate(self) -> i64;
}

impl Wide for i64 {
    #[inline(always)]
    fn of(x: i64) -> Self {
        x
    }
    #[inline(always)]
    fn div_floor(self, d: Self) -> Self {
        self.div_euclid(d)
    }
    #[inline(always)]
    fn saturate(self) -> i64 {
        self
    }
}

impl Wide for i128 {
    #[inline(always)]
    fn of(x: i64) -> Self {
        x as i128
    }
    #[inline(always)]
    fn div_floor(self, d: Self) -> Self {
        self.div_euclid(d)
    }
    #[inline(always)]
    fn saturate(self) -> i64 {
        self.clamp(i64::MIN as i128, i64::MAX as i128) as i64
    }
}

/// Largest triangle extent (lattice units) whose plane test runs in `i64`: relative to the
/// triangle's voxel range, `|n| ≤ 2E²`, offsets `≤ E + 2V`, so every value is below
/// `6·2^34·(2^17 + 2^9) < 2^56`.
const SMALL_EXTENT: i64 = 1 << 17;

/// The plane test as an interval along `z` (the working axis after permutation), relative to
/// the voxel `origin` of the triangle's range: with `x = ca·(i − o_x) + cb·(j − o_y) + c0` for
/// the column `(i, j)`, voxel `k` passes iff `x + d·(k − o_z) + lo ≤ 0 ≤ x + d·(k − o_z) + hi`
/// (`d = |n_z|·VOXEL > 0`). In `i128`, `|x| < 2^93`; in `i64` for triangles under
/// [`SMALL_EXTENT`]. Both are exact, so they agree.
#[derive(Clone, Copy, Debug)]
struct PlaneSpan<T> {
    origin: I64Vec3,
    ca: T,
    cb: T,
    c0: T,
    d: T,
    lo: T,
    hi: T,
}

impl<T: Wide> PlaneSpan<T> {
    #[inline(always)]
    fn new<const THIN: bool>(v: &[I64Vec3; 3], n: I64Vec3, origin: I64Vec3) -> Self {
        let s = T::of(n.z.signum());
        let centre = if THIN { H } else { 0 };
        let r = v[0] - origin * V;
        let w = |a: i64, b: i64| T::of(a) * T::of(b);
        let c0 = w(n.x, centre - r.x) + w(n.y, centre - r.y) + w(n.z, centre - r.z);
        let (lo, hi) = if THIN {
            let m = w(H, n.abs().max_element());
            (-m, m)
        } else {
            // n·VOXEL in `T`: |n| reaches 2^59 for triangles across the whole lattice, and
            // n·VOXEL (2^67) does not fit an i64 (the equivalence suite found this).
            let min = w(n.x.min(0), V) + w(n.y.min(0), V) + w(n.z.min(0), V);
            let max = w(n.x.max(0), V) + w(n.y.max(0), V) + w(n.z.max(0), V);
            if n.z > 0 { (min, max) } else { (-max, -min) }
        };
        PlaneSpan {
            origin,
            ca: s * w(n.x, V),
            cb: s * w(n.y, V),
            c0: s * c0,
            d: w(n.z.abs(), V),
            lo,
            hi,
        }
    }

    #[inline(always)]
    fn column(&self, i: i64, j: i64) -> T {
        self.ca * T::of(i - self.origin.x) + self.cb * T::of(j - self.origin.y) + self.c0
    }

    #[inline(always)]
    fn passes(&self, x: T, k: i64) -> bool {
        let y = x + self.d * T::of(k - self.origin.z);
        y + self.lo <= T::of(0) && T::of(0) <= y + self.hi
    }

    /// The voxels `k` of column value `x` that pass, as `(first, last)` (maybe empty).
    #[inline(always)]
    fn range(&self, x: T) -> (i64, i64) {
        let first = -(x + self.hi).div_floor(self.d);
        let last = (-x + -self.lo).div_floor(self.d);
        (
            first.saturate().saturating_add(self.origin.z),
            last.saturate().saturating_add(self.origin.z),
        )
    }
}

/// Calls `emit` once for every voxel of a `dims` grid that `tri` (snapped vertices) overlaps:
/// conservative ([`super::overlap::box_overlap`]) or, with `thin`, 6-separating
/// ([`super::overlap::diamond_overlap`]). Voxels come column by column, each exactly once.
#[inline]
pub fn for_each_voxel(tri: &[IVec3; 3], thin: bool, dims: UVec3, emit: impl FnMut(UVec3)) {
    if thin { raster::<true>(tri, dims, emit) } else { raster::<false>(tri, dims, emit) }
}

/// [`for_each_voxel`] for one mode.
///
/// The working axis `w` is chosen first and the coordinates permuted cyclically to
/// `(w+1, w+2, w)`, so that all later arithmetic uses fixed components (`z` is `w`); cyclic
/// permutations preserve orientation, so the permuted normal is the permuted normal.
/// Conservative mode has two exact shortcuts: a triangle inside one voxel's closed box overlaps
/// it; and a triangle inside one layer of voxels along some axis overlaps exactly the voxels of
/// that layer whose column its projection along that axis meets (the voxel is the column's
/// prism cut by the layer's slab, which holds the whole triangle), so only that projection's
/// constraints are evaluated.
#[inline(always)]
fn raster<const THIN: bool>(tri: &[IVec3; 3], dims: UVec3, mut emit: impl FnMut(UVec3)) {
    let lo_l = tri[0].min(tri[1]).min(tri[2]).to_array();
    let hi_l = tri[0].max(tri[1]).max(tri[2]).to_array();
    let dims_a = dims.to_array();
    let mut lo = [0i64; 3];
    let mut hi = [0i64; 3];
    let mut single = [false; 3];
    for k in 0..3 {
        let (s0, s1) = voxel_span(lo_l[k], hi_l[k]);
        single[k] = s0 == s1;
        lo[k] = (s0 as i64).max(0);
        hi[k] = (s1 as i64).min(dims_a[k] as i64 - 1);
        if lo[k] > hi[k] {
            return;
        }
    }
    if !THIN && single[0] && single[1] && single[2] {
        emit(UVec3::new(lo[0] as u32, lo[1] as u32, lo[2] as u32));
        return;
    }
    let layer = !THIN && (single[0] || single[1] || single[2]);
    let w = if layer {
        if single[2] {
            2
        } else if single[1] {
            1
        } else {
            0
        }
    } else {
        let n = normal(tri).abs();
        if n != I64Vec3::ZERO {
            if n.z >= n.x && n.z >= n.y {
                2
            } else if n.y >= n.x {
                1
            } else {
                0
            }
        } else {
            // Degenerate: columns along the longest extent keep the column count smallest.
            (0..3).max_by_key(|&k| (hi[k] - lo[k], k)).unwrap()
        }
    };
    let extent = (hi_l[0] - lo_l[0]).max(hi_l[1] - lo_l[1]).max(hi_l[2] - lo_l[2]) as i64;
    let range = (I64Vec3::from_array(lo), I64Vec3::from_array(hi));
    match w {
        0 => along::<THIN, 0>(tri, range, layer, extent, emit),
        1 => along::<THIN, 1>(tri, range, layer, extent, emit),
        _ => along::<THIN, 2>(tri, range, layer, extent, emit),
    }
}

/// The rest of [`raster`] with working axis `W`, permuted at compile time to `z`.
#[inline(always)]
fn along<const THIN: bool, const W: usize>(
    tri: &[IVec3; 3],
    (lo, hi): (I64Vec3, I64Vec3),
    layer: bool,
    extent: i64,
    mut emit: impl FnMut(UVec3),
) {
    let permute = |p: I64Vec3| match W {
        0 => I64Vec3::new(p.y, p.z, p.x),
        1 => I64Vec3::new(p.z, p.x, p.y),
        _ => p,
    };
    let mut put = |i: i64, j: i64, k: i64| {
        let (i, j, k) = (i as u32, j as u32, k as u32);
        emit(match W {
            0 => UVec3::new(k, i, j),
            1 => UVec3::new(j, k, i),
            _ => UVec3::new(i, j, k),
        })
    };
    let v = tri.map(|p| permute(p.as_i64vec3()));
    let (lo, hi) = (permute(lo), permute(hi));
    let (e0, e1) = (v[1] - v[0], v[2] - v[0]);
    let nz = e0.x * e1.y - e0.y * e1.x;
    let dominant = Projection::new::<THIN>(&v, orientation(nz), |p| (p.x, p.y));
    if layer {
        for j in lo.y..hi.y + 1 {
            for i in lo.x..hi.x + 1 {
                if dominant.passes::<THIN>(i, j) {
                    put(i, j, lo.z);
                }
            }
        }
        return;
    }
    let n = e0.cross(e1);
    let drop_x = Projection::new::<THIN>(&v, orientation(n.x), |p| (p.y, p.z));
    let drop_y = Projection::new::<THIN>(&v, orientation(n.y), |p| (p.z, p.x));
    let columns = Columns { lo, hi, dominant: &dominant, drop_x: &drop_x, drop_y: &drop_y };
    if n.z == 0 {
        columns.scan::<THIN, i64>(None, &mut put);
    } else if extent < SMALL_EXTENT {
        columns.scan::<THIN, i64>(Some(PlaneSpan::new::<THIN>(&v, n, lo)), &mut put);
    } else {
        columns.scan::<THIN, i128>(Some(PlaneSpan::new::<THIN>(&v, n, lo)), &mut put);
    }
}

/// The general case: the voxel range, in permuted coordinates, and the three projections.
struct Columns<'a> {
    lo: I64Vec3,
    hi: I64Vec3,
    dominant: &'a Projection,
    drop_x: &'a Projection,
    drop_y: &'a Projection,
}

impl Columns<'_> {
    /// Visits the columns passing the dominant projection, each over the voxels its plane
    /// interval allows (scanned when the range is shallow, divided out otherwise), checking
    /// the two other projections per voxel.
    #[inline(always)]
    fn scan<const THIN: bool, T: Wide>(
        &self,
        plane: Option<PlaneSpan<T>>,
        put: &mut impl FnMut(i64, i64, i64),
    ) {
        let (lo, hi) = (self.lo, self.hi);
        let shallow = hi.z - lo.z < 3;
        for j in lo.y..hi.y + 1 {
            for i in lo.x..hi.x + 1 {
                if !self.dominant.passes::<THIN>(i, j) {
                    continue;
                }
                let (mut k0, mut k1) = (lo.z, hi.z);
                let mut x = T::of(0);
                if let Some(p) = &plane {
                    x = p.column(i, j);
                    if !shallow {
                        let (first, last) = p.range(x);
                        k0 = k0.max(first);
                        k1 = k1.min(last);
                    }
                }
                for k in k0..k1 + 1 {
                    if shallow && plane.as_ref().is_some_and(|p| !p.passes(x, k)) {
                        continue;
                    }
                    if self.drop_x.passes::<THIN>(j, k) && self.drop_y.passes::<THIN>(k, i) {
                        put(i, j, k);
                    }
                }
            }
        }
    }
}

/// The voxels [`for_each_voxel`] emits, collected (for tests and equivalence checks).
pub fn voxels(tri: &[IVec3; 3], thin: bool, dims: UVec3) -> Vec<UVec3> {
    let mut out = Vec::new();
    for_each_voxel(tri, thin, dims, |c| out.push(c));
    out
}

#[cfg(test)]
mod tests;
