//! A 3D DDA (Amanatides & Woo 1987) that walks a ray through the voxels of a [`GridSpec`] in
//! order, with each voxel's entry and exit `t`, and jumps over empty 8³ bricks in one step.
//! Every voxel renderer and voxel shadow ray walks with it; its state is a few registers and
//! its loop has no recursion, so the WGSL mirror is the same code.
//!
//! # Conventions and tie rules
//! - `t` is the parameter of the world-space ray `origin + t·dir` (a distance for a unit `dir`).
//! - Boundary plane `k` of an axis (grid coordinate `k`) is crossed at `(k − o)·(1/d)`, always
//!   computed by that one expression (never by accumulating `Δt`), so stepping voxel by voxel
//!   and jumping over a brick reach the same voxels with bit-identical `t`.
//! - A voxel is visited when the ray's segment inside it has positive length. Where the ray
//!   crosses several planes at the same `t` (through an edge or a corner), all those axes step
//!   at once: the voxels that the ray only touches are not visited, so a ray along a diagonal
//!   through corners visits `(k, k, k)` only.
//! - A direction component that is zero or denormal is treated as exactly zero (the ray is
//!   parallel to those planes); a ray lying in a boundary plane belongs to the voxel on the
//!   plane's `+` side (the half-open `[i, i+1)` convention of [`GridSpec`]).
//! - Where a ray starts exactly on a plane, the voxel it moves into is the first one visited.
//! - A zero, NaN or infinite direction, or a non-finite origin, visits nothing.
//!
//! The ray is moved to grid coordinates on the host (origin in `f64`, then `f32`) and
//! re-based at its grid entry point, so a camera far from the grid keeps full precision; a
//! WGSL port receives the same `f32` grid-space ray or computes it the same way in `f32`.

use glam::{BVec3A, IVec3, UVec3, Vec3, Vec3A};
use voxlod_format::{BRICK_EDGE, GridSpec};

use super::bricks::BrickLookup;

/// One voxel along a ray.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DdaVoxel {
    /// Voxel coordinate.
    pub voxel: UVec3,
    /// Ray parameter where the ray enters the voxel (or starts, if it starts inside).
    pub t_enter: f32,
    /// Ray parameter where it leaves the voxel (or ends).
    pub t_exit: f32,
    /// Outward normal of the face the ray entered through (`−step` along the entry axis; when
    /// it crossed an edge or corner, the axis of the largest `|dir|` component among those
    /// crossed); zero when the ray started inside this voxel.
    pub entry_normal: IVec3,
    /// Index of the voxel's brick in the lookup's brick list, when walked with
    /// [`Dda::next_occupied_brick`]; `u32::MAX` from plain iteration.
    pub brick: u32,
}

/// The state of one ray's walk. Use it as an [`Iterator`] over every voxel, or call
/// [`Dda::next_occupied_brick`] to skip empty bricks.
#[derive(Clone, Copy, Debug)]
pub struct Dda {
    /// Ray origin in grid coordinates, moved to where the ray enters the grid.
    origin: Vec3A,
    /// `1/d` per axis in grid coordinates, 0 for a parallel axis.
    inv: Vec3A,
    /// Direction in grid coordinates, with parallel components set to 0.
    dir: Vec3A,
    step: IVec3,
    /// Per axis, the offset from a cell to the plane the ray crosses next (1 for `step` 1,
    /// else 0), and whether the ray is parallel to the axis's planes: the three crossing
    /// times of a cell in SIMD lanes ([`Dda::next_crossing`]).
    ahead: IVec3,
    parallel: BVec3A,
    dims: IVec3,
    cell: IVec3,
    /// `t` relative to `origin` where the current voxel was entered.
    t: f32,
    /// Where the walk ends, relative to `origin`.
    t_end: f32,
    /// `t` of the world ray at `origin`.
    t_base: f32,
    entry_normal: IVec3,
    done: bool,
    /// The last brick looked up and its index (`u32::MAX`: unallocated).
    cached_brick: IVec3,
    cached_index: u32,
}

impl Dda {
    /// Starts a walk of the ray `origin + t·dir`, `t ∈ [t_min, t_max]`, through `grid`.
    pub fn new(grid: &GridSpec, origin: Vec3, dir: Vec3, t_min: f32, t_max: f32) -> Self {
        let size = grid.voxel_size as f32;
        let o = ((origin.as_dvec3() - grid.origin) / grid.voxel_size).as_vec3();
        let d = dir / size;
        let dims = grid.dims.as_ivec3();
        let mut dda = Self {
            origin: o.into(),
            inv: Vec3A::ZERO,
            dir: Vec3A::ZERO,
            step: IVec3::ZERO,
            ahead: IVec3::ZERO,
            parallel: BVec3A::FALSE,
            dims,
            cell: IVec3::ZERO,
            t: 0.0,
            t_end: 0.0,
            t_base: 0.0,
            entry_normal: IVec3::ZERO,
            done: true,
            cached_brick: IVec3::splat(-1),
            cached_index: u32::MAX,
        };
        if !(o.is_finite() && d.is_finite() && t_min <= t_max) {
            return dda;
        }
        let parallel = d.abs().cmplt(Vec3::splat(f32::MIN_POSITIVE));
        let d = Vec3::select(parallel, Vec3::ZERO, d);
        if d == Vec3::ZERO {
            return dda;
        }
        dda.step = IVec3::select(parallel, IVec3::ZERO, d.signum().as_ivec3());
        dda.inv = Vec3::select(parallel, Vec3::ZERO, d.recip()).into();
        dda.dir = d.into();
        dda.ahead = IVec3::select(dda.step.cmpgt(IVec3::ZERO), IVec3::ONE, IVec3::ZERO);
        dda.parallel = BVec3A::new(parallel.x, parallel.y, parallel.z);
        // Clip [t_min, t_max] to the grid box; parallel axes must contain the origin.
        let (mut t0, mut t1) = (t_min, t_max);
        let mut entry_axis = None;
        for a in 0..3 {
            if parallel.test(a) {
                if !(o[a] >= 0.0 && o[a] < dims[a] as f32) {
                    return dda;
                }
                continue;
            }
            let (near, far) =
                if d[a] > 0.0 { (0.0, dims[a] as f32) } else { (dims[a] as f32, 0.0) };
            let tn = (near - o[a]) * dda.inv[a];
            let tf = (far - o[a]) * dda.inv[a];
            if tn > t0 {
                t0 = tn;
                entry_axis = Some(a);
            }
            t1 = t1.min(tf);
        }
        if t0 >= t1 {
            return dda;
        }
        // Re-origin at the entry point for precision; `t` values stay those of the world ray.
        let start = if t0.is_finite() { t0 } else { 0.0 };
        dda.origin = Vec3::select(parallel, o, o + d * start).into();
        if let Some(a) = entry_axis {
            // Exactly on the entry face, so that its plane is crossed at t = 0.
            dda.origin[a] = if d[a] > 0.0 { 0.0 } else { dims[a] as f32 };
        }
        dda.t_base = start;
        dda.t = t0 - start;
        dda.t_end = t1 - start;
        let lo = IVec3::ZERO;
        let hi = dims - 1;
        dda.cell = dda.locate(dda.t, lo, hi);
        if let Some(a) = entry_axis {
            dda.entry_normal[a] = -dda.step[a];
        }
        dda.done = false;
        dda
    }

    /// `t` (relative to the re-based origin) where the ray crosses plane `k` of axis `a`.
    #[inline(always)]
    fn plane(&self, a: usize, k: i32) -> f32 {
        (k as f32 - self.origin[a]) * self.inv[a]
    }

    /// `t` where the ray leaves `cell` along axis `a` (infinite for a parallel axis).
    #[inline(always)]
    fn next_t(&self, a: usize, cell: i32) -> f32 {
        match self.step[a] {
            1 => self.plane(a, cell + 1),
            -1 => self.plane(a, cell),
            _ => f32::INFINITY,
        }
    }

    /// The voxel holding the ray at `t`, searched in the box `[lo, hi]`: per axis, the cell
    /// entered at or before `t` and left after it, by the plane expression of the stepping.
    fn locate(&self, t: f32, lo: IVec3, hi: IVec3) -> IVec3 {
        // Truncation instead of `floor` (a libm call without SSE4.1): they differ only below
        // 0, where the clamp to `lo ≥ 0` makes them agree.
        let p = self.origin + self.dir * t;
        let mut c = p.as_ivec3().clamp(lo, hi);
        for a in 0..3 {
            let s = self.step[a];
            if s == 0 {
                continue;
            }
            // The planes a cell is entered and left through, and the search bounds.
            let enter = |c: i32| if s > 0 { c } else { c + 1 };
            let (near_end, far_end) = if s > 0 { (lo[a], hi[a]) } else { (hi[a], lo[a]) };
            // Fix-ups of the float estimate: at most a step or two, bounded by the box.
            while c[a] != far_end && self.next_t(a, c[a]) <= t {
                c[a] += s;
            }
            while c[a] != near_end && self.plane(a, enter(c[a])) > t {
                c[a] -= s;
            }
        }
        c
    }

    /// The earliest plane crossing after the current voxel: its `t` and the axes that cross
    /// there (a bit mask).
    #[inline(always)]
    fn next_crossing(&self, cell: IVec3) -> (f32, u32) {
        // `next_t` of the three axes at once: lane by lane the same plane expression.
        let k = (cell + self.ahead).as_vec3a();
        let ts = Vec3A::select(self.parallel, Vec3A::INFINITY, (k - self.origin) * self.inv);
        let t = ts.min_element();
        (t, ts.cmpeq(Vec3A::splat(t)).bitmask())
    }

    /// Entry normal for crossing the planes of `axes` (the largest `|dir|` among them).
    #[inline(always)]
    fn normal_for(&self, axes: u32) -> IVec3 {
        let mut n = IVec3::ZERO;
        if axes.is_power_of_two() {
            // One axis crossed (all but edge and corner crossings): no choice to make.
            let a = axes.trailing_zeros() as usize;
            n[a] = -self.step[a];
            return n;
        }
        let mut best = 0;
        let mut best_d = -1.0;
        for a in 0..3 {
            if axes & (1 << a) != 0 && self.dir[a].abs() > best_d {
                best = a;
                best_d = self.dir[a].abs();
            }
        }
        n[best] = -self.step[best];
        n
    }

    /// The current voxel, then advances past it.
    #[inline]
    fn emit_and_advance(&mut self, brick: u32) -> DdaVoxel {
        let (t_next, axes) = self.next_crossing(self.cell);
        let v = DdaVoxel {
            voxel: self.cell.as_uvec3(),
            t_enter: self.t_base + self.t,
            t_exit: self.t_base + t_next.min(self.t_end),
            entry_normal: self.entry_normal,
            brick,
        };
        self.advance_to(t_next, axes, self.cell + self.step * axes_mask(axes));
        v
    }

    /// Moves to `cell`, entered at `t` through the planes of `axes`; ends the walk past the
    /// grid or past `t_end`.
    #[inline(always)]
    fn advance_to(&mut self, t: f32, axes: u32, cell: IVec3) {
        if t >= self.t_end || cell.cmplt(IVec3::ZERO).any() || cell.cmpge(self.dims).any() {
            self.done = true;
            return;
        }
        self.entry_normal = self.normal_for(axes);
        self.cell = cell;
        self.t = t;
    }

    /// The next voxel whose brick `lookup` reports allocated, walking brick by brick over
    /// unallocated bricks (one step and one look-up per brick); `None` at the end of the ray.
    #[inline]
    pub fn next_occupied_brick(&mut self, lookup: &impl BrickLookup) -> Option<DdaVoxel> {
        if self.done {
            return None;
        }
        let b = self.cell / BRICK_EDGE as i32;
        if b != self.cached_brick {
            self.cached_brick = b;
            self.cached_index = lookup.brick_index(b.as_uvec3()).unwrap_or(u32::MAX);
        }
        if self.cached_index == u32::MAX && !self.skip_empty_bricks(b, lookup) {
            return None;
        }
        Some(self.emit_and_advance(self.cached_index))
    }

    /// From the current voxel, in the unallocated brick `b`, steps brick by brick to the first
    /// allocated one and enters it: its voxel where the ray enters it, located by the plane
    /// expression of the voxel stepping, so the result is what stepping voxel by voxel would
    /// reach. Returns false (and ends the walk) if the ray leaves the grid or ends first.
    fn skip_empty_bricks(&mut self, mut b: IVec3, lookup: &impl BrickLookup) -> bool {
        let edge = BRICK_EDGE as i32;
        let brick_dims = (self.dims + edge - 1) / edge;
        loop {
            let lo = b * edge;
            let hi = (lo + edge).min(self.dims) - 1;
            let exit_cell = IVec3::select(self.step.cmpgt(IVec3::ZERO), hi, lo);
            let (t_exit, axes) = self.next_crossing(exit_cell);
            b += self.step * axes_mask(axes);
            if t_exit >= self.t_end || b.cmplt(IVec3::ZERO).any() || b.cmpge(brick_dims).any() {
                self.done = true;
                return false;
            }
            let Some(index) = lookup.brick_index(b.as_uvec3()) else { continue };
            let lo = b * edge;
            let hi = (lo + edge).min(self.dims) - 1;
            self.cell = self.locate(t_exit, lo, hi);
            // The axes whose planes the ray crosses at t_exit, as voxel stepping would step them.
            let mut entered = 0;
            for a in 0..3 {
                let s = self.step[a];
                let enter = if s > 0 { self.cell[a] } else { self.cell[a] + 1 };
                if s != 0 && self.plane(a, enter) == t_exit {
                    entered |= 1 << a;
                }
            }
            self.entry_normal = self.normal_for(entered | axes);
            self.t = t_exit;
            self.cached_brick = b;
            self.cached_index = index;
            return true;
        }
    }
}

#[inline(always)]
fn axes_mask(axes: u32) -> IVec3 {
    IVec3::new((axes & 1) as i32, (axes >> 1 & 1) as i32, (axes >> 2 & 1) as i32)
}

impl Iterator for Dda {
    type Item = DdaVoxel;

    /// The next voxel along the ray, with no brick skipping.
    #[inline]
    fn next(&mut self) -> Option<DdaVoxel> {
        if self.done {
            return None;
        }
        Some(self.emit_and_advance(u32::MAX))
    }
}

#[cfg(test)]
#[path = "dda_tests.rs"]
mod tests;
