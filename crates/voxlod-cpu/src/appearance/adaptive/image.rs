//! The image-error predictor ([`super`], "The image error"): what a voxel's record changes in
//! the pixels that see it, from the held-out truth of every voxel composited along the
//! direction bins.

use glam::{UVec3, Vec3};
use rayon::prelude::*;
use voxlod_format::records::quant::linear_to_srgb;
use voxlod_format::{BrickMap, GridSpec};
use voxlod_scene::{Light, LightSample, MaterialSample};

use super::heldout::{BINS, HeldOut, MIN_SURFACE_HITS, nearest_bin};
use crate::render::bricks::voxel_index;
use crate::render::dda::Dda;
use crate::shading::shade;

/// Transmittance under which a walk stops (as the renderer's).
const MIN_T: f32 = 0.001;

/// What the held-out lines of one voxel say per direction bin (the truth), and each
/// candidate's opacity per bin.
#[derive(Clone, Copy, Debug)]
pub(super) struct VoxelBins {
    /// Bit `b`: bin `b` has at least one held-out line.
    pub seen: u16,
    /// Bit `b`: bin `b` has at least [`MIN_SURFACE_HITS`] surface hits.
    pub shaded: u16,
    /// True opacity per bin (bins without lines: the mean of the others).
    pub alpha: [f32; 14],
    /// Mean radiance of the bin's surface hits toward their viewers at light visibility 0 and
    /// 1 (the shading is linear in the visibility).
    pub radiance: [[Vec3; 14]; 2],
    /// Per candidate (Averages, \[VJK21\], virtual mesh), its opacity per bin.
    pub alpha_hat: [[f32; 14]; 3],
}

impl VoxelBins {
    /// The truth of `held` under `light` (seen from the voxel centre) with `ambient`, and the
    /// candidates' opacities `alpha_hat`.
    pub fn new(
        held: &HeldOut<'_>,
        light: &LightSample,
        ambient: Vec3,
        alpha_hat: [[f32; 14]; 3],
    ) -> Self {
        let mut bins = VoxelBins {
            seen: 0,
            shaded: 0,
            alpha: [0.0; 14],
            radiance: [[Vec3::ZERO; 14]; 2],
            alpha_hat,
        };
        for (r, &b) in held.samples.rays.iter().zip(&held.bin) {
            let Some(s) = &r.surface else { continue };
            let m = MaterialSample {
                albedo: s.albedo,
                alpha: 1.0,
                specular: Vec3::splat(s.specular),
                shininess: s.shininess,
            };
            for (v, sum) in bins.radiance.iter_mut().enumerate() {
                sum[b as usize] += shade(&m, s.normal, -r.dir, light, v as f32, ambient);
            }
        }
        let (mut sum, mut count) = (0.0, 0u32);
        for b in 0..14 {
            if held.rays[b] > 0 {
                bins.seen |= 1 << b;
                bins.alpha[b] = held.occluded[b] as f32 / held.rays[b] as f32;
                sum += bins.alpha[b];
                count += 1;
            }
            if held.hits[b] >= MIN_SURFACE_HITS {
                bins.shaded |= 1 << b;
            }
            if held.hits[b] > 0 {
                for r in &mut bins.radiance {
                    r[b] /= held.hits[b] as f32;
                }
            }
        }
        let mean = if count > 0 { sum / count as f32 } else { 0.0 };
        for b in 0..14 {
            if bins.seen & (1 << b) == 0 {
                bins.alpha[b] = mean;
            }
        }
        bins
    }
}

/// Walks the occupied voxels of `index` along a ray from the centre of voxel `start` in world
/// direction `dir` (unit) up to distance `t_max`, calling `f(value index, voxel)` until it
/// returns `false`.
pub(super) fn walk(
    index: &BrickMap<()>,
    grid: &GridSpec,
    start: UVec3,
    dir: Vec3,
    t_max: f32,
    mut f: impl FnMut(usize, UVec3) -> bool,
) {
    let size = grid.voxel_size as f32;
    let mut dda =
        Dda::in_grid_space(grid.dims, start.as_vec3() + 0.5, dir / size, 0.0, t_max.min(f32::MAX));
    while let Some(v) = dda.next_occupied_brick(index) {
        if let Some(i) = voxel_index(index, v.brick, v.voxel)
            && !f(i, v.voxel)
        {
            return;
        }
    }
}

/// The light seen from the centre of voxel `c`.
pub(super) fn light_at(light: &Light, grid: &GridSpec, c: UVec3) -> LightSample {
    light.sample(grid.voxel_center(c).as_vec3())
}

/// Per voxel, the visibility of the light from its centre through the true per-bin opacities
/// of the others, skipping the voxels closer than 1.5 voxel sizes as the renderer's shadow
/// rays do.
pub(super) fn visibilities(
    index: &BrickMap<()>,
    grid: &GridSpec,
    coords: &[UVec3],
    bins: &[VoxelBins],
    light: &Light,
) -> Vec<f32> {
    coords
        .par_iter()
        .map(|&c| {
            let l = light_at(light, grid, c);
            if l.irradiance.max_element() <= 0.0 {
                return 1.0;
            }
            let b = nearest_bin(-l.to_light);
            let mut t = 1.0f32;
            walk(index, grid, c, l.to_light, l.distance, |j, u| {
                if (u.as_ivec3() - c.as_ivec3()).length_squared() <= 2 {
                    return true;
                }
                t *= 1.0 - bins[j].alpha[b];
                t >= MIN_T
            });
            t
        })
        .collect()
}

/// The error of each candidate of voxel `i` as one pixel sees it (module docs of [`super`]):
/// per bin, the sRGB difference of the pixel composited with the candidate's opacity and
/// radiance against the truth, everything else at the truth; the root mean square over bins
/// and colour channels.
pub(super) struct Compositor<'a> {
    pub index: &'a BrickMap<()>,
    pub grid: &'a GridSpec,
    pub coords: &'a [UVec3],
    pub bins: &'a [VoxelBins],
    /// True radiance of every voxel per bin (at its own light visibility).
    pub truth: &'a [[Vec3; 14]],
    pub background: Vec3,
}

impl Compositor<'_> {
    /// The image error of each candidate of voxel `i`, whose radiance toward `−BINS[b]` is
    /// `radiance[k][b]`.
    pub fn errors(&self, i: usize, radiance: &[[Vec3; 14]; 3]) -> [f32; 3] {
        let c = self.coords[i];
        let v = &self.bins[i];
        let mut sums = [0.0f32; 3];
        let mut count = 0u32;
        for (b, &d) in BINS.iter().enumerate() {
            if v.seen & (1 << b) == 0 {
                continue;
            }
            count += 1;
            // In front (toward the viewer at −d): the colour `front` they add and their
            // transmittance `t_front`, composited back to front from the voxel outward.
            let (mut front, mut t_front) = (Vec3::ZERO, 1.0f32);
            walk(self.index, self.grid, c, -d, f32::INFINITY, |j, _| {
                if j != i {
                    let a = self.bins[j].alpha[b];
                    front = a * self.truth[j][b] + (1.0 - a) * front;
                    t_front *= 1.0 - a;
                }
                t_front >= MIN_T
            });
            if t_front < MIN_T {
                continue;
            }
            // Behind (along d), front to back, then the background.
            let (mut behind, mut t) = (Vec3::ZERO, 1.0f32);
            walk(self.index, self.grid, c, d, f32::INFINITY, |j, _| {
                if j != i {
                    let a = self.bins[j].alpha[b];
                    behind += t * a * self.truth[j][b];
                    t *= 1.0 - a;
                }
                t >= MIN_T
            });
            behind += t * self.background;
            let shaded = v.shaded & (1 << b) != 0;
            for k in 0..3 {
                let l_hat = radiance[k][b];
                let l_true = if shaded { self.truth[i][b] } else { l_hat };
                let a = v.alpha[b];
                let a_hat = v.alpha_hat[k][b];
                let truth = front + t_front * (a * l_true + (1.0 - a) * behind);
                let test = front + t_front * (a_hat * l_hat + (1.0 - a_hat) * behind);
                sums[k] += srgb_sq_diff(test, truth);
            }
        }
        if count == 0 {
            return [0.0; 3];
        }
        sums.map(|s| (s / (3 * count) as f32).sqrt())
    }
}

/// Sum over the colour channels of the squared difference of the sRGB encodings (clamped to
/// [0, 1]) of two linear colours.
fn srgb_sq_diff(a: Vec3, b: Vec3) -> f32 {
    let enc = |x: f32| linear_to_srgb(x.clamp(0.0, 1.0));
    (0..3).map(|c| (enc(a[c]) - enc(b[c])).powi(2)).sum()
}
