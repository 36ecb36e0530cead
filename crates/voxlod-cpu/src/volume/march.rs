//! The eye-view ray march (McNabb 2015, §5.5.4, Listing 5.3) in the metavoxel sort order of §5.5.5,
//! the per-pixel checks it is measured against, and compositing over the mesh image.
//!
//! **Samples.** Eye rays are `eye + t · dir` with unit `dir` (`CameraFrame::ray_dir` through the
//! pixel centre, the ground-truth G-buffer's ray), so `t` is the distance the G-buffer's
//! `depth` holds. Samples sit at `t = (n + ½) · step` from the eye, the same positions whoever
//! marches them; a sample reads the voxel it falls in (nearest, the piecewise-constant field);
//! a ray stops at the pixel's depth. Per sample, `b = transmittance(σ · step)`, colour
//! `+= T · (1 − b) · radiance`, `T *= b` (Listing 5.3's lerp, front to back).
//!
//! **Sort order** ([`sort_order`]). Metavoxels are processed one at a time and each one's
//! segment (colour, transmittance) is blended into the pixel. With `e` the eye's metavoxel
//! coordinate (possibly outside the volume), the Manhattan distance `Σ|c − e|` strictly grows
//! along any ray from the eye as it enters new metavoxels, so sorting by it is a visibility
//! order. Metavoxels in the eye's slab or above it (`k ≤ e_k`, nearer the light: above the
//! perpendicular) go first, far to near, with **over** blending; those below go next, near to
//! far, with **under** blending (Ikits et al. 2004). Within each group the order is also top to
//! bottom in every column, the order light propagation needs (a test checks both). The eye's
//! own slab belongs with the first group: a ray leaving upward sees it in front of everything
//! above, a ray leaving downward sees it before everything below, and over-blending into an
//! empty pixel equals under-blending.
//!
//! The loops are nested the other way round for rayon (rows in parallel; within a row, the
//! metavoxels in sort order, each over the pixels its screen rectangle covers): the same
//! per-pixel sequence of blends, deterministic.
//!
//! Checks: [`render_front_to_back`] marches each pixel's samples in ray order through the whole
//! volume (no metavoxel order, no blending of segments); [`render_exact`] is the
//! [`Attenuation::Exact`] reference.

use glam::{Vec2, Vec3, Vec4};
use rayon::prelude::*;
use voxlod_scene::camera::CameraFrame;
use voxlod_scene::{Camera, Image};

use super::{Attenuation, Metavoxel, Volume};
use crate::render::check_image_size;
use crate::{Error, Result};

/// Options of the eye march.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MarchOptions {
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// Distance between samples, in voxels (> 0; the chapter steps one voxel). Cost is inverse
    /// to it; [`Attenuation::Exact`] ignores it.
    pub step: f32,
}

impl Default for MarchOptions {
    fn default() -> Self {
        Self { width: 512, height: 512, step: 1.0 }
    }
}

/// A pixel's accumulated colour (premultiplied) and transmittance.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Pixel {
    color: Vec3,
    t: f32,
}

impl Pixel {
    const EMPTY: Self = Self { color: Vec3::ZERO, t: 1.0 };

    fn rgba(self) -> Vec4 {
        self.color.extend(1.0 - self.t)
    }
}

/// Entry and exit `t` of the ray `o + t·d` through the box `[lo, hi]` (slab test), or `None`.
#[inline]
fn slab(o: Vec3, inv: Vec3, lo: Vec3, hi: Vec3) -> Option<(f32, f32)> {
    let a = (lo - o) * inv;
    let b = (hi - o) * inv;
    // NaN (0 · ∞ for a ray in a slab plane) is dropped by min/max.
    let t0 = a.min(b).max_element();
    let t1 = a.max(b).min_element();
    (t0 <= t1).then_some((t0, t1))
}

/// One checked pass of the common input: image size, step, camera, depth-buffer length.
fn check(camera: &Camera, options: &MarchOptions, depth: Option<&[f32]>) -> Result<CameraFrame> {
    check_image_size(options.width, options.height)?;
    if !(options.step.is_finite() && options.step > 0.0) {
        return Err(Error::InvalidParameter {
            name: "march step",
            value: options.step.to_string(),
            reason: "must be finite and > 0 voxels".into(),
        });
    }
    camera.validate()?;
    let pixels = options.width as usize * options.height as usize;
    if let Some(d) = depth
        && d.len() != pixels
    {
        return Err(Error::InvalidParameter {
            name: "depth buffer",
            value: format!("{} entries", d.len()),
            reason: format!("must have one per pixel ({pixels})"),
        });
    }
    Ok(camera.frame(options.width, options.height))
}

/// The pixel's depth limit (NaN or negative depths stop the ray at the eye).
#[inline]
fn limit(depth: Option<&[f32]>, pixel: usize) -> f32 {
    depth.map_or(f32::INFINITY, |d| if d[pixel] >= 0.0 { d[pixel] } else { 0.0 })
}

/// The processing order of the kept metavoxels for a camera at `eye`: indices into
/// `volume.metavoxels` and whether each is over-blended (true) or under-blended.
pub fn sort_order(volume: &Volume, eye: Vec3) -> Vec<(usize, bool)> {
    let q = volume.spec.frame.to_voxel(eye) / volume.spec.metavoxel_edge as f32;
    let e = q.floor().clamp(Vec3::splat(-1e6), Vec3::splat(1e6)).as_ivec3().as_i64vec3();
    let dist = |c: [u32; 3]| {
        (c[0] as i64 - e.x).abs() + (c[1] as i64 - e.y).abs() + (c[2] as i64 - e.z).abs()
    };
    let mut over = Vec::new();
    let mut under = Vec::new();
    for (i, mv) in volume.metavoxels.iter().enumerate() {
        let d = dist(mv.coord);
        if mv.coord[2] as i64 <= e.z { over.push((d, i)) } else { under.push((d, i)) }
    }
    // Far to near (ties by index, which is top to bottom within a column), then near to far.
    over.sort_by(|a, b| b.0.cmp(&a.0).then(a.1.cmp(&b.1)));
    under.sort();
    over.into_iter()
        .map(|(_, i)| (i, true))
        .chain(under.into_iter().map(|(_, i)| (i, false)))
        .collect()
}

/// The box a ray marches through in metavoxel `mv` (voxel coordinates): its occupied box
/// grown by one voxel and clipped to the metavoxel, so that every sample that can fall in a
/// non-zero voxel lies in it (the samples skipped all read zero voxels: the same image).
fn march_box(volume: &Volume, mv: &Metavoxel) -> (Vec3, Vec3) {
    let m = volume.spec.metavoxel_edge as f32;
    let base = Vec3::new(mv.coord[0] as f32, mv.coord[1] as f32, mv.coord[2] as f32) * m;
    let [lo, hi] = mv.occupied;
    let lo = (Vec3::new(lo[0] as f32, lo[1] as f32, lo[2] as f32) - 1.0).max(Vec3::ZERO);
    let hi = (Vec3::new(hi[0] as f32, hi[1] as f32, hi[2] as f32) + 1.0).min(Vec3::splat(m));
    (base + lo, base + hi)
}

/// Screen rectangle (x0, y0, x1, y1), exclusive ends, that the voxel-space box `[lo, hi]`
/// projects to; the whole image when a corner is behind the eye.
fn screen_rect(volume: &Volume, frame: &CameraFrame, (lo, hi): (Vec3, Vec3)) -> [u32; 4] {
    let (mut a, mut b) = (Vec2::splat(f32::INFINITY), Vec2::splat(f32::NEG_INFINITY));
    for k in 0..8 {
        let q = Vec3::select(glam::BVec3::new(k & 1 != 0, k & 2 != 0, k & 4 != 0), hi, lo);
        match frame.project(volume.spec.frame.to_world(q)) {
            Some((p, _)) if p.is_finite() => {
                a = a.min(p);
                b = b.max(p);
            }
            _ => return [0, 0, frame.width, frame.height],
        }
    }
    let (w, h) = (frame.width as f32, frame.height as f32);
    let x0 = (a.x - 1.0).floor().clamp(0.0, w) as u32;
    let y0 = (a.y - 1.0).floor().clamp(0.0, h) as u32;
    let x1 = (b.x + 1.0).ceil().clamp(0.0, w) as u32;
    let y1 = (b.y + 1.0).ceil().clamp(0.0, h) as u32;
    [x0, y0, x1, y1]
}

/// Samples of the ray in metavoxel `mv` between `t0` and `t1`: its segment's (colour,
/// transmittance), front to back.
#[allow(clippy::too_many_arguments)]
#[inline]
fn march_segment(
    volume: &Volume,
    voxels: &[Vec4],
    base: Vec3,
    o: Vec3,
    d: Vec3,
    (t0, t1): (f32, f32),
    step: f32,
) -> Pixel {
    let m = volume.spec.metavoxel_edge as usize;
    let last = (m - 1) as i32;
    let att = volume.attenuation;
    let mut px = Pixel::EMPTY;
    let mut n = (t0 / step - 0.5).ceil().max(0.0);
    loop {
        let t = (n + 0.5) * step;
        if t >= t1 {
            break;
        }
        if t >= t0 {
            // Truncation clamped at 0 is the floor clamped at 0 (NaN reads voxel 0 either way).
            let l = o + d * t - base;
            let (x, y, z) = (
                (l.x as i32).clamp(0, last),
                (l.y as i32).clamp(0, last),
                (l.z as i32).clamp(0, last),
            );
            let v = voxels[(z as usize * m + y as usize) * m + x as usize];
            if v.w > 0.0 {
                let b = att.transmittance(v.w * step);
                px.color += v.truncate() * (px.t * (1.0 - b));
                px.t *= b;
            }
        }
        n += 1.0;
    }
    px
}

/// Renders `volume` from `camera` in the chapter's metavoxel order with over/under blending
/// (see the module docs): a premultiplied RGBA image, alpha the opacity `1 − T`. `depth` (one
/// distance per pixel, as in the ground truth's G-buffer; `INFINITY` on a miss) stops the rays
/// at the mesh. A volume built with [`Attenuation::Exact`] is rendered by [`render_exact`].
pub fn render(
    volume: &Volume,
    camera: &Camera,
    options: &MarchOptions,
    depth: Option<&[f32]>,
) -> Result<Image> {
    if volume.attenuation == Attenuation::Exact {
        return render_exact(volume, camera, options, depth);
    }
    let frame = check(camera, options, depth)?;
    // Metavoxels the fill wrote nothing into are skipped (they would add nothing).
    let order: Vec<(usize, bool)> = sort_order(volume, frame.eye)
        .into_iter()
        .filter(|&(i, _)| !volume.metavoxels[i].is_empty())
        .collect();
    let boxes: Vec<(Vec3, Vec3)> =
        order.iter().map(|&(i, _)| march_box(volume, &volume.metavoxels[i])).collect();
    let rects: Vec<[u32; 4]> = boxes.iter().map(|&b| screen_rect(volume, &frame, b)).collect();
    let f = &volume.spec.frame;
    let o = f.to_voxel(frame.eye);
    let m = volume.spec.metavoxel_edge as f32;
    let step = options.step * f.voxel_size;
    let w = options.width as usize;
    let mut image = Image::new(options.width, options.height, Vec4::ZERO);
    image.pixels.par_chunks_mut(w).enumerate().for_each(|(y, row)| {
        let mut acc = vec![Pixel::EMPTY; w];
        let dirs: Vec<Vec3> = (0..w)
            .map(|x| f.dir_to_voxel(frame.ray_dir(Vec2::new(x as f32 + 0.5, y as f32 + 0.5))))
            .collect();
        for ((&(i, over), rect), &(lo, hi)) in order.iter().zip(&rects).zip(&boxes) {
            if (y as u32) < rect[1] || (y as u32) >= rect[3] {
                continue;
            }
            let mv = &volume.metavoxels[i];
            let base = Vec3::new(mv.coord[0] as f32, mv.coord[1] as f32, mv.coord[2] as f32) * m;
            for x in rect[0] as usize..rect[2] as usize {
                let d = dirs[x];
                // The segment within the metavoxel (which decides the sample set, as before),
                // clipped to its marched box.
                let inv = d.recip();
                let Some((t0, t1)) = slab(o, inv, base, base + m) else { continue };
                let Some((b0, b1)) = slab(o, inv, lo, hi) else { continue };
                let (t0, t1) = (t0.max(b0), t1.min(b1));
                let t1 = t1.min(limit(depth, y * w + x));
                let t0 = t0.max(0.0);
                if t0 >= t1 {
                    continue;
                }
                let seg = march_segment(volume, &mv.voxels, base, o, d, (t0, t1), step);
                let p = &mut acc[x];
                if over {
                    p.color = seg.color + p.color * seg.t;
                } else {
                    p.color += seg.color * p.t;
                }
                p.t *= seg.t;
            }
        }
        for (out, p) in row.iter_mut().zip(acc) {
            *out = p.rgba();
        }
    });
    Ok(image)
}

/// The per-pixel check of [`render`]: each pixel's samples in ray order through the whole
/// volume, one accumulator, empty and culled metavoxels skipped. Equal to [`render`] up to
/// float rounding (and samples that fall exactly on a metavoxel face).
pub fn render_front_to_back(
    volume: &Volume,
    camera: &Camera,
    options: &MarchOptions,
    depth: Option<&[f32]>,
) -> Result<Image> {
    let frame = check(camera, options, depth)?;
    let f = &volume.spec.frame;
    let o = f.to_voxel(frame.eye);
    let mu = volume.spec.metavoxel_edge;
    let (m, mm) = (mu as f32, mu as usize);
    let n = volume.spec.voxels_per_axis() as f32;
    let step = options.step * f.voxel_size;
    let att = volume.attenuation;
    let w = options.width as usize;
    let mut image = Image::new(options.width, options.height, Vec4::ZERO);
    image.pixels.par_iter_mut().enumerate().for_each(|(pixel, out)| {
        let (x, y) = (pixel % w, pixel / w);
        let d = f.dir_to_voxel(frame.ray_dir(Vec2::new(x as f32 + 0.5, y as f32 + 0.5)));
        let inv = d.recip();
        let mut px = Pixel::EMPTY;
        if let Some((t0, t1)) = slab(o, inv, Vec3::ZERO, Vec3::splat(n)) {
            let t1 = t1.min(limit(depth, pixel));
            let mut k = (t0.max(0.0) / step - 0.5).ceil().max(0.0);
            loop {
                let t = (k + 0.5) * step;
                if t >= t1 {
                    break;
                }
                let g = (o + d * t).floor().clamp(Vec3::ZERO, Vec3::splat(n - 1.0));
                let c = (g / m).floor();
                let coord = [c.x as u32, c.y as u32, c.z as u32];
                match volume.metavoxel(coord) {
                    Some(mv) => {
                        let l = g - c * m;
                        let v = mv.voxels[(l.z as usize * mm + l.y as usize) * mm + l.x as usize];
                        if v.w > 0.0 {
                            let b = att.transmittance(v.w * step);
                            px.color += v.truncate() * (px.t * (1.0 - b));
                            px.t *= b;
                        }
                        k += 1.0;
                    }
                    None => {
                        // Jump to the first sample beyond this empty metavoxel.
                        let lo = c * m;
                        let exit = slab(o, inv, lo, lo + m).map_or(t, |s| s.1);
                        k = (k + 1.0).max((exit / step - 0.5).ceil());
                    }
                }
            }
        }
        *out = px.rgba();
    });
    Ok(image)
}

/// The [`Attenuation::Exact`] reference: per pixel, every voxel the ray crosses in order, with
/// its exact segment length `ℓ`: colour `+= T · (1 − e^(−σℓ)) · radiance`, `T *= e^(−σℓ)` —
/// Beer–Lambert integrated exactly over the piecewise-constant field. Whatever attenuation the
/// volume was lit with, this march uses the exponential; build with [`Attenuation::Exact`] for
/// the reference lighting too.
pub fn render_exact(
    volume: &Volume,
    camera: &Camera,
    options: &MarchOptions,
    depth: Option<&[f32]>,
) -> Result<Image> {
    let frame = check(camera, options, depth)?;
    let f = &volume.spec.frame;
    let o = f.to_voxel(frame.eye);
    let mu = volume.spec.metavoxel_edge;
    let (m, mm) = (mu as f32, mu as usize);
    let n = volume.spec.voxels_per_axis() as f32;
    // A nudge past a cell's exit face, so the next cell is looked up from inside it.
    let nudge = 1e-4 * f.voxel_size;
    let w = options.width as usize;
    let mut image = Image::new(options.width, options.height, Vec4::ZERO);
    image.pixels.par_iter_mut().enumerate().for_each(|(pixel, out)| {
        let (x, y) = (pixel % w, pixel / w);
        let d = f.dir_to_voxel(frame.ray_dir(Vec2::new(x as f32 + 0.5, y as f32 + 0.5)));
        let inv = d.recip();
        let mut px = Pixel::EMPTY;
        if let Some((t0, t1)) = slab(o, inv, Vec3::ZERO, Vec3::splat(n)) {
            let t1 = t1.min(limit(depth, pixel));
            let mut t = t0.max(0.0);
            while t < t1 && px.t > 0.0 {
                let g = (o + d * (t + nudge)).floor().clamp(Vec3::ZERO, Vec3::splat(n - 1.0));
                let c = (g / m).floor();
                let coord = [c.x as u32, c.y as u32, c.z as u32];
                let (cell_lo, size, voxel) = match volume.metavoxel(coord) {
                    Some(mv) => {
                        let l = g - c * m;
                        (
                            g,
                            1.0,
                            Some(mv.voxels[(l.z as usize * mm + l.y as usize) * mm + l.x as usize]),
                        )
                    }
                    None => (c * m, m, None),
                };
                let exit = slab(o, inv, cell_lo, cell_lo + size).map_or(t + nudge, |s| s.1);
                let end = exit.max(t + nudge).min(t1);
                if end <= t {
                    break; // t too large for the nudge to move it
                }
                if let Some(v) = voxel
                    && v.w > 0.0
                {
                    let b = (-(v.w * (end - t))).exp();
                    px.color += v.truncate() * (px.t * (1.0 - b));
                    px.t *= b;
                }
                t = end;
            }
        }
        *out = px.rgba();
    });
    Ok(image)
}

/// Composites a premultiplied volume image over the mesh image: `rgb = v.rgb + (1 − v.a) ·
/// mesh.rgb`, `a = v.a + (1 − v.a) · mesh.a`. Errors when the sizes differ.
pub fn composite(volume: &Image, mesh: &Image) -> Result<Image> {
    if (volume.width, volume.height) != (mesh.width, mesh.height) {
        return Err(Error::InvalidParameter {
            name: "composite image size",
            value: format!(
                "{}×{} over {}×{}",
                volume.width, volume.height, mesh.width, mesh.height
            ),
            reason: "both images must have the same size".into(),
        });
    }
    let pixels = volume
        .pixels
        .iter()
        .zip(&mesh.pixels)
        .map(|(v, m)| {
            let k = 1.0 - v.w;
            (v.truncate() + m.truncate() * k).extend(v.w + m.w * k)
        })
        .collect();
    Ok(Image { width: mesh.width, height: mesh.height, pixels })
}
