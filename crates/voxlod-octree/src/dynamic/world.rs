//! [`DynamicWorld`]: the world grid with its static voxels, and one frame's leaves or octree from
//! the moving objects' caches and placements (place, transform, blend, merge, resolve, build).

use voxlod_format::GridSpec;

use super::blend::{BlendInput, BlendStats, WorldSums, blend};
use super::cache::VoxelCache;
use super::place::{Placement, place};
use super::transform::{Filter, Placed, transform};
use crate::payload::AveragePayload;
use crate::{BuildOptions, Octree, Result};

/// Default occupancy threshold: a world voxel is occupied when moved voxels cover at least
/// half of its volume. A surface moved by a fraction of a voxel then stays one voxel thick where
/// most of it lies, as re-voxelizing it would make it; lower thresholds thicken surfaces, higher
/// ones open holes (the dynamic study measures the trade).
pub const DEFAULT_OCCUPANCY: f32 = 0.5;

/// Options of a frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FrameOptions {
    /// Nearest or 8-neighbour (default).
    pub filter: Filter,
    /// Covered volume (voxels) at which a world voxel becomes occupied, in \[0, 8\] (default
    /// [`DEFAULT_OCCUPANCY`]; nearest writes whole voxels, so any value ≤ 1 keeps them all).
    pub occupancy_threshold: f32,
    /// Relative tolerance of the rigidity and resolution checks (default 10⁻³).
    pub rigidity_tolerance: f64,
    /// The octree's depth and dense levels.
    pub build: BuildOptions,
}

impl Default for FrameOptions {
    fn default() -> Self {
        Self {
            filter: Filter::EightNeighbour,
            occupancy_threshold: DEFAULT_OCCUPANCY,
            rigidity_tolerance: 1e-3,
            build: BuildOptions::default(),
        }
    }
}

/// What one frame did.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct FrameStats {
    /// The blend's counts (moved voxels, contributions, clipped).
    pub blend: BlendStats,
    /// Objects entirely outside (anchor beyond ±2³⁰ voxels).
    pub objects_outside: u64,
    /// World voxels any contribution or static voxel touched.
    pub touched: u64,
    /// Occupied world voxels (the octree's leaves).
    pub occupied: u64,
    /// Touched world voxels below the occupancy threshold (or transparent).
    pub dropped: u64,
    /// Bytes of the frame's transient arrays (moved voxels, sums, leaves) at their peak.
    pub transient_bytes: u64,
}

/// The world grid and its static voxels (module docs of [`super`]).
#[derive(Clone, Debug)]
pub struct DynamicWorld {
    /// The world grid.
    pub grid: GridSpec,
    /// The static voxels' sums (computed once).
    pub statics: WorldSums,
}

impl DynamicWorld {
    /// A world over `grid` with static voxels (coordinates and records; outside the grid is an
    /// error).
    pub fn new(
        grid: GridSpec,
        statics: impl IntoIterator<Item = (glam::UVec3, voxlod_format::records::AverageRecord)>,
    ) -> Result<Self> {
        grid.validate()?;
        Ok(Self { statics: WorldSums::from_static(&grid, statics)?, grid })
    }

    /// Places and moves every object (in order), each into its own array.
    pub fn transform_all(
        &self,
        objects: &[(&VoxelCache, &Placement)],
        options: &FrameOptions,
    ) -> Result<(Vec<Vec<Placed>>, u64)> {
        let mut outside = 0;
        let mut placed = Vec::with_capacity(objects.len());
        for (cache, placement) in objects {
            let frame = place(cache, placement, &self.grid, options.rigidity_tolerance)?;
            outside += frame.outside as u64;
            placed.push(transform(cache, &frame, options.filter));
        }
        Ok((placed, outside))
    }

    /// Blends moved voxels and merges the static ones: every touched world voxel's sums.
    pub fn sums(
        &self,
        objects: &[(&VoxelCache, &Placement)],
        placed: &[Vec<Placed>],
        options: &FrameOptions,
    ) -> Result<(WorldSums, BlendStats)> {
        let inputs: Vec<BlendInput> = objects
            .iter()
            .zip(placed)
            .map(|((c, _), p)| BlendInput { placed: p, records: &c.records })
            .collect();
        let (moving, stats) =
            blend(&self.grid, &inputs, options.filter, self.statics.len() as u64)?;
        Ok((moving.merge(&self.statics), stats))
    }

    /// One frame's occupied world voxels with their leaf payloads, in Morton order.
    pub fn leaves(
        &self,
        objects: &[(&VoxelCache, &Placement)],
        options: &FrameOptions,
    ) -> Result<(Vec<(u64, AveragePayload)>, FrameStats)> {
        let (placed, objects_outside) = self.transform_all(objects, options)?;
        let placed_bytes: usize = placed.iter().map(|p| p.capacity() * size_of::<Placed>()).sum();
        let (sums, blend) = self.sums(objects, &placed, options)?;
        drop(placed);
        let (leaves, dropped) = sums.resolve(options.occupancy_threshold)?;
        let transient = placed_bytes.max(sums.memory_bytes())
            + leaves.capacity() * size_of::<(u64, AveragePayload)>();
        let stats = FrameStats {
            blend,
            objects_outside,
            touched: sums.len() as u64,
            occupied: leaves.len() as u64,
            dropped,
            transient_bytes: transient as u64,
        };
        Ok((leaves, stats))
    }

    /// One frame's octree: [`DynamicWorld::leaves`] then
    /// [`Octree::from_morton_sorted`].
    pub fn octree(
        &self,
        objects: &[(&VoxelCache, &Placement)],
        options: &FrameOptions,
    ) -> Result<(Octree<AveragePayload>, FrameStats)> {
        let (leaves, stats) = self.leaves(objects, options)?;
        Ok((Octree::from_morton_sorted(self.grid, leaves, &options.build)?, stats))
    }
}
