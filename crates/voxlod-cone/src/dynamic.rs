//! One frame of a dynamic scene for cone tracing (Yalçıner and Sahillioğlu 2020, §4.1): move the
//! cached voxels into the world grid, rebuild the octree from scratch with the static voxels,
//! re-inject the light — then cone trace through the result with [`crate::ConeTracer`].
//! [`FramePipeline`] skips the rebuild and the injection when no object moved since the last
//! frame (the placements are equal), so a still scene costs nothing per frame.

use std::time::Instant;

use voxlod_octree::dynamic::{DynamicWorld, FrameOptions, FrameStats, Placement, VoxelCache};
use voxlod_octree::{AveragePayload, Octree};

use crate::inject::{Light, Shadows, inject};
use crate::medium::RadianceLeaf;
use crate::{Error, Result};

/// What one [`FramePipeline::frame`] did and how long each step took (wall-clock, ms).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct FrameReport {
    /// Whether the octree was rebuilt and the light re-injected (false: nothing moved).
    pub rebuilt: bool,
    /// The transform and blend's counts (of the last rebuild).
    pub stats: FrameStats,
    /// Placing and transforming the cached voxels.
    pub transform_ms: f64,
    /// Blending, merging the static voxels and resolving the leaves.
    pub blend_ms: f64,
    /// Building the octree.
    pub build_ms: f64,
    /// Injecting the light (with shadows) and building the radiance octree.
    pub inject_ms: f64,
}

/// The per-frame pipeline over one world and its objects' caches.
#[derive(Debug)]
pub struct FramePipeline<'a, R> {
    world: &'a DynamicWorld,
    caches: &'a [VoxelCache],
    options: FrameOptions,
    light: Light,
    shadows: Shadows<'static>,
    last: Option<(Vec<Placement>, Octree<AveragePayload>, Octree<R>)>,
    report: FrameReport,
    rebuilds: u64,
}

fn ms(t: Instant) -> f64 {
    t.elapsed().as_secs_f64() * 1e3
}

impl<'a, R: RadianceLeaf> FramePipeline<'a, R> {
    /// A pipeline for `caches` (one per moving object, in the order placements will come) in
    /// `world`, lit by `light` with `shadows`.
    pub fn new(
        world: &'a DynamicWorld,
        caches: &'a [VoxelCache],
        options: FrameOptions,
        light: Light,
        shadows: Shadows<'static>,
    ) -> Self {
        Self {
            world,
            caches,
            options,
            light,
            shadows,
            last: None,
            report: FrameReport::default(),
            rebuilds: 0,
        }
    }

    /// How many frames rebuilt the octree.
    pub fn rebuilds(&self) -> u64 {
        self.rebuilds
    }

    /// The frame for `placements` (one per cache): the geometry octree, the radiance octree and
    /// the report. Errors: a placement count other than the caches', and every error of the
    /// transform, the blend, the build and the injection.
    pub fn frame(
        &mut self,
        placements: &[Placement],
    ) -> Result<(&Octree<AveragePayload>, &Octree<R>, FrameReport)> {
        if placements.len() != self.caches.len() {
            return Err(Error::InvalidParameter {
                name: "placements",
                value: placements.len().to_string(),
                reason: "one placement per cached object",
            });
        }
        let same = self.last.as_ref().is_some_and(|(p, _, _)| p.as_slice() == placements);
        if !same {
            let objects: Vec<(&VoxelCache, &Placement)> =
                self.caches.iter().zip(placements).collect();
            let t = Instant::now();
            let (placed, outside) =
                self.world.transform_all(&objects, &self.options).map_err(Error::Frame)?;
            let transform_ms = ms(t);
            let t = Instant::now();
            let (sums, blend) =
                self.world.sums(&objects, &placed, &self.options).map_err(Error::Frame)?;
            let placed_bytes: usize = placed
                .iter()
                .map(|p| p.capacity() * size_of::<voxlod_octree::dynamic::Placed>())
                .sum();
            drop(placed);
            let (leaves, dropped) =
                sums.resolve(self.options.occupancy_threshold).map_err(Error::Frame)?;
            let blend_ms = ms(t);
            let stats = FrameStats {
                blend,
                objects_outside: outside,
                touched: sums.len() as u64,
                occupied: leaves.len() as u64,
                dropped,
                transient_bytes: (placed_bytes.max(sums.memory_bytes())
                    + leaves.capacity() * size_of::<(u64, AveragePayload)>())
                    as u64,
            };
            drop(sums);
            let t = Instant::now();
            let geometry = Octree::from_morton_sorted(self.world.grid, leaves, &self.options.build)
                .map_err(Error::Frame)?;
            let build_ms = ms(t);
            let t = Instant::now();
            let radiance = inject(&geometry, &self.light, &self.shadows)?;
            let inject_ms = ms(t);
            self.last = Some((placements.to_vec(), geometry, radiance));
            self.report =
                FrameReport { rebuilt: true, stats, transform_ms, blend_ms, build_ms, inject_ms };
            self.rebuilds += 1;
        } else {
            self.report = FrameReport { rebuilt: false, ..self.report };
        }
        let (_, geometry, radiance) = self.last.as_ref().expect("set above");
        Ok((geometry, radiance, self.report))
    }
}

#[cfg(test)]
mod tests {
    use glam::{DMat4, DVec3, UVec3, Vec3};
    use voxlod_format::records::AverageRecord;
    use voxlod_format::{BrickMap, GridSpec};

    use super::*;
    use crate::{ConeTracer, RadiancePayload, TraceOptions};

    /// A lit 8×8 white plate moving over a floor: the octree follows it, a cone from the floor
    /// below it sees it, and a repeated placement rebuilds nothing.
    #[test]
    fn frames_follow_the_objects_and_skip_work_when_nothing_moved() {
        let grid = GridSpec::new(DVec3::ZERO, 1.0, UVec3::splat(32)).unwrap();
        let white = |n: Vec3| AverageRecord::new(Vec3::splat(0.8), n, 1.0);
        let floor =
            (0..32).flat_map(|x| (0..32).map(move |z| (UVec3::new(x, 0, z), white(Vec3::Y))));
        let world = DynamicWorld::new(grid, floor).unwrap();
        let og = GridSpec::new(DVec3::ZERO, 1.0, UVec3::new(8, 1, 8)).unwrap();
        let plate = BrickMap::from_voxels(
            og.dims,
            (0..8).flat_map(|x| (0..8).map(move |z| (UVec3::new(x, 0, z), white(Vec3::NEG_Y)))),
        )
        .unwrap();
        let caches = [VoxelCache::rigid("plate", og, 1.0, &plate).unwrap()];
        let light = Light::Directional { to_light: Vec3::Y, irradiance: Vec3::splat(3.0) };
        let mut pipeline: FramePipeline<RadiancePayload> =
            FramePipeline::new(&world, &caches, FrameOptions::default(), light, Shadows::MARCH);
        let at = |x: f64| [Placement::Rigid(DMat4::from_translation(DVec3::new(x, 3.0, 12.0)))];
        let ao_at = |radiance: &Octree<RadiancePayload>, x: f32| {
            let options = TraceOptions { ao_radius: 6.0, ..TraceOptions::default() };
            ConeTracer::new(radiance, options)
                .unwrap()
                .ambient_occlusion(Vec3::new(x, 1.0, 16.0), Vec3::Y)
        };
        let (g, r, report) = pipeline.frame(&at(4.0)).unwrap();
        assert!(report.rebuilt);
        assert_eq!(g.voxel_count(), 32 * 32 + 64);
        let (under, away) = (ao_at(r, 8.0), ao_at(r, 26.0));
        assert!(under < away - 0.1, "AO under the plate {under}, away from it {away}");
        let (_, _, report) = pipeline.frame(&at(4.0)).unwrap();
        assert!(!report.rebuilt);
        assert_eq!(pipeline.rebuilds(), 1);
        // Moved over x = 26: now that floor point is the occluded one.
        let (_, r, report) = pipeline.frame(&at(22.0)).unwrap();
        assert!(report.rebuilt && report.stats.occupied == 32 * 32 + 64);
        assert!(ao_at(r, 26.0) < ao_at(r, 8.0) - 0.1);
        assert!(pipeline.frame(&[]).is_err());
    }
}
