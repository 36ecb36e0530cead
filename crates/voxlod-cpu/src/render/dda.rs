//! A 3D DDA (Amanatides & Woo 1987) that walks a ray through the voxels of a [`GridSpec`] in
//! order, with each voxel's entry and exit `t`, and jumps over empty 8³ bricks in one step
//! (and over empty 2³-brick blocks, where the look-up knows them: [`DenseBricks`]).
//! Every voxel renderer and voxel shadow ray walks with it; its state is a few registers and
//! its loop has no recursion, so the WGSL mirror is the same code (the WGSL walks step brick
//! by brick; the block jumps reach the same voxels with the same `t`s, so they are a CPU-only
//! shortcut).
//!
//! [`DenseBricks`]: super::bricks::DenseBricks
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

use super::bricks::{BrickLookup, VoxelOccupancy};
use super::lanes::{trunc_index, trunc_ivec3, trunc_uvec3, trunc_vec3a};

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
///
/// Cells, steps and bounds are kept as integer-valued `f32` lanes (exact: grid coordinates
/// are below 2²¹, [`voxlod_format::morton::MAX_COORD`]), so a step is a handful of SIMD
/// instructions; the plane expression and hence every `t` is the same as with integers.
#[derive(Clone, Copy, Debug)]
pub struct Dda {
    /// Ray origin in grid coordinates, moved to where the ray enters the grid.
    origin: Vec3A,
    /// `1/d` per axis in grid coordinates, 0 for a parallel axis.
    inv: Vec3A,
    /// Direction in grid coordinates, with parallel components set to 0.
    dir: Vec3A,
    /// −1, 0 or 1 per axis; as integers for the scalar paths.
    step: Vec3A,
    step_i: IVec3,
    /// Axes with `step` 1.
    up: BVec3A,
    /// Per axis, the offset from a cell to the plane the ray crosses next (1 for `step` 1,
    /// else 0), and whether the ray is parallel to the axis's planes: the three crossing
    /// times of a cell in SIMD lanes ([`Dda::next_crossing`]).
    ahead: Vec3A,
    parallel: BVec3A,
    /// Grid size in voxels and in bricks.
    dims: Vec3A,
    brick_dims: Vec3A,
    cell: Vec3A,
    /// `t` relative to `origin` where the current voxel was entered.
    t: f32,
    /// Where the walk ends, relative to `origin`.
    t_end: f32,
    /// `t` of the world ray at `origin`.
    t_base: f32,
    /// The axes whose planes the ray crossed into the current voxel (none: it started there).
    entry_axes: u32,
    done: bool,
    /// The last brick looked up and its index (`u32::MAX`: unallocated).
    cached_brick: Vec3A,
    cached_index: u32,
}

impl Dda {
    /// Starts a walk of the ray `origin + t·dir`, `t ∈ [t_min, t_max]`, through `grid`.
    pub fn new(grid: &GridSpec, origin: Vec3, dir: Vec3, t_min: f32, t_max: f32) -> Self {
        let size = grid.voxel_size as f32;
        let o = ((origin.as_dvec3() - grid.origin) / grid.voxel_size).as_vec3();
        Self::in_grid_space(grid.dims, o, dir / size, t_min, t_max)
    }

    /// [`Dda::new`] for a ray already in grid coordinates: origin `o` in voxels from the
    /// grid's corner, direction `d` = world direction / voxel size (so `t` stays the world
    /// ray's parameter). A shadow ray starts at a voxel centre `c + ½` exactly this way.
    pub fn in_grid_space(dims: UVec3, o: Vec3, d: Vec3, t_min: f32, t_max: f32) -> Self {
        let dims_f = dims.as_vec3a();
        let mut dda = Self {
            origin: o.into(),
            inv: Vec3A::ZERO,
            dir: Vec3A::ZERO,
            step: Vec3A::ZERO,
            step_i: IVec3::ZERO,
            up: BVec3A::FALSE,
            ahead: Vec3A::ZERO,
            parallel: BVec3A::FALSE,
            dims: dims_f,
            brick_dims: ((dims + (BRICK_EDGE - 1)) / BRICK_EDGE).as_vec3a(),
            cell: Vec3A::ZERO,
            t: 0.0,
            t_end: 0.0,
            t_base: 0.0,
            entry_axes: 0,
            done: true,
            cached_brick: Vec3A::splat(-1.0),
            cached_index: u32::MAX,
        };
        if !(o.is_finite() && d.is_finite() && t_min <= t_max) {
            return dda;
        }
        // In SIMD lanes, each the expression of one axis.
        let (o, d) = (Vec3A::from(o), Vec3A::from(d));
        let parallel = d.abs().cmplt(Vec3A::splat(f32::MIN_POSITIVE));
        let d = Vec3A::select(parallel, Vec3A::ZERO, d);
        if d.cmpeq(Vec3A::ZERO).all() {
            return dda;
        }
        // Parallel axes must contain the origin.
        if (parallel & !(o.cmpge(Vec3A::ZERO) & o.cmplt(dims_f))).any() {
            return dda;
        }
        let up = d.cmpgt(Vec3A::ZERO);
        dda.step = Vec3A::select(
            up,
            Vec3A::ONE,
            Vec3A::select(d.cmplt(Vec3A::ZERO), Vec3A::NEG_ONE, Vec3A::ZERO),
        );
        dda.step_i = trunc_ivec3(dda.step);
        dda.up = up;
        dda.inv = Vec3A::select(parallel, Vec3A::ZERO, d.recip());
        dda.dir = d;
        dda.ahead = Vec3A::select(up, Vec3A::ONE, Vec3A::ZERO);
        dda.parallel = parallel;
        // Clip [t_min, t_max] to the grid box: the slab times of all axes at once, then the
        // axis-ordered comparisons (ties and signed zeros as one axis after the other).
        let (near, far) =
            (Vec3A::select(up, Vec3A::ZERO, dims_f), Vec3A::select(up, dims_f, Vec3A::ZERO));
        let (tn, tf) = (((near - o) * dda.inv).to_array(), ((far - o) * dda.inv).to_array());
        let (mut t0, mut t1) = (t_min, t_max);
        let mut entry_axis = None;
        for a in 0..3 {
            if parallel.test(a) {
                continue;
            }
            if tn[a] > t0 {
                t0 = tn[a];
                entry_axis = Some(a);
            }
            t1 = t1.min(tf[a]);
        }
        if t0 >= t1 {
            return dda;
        }
        // Re-origin at the entry point for precision; `t` values stay those of the world ray.
        let start = if t0.is_finite() { t0 } else { 0.0 };
        dda.origin = Vec3A::select(parallel, o, o + d * start);
        if let Some(a) = entry_axis {
            // Exactly on the entry face, so that its plane is crossed at t = 0.
            dda.origin[a] = if up.test(a) { 0.0 } else { dims_f[a] };
        }
        dda.t_base = start;
        dda.t = t0 - start;
        dda.t_end = t1 - start;
        dda.cell = dda.locate(dda.t, Vec3A::ZERO, dims_f - 1.0);
        dda.entry_axes = entry_axis.map_or(0, |a| 1 << a);
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
        match self.step_i[a] {
            1 => self.plane(a, cell + 1),
            -1 => self.plane(a, cell),
            _ => f32::INFINITY,
        }
    }

    /// The voxel holding the ray at `t`, searched in the box `[lo, hi]` (integer-valued
    /// lanes): per axis, the cell entered at or before `t` and left after it, by the plane
    /// expression of the stepping.
    #[inline]
    fn locate(&self, t: f32, lo: Vec3A, hi: Vec3A) -> Vec3A {
        // Truncation instead of `floor` (a libm call without SSE4.1): they differ only below
        // 0, where the clamp to `lo ≥ 0` makes them agree.
        let p = self.origin + self.dir * t;
        let c = trunc_ivec3(p).as_vec3a().clamp(lo, hi);
        // The float estimate is nearly always right: the fix-ups' two tests on all three axes
        // at once (lane by lane the plane expressions of the loops below), and only where one
        // of them fails the loops.
        let exit = (c + self.ahead - self.origin) * self.inv;
        let entry = (c + (Vec3A::ONE - self.ahead) - self.origin) * self.inv;
        let t = Vec3A::splat(t);
        let (near_end, far_end) = (Vec3A::select(self.up, lo, hi), Vec3A::select(self.up, hi, lo));
        let forward = c.cmpne(far_end) & exit.cmple(t);
        let back = c.cmpne(near_end) & entry.cmpgt(t);
        if ((forward | back) & !self.parallel).any() {
            self.locate_stepping(t.x, trunc_ivec3(c), trunc_ivec3(lo), trunc_ivec3(hi))
        } else {
            c
        }
    }

    /// The fix-ups of [`Dda::locate`] from the estimate `c`: at most a step or two per axis,
    /// bounded by the box.
    #[cold]
    fn locate_stepping(&self, t: f32, mut c: IVec3, lo: IVec3, hi: IVec3) -> Vec3A {
        for a in 0..3 {
            let s = self.step_i[a];
            if s == 0 {
                continue;
            }
            // The planes a cell is entered and left through, and the search bounds.
            let enter = |c: i32| if s > 0 { c } else { c + 1 };
            let (near_end, far_end) = if s > 0 { (lo[a], hi[a]) } else { (hi[a], lo[a]) };
            while c[a] != far_end && self.next_t(a, c[a]) <= t {
                c[a] += s;
            }
            while c[a] != near_end && self.plane(a, enter(c[a])) > t {
                c[a] -= s;
            }
        }
        c.as_vec3a()
    }

    /// The earliest plane crossing after `cell`: its `t` and the axes that cross there.
    #[inline(always)]
    fn next_crossing(&self, cell: Vec3A) -> (f32, BVec3A) {
        // `next_t` of the three axes at once: lane by lane the same plane expression.
        let ts = Vec3A::select(
            self.parallel,
            Vec3A::INFINITY,
            (cell + self.ahead - self.origin) * self.inv,
        );
        let t = ts.min_element();
        (t, ts.cmpeq(Vec3A::splat(t)))
    }

    /// Whether `cell` lies outside the grid.
    #[inline(always)]
    fn outside(&self, cell: Vec3A) -> bool {
        (cell.cmplt(Vec3A::ZERO) | cell.cmpge(self.dims)).any()
    }

    /// Entry normal for crossing the planes of `axes` (the largest `|dir|` among them; zero
    /// for none).
    #[inline(always)]
    fn normal_for(&self, axes: u32) -> IVec3 {
        let mut n = IVec3::ZERO;
        if axes == 0 {
            return n;
        }
        if axes.is_power_of_two() {
            // One axis crossed (all but edge and corner crossings): no choice to make.
            let a = axes.trailing_zeros() as usize;
            n[a] = -self.step_i[a];
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
        n[best] = -self.step_i[best];
        n
    }

    /// The current voxel, then advances past it.
    #[inline]
    fn emit_and_advance(&mut self, brick: u32) -> DdaVoxel {
        let (t_next, axes) = self.next_crossing(self.cell);
        let v = DdaVoxel {
            voxel: trunc_uvec3(self.cell),
            t_enter: self.t_base + self.t,
            t_exit: self.t_base + t_next.min(self.t_end),
            entry_normal: self.normal_for(self.entry_axes),
            brick,
        };
        self.advance(t_next, axes);
        v
    }

    /// Crosses the planes of `axes` at `t` into the next voxel; ends the walk past the grid
    /// or past `t_end`.
    #[inline(always)]
    fn advance(&mut self, t: f32, axes: BVec3A) {
        let cell = self.cell + Vec3A::select(axes, self.step, Vec3A::ZERO);
        if t >= self.t_end || self.outside(cell) {
            self.done = true;
            return;
        }
        self.entry_axes = axes.bitmask();
        self.cell = cell;
        self.t = t;
    }

    /// The brick holding the current cell (cells are non-negative: truncation is the floor).
    #[inline(always)]
    fn brick(&self) -> Vec3A {
        trunc_vec3a(self.cell * (1.0 / BRICK_EDGE as f32))
    }

    /// Looks up the current cell's brick if it changed; skips it (and every following empty
    /// brick) if it is unallocated. False if the walk ended.
    #[inline(always)]
    fn enter_brick(&mut self, lookup: &impl BrickLookup) -> bool {
        let b = self.brick();
        if b.cmpne(self.cached_brick).any() {
            self.cached_brick = b;
            self.cached_index = lookup.brick_index_f(b).unwrap_or(u32::MAX);
            if self.cached_index == u32::MAX {
                return self.skip_empty_bricks(b, lookup);
            }
        }
        true
    }

    /// The next voxel in an allocated brick (see [`BrickLookup`]), with that brick's index;
    /// the voxels of unallocated bricks are jumped over.
    #[inline]
    pub fn next_occupied_brick(&mut self, lookup: &impl BrickLookup) -> Option<DdaVoxel> {
        if self.done || !self.enter_brick(lookup) {
            return None;
        }
        Some(self.emit_and_advance(self.cached_index))
    }

    /// The next **occupied** voxel: as [`Dda::next_occupied_brick`] followed by the voxel test
    /// of `occupancy`, with the same voxels, `t`s and entry normals, but the empty voxels of
    /// an allocated brick are stepped over without being returned, and its empty 2³ blocks
    /// are crossed in one jump (as empty bricks are: exit planes by the one expression, then
    /// the cell at the exit `t`).
    #[inline]
    pub fn next_occupied_voxel(&mut self, occupancy: &impl VoxelOccupancy) -> Option<DdaVoxel> {
        loop {
            if self.done || !self.enter_brick(occupancy) {
                return None;
            }
            let masks = occupancy.masks(self.cached_index);
            // Linear index x + 8y + 64z of the cell in its brick: one conversion.
            let local = self.cell - self.cached_brick * BRICK_EDGE as f32;
            let linear = trunc_index(local.dot(Vec3A::new(1.0, 8.0, 64.0))) as u32;
            if masks.has_voxel_linear(linear) {
                return Some(self.emit_and_advance(self.cached_index));
            }
            if masks.has_block_linear(linear) {
                let (t_next, axes) = self.next_crossing(self.cell);
                self.advance(t_next, axes);
            } else {
                self.skip_block();
            }
        }
    }

    /// Leaves the 2³ block (blocks are aligned to even coordinates, so never straddle a brick)
    /// holding the current cell: the cell becomes the one the ray enters at the block's exit
    /// `t`, as stepping voxel by voxel would reach it; ends the walk if that is past its end.
    #[inline]
    fn skip_block(&mut self) {
        let lo = trunc_vec3a(self.cell * 0.5) * 2.0;
        let hi = (lo + 1.0).min(self.dims - 1.0);
        let exit_cell = Vec3A::select(self.up, hi, lo);
        let (t_exit, axes) = self.next_crossing(exit_cell);
        let next = exit_cell + Vec3A::select(axes, self.step, Vec3A::ZERO);
        if t_exit >= self.t_end || self.outside(next) {
            self.done = true;
            return;
        }
        // On the other axes the ray stays in the block: past its middle plane `lo + 1` iff it
        // crosses that plane at or before `t_exit` (the locate rule of the voxel stepping).
        let mid =
            Vec3A::select(self.parallel, Vec3A::INFINITY, (lo + 1.0 - self.origin) * self.inv);
        let t = Vec3A::splat(t_exit);
        // Near half: `lo` going up, `lo + 1` going down; the far half the other one.
        let near = Vec3A::select(self.up, lo, lo + 1.0);
        let inside = near + Vec3A::select(mid.cmple(t), self.step, Vec3A::ZERO);
        let stay = Vec3A::select(self.parallel, self.cell, inside);
        self.cell = Vec3A::select(axes, next, stay);
        self.entry_axes = axes.bitmask() | mid.cmpeq(t).bitmask();
        self.t = t_exit;
    }

    /// Moves to the cell of `[lo, hi]` that the ray is in at `t`, reached by crossing the
    /// planes of `axes` at `t`: located by the plane expression of the voxel stepping, its
    /// entry axes every axis whose plane is crossed at exactly `t`, as stepping voxel by voxel
    /// would step them.
    fn enter_at(&mut self, t: f32, axes: u32, lo: Vec3A, hi: Vec3A) {
        let cell = self.locate(t, lo, hi);
        // The entry plane of each axis (`cell` going up, `cell + 1` going down), lane by lane
        // the expression of `plane`.
        let entry = (cell + (Vec3A::ONE - self.ahead) - self.origin) * self.inv;
        let crossed = entry.cmpeq(Vec3A::splat(t)) & !self.parallel;
        self.cell = cell;
        self.entry_axes = axes | crossed.bitmask();
        self.t = t;
    }

    /// From the current voxel, in the unallocated brick `b`, steps brick by brick to the first
    /// allocated one and enters it: its voxel where the ray enters it, located by the plane
    /// expression of the voxel stepping, so the result is what stepping voxel by voxel would
    /// reach. Returns false (and ends the walk) if the ray leaves the grid or ends first.
    ///
    /// Where the look-up says the 2³-brick block around an empty brick is empty
    /// ([`BrickLookup::empty_block_f`]), the whole block is crossed in one jump, as
    /// [`Dda::skip_block`] crosses an empty 2³-voxel block: its exit plane by the one
    /// expression, and on the other axes the half of the block the ray is in at that `t` (past
    /// the block's middle plane iff it crosses it at or before then) — the brick that stepping
    /// brick by brick reaches.
    fn skip_empty_bricks(&mut self, mut b: Vec3A, lookup: &impl BrickLookup) -> bool {
        let edge = BRICK_EDGE as f32;
        loop {
            let (t_exit, axes) = if lookup.empty_block_f(b) {
                let (t_exit, axes, next) = self.block_exit(b);
                b = next;
                (t_exit, axes)
            } else {
                let lo = b * edge;
                let hi = (lo + edge).min(self.dims) - 1.0;
                let exit_cell = Vec3A::select(self.up, hi, lo);
                let (t_exit, axes) = self.next_crossing(exit_cell);
                b += Vec3A::select(axes, self.step, Vec3A::ZERO);
                (t_exit, axes)
            };
            if t_exit >= self.t_end || (b.cmplt(Vec3A::ZERO) | b.cmpge(self.brick_dims)).any() {
                self.done = true;
                return false;
            }
            let Some(index) = lookup.brick_index_f(b) else { continue };
            let lo = b * edge;
            let hi = (lo + edge).min(self.dims) - 1.0;
            self.enter_at(t_exit, axes.bitmask(), lo, hi);
            self.cached_brick = b;
            self.cached_index = index;
            return true;
        }
    }

    /// Where the ray leaves the 2³-brick block holding brick `b` (which it is in): the `t`, the
    /// axes whose planes it crosses there, and the brick it enters then — on the axes crossed,
    /// the brick past the block; on the others, the block's near or far half by its middle
    /// plane (see [`Dda::skip_empty_bricks`]). A block cut by the grid's end has one brick on
    /// that axis, and the rule gives that brick: going down the ray is past the middle plane
    /// already, going up it leaves the grid before reaching it.
    #[inline]
    fn block_exit(&self, b: Vec3A) -> (f32, BVec3A, Vec3A) {
        let edge = BRICK_EDGE as f32;
        let first = trunc_vec3a(b * 0.5) * 2.0;
        let last = (first + 1.0).min(self.brick_dims - 1.0);
        let exit_brick = Vec3A::select(self.up, last, first);
        let lo = exit_brick * edge;
        let hi = (lo + edge).min(self.dims) - 1.0;
        let (t_exit, axes) = self.next_crossing(Vec3A::select(self.up, hi, lo));
        let mid = Vec3A::select(
            self.parallel,
            Vec3A::INFINITY,
            ((first + 1.0) * edge - self.origin) * self.inv,
        );
        let near = Vec3A::select(self.up, first, first + 1.0);
        let inside = near + Vec3A::select(mid.cmple(Vec3A::splat(t_exit)), self.step, Vec3A::ZERO);
        let stay = Vec3A::select(self.parallel, b, inside);
        (t_exit, axes, Vec3A::select(axes, exit_brick + self.step, stay))
    }
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
mod tests;
