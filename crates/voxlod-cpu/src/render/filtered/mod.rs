//! The filtered voxel renderer (HPG 2023 paper §4; design note §7): front-to-back compositing
//! of per-voxel [`Appearance`] records along DDA rays, with per-voxel cached shading, opacity
//! and shadows ([`FrameCache`]).
//!
//! # Rules
//! - **Camera rays.** 4 per pixel through the fixed sub-pixel pattern [`PATTERN_4`], box
//!   filtered; each walks the grid with the brick-skipping [`Dda`] from the eye. With
//!   [`PixelPattern::Jittered`] the 4 rays are a jittered 2×2 grid drawn per pixel from a seed
//!   instead ([`stratified`] with the jitter of [`Streams`]), the paper's "precomputed jittered
//!   patterns" (§4) made reproducible.
//! - **Per-voxel values.** For a voxel with a record, its radiance and opacity are those for
//!   `v = normalize(eye − centre)` (the direction from the voxel centre to the camera, `+z`
//!   if the eye is at the centre), computed once per voxel and frame and cached: every ray
//!   through the voxel uses them, whatever its own direction.
//! - **Compositing.** Front to back from `T = 1`, `C = 0`: per voxel, `T' = opacity.apply(T, ℓ)`
//!   ([`Opacity::apply`]) with `ℓ` the ray's exact chord through the voxel in voxel units,
//!   then `C += (T − T')·radiance`, `T ← T'`. For [`Opacity::Alpha`] that is `C += T·α·c`,
//!   `T ← T(1 − α)`; for [`Opacity::NonExponential`] it is the \[VJK21\] update
//!   `T ← min(T, f(f⁻¹(T, γ) + σℓ, γ))`, whose chord is per ray (only σ and γ are cached). In a
//!   mixed grid each voxel applies its own update to the running `T`. [`VjkChord`] chooses a
//!   chord cached per voxel instead (the chord of the line through the voxel centre along the
//!   cached direction), as the paper caches every method's opacity per voxel (§4). The walk stops as soon
//!   as `T < 0.001` or the ray leaves the grid; the ray's colour is `C + T·background` and its
//!   alpha (coverage) `1 − T`.
//! - **Shadows.** A voxel's visibility is the final transmittance of one ray from its centre
//!   (exactly `c + ½` in grid coordinates) toward the light (up to a point light's distance)
//!   through the voxels. The ray ignores the
//!   voxels whose centres are closer than 1.5 voxel sizes to the start (the voxel itself and
//!   its 18 face and edge neighbours, not the 8 corner neighbours at √3), as the baseline
//!   does. Every other voxel it crosses applies its own opacity for the direction the light
//!   travels at that voxel's centre (cached per voxel), with the shadow ray's chord; it stops
//!   at `T < 0.001`. Visibility is cached per voxel and kept across frames while the light
//!   is unchanged; with `shadows` off every voxel sees the light. A voxel whose radiance
//!   cannot depend on its visibility ([`Appearance::needs_visibility`]: an Averages voxel
//!   facing away from the light) traces no shadow ray: the image is the same. All shadow rays
//!   of a directional light cross the same sequence of cell offsets with the same `t`s, so they
//!   are walked from one step pattern per light (`shadow.rs`: a brick look-up per brick crossed
//!   and a mask bit per cell, no plane arithmetic), meeting the voxels a DDA walk meets with
//!   bit-identical chords (tested).
//! - **Shading.** The representation's [`Appearance::radiance`] for `v`, the light seen from
//!   the voxel centre, the visibility and the ambient term; every representation shades with
//!   the one [`crate::shading::shade`].
//! - **Empty space.** Walks skip empty 8³ bricks (whole empty 16³ blocks of bricks in one
//!   jump) and, inside allocated bricks, empty 2³ blocks (the DDA's
//!   [`Dda::next_occupied_voxel`]; same voxels and `t`s as stepping voxel by voxel). Beyond that, only conservative bounds that shorten a walk's `t_max`: a pixel
//!   whose 8×8 tile no allocated brick projects onto is background without a walk, a camera
//!   ray ends past the farthest brick projecting onto its tile, and a shadow ray toward a
//!   directional light ends past the highest voxel projecting onto its cell of a light-space
//!   height map. Shortening `t_max` never changes the `t` of a voxel visited before it, so
//!   the image equals that of unbounded walks (tested).
//!
//! Threads racing on a voxel's cache slot compute bit-identical values, so images are
//! deterministic and equal to [`render_uncached`], which evaluates everything per ray.

mod bounds;
mod cache;
mod lookup;
mod shadow;

#[cfg(test)]
mod tests;

pub use cache::{FrameCache, MAX_SCAN_VOXELS};

use glam::{UVec3, Vec2, Vec3, Vec4};
use rayon::prelude::*;
use voxlod_format::GridSpec;
use voxlod_scene::{Camera, Image, Light};

use super::bricks::BrickLookup;
use super::dda::{Dda, DdaVoxel};
use super::pixel_samples::{PATTERN_4, Streams, stratified};
use super::{check_colour, check_image_size};
use crate::appearance::{Appearance, Opacity, transmittance};
use crate::{Error, Result};
use bounds::{LightBounds, ScreenTiles};
use cache::{Slots, ViewKey, light_bounds, shadow_pattern};
use lookup::VoxelLookup;
use shadow::ShadowPattern;

/// Options of [`render`]. Cost: 4 DDA walks per pixel; per voxel met and frame, one radiance
/// and one opacity evaluation, plus (cache cold) one shadow walk.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Options {
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// Ambient irradiance term of [`crate::shading::shade`], zero for none.
    pub ambient: Vec3,
    /// Whether to trace voxel shadow rays (off: every voxel sees the light).
    pub shadows: bool,
    /// The chord a \[VJK21\] voxel ([`Opacity::NonExponential`]) is evaluated with; the other
    /// opacities do not depend on it.
    pub vjk_chord: VjkChord,
    /// Where the 4 rays of a pixel go.
    pub pattern: PixelPattern,
}

impl Default for Options {
    fn default() -> Self {
        Self {
            width: 512,
            height: 512,
            ambient: Vec3::ZERO,
            shadows: true,
            vjk_chord: VjkChord::default(),
            pattern: PixelPattern::default(),
        }
    }
}

/// The chord a \[VJK21\] voxel's non-exponential transmittance is evaluated with (Vicini,
/// Jakob and Kaplanyan 2021; Brito, Poulin and Teichrieb 2023, §4 caches "shading and opacity"
/// per voxel for every method).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum VjkChord {
    /// Ours: each ray's exact chord through the voxel, `T ← min(T, f(f⁻¹(T, γ) + σℓ, γ))`.
    #[default]
    PerRay,
    /// The same update with one chord per voxel and direction: `ℓ_c = 1/max|d_i|`, the chord of
    /// the line through the voxel centre along the cached direction (toward the eye, or the
    /// direction the light travels for shadow rays), for every ray through the voxel.
    CachedChord,
    /// The voxel's opacity cached as a plain alpha, `α = 1 − f(σ ℓ_c, γ)`, and composited as
    /// every other alpha (`T ← T(1 − α)`): what a renderer that caches one opacity per voxel
    /// does with \[VJK21\].
    CachedAlpha,
}

/// Where the 4 camera rays of a pixel go.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum PixelPattern {
    /// Ours: the fixed rotated-grid pattern [`PATTERN_4`], the same in every pixel.
    #[default]
    Fixed,
    /// A 2×2 jittered grid per pixel: ray `k` at [`stratified`]`(k, 4, jitter)` with the
    /// jitter of [`Streams::new`]`(seed)` for (pixel index `x + width·y`, `k`); another seed
    /// gives an independent pattern.
    Jittered {
        /// Seed of the jitter.
        seed: u32,
    },
}

/// The chord in voxel units of the line through a voxel's centre along `d` (any length):
/// `1/max|d̂_i|`, in `[1, √3]`; 1 for a zero or non-finite `d`.
#[inline]
pub fn centre_chord(d: Vec3) -> f32 {
    let m = d.try_normalize().map_or(1.0, |d| d.abs().max_element());
    (1.0 / m).clamp(1.0, 3f32.sqrt())
}

/// The opacity a voxel caches under `mode` for direction `d`: [`VjkChord::CachedAlpha`] turns
/// a non-exponential opacity into the alpha of its centre chord; everything else is unchanged.
#[inline]
fn cached_opacity(opacity: Opacity, mode: VjkChord, d: Vec3) -> Opacity {
    match (mode, opacity) {
        (VjkChord::CachedAlpha, Opacity::NonExponential { sigma, gamma }) => {
            Opacity::Alpha(1.0 - transmittance::f(sigma * centre_chord(d), gamma))
        }
        _ => opacity,
    }
}

/// The walk stops once the transmittance falls below this.
pub const MIN_TRANSMITTANCE: f32 = 0.001;

/// Squared distance, in voxels, under which a voxel is ignored by shadow rays: centres closer
/// than 1.5 voxel sizes (integer offsets with `dx² + dy² + dz² < 2.25`).
const SHADOW_SKIP_SQ: i32 = 2;

/// Renders `cache`'s appearance from `camera` (see the [module docs](self)), reusing and
/// updating the cache: view slots are forgotten automatically when the eye, light, ambient
/// term or shadows switch differ from the previous frame's; shadows when the light differs.
/// Errors on a zero or oversized image, an invalid camera or light, a non-finite or negative
/// ambient term or background, or an appearance whose grid changed since the cache was built.
pub fn render<A: Appearance + ?Sized>(
    cache: &mut FrameCache<'_, A>,
    camera: &Camera,
    light: &Light,
    background: Vec3,
    options: &Options,
) -> Result<Image> {
    let light = validate(cache, camera, light, background, options)?;
    let key = ViewKey {
        eye: camera.eye,
        light,
        ambient: options.ambient,
        shadows: options.shadows,
        vjk_chord: options.vjk_chord,
    };
    cache.prepare(key);
    let cache = &*cache;
    let shadows =
        ShadowRays { bounds: cache.light_bounds.as_ref(), pattern: cache.shadow_pattern.as_ref() };
    Ok(frame(cache, light, background, options, Some(&cache.slots), shadows).render(camera))
}

/// [`render`] without caching: every camera ray evaluates the radiance, opacity and shadow ray
/// of every voxel it meets (a reference for tests; the same image, much slower). The cache's
/// slots are neither read nor written, only its voxel look-up is used.
pub fn render_uncached<A: Appearance + ?Sized>(
    cache: &FrameCache<'_, A>,
    camera: &Camera,
    light: &Light,
    background: Vec3,
    options: &Options,
) -> Result<Image> {
    let light = validate(cache, camera, light, background, options)?;
    let bounds = light_bounds(&light, &cache.lookup.map, cache.grid());
    let pattern = shadow_pattern(&light, cache.grid());
    let shadows = ShadowRays { bounds: bounds.as_ref(), pattern: pattern.as_ref() };
    Ok(frame(cache, light, background, options, None, shadows).render(camera))
}

/// Checks the inputs of a frame; returns the validated light.
fn validate<A: Appearance + ?Sized>(
    cache: &FrameCache<'_, A>,
    camera: &Camera,
    light: &Light,
    background: Vec3,
    options: &Options,
) -> Result<Light> {
    let light = check_frame(camera, light, background, options)?;
    let app = cache.appearance();
    if app.grid() != cache.grid() || app.len() != cache.slots_len() {
        return Err(Error::InvalidParameter {
            name: "appearance",
            value: format!("grid {:?} with {} records", app.grid(), app.len()),
            reason: format!(
                "the cache was built for grid {:?} with {} records",
                cache.grid(),
                cache.slots_len()
            ),
        });
    }
    Ok(light)
}

/// The checks of a frame that do not depend on the appearance: image size, camera, light,
/// ambient term and background (finite, non-negative). Returns the validated light. Other
/// backends of this renderer (voxlod-gpu) call it, so bad input gets the same errors.
pub fn check_frame(
    camera: &Camera,
    light: &Light,
    background: Vec3,
    options: &Options,
) -> Result<Light> {
    check_image_size(options.width, options.height)?;
    camera.validate()?;
    let light = light.validated()?;
    check_colour("ambient", options.ambient)?;
    check_colour("background", background)?;
    Ok(light)
}

/// What a directional light's shadow rays are walked with (both `None` for a point light).
#[derive(Clone, Copy)]
struct ShadowRays<'a> {
    bounds: Option<&'a LightBounds>,
    pattern: Option<&'a ShadowPattern>,
}

/// The frame over `cache`'s look-up, caching in `slots` if given, with the shadow-ray bounds
/// and step pattern of `light` (if directional).
fn frame<'c, A: Appearance + ?Sized>(
    cache: &'c FrameCache<'_, A>,
    light: Light,
    background: Vec3,
    options: &'c Options,
    slots: Option<&'c Slots>,
    shadows: ShadowRays<'c>,
) -> Frame<'c, A> {
    Frame {
        app: cache.appearance(),
        grid: cache.grid(),
        lookup: &cache.lookup,
        light,
        background,
        options,
        slots,
        shadows,
        inv_size: (1.0 / cache.grid().voxel_size) as f32,
    }
}

/// What every ray of one frame reads.
struct Frame<'a, A: ?Sized> {
    app: &'a A,
    grid: &'a GridSpec,
    lookup: &'a VoxelLookup,
    light: Light,
    background: Vec3,
    options: &'a Options,
    slots: Option<&'a Slots>,
    /// Shadow-ray bounds and step pattern of a directional light.
    shadows: ShadowRays<'a>,
    /// Voxels per world unit: world chords to voxel units.
    inv_size: f32,
}

/// What one camera ray gathered.
#[derive(Clone, Copy, Debug, PartialEq)]
struct RayResult {
    /// Composited radiance, without the background.
    radiance: Vec3,
    /// Transmittance left.
    transmittance: f32,
    /// Voxels with a record that were composited.
    voxels: u32,
}

impl RayResult {
    /// A ray that met no voxel with a record.
    const MISS: Self = Self { radiance: Vec3::ZERO, transmittance: 1.0, voxels: 0 };
}

impl<A: Appearance + ?Sized> Frame<'_, A> {
    fn render(&self, camera: &Camera) -> Image {
        match &self.lookup.dense {
            Some(dense) => self.render_with(camera, dense),
            None => self.render_with(camera, &self.lookup.map),
        }
    }

    fn render_with(&self, camera: &Camera, lookup: &(impl BrickLookup + Sync)) -> Image {
        let (width, height) = (self.options.width, self.options.height);
        let frame = camera.frame(width, height);
        let tiles = ScreenTiles::new(&frame, &self.lookup.map, self.grid);
        let streams = match self.options.pattern {
            PixelPattern::Fixed => Streams::new(0),
            PixelPattern::Jittered { seed } => Streams::new(seed),
        };
        let mut image = Image::new(width, height, Vec4::ZERO);
        image.pixels.par_chunks_mut(width as usize).enumerate().for_each(|(y, row)| {
            for (x, px) in row.iter_mut().enumerate() {
                let corner = Vec2::new(x as f32, y as f32);
                let t_max = tiles.t_max(x as u32, y as u32);
                let mut sum = Vec4::ZERO;
                let pixel = x as u32 + width * y as u32;
                for (k, fixed) in PATTERN_4.into_iter().enumerate() {
                    let offset = match self.options.pattern {
                        PixelPattern::Fixed => fixed,
                        PixelPattern::Jittered { .. } => {
                            stratified(k as u32, 4, streams.jitter(pixel, k as u32))
                        }
                    };
                    let r = match t_max {
                        Some(t) => self.trace(frame.eye, frame.ray_dir(corner + offset), t, lookup),
                        None => RayResult::MISS,
                    };
                    let colour = r.radiance + r.transmittance * self.background;
                    sum += colour.extend(1.0 - r.transmittance);
                }
                *px = sum / PATTERN_4.len() as f32;
            }
        });
        image
    }

    /// Composites the camera ray `eye + t·dir` (unit `dir`), `t ∈ [0, t_max]`, front to back.
    #[inline]
    fn trace(&self, eye: Vec3, dir: Vec3, t_max: f32, lookup: &impl BrickLookup) -> RayResult {
        let mut r = RayResult::MISS;
        let mut walk = Walk::new(self, eye, dir, t_max);
        while let Some((v, index)) = walk.next(lookup) {
            let (radiance, opacity) = match self.slots {
                Some(s) => s.view(index, || self.view(index, v.voxel, eye, lookup)),
                None => self.view(index, v.voxel, eye, lookup),
            };
            let chord = match (self.options.vjk_chord, opacity) {
                (VjkChord::CachedChord, Opacity::NonExponential { .. }) => {
                    centre_chord(eye - self.grid.voxel_center(v.voxel).as_vec3())
                }
                _ => (v.t_exit - v.t_enter) * self.inv_size,
            };
            let t = opacity.apply(r.transmittance, chord);
            r.radiance += (r.transmittance - t) * radiance;
            r.transmittance = t;
            r.voxels += 1;
            if t < MIN_TRANSMITTANCE {
                break;
            }
        }
        r
    }

    /// Radiance and opacity of voxel `voxel` (record `index`) toward `eye`.
    fn view(
        &self,
        index: usize,
        voxel: UVec3,
        eye: Vec3,
        lookup: &impl BrickLookup,
    ) -> (Vec3, Opacity) {
        let centre = self.grid.voxel_center(voxel).as_vec3();
        let to_eye = (eye - centre).try_normalize().unwrap_or(Vec3::Z);
        let light = self.light.sample(centre);
        let ambient = self.options.ambient;
        // Without shadows, or where the radiance cannot depend on it (the voxel faces away
        // from the light), the visibility is 1 and no shadow ray is traced.
        let visibility =
            if !self.options.shadows || !self.app.needs_visibility(index, to_eye, &light) {
                1.0
            } else {
                match self.slots {
                    Some(s) => s.visibility(index, || self.shadow(voxel, lookup)),
                    None => self.shadow(voxel, lookup),
                }
            };
        let radiance = self.app.radiance(index, to_eye, &light, visibility, ambient);
        (radiance, cached_opacity(self.app.opacity(index, to_eye), self.options.vjk_chord, to_eye))
    }

    /// The transmittance of the shadow ray of `voxel` (see the module docs): from the voxel's
    /// centre `c + ½` in grid coordinates, walked with the light's [`ShadowPattern`] for a
    /// directional light (the same voxels and chords as a DDA walk, tested), else by a DDA
    /// walk.
    fn shadow(&self, voxel: UVec3, lookup: &impl BrickLookup) -> f32 {
        let mut t = 1.0f32;
        // Applies the opacity of voxel `at` (record `index`) over `chord`; false once opaque.
        let mut cross = |index: usize, at: UVec3, chord: f32| {
            let opacity = match self.slots {
                Some(s) => s.light_opacity(index, || self.light_opacity(index, at)),
                None => self.light_opacity(index, at),
            };
            let chord = match (self.options.vjk_chord, opacity) {
                (VjkChord::CachedChord, Opacity::NonExponential { .. }) => {
                    centre_chord(self.light_direction(at))
                }
                _ => chord * self.inv_size,
            };
            t = opacity.apply(t, chord);
            t >= MIN_TRANSMITTANCE
        };
        let start = voxel.as_vec3() + 0.5;
        if let Some(pattern) = self.shadows.pattern {
            let t_max = self.shadows.bounds.map_or(f32::INFINITY, |b| b.t_max(self.grid, voxel));
            let lookup_of = &self.lookup;
            pattern.walk(
                voxel,
                self.lookup.map.brick_dims(),
                t_max,
                |b| lookup.brick_index(b),
                |b, i| lookup_of.masks(b).has_voxel_linear(i),
                |b, i, at, chord| match lookup_of.record_linear(b, i) {
                    Some(index) => cross(index, at, chord),
                    None => true,
                },
            );
            return t;
        }
        let light = self.light.sample(self.grid.voxel_center(voxel).as_vec3());
        let t_max = self.shadows.bounds.map_or(light.distance, |b| b.t_max(self.grid, voxel));
        let d = light.to_light / self.grid.voxel_size as f32;
        let mut walk = Walk::in_grid_space(self, start, d, t_max);
        while let Some((v, index)) = walk.next(lookup) {
            let offset = v.voxel.as_ivec3() - voxel.as_ivec3();
            if offset.length_squared() <= SHADOW_SKIP_SQ {
                continue;
            }
            if !cross(index, v.voxel, v.t_exit - v.t_enter) {
                break;
            }
        }
        t
    }

    /// Opacity of voxel `voxel` (record `index`) for the direction the light travels at its
    /// centre.
    fn light_opacity(&self, index: usize, voxel: UVec3) -> Opacity {
        let d = self.light_direction(voxel);
        cached_opacity(self.app.opacity(index, d), self.options.vjk_chord, d)
    }

    /// The direction the light travels at `voxel`'s centre.
    fn light_direction(&self, voxel: UVec3) -> Vec3 {
        let centre = self.grid.voxel_center(voxel).as_vec3();
        -self.light.sample(centre).to_light
    }
}

/// A DDA walk that skips empty bricks and empty 2³ blocks and yields the voxels with a
/// record and their record index.
struct Walk<'a> {
    dda: Dda,
    lookup: &'a VoxelLookup,
}

impl<'a> Walk<'a> {
    #[inline]
    fn new<A: ?Sized>(frame: &Frame<'a, A>, origin: Vec3, dir: Vec3, t_max: f32) -> Self {
        Self { dda: Dda::new(frame.grid, origin, dir, 0.0, t_max), lookup: frame.lookup }
    }

    /// A walk of a ray given in grid coordinates ([`Dda::in_grid_space`]).
    #[inline]
    fn in_grid_space<A: ?Sized>(frame: &Frame<'a, A>, o: Vec3, d: Vec3, t_max: f32) -> Self {
        Self { dda: Dda::in_grid_space(frame.grid.dims, o, d, 0.0, t_max), lookup: frame.lookup }
    }

    /// The next voxel with a record, and the record's index.
    #[inline]
    fn next(&mut self, lookup: &impl BrickLookup) -> Option<(DdaVoxel, usize)> {
        loop {
            let v = self.dda.next_occupied_voxel(&self.lookup.occupancy(lookup))?;
            // Every voxel the occupancy marks has a record.
            if let Some(record) = self.lookup.record(v.brick, v.voxel) {
                return Some((v, record));
            }
        }
    }
}
