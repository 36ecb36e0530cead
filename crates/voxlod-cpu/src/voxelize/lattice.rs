//! The fixed-point lattice every voxelizer works on: vertices are mapped into grid space on the
//! host in `f64` and snapped to integers, and from there on every decision is integer
//! arithmetic that any backend can reproduce bit for bit.
//!
//! A vertex `p` (world space, `f32`) becomes `g = (p − origin) · (1/voxel_size)` in `f64`, then
//! `x = ⌊g · 2^F + ½⌋` (round to nearest, ties toward +∞, so that translating a scene by whole
//! lattice steps translates its snapped vertices exactly). Voxel `i` spans the lattice interval
//! `[i·2^F, (i+1)·2^F]`; its centre `i·2^F + 2^(F−1)` is a lattice point because `F ≥ 1`.
//!
//! # Parameters
//! | name | value | meaning |
//! |---|---|---|
//! | [`FRACTION_BITS`] `F` | 8 | a lattice step is 1/256 voxel |
//! | [`VOXEL`] | 2^8 | voxel edge in lattice units |
//! | [`MAX_GRID_DIM`] | 2^20 | most voxels per grid axis: the grid spans ≤ 2^28 lattice units |
//! | [`COORD_LIMIT`] | 2^29 | a vertex of a triangle that reaches the grid must satisfy `|x| ≤ 2^29` on every axis (2^21 voxels from the grid origin, at least one grid width on every side of the largest grid) |
//!
//! So a snapped vertex fits an `i32` with two bits to spare, and an edge vector
//! (difference of two vertices, `|e| ≤ 2^30`) still fits an `i32` — what the WGSL port needs.
//! The bit widths of the overlap arithmetic built on this are in [`super::overlap`].
//!
//! # Far vertices
//! Clamping a far vertex would change the triangle's shape and so which voxels it overlaps.
//! Instead a triangle whose bounding box misses the grid is culled (it cannot overlap a voxel),
//! and a triangle that may reach the grid but has a vertex outside `±COORD_LIMIT` is an error
//! naming the triangle, the vertex and the limit. Non-finite vertices are errors naming the
//! vertex, whether or not the scene was validated before.
//!
//! # Scale
//! Occupancy is a function of the snapped `g` alone. Scaling a scene and its grid together by a
//! power of two leaves every `g` bit-identical (exact `f64` operations), hence the occupancy.
//! Other factors (1e-4, 1e5) perturb `g` only by the `f32` rounding of the scaled input, about
//! `2^−24·|g|` voxels; snapping to 1/256 voxel absorbs that unless a vertex lies within that
//! distance of a rounding boundary — the scale tests build their meshes away from those.

use std::sync::atomic::{AtomicBool, Ordering};

use glam::{DVec3, IVec3, UVec3};
use rayon::prelude::*;
use voxlod_format::GridSpec;
use voxlod_scene::Geometry;

use crate::{Error, Result};

/// Fractional bits `F` of the lattice: a voxel edge is `2^F` lattice units.
pub const FRACTION_BITS: u32 = 8;
/// A voxel edge in lattice units (`2^F`).
pub const VOXEL: i32 = 1 << FRACTION_BITS;
/// Half a voxel edge in lattice units (`2^(F−1)`): voxel centres are lattice points.
pub const HALF_VOXEL: i32 = VOXEL / 2;
/// Most voxels per grid axis the lattice supports (`2^20`); larger grids are
/// [`voxlod_format::Error::GridTooLarge`].
pub const MAX_GRID_DIM: u32 = 1 << 20;
/// Largest magnitude of a snapped vertex coordinate (`2^29` lattice units = `2^21` voxels).
pub const COORD_LIMIT: i32 = 1 << 29;

/// Marks a vertex outside `±COORD_LIMIT` in [`Lattice`] (its x coordinate).
const FAR: i32 = i32::MIN;

/// Snaps one continuous grid coordinate (in voxels) to the lattice; `None` if it is outside
/// `±COORD_LIMIT` or not finite.
#[inline]
pub fn snap(g: f64) -> Option<i32> {
    let y = g * VOXEL as f64 + 0.5;
    // NaN fails the comparison; inside it, truncation then a correction is ⌊y⌋ (cheaper than a
    // call to `floor` without SSE4.1).
    if y.is_nan() || y.abs() > COORD_LIMIT as f64 + 1.0 {
        return None;
    }
    let t = y as i64;
    let x = t - ((t as f64) > y) as i64;
    (x.abs() <= COORD_LIMIT as i64).then_some(x as i32)
}

/// Checks that `grid` is valid and within the lattice's range ([`MAX_GRID_DIM`]).
pub fn check_grid(grid: &GridSpec) -> Result<()> {
    grid.validate()?;
    if grid.dims.max_element() > MAX_GRID_DIM {
        return Err(Error::Format(voxlod_format::Error::GridTooLarge {
            requested: grid.dims.as_u64vec3().to_array(),
            max: MAX_GRID_DIM as u64,
        }));
    }
    Ok(())
}

/// Which triangles can influence a voxelization, for culling.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Reach {
    /// Surface modes: the triangle's closed bounding box meets the closed grid box.
    Surface,
    /// Solid mode: for some axis, the bounding box meets the grid's cross-section and does not
    /// lie entirely beyond the grid's far end along that axis (a triangle below the grid still
    /// flips the parity of the columns above it).
    Solid,
}

impl Reach {
    /// Whether a triangle with bounding box `[lo, hi]` (in voxels) can influence a grid of
    /// `dims` voxels whose box is grown by `margin` voxels on every side.
    pub fn reaches(self, lo: DVec3, hi: DVec3, dims: UVec3, margin: f64) -> bool {
        let max = dims.as_dvec3() + margin;
        let min = -margin;
        let across = |k: usize| lo[k] <= max[k] && hi[k] >= min;
        match self {
            Reach::Surface => (0..3).all(across),
            Reach::Solid => {
                (0..3).any(|w| across((w + 1) % 3) && across((w + 2) % 3) && lo[w] <= max[w])
            }
        }
    }
}

impl Reach {
    /// [`Reach::reaches`] for a snapped triangle (exact: lattice values are exact in `f64`).
    #[inline]
    pub fn reaches_snapped(self, tri: &[IVec3; 3], dims: UVec3) -> bool {
        let lo = tri[0].min(tri[1]).min(tri[2]).as_dvec3() / VOXEL as f64;
        let hi = tri[0].max(tri[1]).max(tri[2]).as_dvec3() / VOXEL as f64;
        self.reaches(lo, hi, dims, 0.0)
    }
}

/// The scene's vertices snapped to the lattice of one grid.
#[derive(Clone, Debug)]
pub struct Lattice {
    grid: GridSpec,
    vertices: Vec<IVec3>,
}

impl Lattice {
    /// Snaps every vertex of `geometry` to the lattice of `grid` (checked with
    /// [`check_grid`]). A non-finite position is an error naming the vertex.
    pub fn new(geometry: &Geometry, grid: &GridSpec) -> Result<Self> {
        check_grid(grid)?;
        let non_finite = AtomicBool::new(false);
        let (origin, inv) = (grid.origin, 1.0 / grid.voxel_size);
        let vertices = geometry
            .positions
            .par_iter()
            .map(|p| {
                let g = (p.as_dvec3() - origin) * inv;
                match (snap(g.x), snap(g.y), snap(g.z)) {
                    (Some(x), Some(y), Some(z)) => IVec3::new(x, y, z),
                    _ => {
                        if !p.is_finite() {
                            non_finite.store(true, Ordering::Relaxed);
                        }
                        IVec3::splat(FAR)
                    }
                }
            })
            .collect();
        if non_finite.into_inner() {
            let i = geometry.positions.iter().position(|p| !p.is_finite()).expect("flagged");
            return Err(Error::Scene(voxlod_scene::Error::NonFinite {
                mesh: "geometry".into(),
                attribute: "position",
                vertex: i,
                value: geometry.positions[i].to_array(),
            }));
        }
        Ok(Self { grid: *grid, vertices })
    }

    /// Continuous grid coordinates of a world position, as the lattice computes them:
    /// `(p − origin) · (1 / voxel_size)` in `f64` (a product by the reciprocal, which scales
    /// exactly with the grid under powers of two).
    #[inline]
    pub fn to_grid(&self, p: DVec3) -> DVec3 {
        (p - self.grid.origin) * (1.0 / self.grid.voxel_size)
    }

    /// The grid snapped to.
    pub fn grid(&self) -> &GridSpec {
        &self.grid
    }

    /// The snapped vertex `i`, or `None` if it lies outside `±COORD_LIMIT` (or does not
    /// exist).
    #[inline]
    pub fn vertex(&self, i: u32) -> Option<IVec3> {
        self.vertices.get(i as usize).copied().filter(|v| v.x != FAR)
    }

    /// Heap bytes held.
    pub fn memory_bytes(&self) -> usize {
        self.vertices.capacity() * size_of::<IVec3>()
    }

    /// The snapped vertices of triangle `t` if it can influence the grid, `Ok(None)` if it is
    /// culled. Errors: a vertex index out of range, or a triangle that may reach the grid with a
    /// vertex outside the lattice's range (named with the limit).
    pub fn triangle(
        &self,
        geometry: &Geometry,
        t: usize,
        reach: Reach,
    ) -> Result<Option<[IVec3; 3]>> {
        let idx = geometry.indices[t];
        if let Some(&index) = idx.iter().find(|&&i| i as usize >= self.vertices.len()) {
            return Err(Error::Scene(voxlod_scene::Error::IndexOutOfRange {
                mesh: "geometry".into(),
                triangle: t,
                index,
                vertex_count: self.vertices.len(),
            }));
        }
        let dims = self.grid.dims;
        if let (Some(a), Some(b), Some(c)) =
            (self.vertex(idx[0]), self.vertex(idx[1]), self.vertex(idx[2]))
        {
            let v = [a, b, c];
            return Ok(reach.reaches_snapped(&v, dims).then_some(v));
        }
        // A far vertex: decide in f64 with a one-voxel margin (rounding moves nothing that far).
        let g = idx.map(|i| self.to_grid(geometry.positions[i as usize].as_dvec3()));
        let lo = g[0].min(g[1]).min(g[2]);
        let hi = g[0].max(g[1]).max(g[2]);
        if !reach.reaches(lo, hi, dims, 1.0) {
            return Ok(None);
        }
        let k = (0..3).find(|&k| self.vertex(idx[k]).is_none()).expect("a far vertex exists");
        Err(Error::InvalidParameter {
            name: "triangle",
            value: format!(
                "{t} (vertex {} at {:?} is {:?} voxels from the grid origin)",
                idx[k],
                geometry.positions[idx[k] as usize].to_array(),
                g[k].to_array()
            ),
            reason: format!(
                "it may reach the {dims} grid, but a vertex lies beyond the fixed-point lattice's \
                 range of ±{} voxels (±2^29 lattice units) from the grid origin; split the \
                 triangle or voxelize into a grid that lies closer to it",
                COORD_LIMIT / VOXEL
            ),
        })
    }
}

/// The inclusive range of voxel indices along one axis whose closed extent
/// `[i·VOXEL, (i+1)·VOXEL]` meets the closed lattice interval `[lo, hi]`, before clipping to the
/// grid: `⌈lo/VOXEL⌉ − 1 ..= ⌊hi/VOXEL⌋`.
#[inline]
pub fn voxel_span(lo: i32, hi: i32) -> (i32, i32) {
    ((lo - 1) >> FRACTION_BITS, hi >> FRACTION_BITS)
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    fn grid(n: u32) -> GridSpec {
        GridSpec::new(DVec3::ZERO, 1.0, UVec3::splat(n)).unwrap()
    }

    #[test]
    fn snapping_rounds_to_nearest_with_ties_up() {
        assert_eq!(snap(0.0), Some(0));
        assert_eq!(snap(1.0), Some(VOXEL));
        assert_eq!(snap(0.5 / 256.0), Some(1));
        assert_eq!(snap(-0.5 / 256.0), Some(0));
        assert_eq!(snap(0.49 / 256.0), Some(0));
        assert_eq!(snap(-3.75), Some(-3 * VOXEL - 3 * HALF_VOXEL / 2));
        assert_eq!(snap((1 << 21) as f64), Some(COORD_LIMIT));
        assert_eq!(snap((1 << 21) as f64 + 0.01), None);
        assert_eq!(snap(f64::NAN), None);
        assert_eq!(snap(f64::INFINITY), None);
        assert_eq!(snap(-1e300), None);
    }

    #[test]
    fn voxel_span_includes_voxels_touched_at_a_face() {
        // A point on the boundary between voxels 1 and 2 touches both.
        assert_eq!(voxel_span(2 * VOXEL, 2 * VOXEL), (1, 2));
        // Strictly inside voxel 1.
        assert_eq!(voxel_span(VOXEL + 1, 2 * VOXEL - 1), (1, 1));
        // Negative coordinates floor correctly.
        assert_eq!(voxel_span(-1, -1), (-1, -1));
        assert_eq!(voxel_span(-VOXEL, 0), (-2, 0));
    }

    #[test]
    fn grids_beyond_the_lattice_are_rejected() {
        let g = GridSpec::new(DVec3::ZERO, 1.0, UVec3::new(MAX_GRID_DIM + 1, 1, 1)).unwrap();
        let err = check_grid(&g).unwrap_err();
        assert!(
            matches!(err, Error::Format(voxlod_format::Error::GridTooLarge { max, .. }) if max == MAX_GRID_DIM as u64),
            "{err}"
        );
        check_grid(&GridSpec::new(DVec3::ZERO, 1.0, UVec3::splat(MAX_GRID_DIM)).unwrap()).unwrap();
    }

    fn geometry(positions: Vec<Vec3>, indices: Vec<[u32; 3]>) -> Geometry {
        Geometry { positions, indices, ..Default::default() }
    }

    #[test]
    fn non_finite_vertices_are_named() {
        for bad in [f32::NAN, f32::INFINITY, f32::NEG_INFINITY] {
            let g = geometry(vec![Vec3::ZERO, Vec3::X, Vec3::new(1.0, bad, 0.0)], vec![[0, 1, 2]]);
            let err = Lattice::new(&g, &grid(4)).unwrap_err().to_string();
            assert!(err.contains("vertex 2") && err.contains("not finite"), "{err}");
        }
    }

    #[test]
    fn far_triangles_are_culled_or_rejected_never_clamped() {
        let far = 1e30_f32;
        let g = geometry(
            vec![
                Vec3::new(far, 0.0, 0.0),
                Vec3::new(far, 1.0, 0.0),
                Vec3::new(far, 0.0, 1.0),
                Vec3::new(1.0, 1.0, 1.0),
                Vec3::new(2.0, 1.0, 1.0),
            ],
            vec![[0, 1, 2], [3, 4, 0], [3, 4, 4]],
        );
        let lattice = Lattice::new(&g, &grid(4)).unwrap();
        // Entirely beyond the grid: culled, whatever its coordinates.
        assert_eq!(lattice.triangle(&g, 0, Reach::Surface).unwrap(), None);
        // Reaches into the grid with a vertex at 1e30: an error naming triangle, vertex, limit.
        let err = lattice.triangle(&g, 1, Reach::Surface).unwrap_err().to_string();
        assert!(err.contains("triangle = 1") && err.contains("vertex 0"), "{err}");
        assert!(err.contains("±2097152 voxels"), "{err}");
        assert_eq!(
            lattice.triangle(&g, 2, Reach::Surface).unwrap(),
            Some([
                IVec3::splat(VOXEL),
                IVec3::new(2 * VOXEL, VOXEL, VOXEL),
                IVec3::new(2 * VOXEL, VOXEL, VOXEL)
            ])
        );
    }

    #[test]
    fn solid_reach_keeps_triangles_below_the_grid() {
        let dims = UVec3::splat(4);
        let below = (DVec3::new(1.0, 1.0, -9.0), DVec3::new(2.0, 2.0, -8.0));
        let above = (DVec3::new(1.0, 1.0, 8.0), DVec3::new(2.0, 2.0, 9.0));
        assert!(!Reach::Surface.reaches(below.0, below.1, dims, 0.0));
        assert!(Reach::Solid.reaches(below.0, below.1, dims, 0.0));
        assert!(!Reach::Solid.reaches(above.0, above.1, dims, 0.0));
        // Touching the grid's far face counts (closed boxes).
        assert!(Reach::Surface.reaches(DVec3::splat(4.0), DVec3::splat(5.0), dims, 0.0));
    }

    #[test]
    fn bad_indices_are_named() {
        let g = geometry(vec![Vec3::ZERO, Vec3::X, Vec3::Y], vec![[0, 1, 2], [0, 1, 7]]);
        let lattice = Lattice::new(&g, &grid(4)).unwrap();
        let err = lattice.triangle(&g, 1, Reach::Surface).unwrap_err().to_string();
        assert!(err.contains("triangle 1") && err.contains("vertex 7"), "{err}");
    }
}
