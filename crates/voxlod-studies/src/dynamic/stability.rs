//! Temporal stability (the paper's flicker claim): one rigid object moving slowly above the
//! static floor — a fraction of a voxel and half a degree per frame — and the ambient occlusion
//! it casts on fixed shading points of the floor, cone traced through each frame's octree. The
//! object is first lowered (or raised) so that its lowest point hovers a quarter of the AO
//! radius above the static surface under its centre: the AO it casts then reaches the floor. The
//! measure is the mean absolute difference of AO between consecutive frames (over the floor's
//! pixels): the true change is small and smooth, so what a method adds to it is flicker. The
//! ray-traced AO of the moving mesh (same rays every frame) gives the true change.

use glam::{DMat4, DVec3, Vec3};
use serde::Serialize;
use voxlod_cone::{ConeTracer, TraceOptions};
use voxlod_cpu::dynamic::{ObjectKind, RecordSource, revoxelize};
use voxlod_cpu::raycast::Bvh;
use voxlod_cpu::render::ground_truth::{self, GBuffer};
use voxlod_cpu::render::indirect;
use voxlod_cpu::voxelize::Mode;
use voxlod_octree::dynamic::{Filter, FrameOptions, Placement, WorldSums};
use voxlod_octree::{AveragePayload, BuildOptions, Octree};
use voxlod_scene::{Camera, Scene};

use super::agreement::mode_name;
use super::setup::Prepared;
use crate::Error;

/// One method's frame-to-frame change of AO.
#[derive(Clone, Debug, Serialize)]
pub struct StabilityRow {
    /// `conservative` or `thin` (the caches' and the re-voxelization's voxelizer).
    pub voxelizer: String,
    /// `transform, nearest`, `transform, 8-neighbour`, `re-voxelized` or `mesh (ray traced)`.
    pub method: String,
    /// Frames of the sequence.
    pub frames: u32,
    /// Mean over consecutive frames of the mean absolute AO difference over the floor pixels.
    pub mean_change: f64,
    /// The largest frame-to-frame mean absolute difference.
    pub max_change: f64,
}

/// Settings of the stability part.
pub struct StabilitySettings {
    /// Frames.
    pub frames: u32,
    /// Translation per frame, voxels (along x).
    pub voxels_per_frame: f64,
    /// Rotation per frame about y, degrees.
    pub degrees_per_frame: f64,
    /// Image width (height ¾ of it).
    pub image_width: u32,
    /// Reference rays per pixel.
    pub spp: u32,
    /// AO radius, world units.
    pub ao_radius: f32,
    /// Records of the re-voxelization.
    pub records: RecordSource,
}

/// Frame-to-frame changes of each method (module docs), for every prepared voxelizer.
pub fn run(
    prepared: &[(Mode, Prepared)],
    s: &StabilitySettings,
    say: &dyn Fn(&str),
) -> Result<Vec<StabilityRow>, Error> {
    let mut rows = Vec::new();
    for (mode, p) in prepared {
        let Some(o) = p.ds.objects.iter().position(|o| matches!(o.kind, ObjectKind::Rigid { .. }))
        else {
            continue;
        };
        let ObjectKind::Rigid { node } = p.ds.objects[o].kind else { continue };
        say(&format!(
            "stability: {} frames of '{}' ({})",
            s.frames,
            p.ds.objects[o].name,
            mode_name(*mode)
        ));
        let rest = p.ds.scene.nodes[node].world.as_dmat4();
        let (g, _) = p.ds.object_geometry(&p.ds.objects[o])?;
        let (lo, hi) = g.bounds().ok_or_else(|| Error::NothingToMeasure {
            scene: p.ds.scene.name.clone(),
            why: "the rigid object has no triangles".into(),
        })?;
        let centre = (lo + hi).as_dvec3() * 0.5;
        let world_centre = rest.transform_point3(centre);
        // Fixed shading points: the static meshes under the object, seen from above and front.
        let mut statics = p.ds.scene.clone();
        statics.meshes = p.ds.statics.iter().map(|&i| p.ds.scene.meshes[i].clone()).collect();
        let floor_geometry = statics.geometry();
        if floor_geometry.indices.is_empty() {
            continue;
        }
        let floor_bvh = Bvh::new(&floor_geometry)?;
        // The static surface under the object's centre, and how far to move the object down
        // so its lowest point hovers a quarter of the AO radius above it.
        let Some(below) =
            floor_bvh.intersect(world_centre.as_vec3(), Vec3::NEG_Y, 0.0, f32::INFINITY)
        else {
            continue;
        };
        let floor_y = world_centre.y - below.t as f64;
        let lowest = g
            .positions
            .iter()
            .map(|v| rest.transform_point3(v.as_dvec3()).y)
            .fold(f64::INFINITY, f64::min);
        let drop = lowest - (floor_y + 0.25 * s.ao_radius as f64);
        let target = Vec3::new(world_centre.x as f32, floor_y as f32, world_centre.z as f32);
        let eye = target + Vec3::new(0.0, 2.5, 1.5) * (hi - lo).length().max(0.5);
        let camera = Camera::look_at(eye, target, Vec3::Y, 45.0);
        let (w, h) = (s.image_width, (s.image_width * 3 / 4).max(1));
        let gb = ground_truth::gbuffer(&statics, &floor_geometry, &floor_bvh, &camera, w, h)?;
        let placement = |k: u32| {
            let shift = DVec3::new(k as f64 * s.voxels_per_frame * p.grid.voxel_size, -drop, 0.0);
            let turn = DMat4::from_rotation_y((k as f64 * s.degrees_per_frame).to_radians());
            DMat4::from_translation(shift)
                * rest
                * DMat4::from_translation(centre)
                * turn
                * DMat4::from_translation(-centre)
        };
        let trace = TraceOptions { ao_radius: s.ao_radius, ..Default::default() };
        let methods =
            ["transform, nearest", "transform, 8-neighbour", "re-voxelized", "mesh (ray traced)"];
        let mut previous: Vec<Option<Vec<f32>>> = vec![None; methods.len()];
        let mut changes: Vec<Vec<f64>> = vec![Vec::new(); methods.len()];
        for k in 0..s.frames {
            let m = placement(k);
            let mut moved = g.clone();
            for v in &mut moved.positions {
                *v = m.transform_point3(v.as_dvec3()).as_vec3();
            }
            let rot = glam::DMat3::from_mat4(m);
            for n in &mut moved.normals {
                *n = (rot * n.as_dvec3()).normalize_or_zero().as_vec3();
            }
            let mut aos: Vec<Vec<f32>> = Vec::with_capacity(methods.len());
            let rigid = Placement::Rigid(m);
            for filter in [Filter::Nearest, Filter::EightNeighbour] {
                let opts = FrameOptions { filter, ..Default::default() };
                let (tree, _) = p.world.octree(&[(&p.caches[o], &rigid)], &opts)?;
                aos.push(ao_through(&tree, &gb, trace)?);
            }
            let reference = revoxelize(&p.ds.scene, &moved, &p.grid, *mode, s.records)?;
            let sums =
                WorldSums::from_static(&p.grid, reference.records.iter().map(|(c, r)| (c, *r)))?;
            let (leaves, _) = sums.merge(&p.world.statics).resolve(0.5)?;
            let tree = Octree::from_morton_sorted(p.grid, leaves, &BuildOptions::default())?;
            aos.push(ao_through(&tree, &gb, trace)?);
            aos.push(mesh_ao(&statics, &moved, &gb, s)?);
            for (i, ao) in aos.into_iter().enumerate() {
                if let Some(prev) = &previous[i] {
                    changes[i].push(mean_abs_change(&gb, prev, &ao));
                }
                previous[i] = Some(ao);
            }
        }
        for (i, method) in methods.iter().enumerate() {
            let c = &changes[i];
            rows.push(StabilityRow {
                voxelizer: mode_name(*mode).into(),
                method: (*method).into(),
                frames: s.frames,
                mean_change: c.iter().sum::<f64>() / c.len().max(1) as f64,
                max_change: c.iter().copied().fold(0.0, f64::max),
            });
        }
    }
    Ok(rows)
}

/// AO at the G-buffer's points through a geometry octree (opacity only).
fn ao_through(
    tree: &Octree<AveragePayload>,
    gb: &GBuffer,
    trace: TraceOptions,
) -> Result<Vec<f32>, Error> {
    use rayon::prelude::*;
    let tracer = ConeTracer::new(tree, trace)?;
    Ok(gb
        .texels
        .par_iter()
        .map(|t| {
            if t.triangle == u32::MAX {
                1.0
            } else {
                tracer.ambient_occlusion(t.position, t.normal)
            }
        })
        .collect())
}

/// Ray-traced AO of the static meshes and the moved object, at the G-buffer's points.
fn mesh_ao(
    statics: &Scene,
    moved: &voxlod_scene::Geometry,
    gb: &GBuffer,
    s: &StabilitySettings,
) -> Result<Vec<f32>, Error> {
    let mut g = statics.geometry();
    let base = g.positions.len() as u32;
    g.positions.extend_from_slice(&moved.positions);
    g.normals.extend_from_slice(&moved.normals);
    g.uvs.extend_from_slice(&moved.uvs);
    g.indices.extend(moved.indices.iter().map(|t| t.map(|v| v + base)));
    g.materials.extend_from_slice(&moved.materials);
    let bvh = Bvh::new(&g)?;
    let opts = indirect::Options { spp: s.spp, seed: 0, ao_radius: s.ao_radius };
    Ok(indirect::ambient_occlusion(statics, &g, &bvh, gb, &opts)?)
}

/// Mean |a − b| over the pixels that hit something.
fn mean_abs_change(gb: &GBuffer, a: &[f32], b: &[f32]) -> f64 {
    let (mut sum, mut n) = (0.0f64, 0usize);
    for ((t, x), y) in gb.texels.iter().zip(a).zip(b) {
        if t.triangle != u32::MAX {
            sum += (x - y).abs() as f64;
            n += 1;
        }
    }
    sum / n.max(1) as f64
}
