//! Primary visibility with level of detail chosen by distance ("mip-mapping for voxels"): one
//! cone per pixel from the camera, as wide as the pixel, marched front to back through the
//! geometry octree of pre-filtered Averages ([`voxlod_octree::AveragePayload`]: colour, normal,
//! opacity), each sample shaded under the scene's light ([`PrimaryRenderer`]).
//!
//! # Definitions (the march itself is [`crate::cone`]'s: steps, opacity correction, accumulation)
//! - **Camera**: a pinhole ([`PinholeCamera`]) with the ray convention of voxlod-scene's
//!   `CameraFrame::ray_dir` (pixel `(x, y)` from the top-left, its centre at `(x + ½, y + ½)`,
//!   vertical field of view `fov_y`, square pixels), so images align with the ground truth.
//! - **Footprint**: at distance `t` along a pixel's ray the cone's diameter is
//!   `d(t) = bias · t · 2·tan(fov_y/2) / height` — the cone that covers one pixel (on the optical
//!   axis; off-axis pixels are slightly larger and not corrected), scaled by the **LOD bias**
//!   `b ≥ 0`. That is a cone of full aperture `θ = 2·atan(b·tan(fov_y/2)/height)`; the octree is
//!   read with diameter `max(d, 1)` voxels (level `log2`), so near voxels come from fine levels
//!   and far ones from coarse levels. `b = 1` is the pixel footprint, `b = 0` always reads level
//!   0 (the finest-level march, the reference), `b < 1` sharper, `b > 1` blurrier and cheaper.
//! - **Step**: `step_factor · max(d, 1 voxel)` (fine levels step by voxels, coarse ones by their
//!   node size), so with `b = 0` the march steps `step_factor` voxels.
//! - **Shading**: every sample that adds opacity is shaded by the caller's function with the
//!   sample's opacity-weighted mean colour (albedo) and its mean normal turned toward the viewer
//!   (two-sided, as voxlod-cpu shades Averages records; the direction to the viewer where the
//!   normals cancel), the direction to the viewer and the light's visibility; the renderer
//!   composites the results front to back. The `voxlod` CLI passes voxlod-cpu's `shade()`.
//! - **Visibility** (with [`PrimaryOptions::shadows`]): a shadow cone toward the light through
//!   the same octree, starting as wide as the sample's footprint and widening at the same
//!   aperture, from the sample moved `1.5·max(d, 1)` voxels along its shading normal; `V = 1 − A`
//!   with `A` its accumulated opacity, ending one voxel short of a point light. Computed at a
//!   pixel's first contributing sample and again only once the march has moved more than one
//!   footprint from where it was last computed (the samples of one surface crossing share it).
//!   Zero where the normal faces away from the light (`n·l ≤ 0`: the Lambert term is zero).
//! - **Opacity at coarse levels**: with [`AveragePayload`] a node's opacity is its coverage (the
//!   mean of its children), so a one-voxel surface read at level `l` has opacity `2^−l` and
//!   fades toward the background with distance (a ground plane turns translucent);
//!   `Directional<AveragePayload>` ([`SurfaceMedium`]) stores the opacity of crossing each node
//!   along the axes, which keeps it opaque face-on (tested). Even then the trilinear hat and the
//!   step correction composite a surface one node thick to ≈ 0.8, not 1.
//! - **Output**: RGBA per pixel, `rgb = L + (1 − A)·background`, `a = A` (coverage), linear.

use glam::{Vec3, Vec4};
use rayon::prelude::*;
use voxlod_octree::{AveragePayload, Directional, Octree};

use crate::cone::{Cone, March, SampleInfo, march_cone};
use crate::error::check;
use crate::inject::Light;
use crate::medium::ConeMedium;
use crate::{Error, Result};

/// A payload primary visibility can shade: a [`ConeMedium`] with an opacity-weighted mean
/// colour and normal. [`AveragePayload`] (isotropic opacity: coverage, the mean of eight
/// children) and `Directional<AveragePayload>` (six opacities composited along the axes, the
/// opacity of crossing a node: a thin surface seen face-on stays opaque at coarse levels).
pub trait SurfaceMedium: ConeMedium {
    /// Opacity-weighted mean colour (linear albedo).
    fn albedo(&self) -> Vec3;
    /// Unit mean normal, zero where the weighted normals cancel.
    fn mean_normal(&self) -> Vec3;
}

impl SurfaceMedium for AveragePayload {
    fn albedo(&self) -> Vec3 {
        self.color()
    }
    fn mean_normal(&self) -> Vec3 {
        self.normal()
    }
}

impl SurfaceMedium for Directional<AveragePayload> {
    fn albedo(&self) -> Vec3 {
        self.inner.color()
    }
    fn mean_normal(&self) -> Vec3 {
        self.inner.normal()
    }
}

/// Largest image side [`PrimaryRenderer`] accepts.
pub const MAX_IMAGE_SIDE: u32 = 16384;

/// A pinhole camera (module docs for the ray convention).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PinholeCamera {
    /// Eye position (world).
    pub eye: Vec3,
    /// Point looked at (world).
    pub target: Vec3,
    /// Up hint (world), not parallel to `target − eye`.
    pub up: Vec3,
    /// Vertical field of view, full angle in degrees, in (0, 180).
    pub fov_y_deg: f32,
    /// Image width in pixels, in 1..=[`MAX_IMAGE_SIDE`].
    pub width: u32,
    /// Image height in pixels, in 1..=[`MAX_IMAGE_SIDE`].
    pub height: u32,
}

/// Options of a [`PrimaryRenderer`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PrimaryOptions {
    /// Footprint multiplier `b` (module docs), finite and ≥ 0 (default 1: the pixel footprint;
    /// 0: always the finest level).
    pub lod_bias: f32,
    /// Step as a fraction of the footprint diameter, in \[0.05, 4\] (default 0.5).
    pub step_factor: f32,
    /// Longest distance marched from the eye, world units, > 0 (`f32::INFINITY`: until the
    /// cone leaves the octree).
    pub max_distance: f32,
    /// Accumulated opacity at which a pixel's march stops, in (0, 1\] (default 0.99).
    pub opacity_cutoff: f32,
    /// Trace shadow cones toward the light (module docs; default on).
    pub shadows: bool,
    /// Linear RGB composited behind what the march did not cover, finite.
    pub background: Vec3,
}

impl Default for PrimaryOptions {
    fn default() -> Self {
        Self {
            lod_bias: 1.0,
            step_factor: 0.5,
            max_distance: f32::INFINITY,
            opacity_cutoff: 0.99,
            shadows: true,
            background: Vec3::ZERO,
        }
    }
}

impl PrimaryOptions {
    /// Checks every field against its documented range; errors name the field.
    pub fn validate(&self) -> Result<()> {
        let b = self.lod_bias;
        check(b.is_finite() && b >= 0.0, "lod_bias", b, "finite and >= 0")?;
        let s = self.step_factor;
        check((0.05..=4.0).contains(&s), "step_factor", s, "in [0.05, 4]")?;
        let m = self.max_distance;
        check(m > 0.0, "max_distance", m, "> 0 (infinity allowed)")?;
        let c = self.opacity_cutoff;
        check(c > 0.0 && c <= 1.0, "opacity_cutoff", c, "in (0, 1]")?;
        let g = self.background;
        check(g.is_finite(), "background", g.max_element(), "finite")?;
        Ok(())
    }
}

impl PinholeCamera {
    /// Checks the camera; errors name the field.
    pub fn validate(&self) -> Result<()> {
        check(self.eye.is_finite(), "camera eye", self.eye.length(), "finite")?;
        let f = self.target - self.eye;
        check(
            f.is_finite() && f.length() > 0.0,
            "camera target",
            f.length(),
            "finite, not the eye",
        )?;
        let cross = f.normalize().cross(self.up);
        check(
            self.up.is_finite() && cross.length_squared() > 1e-12,
            "camera up",
            self.up.length(),
            "finite, not parallel to the view direction",
        )?;
        let v = self.fov_y_deg;
        check(v > 0.0 && v < 180.0, "fov_y_deg", v, "a full angle in (0, 180)")?;
        for (name, side) in [("width", self.width), ("height", self.height)] {
            if !(1..=MAX_IMAGE_SIDE).contains(&side) {
                return Err(Error::InvalidParameter {
                    name,
                    value: side.to_string(),
                    reason: "in 1..=16384 pixels",
                });
            }
        }
        Ok(())
    }
}

/// What the caller's shading function gets for one sample (module docs).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ShadeInput {
    /// World position of the sample.
    pub position: Vec3,
    /// Opacity-weighted mean colour of the sample (linear albedo).
    pub albedo: Vec3,
    /// Unit shading normal, turned toward the viewer (two-sided).
    pub normal: Vec3,
    /// Unit direction toward the eye.
    pub to_viewer: Vec3,
    /// Light visibility in \[0, 1\] (1 without shadows).
    pub visibility: f32,
    /// Footprint diameter read, voxels (≥ 1), and the fractional level sampled.
    pub diameter: f32,
    /// Fractional octree level sampled (0 = leaves).
    pub level: f32,
    /// Distance from the eye, voxels.
    pub distance_voxels: f32,
}

/// One pixel's outcome.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PrimaryPixel {
    /// Linear RGB with the background composited, and coverage.
    pub rgba: Vec4,
    /// Octree samples of the primary cone.
    pub samples: u32,
    /// Octree samples of its shadow cones.
    pub shadow_samples: u32,
}

/// A rendered image: row-major from the top-left, and the samples it took.
#[derive(Clone, Debug, PartialEq)]
pub struct PrimaryImage {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// `width × height` linear RGBA pixels (module docs).
    pub pixels: Vec<Vec4>,
    /// Primary-cone octree samples over all pixels.
    pub samples: u64,
    /// Shadow-cone octree samples over all pixels.
    pub shadow_samples: u64,
}

/// Renders an Averages octree ([`SurfaceMedium`]) from a [`PinholeCamera`] with
/// footprint-driven level of detail (module docs).
#[derive(Clone, Debug)]
pub struct PrimaryRenderer<'a, M = AveragePayload> {
    tree: &'a Octree<M>,
    camera: PinholeCamera,
    light: Light,
    options: PrimaryOptions,
    forward: Vec3,
    right: Vec3,
    up: Vec3,
    /// `b · 2·tan(fov/2) / height`: footprint per unit distance.
    spread: f32,
    voxel: f32,
}

impl<'a, M: SurfaceMedium> PrimaryRenderer<'a, M> {
    /// A renderer of `tree` seen from `camera` under `light`. Errors on an invalid camera,
    /// option or light, each naming the field.
    pub fn new(
        tree: &'a Octree<M>,
        camera: PinholeCamera,
        light: Light,
        options: PrimaryOptions,
    ) -> Result<Self> {
        camera.validate()?;
        options.validate()?;
        light.validate()?;
        let forward = (camera.target - camera.eye).normalize();
        let right = forward.cross(camera.up).normalize();
        let up = right.cross(forward);
        let tan = (camera.fov_y_deg.to_radians() * 0.5).tan();
        let aspect = camera.width as f32 / camera.height as f32;
        let spread = options.lod_bias * 2.0 * tan / camera.height as f32;
        check(spread.is_finite(), "lod_bias", options.lod_bias, "a finite footprint per distance")?;
        Ok(Self {
            tree,
            camera,
            light,
            options,
            forward,
            right: right * (tan * aspect),
            up: up * tan,
            spread,
            voxel: tree.grid().voxel_size as f32,
        })
    }

    /// The options.
    pub fn options(&self) -> &PrimaryOptions {
        &self.options
    }

    /// Footprint diameter (voxels, before the 1-voxel floor) at `t` voxels from the eye:
    /// `bias · t · 2·tan(fov/2)/height` (module docs). Linear in `t`.
    pub fn footprint_voxels(&self, t: f32) -> f32 {
        self.spread * t
    }

    /// The fractional level a sample `t` voxels from the eye reads.
    pub fn level_at(&self, t: f32) -> f32 {
        self.tree.level_for_diameter(self.footprint_voxels(t))
    }

    /// The distance from the eye, voxels, at which the footprint spans `voxels` voxels (`None`
    /// with bias 0: never).
    pub fn distance_for_footprint(&self, voxels: f32) -> Option<f32> {
        (self.spread > 0.0).then(|| voxels / self.spread)
    }

    /// The full aperture of the pixel cones, radians: `2·atan(spread/2)`.
    pub fn aperture(&self) -> f32 {
        2.0 * (0.5 * self.spread).atan()
    }

    /// Unit direction of the ray through image point `p` (pixels from the top-left).
    pub fn ray_dir(&self, px: f32, py: f32) -> Vec3 {
        let ndc_x = 2.0 * px / self.camera.width as f32 - 1.0;
        let ndc_y = 1.0 - 2.0 * py / self.camera.height as f32;
        (self.forward + self.right * ndc_x + self.up * ndc_y).normalize()
    }

    /// Visibility of the light from a sample (module docs) and the samples it took.
    /// `t`: the sample's distance from the eye, voxels.
    fn visibility(&self, position: Vec3, normal: Vec3, t: f32) -> (f32, u32) {
        let footprint = self.footprint_voxels(t);
        let Some((l, e, _)) = self.light.at(position) else { return (1.0, 0) };
        if normal.dot(l) <= 0.0 || e == Vec3::ZERO {
            return (0.0, 0);
        }
        let offset = 1.5 * footprint.max(1.0) * self.voxel;
        let apex = position + normal * offset;
        let Some((dir, _, to_light)) = self.light.at(apex) else { return (1.0, 0) };
        let march = March {
            start_voxels: 0.0,
            step_factor: self.options.step_factor,
            max_distance: (to_light - self.voxel).max(0.0),
            opacity_cutoff: 0.99,
            ao: None,
        };
        let cone = Cone { apex, dir, aperture: self.aperture() };
        let r = march_cone(self.tree, &cone, &march, footprint, |_: &M, _| Vec3::ZERO);
        (1.0 - r.opacity, r.steps)
    }

    /// Marches pixel `(x, y)`'s cone, shading each contributing sample with `shade`.
    pub fn pixel(
        &self,
        x: u32,
        y: u32,
        shade: &(impl Fn(&ShadeInput) -> Vec3 + ?Sized),
    ) -> PrimaryPixel {
        let dir = self.ray_dir(x as f32 + 0.5, y as f32 + 0.5);
        let cone = Cone { apex: self.camera.eye, dir, aperture: self.aperture() };
        let march = March {
            start_voxels: 0.0,
            step_factor: self.options.step_factor,
            max_distance: self.options.max_distance,
            opacity_cutoff: self.options.opacity_cutoff,
            ao: None,
        };
        // (where the visibility was last computed, grid coordinates; the visibility)
        let mut shadow: Option<(Vec3, f32)> = None;
        let mut shadow_samples = 0u32;
        let r = march_cone(self.tree, &cone, &march, 0.0, |s: &M, i: &SampleInfo| {
            let position = self.camera.eye + dir * (i.t * self.voxel);
            let n = s.mean_normal();
            let normal = if n == Vec3::ZERO {
                -dir
            } else if n.dot(dir) > 0.0 {
                -n
            } else {
                n
            };
            let visibility = if self.options.shadows {
                match shadow {
                    Some((at, v)) if at.distance(i.pos) <= i.diameter => v,
                    _ => {
                        let (v, n) = self.visibility(position, normal, i.t);
                        shadow_samples += n;
                        shadow = Some((i.pos, v));
                        v
                    }
                }
            } else {
                1.0
            };
            shade(&ShadeInput {
                position,
                albedo: s.albedo(),
                normal,
                to_viewer: -dir,
                visibility,
                diameter: i.diameter,
                level: i.level,
                distance_voxels: i.t,
            })
        });
        let rgb = r.radiance + (1.0 - r.opacity) * self.options.background;
        PrimaryPixel { rgba: rgb.extend(r.opacity), samples: r.steps, shadow_samples }
    }

    /// Renders every pixel (rayon over rows).
    pub fn render(&self, shade: &(impl Fn(&ShadeInput) -> Vec3 + Sync + ?Sized)) -> PrimaryImage {
        let (w, h) = (self.camera.width, self.camera.height);
        let rows: Vec<Vec<PrimaryPixel>> = (0..h)
            .into_par_iter()
            .map(|y| (0..w).map(|x| self.pixel(x, y, shade)).collect())
            .collect();
        let mut img = PrimaryImage {
            width: w,
            height: h,
            pixels: Vec::with_capacity(w as usize * h as usize),
            samples: 0,
            shadow_samples: 0,
        };
        for p in rows.into_iter().flatten() {
            img.pixels.push(p.rgba);
            img.samples += p.samples as u64;
            img.shadow_samples += p.shadow_samples as u64;
        }
        img
    }
}

#[cfg(test)]
mod tests;
