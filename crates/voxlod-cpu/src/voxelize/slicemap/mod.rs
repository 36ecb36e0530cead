//! Slicemaps (Eisemann and Décoret 2006): a scene voxelized by rasterization into one bitmask
//! per pixel column.
//!
//! A [`SliceCamera`] (orthographic or perspective) and a viewport define the columns; each
//! column holds `slices` bits (1..=[`MAX_SLICES`], stored in `⌈slices/32⌉` words, so up to 16
//! words of 32 bits), bit 0 nearest the camera (§2.1). Rasterizing the scene gives one fragment
//! per covered column; the fragment's depth picks its slice and sets that bit (§2.2: the paper
//! ORs a looked-up mask into the colour buffer; here a shift makes the mask and an atomic OR
//! sets it). This is the CPU reference of voxlod-gpu's render pipeline, which the equivalence
//! suite compares with it.
//!
//! # Slicing (§2.3)
//! - [`Slicing::Uniform`]: every column divided evenly between the camera's `near` and `far`.
//! - [`Slicing::Local`]: each column divided evenly between the nearest and farthest fragment
//!   depths in it, found by a first rasterization pass (the paper's two depth maps): finer cells
//!   where the geometry is thin along the column, at the cost of one more pass.
//!
//! A slice is chosen by eye-space z, never by distance to the eye ([`camera`] module docs).
//! With `d = z − near` (in `f32`) and the column's range `[lo, hi]` (uniform: `[0, far − near]`),
//! a fragment's normalized depth is `z' = (d − lo)/(hi − lo)` (0 when `hi = lo`) and its slice
//! `min(⌊z'·slices⌋, slices − 1)`: `far` belongs to the last slice. Fragments with `d` outside
//! `[0, far − near]` are discarded (clipping to the depth range).
//!
//! # Coverage ([`Coverage`])
//! [`Coverage::Standard`] is the hardware's: fragments at covered pixel centres, one depth each,
//! so triangles seen edge-on are missed and steep ones leave holes between slices (§2.5).
//! [`Coverage::Conservative`] emulates conservative rasterization with a depth range per
//! fragment: every cell of the map that a triangle meets is set ([`raster`] module docs).
//!
//! # Orientation ([`Faces`])
//! [`Faces::Split`] keeps front- and back-facing triangles in two layers of bits sharing the
//! same local ranges: the front and back slicemaps of the paper's refraction (§3.3).
//!
//! # Errors
//! An invalid camera, slice count or option, a non-finite vertex or a dangling index is an
//! error naming it; a map over [`Options::memory_limit_bytes`] is [`Error::OutOfMemory`]
//! before anything large is allocated. Geometry with nothing in the map gives an empty map.

pub mod camera;
pub mod compare;
pub mod query;
pub mod raster;
pub mod shadow;

use std::sync::atomic::{AtomicU32, Ordering};

use rayon::prelude::*;
use voxlod_scene::Geometry;

pub use camera::{Prepared, Projection, SliceCamera, SliceFrame, SliceTriangle, prepare};
use raster::DepthParams;

use crate::{Error, Result};

/// Most slices per column (16 words of 32 bits).
pub const MAX_SLICES: u32 = 512;

/// How columns are divided into slices (§2.3).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum Slicing {
    /// Evenly between the camera's `near` and `far`.
    #[default]
    Uniform,
    /// Evenly between the nearest and farthest fragment of each column (one more pass).
    Local,
}

/// Which pixels a triangle produces fragments in ([`raster`] module docs).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum Coverage {
    /// Pixel centres inside the snapped triangle, top-left rule; one depth per fragment.
    #[default]
    Standard,
    /// Pixels whose closed square meets the triangle, with the triangle's depth range there.
    Conservative,
}

/// Whether orientation splits the map into front and back layers.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum Faces {
    /// One layer with every triangle.
    #[default]
    All,
    /// Layer 0 holds front-facing triangles, layer 1 back-facing ones.
    Split,
}

impl Faces {
    /// Number of bit layers.
    pub fn layers(self) -> u32 {
        match self {
            Faces::All => 1,
            Faces::Split => 2,
        }
    }
}

/// Options of [`build`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Options {
    /// Slices per column, 1..=[`MAX_SLICES`].
    pub slices: u32,
    /// Uniform or local slicing.
    pub slicing: Slicing,
    /// Standard or conservative coverage.
    pub coverage: Coverage,
    /// One layer, or front and back layers.
    pub faces: Faces,
    /// Refuse a map whose bits and ranges exceed this many bytes.
    pub memory_limit_bytes: u64,
}

impl Default for Options {
    fn default() -> Self {
        Options {
            slices: 32,
            slicing: Slicing::Uniform,
            coverage: Coverage::Standard,
            faces: Faces::All,
            memory_limit_bytes: 4 << 30,
        }
    }
}

impl Options {
    /// 32-bit words per column and layer: `⌈slices/32⌉`.
    pub fn words(&self) -> u32 {
        self.slices.div_ceil(32)
    }

    /// Checks the slice count and the memory the map of `camera` needs.
    pub fn validate(&self, camera: &SliceCamera) -> Result<()> {
        if self.slices == 0 || self.slices > MAX_SLICES {
            return Err(Error::InvalidParameter {
                name: "slices",
                value: self.slices.to_string(),
                reason: format!("must be in 1..={MAX_SLICES} (16 words of 32 bits per column)"),
            });
        }
        let columns = camera.width as u64 * camera.height as u64;
        let bytes = columns * (self.faces.layers() * self.words()) as u64 * 4 + columns * 8;
        if bytes > self.memory_limit_bytes {
            return Err(Error::OutOfMemory {
                dims: [camera.width, camera.height, self.slices],
                estimated_bytes: bytes,
                limit_bytes: self.memory_limit_bytes,
            });
        }
        Ok(())
    }
}

/// The per-column depth range of an empty local column (`lo > hi`).
pub const EMPTY_RANGE: [f32; 2] = [f32::INFINITY, 0.0];

/// A slicemap: `layers × height × width` columns of `words` 32-bit words.
#[derive(Clone, Debug, PartialEq)]
pub struct Slicemap {
    /// The camera that defines the columns.
    pub camera: SliceCamera,
    /// The options it was built with.
    pub options: Options,
    /// Bits, column `(x, y)` of layer `l` at words `((l·height + y)·width + x)·words ..`;
    /// slice `s` is bit `s % 32` of word `s / 32`.
    pub bits: Vec<u32>,
    /// Local slicing: per column `[lo, hi]` of `d = z − near` ([`EMPTY_RANGE`] where no
    /// fragment fell); `None` for uniform slicing.
    pub ranges: Option<Vec<[f32; 2]>>,
}

impl Slicemap {
    /// An empty map (no bit set; local ranges empty).
    pub fn empty(camera: SliceCamera, options: Options) -> Self {
        let columns = camera.width as usize * camera.height as usize;
        let words = options.words() as usize * options.faces.layers() as usize;
        Slicemap {
            camera,
            options,
            bits: vec![0; columns * words],
            ranges: (options.slicing == Slicing::Local).then(|| vec![EMPTY_RANGE; columns]),
        }
    }

    /// Words per column and layer.
    pub fn words(&self) -> u32 {
        self.options.words()
    }

    /// The words of column `(x, y)` in `layer`.
    pub fn column(&self, layer: u32, x: u32, y: u32) -> &[u32] {
        let k = self.words() as usize;
        let i = ((layer as usize * self.camera.height as usize + y as usize)
            * self.camera.width as usize
            + x as usize)
            * k;
        &self.bits[i..i + k]
    }

    /// Whether slice `s` of column `(x, y)` in `layer` is set.
    pub fn get(&self, layer: u32, x: u32, y: u32, s: u32) -> bool {
        self.column(layer, x, y)[(s / 32) as usize] >> (s % 32) & 1 == 1
    }

    /// The depth range `[lo, hi]` of `d = z − near` that column `(x, y)` is sliced over;
    /// `None` for an empty local column.
    pub fn range(&self, x: u32, y: u32) -> Option<(f32, f32)> {
        match &self.ranges {
            None => Some((0.0, self.depth_span())),
            Some(r) => {
                let [lo, hi] = r[y as usize * self.camera.width as usize + x as usize];
                (lo <= hi).then_some((lo, hi))
            }
        }
    }

    /// `far − near` as the kernels see it (both rounded to `f32` first).
    pub fn depth_span(&self) -> f32 {
        self.camera.far as f32 - self.camera.near as f32
    }

    /// The depth constants of fragments.
    pub fn depth_params(&self) -> DepthParams {
        DepthParams { perspective: self.camera.is_perspective(), near: self.camera.near as f32 }
    }

    /// Number of set bits (occupied cells) over all layers.
    pub fn occupied(&self) -> u64 {
        self.bits.iter().map(|w| w.count_ones() as u64).sum()
    }

    /// Number of columns with at least one bit set in some layer.
    pub fn covered_columns(&self) -> u64 {
        let k = self.words() as usize;
        let columns = self.camera.width as usize * self.camera.height as usize;
        (0..columns)
            .filter(|&c| {
                (0..self.options.faces.layers() as usize)
                    .any(|l| self.bits[(l * columns + c) * k..][..k].iter().any(|&w| w != 0))
            })
            .count() as u64
    }
}

/// The normalized depth `z'` of `d` in a column sliced over `[lo, hi]`: `(d − lo)/(hi − lo)`
/// clamped into `[0, 1]`, 0 when `hi ≤ lo` (`f32`, as the WGSL).
#[inline]
pub fn normalized(d: f32, lo: f32, hi: f32) -> f32 {
    let r = hi - lo;
    if r > 0.0 { ((d - lo) / r).clamp(0.0, 1.0) } else { 0.0 }
}

/// The slice of normalized depth `z'` in `[0, 1]`: `min(⌊z'·slices⌋, slices − 1)`.
#[inline]
pub fn slice_of(z: f32, slices: u32) -> u32 {
    ((z * slices as f32) as u32).min(slices - 1)
}

/// The mask of slices `first..=last` within word `w` (slices `32w ..= 32w + 31`).
#[inline]
pub fn word_mask(first: u32, last: u32, w: u32) -> u32 {
    let (lo, hi) = (w * 32, w * 32 + 31);
    if last < lo || first > hi {
        return 0;
    }
    let a = first.max(lo) - lo;
    let b = last.min(hi) - lo;
    (u32::MAX >> (31 - b)) & (u32::MAX << a)
}

/// One fragment of a pass: pixel, layer and interval of `d` (a point for standard coverage).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Fragment {
    /// Column x.
    pub x: u32,
    /// Column y.
    pub y: u32,
    /// Bit layer (0, or 1 for a back-facing triangle with [`Faces::Split`]).
    pub layer: u32,
    /// Nearest `d = z − near` of the fragment, clamped into the depth range.
    pub d_lo: f32,
    /// Farthest `d`, clamped into the depth range.
    pub d_hi: f32,
}

/// Calls `emit` for every fragment `t` produces in the map of `camera` with `options` that
/// survives the depth-range test (module docs), in the order the rasterizer visits pixels.
pub fn for_each_fragment(
    t: &SliceTriangle,
    camera: &SliceCamera,
    options: &Options,
    mut emit: impl FnMut(Fragment),
) {
    let depth = DepthParams { perspective: camera.is_perspective(), near: camera.near as f32 };
    let span = camera.far as f32 - camera.near as f32;
    let layer = (options.faces == Faces::Split && !t.is_front()) as u32;
    let (w, h) = (camera.width, camera.height);
    match options.coverage {
        Coverage::Standard => raster::for_each_covered(t, w, h, |x, y| {
            let d = depth.d_of_q(raster::q_at_centre(t, x, y));
            if d >= 0.0 && d <= span {
                emit(Fragment { x, y, layer, d_lo: d, d_hi: d });
            }
        }),
        Coverage::Conservative => raster::for_each_conservative(t, w, h, |x, y, q_lo, q_hi| {
            let (lo, hi) = depth.d_range(q_lo, q_hi);
            if hi >= 0.0 && lo <= span {
                emit(Fragment { x, y, layer, d_lo: lo.max(0.0), d_hi: hi.min(span) });
            }
        }),
    }
}

/// Rasterizes `geometry` into the slicemap of `camera` (module docs).
pub fn build(geometry: &Geometry, camera: &SliceCamera, options: &Options) -> Result<Slicemap> {
    options.validate(camera)?;
    let prepared = prepare(geometry, camera)?;
    Ok(build_prepared(&prepared.triangles, camera, options))
}

/// [`build`] from records already [`prepare`]d for `camera` (options validated by the caller).
pub fn build_prepared(
    triangles: &[SliceTriangle],
    camera: &SliceCamera,
    options: &Options,
) -> Slicemap {
    let mut map = Slicemap::empty(*camera, *options);
    let w = camera.width as usize;
    let columns = w * camera.height as usize;
    if let Some(ranges) = &mut map.ranges {
        // Pass 1: the nearest and farthest fragment per column (d ≥ 0, so its bits order).
        let lo: Vec<AtomicU32> =
            (0..columns).map(|_| AtomicU32::new(f32::INFINITY.to_bits())).collect();
        let hi: Vec<AtomicU32> = (0..columns).map(|_| AtomicU32::new(0)).collect();
        triangles.par_chunks(CHUNK).for_each(|chunk| {
            for t in chunk {
                for_each_fragment(t, camera, options, |f| {
                    let c = f.y as usize * w + f.x as usize;
                    lo[c].fetch_min(f.d_lo.to_bits(), Ordering::Relaxed);
                    hi[c].fetch_max(f.d_hi.to_bits(), Ordering::Relaxed);
                });
            }
        });
        for (r, (lo, hi)) in ranges.iter_mut().zip(lo.into_iter().zip(hi)) {
            *r = [f32::from_bits(lo.into_inner()), f32::from_bits(hi.into_inner())];
        }
    }
    set_bits(&mut map, triangles);
    map
}

/// Rasterizes prepared records into a map sliced over the given per-column ranges `[lo, hi]`
/// of `d` (local slicing with ranges from elsewhere, e.g. another map's): each fragment's
/// interval is cut to its column's range, and what lies outside it is not in the map. With
/// `options.coverage` conservative and another map's ranges, this gives the exact cells of that
/// map that the geometry meets ([`compare`] module docs).
pub fn build_in_ranges(
    triangles: &[SliceTriangle],
    camera: &SliceCamera,
    options: &Options,
    ranges: &[[f32; 2]],
) -> Result<Slicemap> {
    let columns = camera.width as usize * camera.height as usize;
    if ranges.len() != columns || options.slicing != Slicing::Local {
        return Err(Error::InvalidParameter {
            name: "slicemap ranges",
            value: format!("{} ranges, {:?} slicing", ranges.len(), options.slicing),
            reason: format!("local slicing with one range per column ({columns})"),
        });
    }
    let mut map = Slicemap::empty(*camera, *options);
    map.ranges = Some(ranges.to_vec());
    set_bits(&mut map, triangles);
    Ok(map)
}

/// Records per parallel task.
const CHUNK: usize = 1024;

/// The slicemap pass: every fragment's interval, cut to its column's range, sets its slices.
fn set_bits(map: &mut Slicemap, triangles: &[SliceTriangle]) {
    let (camera, options) = (&map.camera, &map.options);
    let w = camera.width as usize;
    let columns = w * camera.height as usize;
    let k = options.words() as usize;
    let n = options.slices;
    let span = map.depth_span();
    let bits: Vec<AtomicU32> = (0..map.bits.len()).map(|_| AtomicU32::new(0)).collect();
    let ranges = map.ranges.as_deref();
    triangles.par_chunks(CHUNK).for_each(|chunk| {
        for t in chunk {
            for_each_fragment(t, camera, options, |f| {
                let c = f.y as usize * w + f.x as usize;
                let [lo, hi] = ranges.map_or([0.0, span], |r| r[c]);
                if let Some((first, last)) = fragment_slices(f, lo, hi, n) {
                    let base = (f.layer as usize * columns + c) * k;
                    for word in first / 32..=last / 32 {
                        let m = word_mask(first, last, word);
                        bits[base + word as usize].fetch_or(m, Ordering::Relaxed);
                    }
                }
            });
        }
    });
    map.bits = bits.into_iter().map(AtomicU32::into_inner).collect();
}

/// The slices `first..=last` a fragment sets in a column sliced over `[lo, hi]`, or `None` when
/// its interval misses the range (or the column is empty).
#[inline]
pub fn fragment_slices(f: Fragment, lo: f32, hi: f32, slices: u32) -> Option<(u32, u32)> {
    if !(f.d_hi >= lo && f.d_lo <= hi) {
        return None;
    }
    let first = slice_of(normalized(f.d_lo.max(lo), lo, hi), slices);
    let last = slice_of(normalized(f.d_hi.min(hi), lo, hi), slices);
    Some((first, last))
}

#[cfg(test)]
mod tests;
