//! What the slicemap's uses read from it: occupied slices in front of a point (transmittance
//! shadow maps, Eisemann and Décoret 2006, §3.1) and the inner voxels of a column from its
//! front and back layers (the traversed volume for refraction, §3.3).
//!
//! Both are integer functions of the bits once a point's slice is known, computed with shifts
//! and population counts (the paper's "cellmask" and "summask" lookup textures stood in for the
//! integer operations its hardware lacked); voxlod-gpu's query kernel mirrors them exactly.
//!
//! # Occluders in front of a point
//! [`Slicemap::count_nearer`]: in column `(x, y)` with range `[lo, hi]`, a point at `d < lo`
//! has none, a point at `d > hi` has every occupied slice of the column; otherwise its slice
//! `s` is found as a fragment's is and the bits `j < s` are counted (`s mod 2^s` in the
//! paper's words): the point's own slice does not shadow it. An empty local column has none.
//!
//! # Inner voxels (Fig. 9)
//! [`inner_voxels`] walks a column from near to far over its non-empty voxels only (lowest set
//! bit first), a voxel being *front* (its bit set in the front layer only), *back* (back
//! layer only) or *ambiguous* (both), with a state outside / inside / unresolved:
//! - a front voxel enters: it counts as inner, and so do the empty voxels after it;
//! - a back voxel leaves: it does not count (front counted and back not, the count of an
//!   interval from slice `i` to slice `j` is `j − i`, unbiased for surfaces uniformly placed
//!   in their voxels);
//! - an ambiguous voxel counts as inner whole (the paper's choice); the empty voxels after it
//!   stay unresolved until the next non-empty voxel: a back voxel means they were inside
//!   (Fig. 9 (b) read backwards: counted), a front voxel that they were outside (not counted),
//!   another ambiguous voxel leaves them unknown and they are not counted (Fig. 9 (c)/(d), the
//!   paper's choice);
//! - a back voxel while outside, or a front voxel while inside (a missed surface), changes
//!   nothing but the state as above; after the last non-empty voxel, inside counts the empty
//!   voxels to the end of the column, unresolved ones are dropped;
//! - with local slicing (`far_end` set), the column's farthest fragment lies exactly at the far
//!   end of the last slice, so a back voxel there counts whole: a convex object seen through a
//!   local column then measures exactly `slices` voxels.

use glam::DVec3;

use super::{Faces, Slicemap, normalized, slice_of};

/// A point located in a map's column: `(x, y)` and its depth `d = z − near` (`f32`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Located {
    /// Column x.
    pub x: u32,
    /// Column y.
    pub y: u32,
    /// Depth below the near plane, `z − near`, in `f32` as the kernels compare it.
    pub d: f32,
}

/// Number of set bits of `words` (slices `32w + i`) below slice `s`.
#[inline]
pub fn count_below(words: &[u32], s: u32) -> u32 {
    let mut n = 0;
    for (w, &word) in words.iter().enumerate() {
        let base = w as u32 * 32;
        if base + 32 <= s {
            n += word.count_ones();
        } else if base < s {
            n += (word & ((1u32 << (s - base)) - 1)).count_ones();
        }
    }
    n
}

impl Slicemap {
    /// The column and depth of world point `p`; `None` outside the map's columns or, for a
    /// perspective map, at or behind the eye.
    pub fn locate(&self, p: DVec3) -> Option<Located> {
        let frame = self.camera.frame();
        let (w, z) = frame.project(p)?;
        let (x, y) = (w.x.floor(), w.y.floor());
        if !(x >= 0.0 && y >= 0.0 && x < self.camera.width as f64 && y < self.camera.height as f64)
        {
            return None;
        }
        Some(Located { x: x as u32, y: y as u32, d: (z as f32) - self.camera.near as f32 })
    }

    /// Occupied slices of `layer` in column `(x, y)` strictly nearer than depth `d` (module
    /// docs).
    pub fn count_nearer(&self, layer: u32, x: u32, y: u32, d: f32) -> u32 {
        let words = self.column(layer, x, y);
        let Some((lo, hi)) = self.range(x, y) else { return 0 };
        if d.is_nan() || d < lo {
            return 0;
        }
        if d > hi {
            return words.iter().map(|w| w.count_ones()).sum();
        }
        count_below(words, slice_of(normalized(d, lo, hi), self.options.slices))
    }

    /// Occupied slices of `layer` between world point `p` and the camera (a light); `None`
    /// when `p` is outside the map.
    pub fn occluders(&self, layer: u32, p: DVec3) -> Option<u32> {
        let l = self.locate(p)?;
        Some(self.count_nearer(layer, l.x, l.y, l.d))
    }

    /// Inner voxels of column `(x, y)` (module docs); `None` unless the map has front and back
    /// layers ([`Faces::Split`]).
    pub fn inner_voxels(&self, x: u32, y: u32) -> Option<u32> {
        (self.options.faces == Faces::Split).then(|| {
            let local = self.ranges.is_some();
            inner_voxels(self.column(0, x, y), self.column(1, x, y), self.options.slices, local)
        })
    }

    /// Length of the eye ray through the centre of pixel `(x, y)` inside the object:
    /// inner voxels × slice depth (column range / slices) / cos of the ray's angle with the
    /// view axis. `None` without front and back layers; 0 for an empty column.
    pub fn thickness(&self, x: u32, y: u32) -> Option<f64> {
        let inner = self.inner_voxels(x, y)?;
        let Some((lo, hi)) = self.range(x, y) else { return Some(0.0) };
        let frame = self.camera.frame();
        let (_, dir) = frame.ray(glam::DVec2::new(x as f64 + 0.5, y as f64 + 0.5));
        let slice = (hi as f64 - lo as f64) / self.options.slices as f64;
        Some(inner as f64 * slice / dir.dot(frame.forward))
    }
}

/// The inner voxels of one column from its `front` and `back` words over `slices` slices
/// (module docs, Fig. 9 rules); `far_end`: the column is sliced locally, so its last slice
/// ends at its farthest fragment.
pub fn inner_voxels(front: &[u32], back: &[u32], slices: u32, far_end: bool) -> u32 {
    #[derive(Clone, Copy, PartialEq)]
    enum State {
        Outside,
        Inside,
        Unresolved,
    }
    let mut state = State::Outside;
    let (mut count, mut pending) = (0u32, 0u32);
    let mut last: i64 = -1;
    for (w, (&f, &b)) in front.iter().zip(back).enumerate() {
        let mut events = f | b;
        while events != 0 {
            let i = events.trailing_zeros();
            events &= events - 1;
            let s = w as i64 * 32 + i as i64;
            let gap = (s - last - 1) as u32;
            match state {
                State::Inside => count += gap,
                State::Unresolved => pending += gap,
                State::Outside => {}
            }
            let (is_f, is_b) = (f >> i & 1 == 1, b >> i & 1 == 1);
            if is_f && is_b {
                count += 1;
                pending = 0;
                state = State::Unresolved;
            } else if is_f {
                count += 1;
                state = State::Inside;
            } else {
                if state == State::Unresolved {
                    count += pending;
                }
                if far_end && s == slices as i64 - 1 && state != State::Outside {
                    count += 1;
                }
                state = State::Outside;
            }
            last = s;
        }
    }
    if state == State::Inside {
        count += (slices as i64 - 1 - last) as u32;
    }
    count
}
