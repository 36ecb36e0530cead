//! The per-voxel caches of the filtered renderer ([`FrameCache`]) and the voxel look-up its
//! DDA walks with.
//!
//! The rules are on [`FrameCache`].

use std::sync::atomic::{AtomicU32, Ordering};

use glam::{UVec3, Vec3};
use rayon::prelude::*;
use voxlod_format::{BRICK_EDGE, BrickMap, GridSpec, morton};
use voxlod_scene::Light;

use super::bounds::LightBounds;
use super::lookup::VoxelLookup;
use super::shadow::ShadowPattern;
use crate::appearance::{Appearance, Opacity};
use crate::{Error, Result};

/// Largest grid (in voxels of its bounding box) that [`FrameCache::new`] scans with
/// `index_of`: 2²⁷, a 512³ grid. Larger grids use [`FrameCache::with_layout`].
pub const MAX_SCAN_VOXELS: u64 = 1 << 27;

/// An empty shadow slot: a NaN bit pattern no computed visibility has.
const NO_VISIBILITY: u32 = u32::MAX;

/// Light-opacity slot states.
const OPACITY_UNKNOWN: u32 = 0;
const OPACITY_ALPHA: u32 = 1;
const OPACITY_NON_EXPONENTIAL: u32 = 2;

/// One voxel's cached radiance and opacity toward the eye. `stamp` is `generation << 1 | kind`
/// (kind 1: non-exponential); 0 is never a valid stamp.
#[derive(Default)]
struct ViewSlot {
    stamp: AtomicU32,
    /// Radiance r, g, b, then the opacity's two parameters (α, or σ and γ), as `f32` bits.
    values: [AtomicU32; 5],
}

/// One voxel's cached opacity for the light direction.
#[derive(Default)]
struct OpacitySlot {
    state: AtomicU32,
    values: [AtomicU32; 2],
}

/// The two parameters and kind bit of an opacity.
#[inline]
fn encode(o: Opacity) -> (u32, f32, f32) {
    match o {
        Opacity::Alpha(a) => (0, a, 0.0),
        Opacity::NonExponential { sigma, gamma } => (1, sigma, gamma),
    }
}

#[inline]
fn decode(kind: u32, a: f32, b: f32) -> Opacity {
    if kind == 0 { Opacity::Alpha(a) } else { Opacity::NonExponential { sigma: a, gamma: b } }
}

#[inline]
fn load(a: &AtomicU32) -> f32 {
    f32::from_bits(a.load(Ordering::Relaxed))
}

#[inline]
fn store(a: &AtomicU32, v: f32) {
    a.store(v.to_bits(), Ordering::Relaxed)
}

/// What everything a view slot depends on besides the voxel: compared bit for bit.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct ViewKey {
    pub eye: Vec3,
    pub light: Light,
    pub ambient: Vec3,
    pub shadows: bool,
    /// The \[VJK21\] chord rule: it changes cached opacities and hence visibilities.
    pub vjk_chord: super::VjkChord,
}

/// The slots, shared by the threads of a frame.
pub(super) struct Slots {
    view: Vec<ViewSlot>,
    /// Current view generation, in `1..2³¹`.
    generation: u32,
    shadow: Vec<AtomicU32>,
    light_opacity: Vec<OpacitySlot>,
}

impl Slots {
    fn new(n: usize) -> Self {
        Self {
            view: (0..n).map(|_| ViewSlot::default()).collect(),
            generation: 1,
            shadow: (0..n).map(|_| AtomicU32::new(NO_VISIBILITY)).collect(),
            light_opacity: (0..n).map(|_| OpacitySlot::default()).collect(),
        }
    }

    /// The cached radiance and opacity toward the eye of voxel `i`, or `compute()`'s, stored.
    #[inline]
    pub fn view(&self, i: usize, compute: impl FnOnce() -> (Vec3, Opacity)) -> (Vec3, Opacity) {
        let slot = &self.view[i];
        let stamp = slot.stamp.load(Ordering::Acquire);
        let v = &slot.values;
        if stamp >> 1 == self.generation {
            let c = Vec3::new(load(&v[0]), load(&v[1]), load(&v[2]));
            return (c, decode(stamp & 1, load(&v[3]), load(&v[4])));
        }
        let (c, o) = compute();
        let (kind, a, b) = encode(o);
        for (slot, x) in v.iter().zip([c.x, c.y, c.z, a, b]) {
            store(slot, x);
        }
        slot.stamp.store(self.generation << 1 | kind, Ordering::Release);
        (c, o)
    }

    /// The cached shadow visibility of voxel `i`, or `compute()`'s, stored.
    #[inline]
    pub fn visibility(&self, i: usize, compute: impl FnOnce() -> f32) -> f32 {
        let bits = self.shadow[i].load(Ordering::Relaxed);
        if bits != NO_VISIBILITY {
            return f32::from_bits(bits);
        }
        let v = compute();
        // A NaN from a broken representation must not read as "empty" forever.
        let v = if v.is_nan() { 0.0 } else { v };
        self.shadow[i].store(v.to_bits(), Ordering::Relaxed);
        v
    }

    /// The cached light-direction opacity of voxel `i`, or `compute()`'s, stored.
    #[inline]
    pub fn light_opacity(&self, i: usize, compute: impl FnOnce() -> Opacity) -> Opacity {
        let slot = &self.light_opacity[i];
        let state = slot.state.load(Ordering::Acquire);
        if state != OPACITY_UNKNOWN {
            let kind = (state == OPACITY_NON_EXPONENTIAL) as u32;
            return decode(kind, load(&slot.values[0]), load(&slot.values[1]));
        }
        let o = compute();
        let (kind, a, b) = encode(o);
        store(&slot.values[0], a);
        store(&slot.values[1], b);
        let state = if kind == 0 { OPACITY_ALPHA } else { OPACITY_NON_EXPONENTIAL };
        slot.state.store(state, Ordering::Release);
        o
    }

    /// Forgets every view slot: a new generation (O(1); every 2³¹ − 1 generations the stamps
    /// are zeroed so that an old stamp can never match).
    fn next_generation(&mut self) {
        if self.generation >= (1 << 31) - 1 {
            self.view.par_iter_mut().for_each(|s| *s.stamp.get_mut() = 0);
            self.generation = 1;
        } else {
            self.generation += 1;
        }
    }

    /// Forgets every shadow and light-opacity slot.
    fn clear_light(&mut self) {
        self.shadow.par_iter_mut().for_each(|s| *s.get_mut() = NO_VISIBILITY);
        self.light_opacity.par_iter_mut().for_each(|s| *s.state.get_mut() = OPACITY_UNKNOWN);
    }
}

/// The shadow-ray bounds of `light` over the allocated bricks of `map`, for a directional
/// light (`None` for a point light: its shadow rays end at the light).
pub(super) fn light_bounds<T>(
    light: &Light,
    map: &BrickMap<T>,
    grid: &GridSpec,
) -> Option<LightBounds> {
    match *light {
        Light::Directional { to_light, .. } => Some(LightBounds::new(to_light, map, grid)),
        Light::Point { .. } => None,
    }
}

/// The step pattern of `light`'s shadow rays in `grid`, for a directional light (`None` for a
/// point light: its shadow rays differ in direction and are walked one by one).
pub(super) fn shadow_pattern(light: &Light, grid: &GridSpec) -> Option<ShadowPattern> {
    match *light {
        Light::Directional { to_light, .. } => Some(ShadowPattern::new(
            grid.dims,
            to_light / grid.voxel_size as f32,
            super::SHADOW_SKIP_SQ,
        )),
        Light::Point { .. } => None,
    }
}

/// The per-voxel caches of the filtered renderer for one [`Appearance`], kept from frame to
/// frame, and the voxel look-up the renderer's DDA skips empty bricks with.
///
/// # What is cached, and when it is forgotten
/// Per voxel with a record, three lazily filled slots, written lock-free: a thread that finds a
/// slot empty computes the value and stores it, and threads racing on one voxel compute
/// bit-identical values (every input is a function of the voxel and the frame's key), so the
/// image does not depend on the schedule.
/// - **View slot**: the radiance toward `v = normalize(eye − centre)` and the voxel's
///   [`Opacity`] for `v`. Valid for one *view key* — eye position, light, ambient term and the
///   shadows switch, everything the radiance depends on. [`render`](super::render) compares the
///   key with the previous frame's and, when anything differs, forgets every view slot at once
///   (the slots carry a generation stamp; a new key is a new generation, O(1)). A camera that
///   only turns about its eye keeps its view slots.
/// - **Shadow slot**: the voxel's shadow visibility, the final transmittance of its shadow ray.
/// - **Light-opacity slot**: the voxel's [`Opacity`] for the direction the light travels at
///   its centre, used where a shadow ray crosses it.
///
///   Shadow and light-opacity slots are kept across frames while the light is unchanged; a
///   different light resets them (O(voxels)) and, for a directional light, rebuilds the
///   light-space height map that bounds shadow rays. The grid cannot change under the cache: the
///   cache borrows the [`Appearance`] it was built for, so a new grid or representation needs
///   a new cache.
///
/// [`FrameCache::clear`] forgets everything (a "cache cold" frame), [`FrameCache::clear_view`]
/// only the view slots.
///
/// Memory: 24 B (view) + 4 B (shadow) + 12 B (light opacity) + 4 B (look-up) per voxel with a
/// record, about 170 B per allocated brick (headers and linear masks), the dense brick table
/// (4 B per brick of the grid, 1 B per 2³ bricks) and, for a directional light, the
/// shadow-ray height map and step pattern (about 5 KB per voxel of the grid's longest edge:
/// 1.4 MB at 256³).
pub struct FrameCache<'a, A: ?Sized> {
    app: &'a A,
    grid: GridSpec,
    pub(super) lookup: VoxelLookup,
    pub(super) slots: Slots,
    view_key: Option<ViewKey>,
    /// The light (and \[VJK21\] chord rule) the shadow slots were computed for.
    shadow_light: Option<(Light, super::VjkChord)>,
    /// Shadow-ray bounds and step pattern of `shadow_light`, if it is directional.
    pub(super) light_bounds: Option<LightBounds>,
    pub(super) shadow_pattern: Option<ShadowPattern>,
}

impl<'a, A: Appearance + ?Sized> FrameCache<'a, A> {
    /// A cold cache for `app`, finding its voxels by calling `app.index_of` on every voxel of
    /// the grid (parallel over bricks). Errors on an invalid grid, a grid of more than
    /// [`MAX_SCAN_VOXELS`] voxels (use [`FrameCache::with_layout`]), or an `app` whose
    /// `index_of` disagrees with its `len` (indices out of range, repeated or missing).
    pub fn new(app: &'a A) -> Result<Self> {
        let grid = *app.grid();
        grid.validate()?;
        if grid.voxel_count() > MAX_SCAN_VOXELS {
            return Err(Error::InvalidParameter {
                name: "appearance grid",
                value: format!("{} voxels", grid.dims),
                reason: format!(
                    "scanning more than {MAX_SCAN_VOXELS} voxels for records is too slow; \
                     build the cache with FrameCache::with_layout"
                ),
            });
        }
        let bricks = (grid.dims + BRICK_EDGE - 1) / BRICK_EDGE;
        let n = bricks.as_u64vec3().element_product() as usize;
        let mut found: Vec<(u64, u32)> = (0..n)
            .into_par_iter()
            .flat_map_iter(|b| {
                let b = UVec3::new(
                    (b % bricks.x as usize) as u32,
                    (b / bricks.x as usize % bricks.y as usize) as u32,
                    (b / (bricks.x as usize * bricks.y as usize)) as u32,
                );
                let lo = b * BRICK_EDGE;
                (0..BRICK_EDGE.pow(3)).filter_map(move |local| {
                    let c = lo + morton::decode(local as u64);
                    if !c.cmplt(grid.dims).all() {
                        return None;
                    }
                    app.index_of(c).map(|i| (morton::encode(c), i.min(u32::MAX as usize) as u32))
                })
            })
            .collect();
        found.par_sort_unstable_by_key(|f| f.0);
        Self::build(app, grid, found)
    }

    /// A cold cache for `app`, whose voxels are those of `layout` (a brick map over the same
    /// grid, typically the records' own map): O(voxels with a record) instead of a scan of the
    /// whole grid. Errors on an invalid grid, a layout of other dimensions, or a layout voxel
    /// that `app` has no record for, or any disagreement of `index_of` with `len`.
    pub fn with_layout<T>(app: &'a A, layout: &BrickMap<T>) -> Result<Self> {
        let grid = *app.grid();
        grid.validate()?;
        if layout.dims() != grid.dims {
            return Err(Error::InvalidParameter {
                name: "layout",
                value: format!("brick map of {} voxels", layout.dims()),
                reason: format!("the appearance grid has {} voxels", grid.dims),
            });
        }
        let mut found = Vec::with_capacity(layout.len());
        for c in layout.coords() {
            let Some(i) = app.index_of(c) else {
                return Err(Error::InvalidParameter {
                    name: "layout",
                    value: format!("voxel {c}"),
                    reason: "is in the layout but has no record in the appearance".into(),
                });
            };
            found.push((morton::encode(c), i.min(u32::MAX as usize) as u32));
        }
        Self::build(app, grid, found)
    }

    /// Checks that `found` (Morton-sorted voxels and their record indices) is a bijection onto
    /// `0..app.len()`, and builds the look-up and empty slots.
    fn build(app: &'a A, grid: GridSpec, found: Vec<(u64, u32)>) -> Result<Self> {
        let len = app.len();
        let bad = |reason: String| {
            Err(Error::InvalidParameter {
                name: "appearance",
                value: format!("{len} records"),
                reason,
            })
        };
        if found.len() != len {
            return bad(format!("index_of finds {} voxels with a record", found.len()));
        }
        let mut seen = vec![false; len];
        for &(code, i) in &found {
            let i = i as usize;
            if i >= len || std::mem::replace(&mut seen[i], true) {
                let c = morton::decode(code);
                return bad(format!("index_of({c}) = {i} is out of range or repeated"));
            }
        }
        Ok(Self {
            app,
            grid,
            lookup: VoxelLookup::new(grid.dims, &found)?,
            slots: Slots::new(len),
            view_key: None,
            shadow_light: None,
            light_bounds: None,
            shadow_pattern: None,
        })
    }

    /// The appearance this cache serves.
    pub fn appearance(&self) -> &'a A {
        self.app
    }

    /// The grid, as it was when the cache was built.
    pub fn grid(&self) -> &GridSpec {
        &self.grid
    }

    /// Forgets every cached value: the next frame runs "cache cold".
    pub fn clear(&mut self) {
        self.clear_view();
        self.slots.clear_light();
        self.shadow_light = None;
    }

    /// Forgets the view slots (radiance and opacity toward the eye) and keeps the shadows.
    pub fn clear_view(&mut self) {
        self.slots.next_generation();
        self.view_key = None;
    }

    /// Number of voxels whose view slot holds a value for the current view key.
    pub fn cached_views(&self) -> usize {
        let g = self.slots.generation;
        self.slots.view.iter().filter(|s| s.stamp.load(Ordering::Relaxed) >> 1 == g).count()
    }

    /// Number of voxels whose shadow visibility is cached.
    pub fn cached_shadows(&self) -> usize {
        self.slots.shadow.iter().filter(|s| s.load(Ordering::Relaxed) != NO_VISIBILITY).count()
    }

    /// Number of voxels with a record when the cache was built (the number of slots).
    pub(super) fn slots_len(&self) -> usize {
        self.slots.view.len()
    }

    /// Heap bytes of the look-up, the slots and the shadow-ray bounds.
    pub fn memory_bytes(&self) -> usize {
        let n = self.slots.view.len();
        self.lookup.memory_bytes()
            + n * (size_of::<ViewSlot>() + size_of::<AtomicU32>() + size_of::<OpacitySlot>())
            + self.light_bounds.as_ref().map_or(0, LightBounds::memory_bytes)
            + self.shadow_pattern.as_ref().map_or(0, ShadowPattern::memory_bytes)
    }

    /// Brings the slots up to date for a frame with `key`: a new view generation if the key
    /// changed; reset shadows and rebuild the shadow-ray bounds if the light changed (only
    /// when the frame traces shadows).
    pub(super) fn prepare(&mut self, key: ViewKey) {
        if self.view_key != Some(key) {
            self.slots.next_generation();
            self.view_key = Some(key);
        }
        if key.shadows && self.shadow_light != Some((key.light, key.vjk_chord)) {
            if self.shadow_light.is_some() {
                self.slots.clear_light();
            }
            self.shadow_light = Some((key.light, key.vjk_chord));
            self.light_bounds = light_bounds(&key.light, &self.lookup.map, &self.grid);
            self.shadow_pattern = shadow_pattern(&key.light, &self.grid);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn slots_round_trip_both_opacity_kinds() {
        let slots = Slots::new(2);
        let vjk = Opacity::NonExponential { sigma: 3.5, gamma: 0.25 };
        let c = Vec3::new(0.1, 0.2, 0.3);
        assert_eq!(slots.view(0, || (c, vjk)), (c, vjk));
        assert_eq!(slots.view(0, || unreachable!()), (c, vjk));
        assert_eq!(slots.view(1, || (c, Opacity::Alpha(0.5))), (c, Opacity::Alpha(0.5)));
        assert_eq!(slots.view(1, || unreachable!()), (c, Opacity::Alpha(0.5)));
        assert_eq!(slots.light_opacity(0, || vjk), vjk);
        assert_eq!(slots.light_opacity(0, || unreachable!()), vjk);
        assert_eq!(slots.visibility(1, || 0.25), 0.25);
        assert_eq!(slots.visibility(1, || unreachable!()), 0.25);
        // A NaN visibility is stored as 0, not as "empty".
        assert_eq!(slots.visibility(0, || f32::NAN), 0.0);
        assert_eq!(slots.visibility(0, || unreachable!()), 0.0);
    }

    #[test]
    fn generations_forget_view_slots_and_wrap_safely() {
        let mut slots = Slots::new(1);
        let a = (Vec3::ONE, Opacity::Alpha(1.0));
        let b = (Vec3::ZERO, Opacity::Alpha(0.0));
        slots.view(0, || a);
        slots.next_generation();
        assert_eq!(slots.view(0, || b), b);
        // At the last generation the stamps are zeroed: an old stamp cannot match again.
        slots.generation = (1 << 31) - 1;
        slots.view(0, || a);
        slots.next_generation();
        assert_eq!(slots.generation, 1);
        assert_eq!(slots.view(0, || b), b);
        slots.clear_light();
        assert_eq!(slots.visibility(0, || 0.5), 0.5);
    }
}
