//! Binning (McNabb 2015, Listing 5.1) on the GPU: the candidate (particle, metavoxel) pairs
//! listed on the host with the CPU reference's range arithmetic, the overlap test in the
//! kernel, the compaction, the near-tie decisions and the grouping into bins on the host.

use glam::Vec3;
use voxlod_cpu::volume::VolumeSpec;
use voxlod_cpu::volume::binning::{self, Bin, Binning, Prepared};
use voxlod_scene::particles::DisplacedSphere;

use super::params::{GpuBinParams, GpuCandidate};
use super::{VolumeKernels, WORKGROUP};
use crate::{Error, Result};

/// Metavoxel index range `[a, b]` on one axis covered by `[x − r, x + r]` (the CPU
/// reference's arithmetic, `binning::axis_range`), or `None` when it misses `[0, K)`.
fn axis_range(x: f32, r: f32, m: u32, k: u32) -> Option<(u32, u32)> {
    let lo = ((x - r) / m as f32).floor();
    let hi = ((x + r) / m as f32).floor();
    if !(hi >= 0.0 && lo < k as f32) {
        return None;
    }
    Some((lo.max(0.0) as u32, hi.min((k - 1) as f32) as u32))
}

/// The box of metavoxel `c` in voxel coordinates.
fn metavoxel_box(c: [u32; 3], m: u32) -> (Vec3, Vec3) {
    let lo = Vec3::new(c[0] as f32, c[1] as f32, c[2] as f32) * m as f32;
    (lo, lo + Vec3::splat(m as f32))
}

/// Sorted `(key, particle)` pairs into bins (the CPU's grouping).
fn group(spec: &VolumeSpec, pairs: &[(u32, u32)]) -> Vec<Bin> {
    let k = spec.metavoxels;
    pairs
        .chunk_by(|a, b| a.0 == b.0)
        .map(|run| {
            let key = run[0].0;
            Bin {
                coord: [key / (k * k), key / k % k, key % k],
                particles: run.iter().map(|p| p.1).collect(),
            }
        })
        .collect()
}

impl VolumeKernels<'_> {
    /// Binning (Listing 5.1) on the GPU: the CPU's [`binning::bin`], exactly (module docs).
    pub fn bin(&self, spheres: &[DisplacedSphere], spec: &VolumeSpec) -> Result<Binning> {
        let ctx = self.ctx;
        if spheres.len() as u64 > u32::MAX as u64 {
            return Err(Error::TooLarge {
                what: "particles (indexed in 32 bits)",
                requested: spheres.len() as u64,
                limit: u32::MAX as u64,
            });
        }
        let prepared = binning::prepare(spheres, spec);
        let (m, k) = (spec.metavoxel_edge, spec.metavoxels);
        let mut records = Vec::new();
        let mut owners = Vec::new();
        let mut total = 0u64;
        for (i, p) in prepared.iter().enumerate() {
            let ranges = (
                axis_range(p.center.x, p.outer, m, k),
                axis_range(p.center.y, p.outer, m, k),
                axis_range(p.center.z, p.outer, m, k),
            );
            let (Some(x), Some(y), Some(z)) = ranges else { continue };
            let count = (x.1 - x.0 + 1) as u64 * (y.1 - y.0 + 1) as u64 * (z.1 - z.0 + 1) as u64;
            if total + count > u32::MAX as u64 {
                return Err(Error::TooLarge {
                    what: "binning candidates (particle, metavoxel)",
                    requested: total + count,
                    limit: u32::MAX as u64,
                });
            }
            records.push(GpuCandidate {
                sphere: p.center.extend(p.outer).to_array(),
                lo: [x.0, y.0, z.0, total as u32],
                hi: [x.1, y.1, z.1, 0],
            });
            owners.push(i as u32);
            total += count;
        }
        if total == 0 {
            return Ok(Binning { prepared, bins: Vec::new() });
        }
        let result_bytes = total * 4;
        ctx.check_storage("binning results", result_bytes)?;
        let params = GpuBinParams { counts: [total as u32, records.len() as u32, m, 0] };
        let uniform = ctx.uniform("binning params", bytemuck::bytes_of(&params))?;
        let cands = ctx.storage_init("binning candidates", bytemuck::cast_slice(&records))?;
        let results = ctx.storage_zeroed("binning results", result_bytes)?;
        let wg = ctx.dispatch_size("binning workgroups", total.div_ceil(WORKGROUP))?;
        self.ctx.dispatch("binning", &self.binning, &[&uniform, &cands, &results], wg)?;
        let results: Vec<u32> = bytemuck::pod_collect_to_vec(&ctx.read(&results, result_bytes)?);
        // Compaction, in candidate order; the undecided ones by the reference predicate.
        let mut pairs = Vec::new();
        for (r, &owner) in records.iter().zip(&owners) {
            let n = [r.hi[0] - r.lo[0] + 1, r.hi[1] - r.lo[1] + 1, r.hi[2] - r.lo[2] + 1];
            let count = n[0] * n[1] * n[2];
            for local in 0..count {
                let c = [
                    r.lo[0] + local % n[0],
                    r.lo[1] + local / n[0] % n[1],
                    r.lo[2] + local / (n[0] * n[1]),
                ];
                let hit = match results[(r.lo[3] + local) as usize] {
                    1 => true,
                    2 => {
                        let p: &Prepared = &prepared[owner as usize];
                        let (lo, hi) = metavoxel_box(c, m);
                        binning::sphere_overlaps_box(p.center, p.outer, lo, hi)
                    }
                    _ => false,
                };
                if hit {
                    pairs.push((spec.key(c), owner));
                }
            }
        }
        pairs.sort_unstable();
        Ok(Binning { bins: group(spec, &pairs), prepared })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn axis_range_is_the_cpu_arithmetic() {
        // A sphere at x = 10 of radius 3 in metavoxels of 4 covers metavoxels 1..=3 of K = 8.
        assert_eq!(axis_range(10.0, 3.0, 4, 8), Some((1, 3)));
        assert_eq!(axis_range(-10.0, 3.0, 4, 8), None);
        assert_eq!(axis_range(40.0, 3.0, 4, 8), None);
        assert_eq!(axis_range(f32::NAN, 3.0, 4, 8), None);
        assert_eq!(axis_range(1.0, 100.0, 4, 8), Some((0, 7)));
    }
}
