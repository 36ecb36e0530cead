//! Differential cone tracing with coverage masks (Heitz and Neyret 2012, §4 and Algorithm 1):
//! primary visibility through an octree of [`MicrosurfacePayload`]s, one cone per pixel cut
//! into elements as long as they are wide, each element's share of the pixel decided by its
//! macro-surface plane as a mask of the pixel's 128 rays, and its colour by the micro-surface
//! statistics (view- and light-dependent). The alpha-blending baseline is
//! [`crate::PrimaryRenderer`] on Averages; [`Compositing::AlphaBlending`] composites this
//! renderer's own elements as if uncorrelated (the paper's Eq. 12), to isolate what the masks
//! change.
//!
//! | module | owns |
//! |---|---|
//! | [`mask`] | the 128 rays, the (θ, v) mask table, an element's mask |
//! | [`shading`] | Λ, Eq. 17, the shadowing of the visible micro-surface, the convolved lobe |
//!
//! # Definitions
//! - **Camera and pixel frame**: [`PinholeCamera`] (the convention of [`crate::primary`]); a
//!   pixel's cone has axis `z̄` through the pixel's centre, and its footprint's axes are the
//!   camera's right and up vectors made perpendicular to `z̄` (`x̄`, then `ȳ = x̄ × z̄`), the
//!   same for every element of the pixel, so that bit `k` is the same ray all along.
//! - **Footprint**: diameter `d(t) = b·t·2·tan(fov/2)/height + 2·R·|t − F|/F` voxels at
//!   distance `t` (voxels) along the axis: the pixel's width scaled by the LOD bias `b`, plus
//!   the circle of confusion of a thin lens of radius `R` focused at distance `F`
//!   ([`DepthOfField`]; depth of field by widening cones, §6).
//! - **Elements**: from the octree's cube entry on, element `k` spans `[t_k, t_k + len_k]`
//!   with `len_k = f·max(d(t_k), 1)` (`f` = [`DifferentialOptions::element_factor`], 1: as
//!   long as wide, the paper's; never shorter than a voxel) and is read at its centre `t_c`:
//!   the octree sampled quadrilinearly with diameter `d(t_c)` (level `log2(max(d, 1))`), the
//!   element's half-width `r = d(t_c)/2` and half-length `l = len/2`. Elements tile the axis.
//! - **Coverage** (§5.4): the sample's plane (through its centroid, normal `n̄`) gives the
//!   element's mask ([`mask::MaskTable::element`]); coverage and `σh` do not enter it. A
//!   sample without coverage covers nothing.
//! - **Accumulation**: [`Compositing::CoverageMasks`]: `L += L_d·|mask ∖ α|/128`,
//!   `α |= mask`, stopping once `α` is full. [`Compositing::AlphaBlending`]: the element's
//!   opacity is `|mask|/128` and it is composited front to back as `w = (1 − A)·a`,
//!   `L += w·L_d`, `A += w`, stopping at `A ≥ 0.999` (correlation ignored).
//! - **Shading** `L_d` (only for elements that add something): the caller's function gets
//!   [`SurfaceShadeInput`], the element's [`shading::LocalIllumination`] with the light's
//!   visibility `V̄(l)·V_shadow`; voxlod's CLI passes voxlod-cpu's `shade()` with the visible
//!   colours, the convolved exponent and the ambient term on `ā(v)`.
//! - **Shadows** ([`DifferentialOptions::shadows`]): a cone toward the light from the element's
//!   centre moved `1.5·max(d, 1)` voxels along its shading normal, starting `d` wide and
//!   widening at the pixel cone's aperture, marched with masks in its own frame (no shading);
//!   `V_shadow = 1 − |α|/128`, ending one voxel short of a point light. Computed at a pixel's
//!   first contributing element and again once the march is more than one footprint from
//!   where it was last computed.
//! - **Output**: RGBA per pixel, `rgb = L + (1 − A)·background`, `a = A` (`|α|/128` with
//!   masks), linear.

pub mod mask;
pub mod shading;

use glam::{DVec3, Vec3, Vec4};
use rayon::prelude::*;
use voxlod_octree::{MicrosurfacePayload, Octree};

use crate::error::check;
use crate::inject::Light;
use crate::primary::PinholeCamera;
use crate::{Error, Result};
use mask::{EMPTY, FULL, MASK_BITS, Mask, MaskTable, count, minus, union};
use shading::{LocalIllumination, local_illumination};

/// How element contributions are combined.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Compositing {
    /// The paper's: masks of the pixel's 128 rays, each ray counted once (correlated).
    #[default]
    CoverageMasks,
    /// Each element's coverage fraction as an opacity, blended front to back (uncorrelated).
    AlphaBlending,
}

/// A thin lens (module docs: depth of field by widening cones).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DepthOfField {
    /// Lens radius, world units, ≥ 0 and finite.
    pub lens_radius: f32,
    /// Distance in focus along the axis, world units, > 0 and finite.
    pub focus_distance: f32,
}

/// Options of a [`DifferentialRenderer`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DifferentialOptions {
    /// Footprint multiplier `b` (module docs), finite and ≥ 0 (default 1: the pixel).
    pub lod_bias: f32,
    /// Element length over footprint diameter, in \[0.25, 4\] (default 1, the paper's).
    pub element_factor: f32,
    /// Masks (default) or alpha blending.
    pub compositing: Compositing,
    /// Shadow cones (default on).
    pub shadows: bool,
    /// A thin lens (default none: a pinhole).
    pub depth_of_field: Option<DepthOfField>,
    /// Longest distance marched from the eye, world units, > 0 (default `f32::INFINITY`).
    pub max_distance: f32,
    /// Linear RGB behind what the cones did not cover, finite.
    pub background: Vec3,
}

impl Default for DifferentialOptions {
    fn default() -> Self {
        Self {
            lod_bias: 1.0,
            element_factor: 1.0,
            compositing: Compositing::CoverageMasks,
            shadows: true,
            depth_of_field: None,
            max_distance: f32::INFINITY,
            background: Vec3::ZERO,
        }
    }
}

impl DifferentialOptions {
    /// Checks every field against its documented range; errors name the field.
    pub fn validate(&self) -> Result<()> {
        let b = self.lod_bias;
        check(b.is_finite() && b >= 0.0, "lod_bias", b, "finite and >= 0")?;
        let f = self.element_factor;
        check((0.25..=4.0).contains(&f), "element_factor", f, "in [0.25, 4]")?;
        let m = self.max_distance;
        check(m > 0.0, "max_distance", m, "> 0 (infinity allowed)")?;
        let g = self.background;
        check(g.is_finite(), "background", g.max_element(), "finite")?;
        if let Some(d) = self.depth_of_field {
            let r = d.lens_radius;
            check(r.is_finite() && r >= 0.0, "lens_radius", r, "finite and >= 0")?;
            let fd = d.focus_distance;
            check(fd.is_finite() && fd > 0.0, "focus_distance", fd, "finite and > 0")?;
        }
        Ok(())
    }
}

/// What the caller's shading function gets for one element (module docs).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SurfaceShadeInput {
    /// World position of the element's centre.
    pub position: Vec3,
    /// Unit direction toward the eye.
    pub to_viewer: Vec3,
    /// The micro-surface's effect on the shading (normal, visible colours, lobe).
    pub illumination: LocalIllumination,
    /// Light visibility in \[0, 1\]: `V̄(l)` times the shadow cone's (1 without shadows).
    pub visibility: f32,
    /// Footprint diameter at the element's centre, voxels (before the 1-voxel floor).
    pub diameter: f32,
    /// Fractional octree level sampled.
    pub level: f32,
    /// Distance of the element's centre from the eye, voxels.
    pub distance_voxels: f32,
}

/// One pixel's outcome.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct DifferentialPixel {
    /// Linear RGB with the background composited, and coverage.
    pub rgba: Vec4,
    /// Elements (octree samples) of the pixel's cone.
    pub elements: u32,
    /// Elements that added coverage (and were shaded).
    pub shaded: u32,
    /// Elements of its shadow cones.
    pub shadow_elements: u32,
}

/// A rendered image: row-major from the top-left, and the work it took.
#[derive(Clone, Debug, PartialEq)]
pub struct DifferentialImage {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// `width × height` linear RGBA pixels (module docs).
    pub pixels: Vec<Vec4>,
    /// Primary-cone elements over all pixels.
    pub elements: u64,
    /// Shaded elements over all pixels.
    pub shaded: u64,
    /// Shadow-cone elements over all pixels.
    pub shadow_elements: u64,
}

/// The set-up a [`DifferentialRenderer`] derives from its camera and options, exposed for GPU
/// mirrors of it (so that both start from the same numbers).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FrameConstants {
    /// Unit view direction.
    pub forward: Vec3,
    /// Camera right, scaled by `tan(fov/2)·aspect` (a pixel's direction is
    /// `normalize(forward + right·ndc_x + up·ndc_y)`).
    pub right: Vec3,
    /// Camera up, scaled by `tan(fov/2)`.
    pub up: Vec3,
    /// Footprint per unit distance, `b·2·tan(fov/2)/height`.
    pub spread: f32,
    /// Circle-of-confusion factor `2R/F` (0 without a lens).
    pub coc: f32,
    /// Focus distance `F`, voxels (1 without a lens).
    pub focus: f32,
    /// The eye in grid coordinates.
    pub origin: Vec3,
    /// Longest march, voxels (`max_distance / voxel size`; may be infinite).
    pub max_t: f32,
}

/// Differential cone tracing of a [`MicrosurfacePayload`] octree (module docs).
#[derive(Clone, Debug)]
pub struct DifferentialRenderer<'a> {
    tree: &'a Octree<MicrosurfacePayload>,
    table: &'static MaskTable,
    camera: PinholeCamera,
    light: Light,
    options: DifferentialOptions,
    forward: Vec3,
    right: Vec3,
    up: Vec3,
    /// Footprint per unit distance (voxels per voxel).
    spread: f32,
    /// Lens radius and focus distance, voxels (radius 0: none).
    lens: (f32, f32),
    voxel: f32,
}

/// Where a cone starts and how its footprint grows: `d(t) = d0 + spread·t + coc·|t − focus|`.
#[derive(Clone, Copy, Debug)]
struct Footprint {
    d0: f32,
    spread: f32,
    coc: f32,
    focus: f32,
}

impl Footprint {
    #[inline]
    fn at(&self, t: f32) -> f32 {
        let d = self.d0 + self.spread * t + self.coc * (t - self.focus).abs();
        if d.is_finite() { d.max(0.0) } else { f32::MAX }
    }
}

/// What a mask march gathered.
struct Gathered {
    radiance: Vec3,
    /// Coverage in \[0, 1\].
    alpha: f32,
    elements: u32,
    shaded: u32,
}

impl<'a> DifferentialRenderer<'a> {
    /// A renderer of `tree` seen from `camera` under `light`. Errors on an invalid camera,
    /// option or light, each naming the field.
    pub fn new(
        tree: &'a Octree<MicrosurfacePayload>,
        camera: PinholeCamera,
        light: Light,
        options: DifferentialOptions,
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
        let voxel = tree.grid().voxel_size as f32;
        let lens = options
            .depth_of_field
            .map_or((0.0, 1.0), |d| (d.lens_radius / voxel, d.focus_distance / voxel));
        if !(lens.0.is_finite() && lens.1.is_finite() && lens.1 > 0.0) {
            return Err(Error::InvalidParameter {
                name: "depth_of_field",
                value: format!("{:?}", options.depth_of_field),
                reason: "lens radius and focus distance must stay finite in voxels",
            });
        }
        Ok(Self {
            tree,
            table: MaskTable::get(),
            camera,
            light,
            options,
            forward,
            right: right * (tan * aspect),
            up: up * tan,
            spread,
            lens,
            voxel,
        })
    }

    /// The options.
    pub fn options(&self) -> &DifferentialOptions {
        &self.options
    }

    /// The octree rendered.
    pub fn tree(&self) -> &'a Octree<MicrosurfacePayload> {
        self.tree
    }

    /// The light.
    pub fn light(&self) -> &Light {
        &self.light
    }

    /// The camera.
    pub fn camera(&self) -> &PinholeCamera {
        &self.camera
    }

    /// The set-up a GPU mirror starts from ([`FrameConstants`]).
    pub fn frame_constants(&self) -> FrameConstants {
        let (r, f) = self.lens;
        FrameConstants {
            forward: self.forward,
            right: self.right,
            up: self.up,
            spread: self.spread,
            coc: 2.0 * r / f,
            focus: f,
            origin: self.tree.grid().to_grid(DVec3::from(self.camera.eye)).as_vec3(),
            max_t: self.options.max_distance / self.voxel,
        }
    }

    /// Footprint diameter (voxels) at `t` voxels from the eye along a pixel's axis (module
    /// docs), before the one-voxel floor of the octree read.
    pub fn footprint_voxels(&self, t: f32) -> f32 {
        self.footprint(0.0).at(t)
    }

    fn footprint(&self, d0: f32) -> Footprint {
        let c = self.frame_constants();
        Footprint { d0, spread: c.spread, coc: c.coc, focus: c.focus }
    }

    /// Unit direction of the ray through image point `(px, py)` (pixels from the top-left).
    pub fn ray_dir(&self, px: f32, py: f32) -> Vec3 {
        let ndc_x = 2.0 * px / self.camera.width as f32 - 1.0;
        let ndc_y = 1.0 - 2.0 * py / self.camera.height as f32;
        (self.forward + self.right * ndc_x + self.up * ndc_y).normalize()
    }

    /// The footprint frame of a cone with unit axis `dir` (module docs): `x̄`, `ȳ`.
    fn frame(&self, dir: Vec3) -> (Vec3, Vec3) {
        let x = (self.right - dir * self.right.dot(dir)).normalize_or_zero();
        let x = if x == Vec3::ZERO { dir.any_orthonormal_vector() } else { x };
        (x, x.cross(dir))
    }

    /// Marches one cone with masks from `origin` (grid coordinates) along unit `dir`, footprint
    /// `fp`, frame `(x, y)`, up to `max_t` voxels; `shade` is called for every element that
    /// adds coverage, with its centre (grid), distance, diameter, level and sample, and returns
    /// its radiance (`None`: no shading, coverage only).
    #[allow(clippy::too_many_arguments)]
    fn march(
        &self,
        origin: Vec3,
        dir: Vec3,
        frame: (Vec3, Vec3),
        fp: Footprint,
        max_t: f32,
        compositing: Compositing,
        mut shade: impl FnMut(Vec3, f32, f32, f32, &voxlod_octree::Microsurface) -> Vec3,
    ) -> Gathered {
        let mut out = Gathered { radiance: Vec3::ZERO, alpha: 0.0, elements: 0, shaded: 0 };
        let res = (1u64 << self.tree.depth()) as f32;
        let (enter, exit) = crate::cone::slab(origin, dir, -1.0, res + 1.0);
        let max_t = max_t.min(exit);
        let mut t = enter.max(0.0);
        let mut alpha: Mask = EMPTY;
        let mut a = 0.0f32;
        let factor = self.options.element_factor;
        while t <= max_t {
            let len = factor * fp.at(t).max(1.0);
            let tc = t + 0.5 * len;
            let d = fp.at(tc);
            let level = self.tree.level_for_diameter(d);
            let p = origin + dir * tc;
            out.elements += 1;
            if let Some(s) = self.tree.sample_at_level(p, level).decode() {
                let n = Vec3::new(s.normal.dot(frame.0), s.normal.dot(frame.1), s.normal.dot(dir));
                let m = self.table.element(n, s.distance, 0.5 * d, 0.5 * len);
                match compositing {
                    Compositing::CoverageMasks => {
                        let new = count(&minus(&m, &alpha));
                        if new > 0 {
                            let l = shade(p, tc, d, level, &s);
                            out.radiance += l * (new as f32 / MASK_BITS as f32);
                            out.shaded += 1;
                            alpha = union(&alpha, &m);
                            if alpha == FULL {
                                break;
                            }
                        }
                    }
                    Compositing::AlphaBlending => {
                        let w = (1.0 - a) * (count(&m) as f32 / MASK_BITS as f32);
                        if w > 0.0 {
                            out.radiance += w * shade(p, tc, d, level, &s);
                            out.shaded += 1;
                            a += w;
                            if a >= 0.999 {
                                break;
                            }
                        }
                    }
                }
            }
            t += len;
        }
        out.alpha = match compositing {
            Compositing::CoverageMasks => count(&alpha) as f32 / MASK_BITS as f32,
            Compositing::AlphaBlending => a.clamp(0.0, 1.0),
        };
        out
    }

    /// Visibility of the light from an element centred at `p` (grid) with shading normal `n`
    /// and footprint `d` voxels (module docs), and the elements it took.
    fn shadow(&self, p: Vec3, n: Vec3, d: f32) -> (f32, u32) {
        let world = self.world(p);
        let Some((l, e, _)) = self.light.at(world) else { return (1.0, 0) };
        if n.dot(l) <= 0.0 || e == Vec3::ZERO {
            return (0.0, 0);
        }
        let apex = p + n * (1.5 * d.max(1.0));
        let Some((dir, _, to_light)) = self.light.at(self.world(apex)) else { return (1.0, 0) };
        let max_t = (to_light / self.voxel - 1.0).max(0.0);
        let frame = (dir.any_orthonormal_vector(), Vec3::ZERO);
        let frame = (frame.0, frame.0.cross(dir));
        let fp = Footprint { d0: d, spread: self.spread, coc: 0.0, focus: 1.0 };
        let g =
            self.march(apex, dir, frame, fp, max_t, Compositing::CoverageMasks, |_, _, _, _, _| {
                Vec3::ZERO
            });
        (1.0 - g.alpha, g.elements)
    }

    fn world(&self, grid: Vec3) -> Vec3 {
        let g = self.tree.grid();
        (g.origin + grid.as_dvec3() * g.voxel_size).as_vec3()
    }

    /// Marches pixel `(x, y)`'s cone, shading each contributing element with `shade`.
    pub fn pixel(
        &self,
        x: u32,
        y: u32,
        shade: &(impl Fn(&SurfaceShadeInput) -> Vec3 + ?Sized),
    ) -> DifferentialPixel {
        let dir = self.ray_dir(x as f32 + 0.5, y as f32 + 0.5);
        let FrameConstants { origin, max_t, .. } = self.frame_constants();
        let frame = self.frame(dir);
        let mut shadow: Option<(Vec3, f32)> = None;
        let mut shadow_elements = 0u32;
        let g = self.march(
            origin,
            dir,
            frame,
            self.footprint(0.0),
            max_t,
            self.options.compositing,
            |p, t, d, level, s| {
                let position = self.world(p);
                let to_light = self.light.at(position).map(|(l, _, _)| l);
                let illumination = local_illumination(s, -dir, to_light);
                let v_shadow = if self.options.shadows && to_light.is_some() {
                    match shadow {
                        Some((at, v)) if at.distance(p) <= d.max(1.0) => v,
                        _ => {
                            let (v, n) = self.shadow(p, illumination.normal, d);
                            shadow_elements += n;
                            shadow = Some((p, v));
                            v
                        }
                    }
                } else {
                    1.0
                };
                shade(&SurfaceShadeInput {
                    position,
                    to_viewer: -dir,
                    illumination,
                    visibility: illumination.light_visibility * v_shadow,
                    diameter: d,
                    level,
                    distance_voxels: t,
                })
            },
        );
        let rgb = g.radiance + (1.0 - g.alpha) * self.options.background;
        DifferentialPixel {
            rgba: rgb.extend(g.alpha),
            elements: g.elements,
            shaded: g.shaded,
            shadow_elements,
        }
    }

    /// Renders every pixel (rayon over rows).
    pub fn render(
        &self,
        shade: &(impl Fn(&SurfaceShadeInput) -> Vec3 + Sync + ?Sized),
    ) -> DifferentialImage {
        let (w, h) = (self.camera.width, self.camera.height);
        let rows: Vec<Vec<DifferentialPixel>> = (0..h)
            .into_par_iter()
            .map(|y| (0..w).map(|x| self.pixel(x, y, shade)).collect())
            .collect();
        let mut img = DifferentialImage {
            width: w,
            height: h,
            pixels: Vec::with_capacity(w as usize * h as usize),
            elements: 0,
            shaded: 0,
            shadow_elements: 0,
        };
        for p in rows.into_iter().flatten() {
            img.pixels.push(p.rgba);
            img.elements += p.elements as u64;
            img.shaded += p.shaded as u64;
            img.shadow_elements += p.shadow_elements as u64;
        }
        img
    }
}

#[cfg(test)]
mod tests;
