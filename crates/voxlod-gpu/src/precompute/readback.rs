//! Readback: the per-voxel sums turned into Averages and specular records exactly as the CPU
//! fit turns the lines into them, the counts and subgrids, and optionally every line as the
//! CPU's [`VoxelSamples`].

use glam::Vec3;
use voxlod_cpu::appearance::AppearanceGrid;
use voxlod_cpu::appearance::eigen::symmetric_eigen;
use voxlod_cpu::appearance::line_sampler::SamplingContext;
use voxlod_cpu::appearance::voxel_samples::{RaySample, SurfaceSample, VoxelSamples};
use voxlod_format::records::{AverageRecord, SpecularRecord};
use voxlod_format::{BrickMap, morton};
use voxlod_scene::Geometry;

use super::params::{GpuLineOut, GpuVoxelOut};
use crate::material::GpuMaterial;
use crate::{Error, Result};

/// The case of one sampling line (the sampler's rules).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum LineCase {
    /// No closest hit.
    Miss,
    /// A closest hit outside the voxel or back-facing: occludes, no surface sample.
    Occluded,
    /// An inside, front-facing closest hit: a surface sample (case (a)).
    Surface,
}

impl LineCase {
    /// The case of a CPU [`RaySample`].
    pub fn of(r: &RaySample) -> Self {
        match (r.occluded, r.surface.is_some()) {
            (_, true) => LineCase::Surface,
            (true, false) => LineCase::Occluded,
            (false, false) => LineCase::Miss,
        }
    }
}

/// Per-voxel counts and subgrid, in the voxelization's (Morton) voxel order.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct VoxelStats {
    /// Occluded lines (any closest hit).
    pub occluded: u32,
    /// Case-(a) lines (inside, front-facing).
    pub front: u32,
    /// The opacity subgrid, as [`voxlod_cpu::appearance::subgrid::build`] returns it.
    pub subgrid: [u8; 27],
}

/// The GPU precompute's results.
#[derive(Clone, Debug)]
pub struct GpuPrecompute {
    /// The Averages grid, what `precompute(ctx, opts, averages::fit)` returns on the CPU.
    pub averages: AppearanceGrid<AverageRecord>,
    /// Counts and subgrid of every voxel of the voxelization.
    pub voxels: Vec<VoxelStats>,
    /// Every voxel's lines, if [`Outputs::lines`](super::Outputs::lines) was asked for.
    pub samples: Option<Vec<VoxelSamples>>,
    /// The line cases behind `samples` with the hit triangle (`u32::MAX`: none), if asked for.
    pub cases: Option<Vec<Vec<(LineCase, u32)>>>,
}

/// The results from the kernel's raw outputs: `out_raw` one [`GpuVoxelOut`] per voxel of
/// `sampling`, `line_raw` (if the lines were asked for) `rays` [`GpuLineOut`] per voxel.
pub(super) fn results(
    sampling: &SamplingContext,
    geometry: &Geometry,
    materials: &[GpuMaterial],
    rays: u32,
    out_raw: &[u8],
    line_raw: Option<&[u8]>,
) -> Result<GpuPrecompute> {
    let n = sampling.voxel_count();
    let outs: Vec<GpuVoxelOut> = bytemuck::pod_collect_to_vec(out_raw);
    let specular = sampling.has_specular();
    let mut entries = Vec::new();
    let mut side = Vec::new();
    let mut stats = Vec::with_capacity(n);
    for (i, o) in outs.iter().enumerate() {
        let bytes: &[u8] = bytemuck::cast_slice(&o.subgrid);
        stats.push(VoxelStats {
            occluded: o.counts[0],
            front: o.counts[1],
            subgrid: bytes[..27].try_into().expect("27 bytes"),
        });
        if let Some(record) = average_record(o) {
            entries.push((morton::encode(sampling.coord(i)), record));
            if specular {
                side.push(specular_record(o));
            }
        }
    }
    let grid = *sampling.grid();
    let records = BrickMap::from_morton_sorted(grid.dims, entries)
        .map_err(|e| Error::Cpu(voxlod_cpu::Error::Format(e)))?;
    let averages = AppearanceGrid { grid, records, specular: specular.then_some(side) };
    let samples = line_raw.map(|raw| {
        let lines: Vec<GpuLineOut> = bytemuck::pod_collect_to_vec(raw);
        to_samples(&lines, rays as usize, materials, geometry)
    });
    let (samples, cases) = samples.unzip();
    Ok(GpuPrecompute { averages, voxels: stats, samples, cases })
}

/// The Averages record of one voxel's sums, as `averages::fit` computes it from the lines.
fn average_record(o: &GpuVoxelOut) -> Option<AverageRecord> {
    let [occluded, count, _, rays] = o.counts;
    if count == 0 || rays == 0 {
        return None;
    }
    let v = |a: &[f32; 4]| Vec3::new(a[0], a[1], a[2]).as_dvec3();
    let (albedo, normal) = (v(&o.albedo), v(&o.normal));
    let [xx, xy, xz, yy] = o.scatter0.map(f64::from);
    let [yz, zz, _, _] = o.scatter1.map(f64::from);
    let n = if normal.length() >= 1e-3 * count as f64 {
        normal.normalize()
    } else {
        symmetric_eigen([[xx, xy, xz], [xy, yy, yz], [xz, yz, zz]]).1[0]
    };
    let opacity = occluded as f32 / rays as f32;
    Some(AverageRecord::new((albedo / count as f64).as_vec3(), n.as_vec3(), opacity))
}

/// The specular side record of one voxel's sums, as the CPU driver's `specular_record`.
fn specular_record(o: &GpuVoxelOut) -> SpecularRecord {
    let (count, level, weighted) = (o.counts[1], o.albedo[3] as f64, o.normal[3] as f64);
    if count == 0 || level <= 0.0 {
        return SpecularRecord::new(0.0, 0.0);
    }
    SpecularRecord::new((level / count as f64) as f32, (weighted / level) as f32)
}

/// The GPU's lines as [`VoxelSamples`] (the kernel's textured albedo; level and exponent from
/// the hit triangle's material, which `Material::sample` does not vary with the UV) and their
/// cases.
#[allow(clippy::type_complexity)]
fn to_samples(
    lines: &[GpuLineOut],
    rays: usize,
    materials: &[GpuMaterial],
    geometry: &Geometry,
) -> (Vec<VoxelSamples>, Vec<Vec<(LineCase, u32)>>) {
    let v3 = |a: &[f32; 4]| Vec3::new(a[0], a[1], a[2]);
    lines
        .chunks(rays.max(1))
        .map(|chunk| {
            let mut samples = VoxelSamples { rays: Vec::with_capacity(chunk.len()) };
            let mut cases = Vec::with_capacity(chunk.len());
            for l in chunk {
                let case = match l.entry[3].to_bits() {
                    0 => LineCase::Miss,
                    1 => LineCase::Occluded,
                    _ => LineCase::Surface,
                };
                let triangle = l.point[3].to_bits();
                let surface = (case == LineCase::Surface).then(|| {
                    let m = &materials[geometry.materials[triangle as usize] as usize];
                    SurfaceSample {
                        point: v3(&l.point),
                        normal: v3(&l.normal),
                        albedo: v3(&l.albedo),
                        specular: (m.specular[0] + m.specular[1] + m.specular[2]) * (1.0 / 3.0),
                        shininess: m.specular[3],
                    }
                });
                samples.rays.push(RaySample {
                    dir: v3(&l.dir),
                    entry: v3(&l.entry),
                    chord: l.dir[3],
                    occluded: case != LineCase::Miss,
                    surface,
                });
                cases.push((case, triangle));
            }
            (samples, cases)
        })
        .unzip()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The host fit from sums is the CPU's fit from lines: mean albedo, normalized sum, the
    /// principal axis when the normals cancel, `occluded / rays`.
    #[test]
    fn records_from_sums_follow_the_averages_rules() {
        let mut o = GpuVoxelOut { counts: [3, 2, 1, 4], ..Default::default() };
        o.albedo = [0.4, 0.6, 0.8, 0.0];
        o.normal = [0.0, 0.0, 2.0, 0.0];
        o.scatter1 = [0.0, 2.0, 0.0, 0.0];
        let r = average_record(&o).unwrap();
        assert_eq!(r, AverageRecord::new(Vec3::new(0.2, 0.3, 0.4), Vec3::Z, 0.75));
        // n and −n: the sum cancels, the principal axis of Σ n nᵀ (canonical sign) remains.
        o.normal = [0.0, 0.0, 0.0, 0.0];
        o.scatter0 = [0.0, 0.0, 0.0, 2.0];
        o.scatter1 = [0.0, 0.0, 0.0, 0.0];
        assert_eq!(average_record(&o).unwrap().normal(), Vec3::Y);
        o.counts[1] = 0;
        assert_eq!(average_record(&o), None);
    }
}
