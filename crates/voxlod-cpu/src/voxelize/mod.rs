//! Exact voxelizers: conservative surface, 6-separating thin surface and solid.
//!
//! Every voxelizer maps the scene's vertices into grid space on the host in `f64`, snaps them
//! to a fixed-point lattice of the grid ([`lattice`]), and decides overlaps in integer
//! arithmetic ([`overlap`]), so the answer is exact, independent of the backend, and unchanged
//! by scaling the scene together with its grid.
//!
//! # The modes and their rules
//! - [`Mode::Conservative`]: every voxel whose **closed** box meets the closed triangle — the
//!   tie rule: touching a face, edge or corner counts, so a face lying exactly on a voxel
//!   boundary sets the voxels on both sides ([`overlap::box_overlap`]).
//! - [`Mode::Thin`]: Schwarz & Seidel's 6-separating test, the voxel's inner diamond instead of
//!   its box, same tie rule ([`overlap::diamond_overlap`]); a subset of conservative without
//!   6-connected tunnels.
//! - [`Mode::Solid`]: every voxel whose **centre** is inside, by exact parity with a top-left
//!   fill rule, and a majority vote of three axes for meshes that are not closed (see
//!   [`solid`](self#solid-voxelization) below and [`Voxelization::boundary_edges`]).
//!
//! Degenerate triangles (zero area after snapping) give exactly the voxels their segment or
//! point touches in the surface modes, and nothing in solid mode.
//!
//! # How
//! Per triangle, only the columns of its bounding box in the plane of its dominant axis are
//! visited, each with a handful of integer edge functions, and the plane gives each column's
//! few voxels ([`raster`]); triangles are processed in parallel chunks (rayon), their
//! (Morton code, triangle) pairs sorted in parallel and grouped into the brick map and the CSR
//! triangle list. Occupancy alone (`triangle_lists: false`) sets bits of a dense brick bitset
//! instead when the grid is not huge: no pairs, no sort.
//!
//! # Solid voxelization
//! Parity along columns of voxel centres, exact for closed meshes (every edge, by snapped end
//! points, shared by an even number of non-degenerate triangles); with boundary edges, a voxel
//! is set when at least two of the three axis-aligned parities say inside, which voxelizes a
//! box missing a face to exactly its interior. Solid voxels keep the triangles whose
//! conservative test overlaps them; interior voxels have empty lists.
//!
//! # Input and errors
//! The geometry is not trusted: a non-finite vertex, a vertex index out of range, or a triangle
//! that reaches the grid with a vertex beyond the lattice's range (`±2^21` voxels from the grid
//! origin) is an error naming it; triangles entirely outside the grid are culled, whatever
//! their coordinates. A grid over [`lattice::MAX_GRID_DIM`] voxels per axis is
//! `GridTooLarge`; a result whose estimated peak memory exceeds
//! [`Options::memory_limit_bytes`] is [`Error::OutOfMemory`],
//! returned before anything large is allocated.
//!
//! Geometry without triangles (or with all of them outside the grid) gives an **empty
//! voxelization, not an error**: "nothing here" is a valid answer for a sub-grid of a scene,
//! and callers that need content (the CLI's "empty scene") check [`BrickMap::is_empty`].

mod budget;
pub mod lattice;
pub mod overlap;
mod pairs;
pub mod raster;
pub mod slicemap;
mod solid;
mod sort;
mod surface;

pub use solid::{boundary_edges, column_inside, first_above};

use voxlod_format::{BrickMap, GridSpec};
use voxlod_scene::Geometry;

use crate::{Error, Result};

/// Which voxels a voxelization sets.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum Mode {
    /// Every voxel a triangle touches (closed voxel boxes: touching a face or an edge counts).
    #[default]
    Conservative,
    /// 6-separating thin surface (Schwarz & Seidel 2010).
    Thin,
    /// Voxels whose centre is inside a closed mesh.
    Solid,
}

/// Options of [`voxelize`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Options {
    /// Which voxels to set.
    pub mode: Mode,
    /// Whether to keep, per occupied voxel, the list of triangles overlapping it (costs memory
    /// and time; the appearance precompute needs it).
    pub triangle_lists: bool,
    /// Refuse a voxelization whose estimated memory exceeds this many bytes.
    pub memory_limit_bytes: u64,
}

impl Default for Options {
    fn default() -> Self {
        Self { mode: Mode::Conservative, triangle_lists: true, memory_limit_bytes: 8 << 30 }
    }
}

/// A run of triangle ids in [`Voxelization::triangles`]: the triangles overlapping one voxel.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
pub struct TriangleRange {
    /// First entry in [`Voxelization::triangles`].
    pub first: u32,
    /// Number of entries (0 for solid-interior voxels, or when lists were not kept).
    pub count: u32,
}

/// The result of a voxelization: occupied voxels (sparse, Morton order) with their triangle
/// lists.
#[derive(Clone, Debug)]
pub struct Voxelization {
    /// The grid voxelized into.
    pub grid: GridSpec,
    /// The mode used.
    pub mode: Mode,
    /// Occupied voxels, each with its range in `triangles`.
    pub voxels: BrickMap<TriangleRange>,
    /// Triangle ids (indices into the [`Geometry`]'s triangles), grouped per voxel, ascending
    /// within a voxel. Empty when lists were not kept.
    pub triangles: Vec<u32>,
    /// Solid mode: the number of boundary edges found — edges, identified by their snapped end
    /// points, used by an odd number of non-degenerate triangles that can influence the grid.
    /// `Some(0)` means closed (exact parity along one axis); otherwise the majority of the three
    /// axis parities decided. `None` in the surface modes, which do not look at topology.
    pub boundary_edges: Option<u64>,
}

impl Voxelization {
    /// Whether the solid voxelization found a closed mesh (no boundary edges); `false` in the
    /// surface modes.
    pub fn is_closed(&self) -> bool {
        self.boundary_edges == Some(0)
    }

    /// Triangles overlapping the voxel at `index` (into `voxels.values()`).
    pub fn triangles_of(&self, index: usize) -> &[u32] {
        let r = self.voxels.values()[index];
        &self.triangles[r.first as usize..(r.first + r.count) as usize]
    }
}

/// Voxelizes `geometry` into `grid` (see the module docs for the rules, errors and the empty
/// case).
///
/// ```
/// use glam::{DVec3, UVec3, Vec3};
/// use voxlod_cpu::voxelize::{Mode, Options, voxelize};
/// use voxlod_format::GridSpec;
/// use voxlod_scene::Geometry;
///
/// // One triangle lying exactly on the boundary between voxel layers z = 1 and z = 2.
/// let geometry = Geometry {
///     positions: vec![Vec3::new(0.0, 0.0, 2.0), Vec3::new(4.0, 0.0, 2.0), Vec3::new(0.0, 4.0, 2.0)],
///     indices: vec![[0, 1, 2]],
///     ..Default::default()
/// };
/// let grid = GridSpec::new(DVec3::ZERO, 1.0, UVec3::splat(4)).unwrap();
/// let v = voxelize(&geometry, &grid, &Options::default()).unwrap();
/// // Closed voxels: the face touches both layers, in the 13 columns whose voxel's lower
/// // corner has x + y ≤ 4.
/// assert_eq!(v.voxels.len(), 2 * 13);
/// assert_eq!(v.triangles_of(0), &[0]);
/// ```
pub fn voxelize(geometry: &Geometry, grid: &GridSpec, options: &Options) -> Result<Voxelization> {
    let lattice = lattice::Lattice::new(geometry, grid)?;
    if geometry.indices.len() as u64 > u32::MAX as u64 {
        return Err(Error::InvalidParameter {
            name: "geometry",
            value: format!("{} triangles", geometry.indices.len()),
            reason: "triangle ids are 32-bit: at most 2^32 − 1 triangles".into(),
        });
    }
    match options.mode {
        Mode::Conservative | Mode::Thin => surface::voxelize(geometry, &lattice, options),
        Mode::Solid => solid::voxelize(geometry, &lattice, options),
    }
}

#[cfg(test)]
mod tests;
