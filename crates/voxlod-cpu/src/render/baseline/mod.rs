//! The baseline voxel renderer: every occupied voxel is an opaque cube of one colour (the
//! average of its triangles, [`build`]), walked with the [`Dda`] that skips empty bricks. The
//! first row of the trade-off table: the error any better representation must beat.
//!
//! Per pixel, 4 camera rays through the fixed sub-pixel pattern [`PATTERN_4`], box filtered.
//! A ray stops in the first occupied voxel; the surface point is where it enters the voxel, the
//! normal is the outward normal of the face it enters through (a ray that starts inside an
//! occupied voxel takes the face opposite its dominant direction), and the voxel's albedo is
//! shaded by [`shade`] (diffuse only) with one light and the optional ambient term. A ray that
//! leaves the grid returns the background colour; the image's alpha is the coverage.
//!
//! Shadows (HPG 2023 paper §4, after Vicini et al. 2021): a voxel's visibility is one ray from
//! its centre toward the light through the voxels, which ignores the voxels whose centres are
//! closer than 1.5 voxel sizes to that centre (the voxel itself and its 18 face and edge
//! neighbours — not the corner neighbours, at √3) and is blocked by any other occupied voxel.
//! Without the skip, a lit surface would shadow itself through its own neighbours. Visibility
//! depends on the voxel only, so it is computed once per voxel and frame and cached (threads
//! racing on a voxel compute the same value, so the image is deterministic).

mod build;

#[cfg(test)]
mod tests;

pub use build::{BaselineVoxel, INTERIOR_ALBEDO, build};

use std::sync::atomic::{AtomicU8, Ordering};

use glam::{IVec3, Vec2, Vec3, Vec4};
use rayon::prelude::*;
use voxlod_format::{BrickMap, GridSpec};
use voxlod_scene::{Camera, Image, Light, MaterialSample};

use super::bricks::{BrickLookup, DenseBricks, voxel_index};
use super::dda::Dda;
use super::pixel_samples::PATTERN_4;
use super::{check_colour, check_image_size};
use crate::shading::shade;
use crate::{Error, Result};

/// Options of [`render`]. Cost: 4 DDA walks per pixel, plus one shadow walk per visible voxel.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Options {
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// Ambient irradiance term of [`shade`], zero for none.
    pub ambient: Vec3,
    /// Whether to trace voxel shadow rays (off: every voxel sees the light).
    pub shadows: bool,
}

impl Default for Options {
    fn default() -> Self {
        Self { width: 512, height: 512, ambient: Vec3::ZERO, shadows: true }
    }
}

/// Shadow-cache states.
const UNKNOWN: u8 = 0;
const LIT: u8 = 1;
const SHADOWED: u8 = 2;

/// Squared distance, in voxels, under which a voxel is ignored by shadow rays: centres closer
/// than 1.5 voxel sizes (integer offsets with `dx² + dy² + dz² < 2.25`).
const SHADOW_SKIP_SQ: i32 = 2;

/// Renders the voxels of `grid` from `camera` (see the module docs). Errors on a zero or
/// oversized image, an invalid grid, camera or light, a brick map of another size than the
/// grid, or a non-finite ambient term or background.
pub fn render(
    grid: &GridSpec,
    voxels: &BrickMap<BaselineVoxel>,
    camera: &Camera,
    light: &Light,
    background: Vec3,
    options: &Options,
) -> Result<Image> {
    check_image_size(options.width, options.height)?;
    grid.validate()?;
    camera.validate()?;
    let light = light.validated()?;
    if voxels.dims() != grid.dims {
        return Err(Error::InvalidParameter {
            name: "voxels",
            value: format!("brick map of {} voxels", voxels.dims()),
            reason: format!("the grid has {} voxels", grid.dims),
        });
    }
    check_colour("ambient", options.ambient)?;
    check_colour("background", background)?;
    let frame = Frame { grid, voxels, light, background, options };
    Ok(match DenseBricks::new(voxels) {
        Some(dense) => frame.render(camera, &dense),
        None => frame.render(camera, voxels),
    })
}

/// What every ray of one frame reads.
struct Frame<'a> {
    grid: &'a GridSpec,
    voxels: &'a BrickMap<BaselineVoxel>,
    light: Light,
    background: Vec3,
    options: &'a Options,
}

impl Frame<'_> {
    fn render(&self, camera: &Camera, lookup: &(impl BrickLookup + Sync)) -> Image {
        let (width, height) = (self.options.width, self.options.height);
        let frame = camera.frame(width, height);
        let cache: Vec<AtomicU8> = (0..self.voxels.len()).map(|_| AtomicU8::new(UNKNOWN)).collect();
        let mut image = Image::new(width, height, Vec4::ZERO);
        image.pixels.par_chunks_mut(width as usize).enumerate().for_each(|(y, row)| {
            for (x, px) in row.iter_mut().enumerate() {
                let corner = Vec2::new(x as f32, y as f32);
                let mut sum = Vec4::ZERO;
                for offset in PATTERN_4 {
                    let dir = frame.ray_dir(corner + offset);
                    sum += match self.trace(frame.eye, dir, lookup, &cache) {
                        Some(radiance) => radiance.extend(1.0),
                        None => self.background.extend(0.0),
                    };
                }
                *px = sum / PATTERN_4.len() as f32;
            }
        });
        image
    }

    /// Radiance along the camera ray `eye + t·dir`, or `None` if it leaves the grid.
    #[inline]
    fn trace(
        &self,
        eye: Vec3,
        dir: Vec3,
        lookup: &impl BrickLookup,
        cache: &[AtomicU8],
    ) -> Option<Vec3> {
        let mut dda = Dda::new(self.grid, eye, dir, 0.0, f32::INFINITY);
        while let Some(v) = dda.next_occupied_brick(lookup) {
            let Some(index) = voxel_index(self.voxels, v.brick, v.voxel) else { continue };
            let normal = if v.entry_normal == IVec3::ZERO {
                started_inside_normal(dir)
            } else {
                v.entry_normal.as_vec3()
            };
            let point = eye + dir * v.t_enter;
            let light = self.light.sample(point);
            let visibility = if self.options.shadows && normal.dot(light.to_light) > 0.0 {
                self.visibility(index, v.voxel.as_ivec3(), lookup, cache)
            } else {
                1.0
            };
            let material = MaterialSample {
                albedo: self.voxels.values()[index].albedo(),
                alpha: 1.0,
                specular: Vec3::ZERO,
                shininess: 0.0,
            };
            return Some(shade(&material, normal, -dir, &light, visibility, self.options.ambient));
        }
        None
    }

    /// The cached shadow-ray visibility (0 or 1) of voxel `voxel` (value index `index`).
    fn visibility(
        &self,
        index: usize,
        voxel: IVec3,
        lookup: &impl BrickLookup,
        cache: &[AtomicU8],
    ) -> f32 {
        let state = match cache[index].load(Ordering::Relaxed) {
            UNKNOWN => {
                let s = if self.shadow_blocked(voxel, lookup) { SHADOWED } else { LIT };
                cache[index].store(s, Ordering::Relaxed);
                s
            }
            s => s,
        };
        if state == LIT { 1.0 } else { 0.0 }
    }

    /// Whether the ray from the centre of `voxel` toward the light meets an occupied voxel at
    /// least 1.5 voxel sizes away.
    fn shadow_blocked(&self, voxel: IVec3, lookup: &impl BrickLookup) -> bool {
        let centre = self.grid.voxel_center(voxel.as_uvec3()).as_vec3();
        let light = self.light.sample(centre);
        let mut dda = Dda::new(self.grid, centre, light.to_light, 0.0, light.distance);
        while let Some(v) = dda.next_occupied_brick(lookup) {
            let offset = v.voxel.as_ivec3() - voxel;
            if offset.length_squared() <= SHADOW_SKIP_SQ {
                continue;
            }
            if voxel_index(self.voxels, v.brick, v.voxel).is_some() {
                return true;
            }
        }
        false
    }
}

/// The normal used when a camera ray starts inside an occupied voxel: the face opposite the
/// ray's dominant direction.
fn started_inside_normal(dir: Vec3) -> Vec3 {
    let a = dir.abs();
    let axis = if a.x >= a.y && a.x >= a.z {
        Vec3::X
    } else if a.y >= a.z {
        Vec3::Y
    } else {
        Vec3::Z
    };
    -axis * dir.dot(axis).signum()
}
