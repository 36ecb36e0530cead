//! Host-side preparation of a voxelization: the CPU reference's snapping, culling and input
//! checks, each triangle's working axis, clipped range and candidate interval, and the
//! batches of at most a given number of invocations.

use glam::{I64Vec3, IVec3, UVec3};
use voxlod_cpu::voxelize::lattice::{Lattice, Reach, VOXEL, voxel_span};
use voxlod_cpu::voxelize::overlap;
use voxlod_format::GridSpec;
use voxlod_scene::Geometry;

use super::GpuTriangle;
use crate::{Error, Result};

/// The host-side preparation of one voxelization: the kernel's triangles and prefix sums, in
/// batches.
#[derive(Clone, Debug, Default)]
pub struct Prepared {
    /// Triangles that reach the grid, in input order.
    pub triangles: Vec<GpuTriangle>,
    /// Per triangle, its first invocation within its batch.
    pub starts: Vec<u32>,
    /// Batches: (first triangle, triangle count, invocations).
    pub batches: Vec<(usize, usize, u64)>,
}

/// The working axis and the record of one snapped triangle, or `None` if its clipped range is
/// empty. `id` goes to `c.w`.
pub fn triangle_record(tri: &[IVec3; 3], dims: UVec3, id: u32) -> Option<(GpuTriangle, u64)> {
    let lo_l = tri[0].min(tri[1]).min(tri[2]);
    let hi_l = tri[0].max(tri[1]).max(tri[2]);
    let mut lo = UVec3::ZERO;
    let mut hi = UVec3::ZERO;
    for k in 0..3 {
        let (s0, s1) = voxel_span(lo_l[k], hi_l[k]);
        let (s0, s1) = (s0.max(0) as i64, (s1 as i64).min(dims[k] as i64 - 1));
        if s0 > s1 {
            return None;
        }
        lo[k] = s0 as u32;
        hi[k] = s1 as u32;
    }
    let n = overlap::normal(tri);
    let a = n.abs();
    let degenerate = n == I64Vec3::ZERO;
    let axis = if degenerate {
        let ext = hi - lo;
        (0..3).max_by_key(|&k| (ext[k], k)).unwrap()
    } else if a.z >= a.x && a.z >= a.y {
        2
    } else if a.y >= a.x {
        1
    } else {
        0
    };
    let (ku, kv) = ((axis + 1) % 3, (axis + 2) % 3);
    let width = hi[ku] - lo[ku] + 1;
    let columns = width as u64 * (hi[kv] - lo[kv] + 1) as u64;
    let plane = if degenerate {
        [0.0; 4]
    } else {
        let nw = n[axis] as f64;
        let extent = (hi_l - lo_l).max_element() as f64 / VOXEL as f64;
        let r = (a.x as f64 + a.y as f64 + a.z as f64) / (2.0 * nw.abs());
        let margin = (extent + 2.0) / 262_144.0 + 1.0 / 64.0;
        [(n[ku] as f64 / nw) as f32, (n[kv] as f64 / nw) as f32, (r + margin) as f32, 0.0]
    };
    let v = |p: IVec3, w: i32| [p.x, p.y, p.z, w];
    let record = GpuTriangle {
        a: v(tri[0], axis as i32),
        b: v(tri[1], degenerate as i32),
        c: v(tri[2], id as i32),
        lo: [lo.x, lo.y, lo.z, width],
        hi: [hi.x, hi.y, hi.z, 0],
        plane,
    };
    Some((record, columns))
}

/// Snaps, culls and validates like the CPU reference, then lays the triangles out in batches
/// of at most `items_per_batch` invocations and `tris_per_batch` triangles.
pub fn prepare(
    geometry: &Geometry,
    grid: &GridSpec,
    items_per_batch: u64,
    tris_per_batch: usize,
) -> Result<Prepared> {
    let lattice = Lattice::new(geometry, grid)?;
    if geometry.indices.len() as u64 > u32::MAX as u64 {
        return Err(voxlod_cpu::Error::InvalidParameter {
            name: "geometry",
            value: format!("{} triangles", geometry.indices.len()),
            reason: "triangle ids are 32-bit: at most 2^32 − 1 triangles".into(),
        }
        .into());
    }
    let dims = grid.dims;
    let mut out = Prepared::default();
    let (mut first, mut items) = (0usize, 0u64);
    for t in 0..geometry.indices.len() {
        let Some(tri) = lattice.triangle(geometry, t, Reach::Surface)? else { continue };
        let Some((record, columns)) = triangle_record(&tri, dims, t as u32) else { continue };
        let in_batch = out.triangles.len() - first;
        if in_batch > 0 && (items + columns > items_per_batch || in_batch >= tris_per_batch) {
            out.batches.push((first, in_batch, items));
            first = out.triangles.len();
            items = 0;
        }
        if columns > u32::MAX as u64 - items {
            return Err(Error::TooLarge {
                what: "invocations of one triangle",
                requested: columns,
                limit: u32::MAX as u64,
            });
        }
        out.starts.push(items as u32);
        out.triangles.push(record);
        items += columns;
    }
    if out.triangles.len() > first {
        out.batches.push((first, out.triangles.len() - first, items));
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn records_pick_the_dominant_axis_and_clip_the_range() {
        let v = VOXEL;
        // A triangle in the plane z = 1.5 voxels, spanning x, y in [0.5, 3.5]: w = z.
        let tri = [
            IVec3::new(v / 2, v / 2, 3 * v / 2),
            IVec3::new(7 * v / 2, v / 2, 3 * v / 2),
            IVec3::new(v / 2, 7 * v / 2, 3 * v / 2),
        ];
        let (r, columns) = triangle_record(&tri, UVec3::splat(8), 5).unwrap();
        assert_eq!(r.a[3], 2);
        assert_eq!(r.b[3], 0);
        assert_eq!(r.c[3], 5);
        assert_eq!(&r.lo[..3], &[0, 0, 1]);
        assert_eq!(&r.hi[..3], &[3, 3, 1]);
        assert_eq!(columns, 16);
        assert_eq!(r.plane[0], 0.0);
        // R = 1/2 for an axis-aligned plane, plus the margin.
        assert!(r.plane[2] > 0.5 && r.plane[2] < 0.52, "{:?}", r.plane);
        // Clipped to a 2-voxel grid.
        let (r, columns) = triangle_record(&tri, UVec3::splat(2), 0).unwrap();
        assert_eq!((&r.hi[..3], columns), (&[1, 1, 1][..], 4));
        // Outside the grid entirely.
        let far = tri.map(|p| p + IVec3::splat(100 * v));
        assert!(triangle_record(&far, UVec3::splat(8), 0).is_none());
    }

    #[test]
    fn degenerate_triangles_scan_along_their_longest_extent() {
        let v = VOXEL;
        let seg = [IVec3::new(10, 10, 10), IVec3::new(10, 10 + 5 * v, 10), IVec3::new(10, 10, 10)];
        let (r, columns) = triangle_record(&seg, UVec3::splat(16), 0).unwrap();
        assert_eq!((r.a[3], r.b[3]), (1, 1));
        assert_eq!(columns, 1);
    }

    #[test]
    fn batches_respect_both_caps_and_keep_every_triangle() {
        let positions: Vec<glam::Vec3> = (0..30)
            .map(|i| glam::Vec3::new((i / 3) as f32 * 0.7, (i % 3) as f32 * 0.9, 1.3))
            .collect();
        let geometry = Geometry {
            positions,
            indices: (0..10).map(|t| [3 * t, 3 * t + 1, 3 * t + 2]).collect(),
            ..Default::default()
        };
        let grid = GridSpec::new(glam::DVec3::ZERO, 1.0, UVec3::splat(8)).unwrap();
        let p = prepare(&geometry, &grid, 6, 3).unwrap();
        assert_eq!(p.triangles.len(), 10);
        let mut next = 0;
        for &(first, count, items) in &p.batches {
            assert_eq!(first, next);
            assert!((1..=3).contains(&count));
            assert!(items <= 6 || count == 1, "{items}");
            assert_eq!(p.starts[first], 0);
            next += count;
        }
        assert_eq!(next, 10);
    }

    #[test]
    fn bad_input_gives_the_cpu_error() {
        let geometry = Geometry {
            positions: vec![glam::Vec3::ZERO, glam::Vec3::X, glam::Vec3::new(f32::NAN, 0.0, 0.0)],
            indices: vec![[0, 1, 2]],
            ..Default::default()
        };
        let grid = GridSpec::new(glam::DVec3::ZERO, 1.0, UVec3::splat(4)).unwrap();
        let gpu = prepare(&geometry, &grid, 64, 64).unwrap_err().to_string();
        let opts = voxlod_cpu::voxelize::Options::default();
        let cpu = voxlod_cpu::voxelize::voxelize(&geometry, &grid, &opts).unwrap_err().to_string();
        assert_eq!(gpu, cpu);
    }
}
