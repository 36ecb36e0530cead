//! Light propagation (McNabb 2015, §5.5.3, Listing 5.2) and the shadows both ways (§5.3).
//!
//! The volume is oriented to the light, so each voxel column is independent: per column the
//! light starts at 1 at the volume's top, and each voxel, top to bottom, is lit with the light
//! that reaches it and then attenuates it by its own optical depth `τ = σ · voxel_size`
//! ([`Attenuation::transmittance`]). The light leaving a metavoxel's column enters the next kept
//! metavoxel below (empty metavoxels in between attenuate nothing). Columns run in parallel,
//! the metavoxels of one column in order (they are consecutive in the key order).
//!
//! The lit radiance of a voxel is `albedo · (E/π · light · visible + ambient) + emission`.
//! For [`Attenuation::Exact`] `light` is the mean of the exponentially decaying light over the
//! voxel's depth, `T · (1 − e^(−τ))/τ`; for the others it is the light at the voxel's top, as
//! in Listing 5.2.
//!
//! **Scene's shadow on the volume**: with a BVH, each voxel column casts one ray up from the
//! volume's top toward the light (anything above the volume shadows the whole column) and one
//! down along the column to the first mesh hit; voxels whose centre lies below that hit get no
//! direct light (`visible = 0`). Blockers are opaque (alpha masks are not consulted); one
//! column's shadow is decided at its centre line.
//!
//! **Volume's shadow on the scene**: [`Volume::transmittance_to_light`] continues the stored
//! per-column light (`light_top`) down to any point; `Volume` is a
//! [`LightFilter`], so the ground-truth renderer takes it in
//! [`crate::render::ground_truth::Options::light_filter`] and multiplies each shading point's
//! direct light by it.

use glam::{Vec2, Vec3, Vec4};
use rayon::prelude::*;

use super::{Attenuation, BuildSettings, Metavoxel, Volume, VolumeSpec};
use crate::raycast::Bvh;
use crate::render::ground_truth::LightFilter;

/// Mean over a voxel's depth of the light decaying as `e^(−τ s)`, `s ∈ [0, 1]`.
#[inline]
fn mean_decay(tau: f32) -> f32 {
    if tau < 1e-4 { 1.0 - 0.5 * tau } else { (1.0 - (-tau).exp()) / tau }
}

/// Depth (in voxels from the volume's top) of the first mesh hit along each voxel column of
/// the metavoxel column `(i, j)`: `−∞` when the column is blocked above the volume, `+∞` when
/// nothing blocks it.
fn scene_shadow_depths(spec: &VolumeSpec, i: u32, j: u32, bvh: &Bvh) -> Vec<f32> {
    let m = spec.metavoxel_edge;
    let f = &spec.frame;
    let depth = spec.voxels_per_axis() as f32 * f.voxel_size;
    (0..m * m)
        .map(|idx| {
            let (a, b) = (idx % m, idx / m);
            let q = Vec2::new((i * m + a) as f32 + 0.5, (j * m + b) as f32 + 0.5);
            let top = f.to_world(q.extend(0.0));
            if bvh.occluded(top, -f.w, f32::INFINITY) {
                return f32::NEG_INFINITY;
            }
            match bvh.intersect(top, f.w, 0.0, depth) {
                Some(hit) => hit.t / f.voxel_size,
                None => f32::INFINITY,
            }
        })
        .collect()
}

/// Lights the filled metavoxels in place (sorted by key: each column's metavoxels consecutive
/// and top to bottom). Each entry's optional emission is added and then dropped.
pub fn propagate(
    metavoxels: &mut [(Metavoxel, Option<Vec<Vec3>>)],
    spec: &VolumeSpec,
    settings: &BuildSettings,
    blocker: Option<&Bvh>,
) {
    let m = spec.metavoxel_edge as usize;
    let att = settings.attenuation;
    let vs = spec.frame.voxel_size;
    let direct = settings.irradiance / std::f32::consts::PI;
    let ambient = settings.ambient;
    metavoxels.par_chunk_by_mut(|a, b| a.0.coord[..2] == b.0.coord[..2]).for_each(|column| {
        let [i, j, _] = column[0].0.coord;
        let shadow = blocker.map(|bvh| scene_shadow_depths(spec, i, j, bvh));
        let mut carry = vec![1.0f32; m * m];
        for (mv, emission) in column.iter_mut() {
            mv.light_top.copy_from_slice(&carry);
            if mv.is_empty() && emission.is_none() {
                continue; // all voxels zero: nothing to light, the light passes unchanged
            }
            // Outside the occupied box every voxel is zero: it stays zero and passes the light
            // unchanged (transmittance of τ = 0 is exactly 1), so only the box is walked.
            let [lo, hi] = mv.occupied;
            let z0 = mv.coord[2] as usize * m;
            for b in lo[1] as usize..hi[1] as usize {
                for a in lo[0] as usize..hi[0] as usize {
                    let col = b * m + a;
                    let light = &mut carry[col];
                    let hit = shadow.as_ref().map_or(f32::INFINITY, |s| s[col]);
                    for c in lo[2] as usize..hi[2] as usize {
                        let index = c * m * m + col;
                        let v = mv.voxels[index];
                        let e = emission.as_ref().map_or(Vec3::ZERO, |e| e[index]);
                        if v == Vec4::ZERO && e == Vec3::ZERO {
                            continue; // the same zero voxel and unchanged light, without exp
                        }
                        let tau = v.w * vs;
                        let t = att.transmittance(tau);
                        let reach = match att {
                            Attenuation::Exact => *light * mean_decay(tau),
                            _ => *light,
                        };
                        let visible = if ((z0 + c) as f32 + 0.5) < hit { 1.0 } else { 0.0 };
                        let mut rgb = v.truncate() * (direct * (reach * visible) + ambient);
                        if emission.is_some() {
                            rgb += e;
                        }
                        mv.voxels[index] = Vec4::from((rgb, v.w));
                        *light *= t;
                    }
                }
            }
            *emission = None;
        }
    });
}

impl Volume {
    /// The volume's transmittance toward the light at world point `p` (1 outside the volume's
    /// columns or above it; the volume alone, not the mesh): the light of `p`'s voxel column
    /// continued from the nearest kept metavoxel at or above `p`, excluding `p`'s own voxel
    /// (Listing 5.2's convention); below the volume, the whole column. Metavoxels removed by
    /// culling cast no shadow: build without a view for shadows outside the camera's view.
    pub fn transmittance_to_light(&self, p: Vec3) -> f32 {
        let spec = &self.spec;
        let q = spec.frame.to_voxel(p);
        let n = spec.voxels_per_axis() as f32;
        if !(q.x >= 0.0 && q.x < n && q.y >= 0.0 && q.y < n && q.z >= 0.0) {
            return 1.0;
        }
        let m = spec.metavoxel_edge;
        let (gx, gy) = (q.x as u32, q.y as u32);
        let (i, j, a, b) = (gx / m, gy / m, gx % m, gy % m);
        let col = (b * m + a) as usize;
        let vs = spec.frame.voxel_size;
        // Global voxel depth of p, and the metavoxel slab it is in (K when below the volume).
        let gz = q.z.min(n) as u32;
        let kz = (gz / m).min(spec.metavoxels);
        for k in (0..=kz.min(spec.metavoxels - 1)).rev() {
            let Some(mv) = self.metavoxel([i, j, k]) else { continue };
            let stop = if k == kz { (gz % m) as usize } else { m as usize };
            let mut t = mv.light_top[col];
            for c in 0..stop {
                let index = c * (m * m) as usize + col;
                t *= self.attenuation.transmittance(mv.voxels[index].w * vs);
            }
            return t;
        }
        1.0
    }
}

/// The volume's shadow on the scene: [`Volume::transmittance_to_light`] at each shading point.
impl LightFilter for Volume {
    #[inline]
    fn transmittance(&self, p: Vec3) -> f32 {
        self.transmittance_to_light(p)
    }
}
