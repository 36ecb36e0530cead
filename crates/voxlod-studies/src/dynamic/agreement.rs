//! Agreement of transformed voxels with re-voxelization of the posed meshes: occupancy (IoU,
//! missing, extra), colour, and the cone-traced images against the ray-traced references of
//! the posed mesh; and the same at exact rotations of one rigid object.

use std::collections::HashMap;

use glam::{DMat4, DQuat, DVec3, UVec3, Vec3};
use serde::Serialize;
use voxlod_cpu::dynamic::{CacheOptions, ObjectKind, RecordSource, geometry_of, revoxelize};
use voxlod_cpu::raycast::Bvh;
use voxlod_cpu::render::ground_truth;
use voxlod_cpu::render::indirect;
use voxlod_cpu::voxelize::Mode;
use voxlod_format::records::AverageRecord;
use voxlod_format::{BrickMap, morton};
use voxlod_octree::dynamic::{
    DynamicWorld, Filter, FrameOptions, Placement, VoxelCache, WorldSums,
};
use voxlod_octree::{AveragePayload, BuildOptions, Octree};
use voxlod_scene::Srgb8Image;

use super::setup::{Prepared, colour, gray, inject_and_trace};
use crate::Error;

/// Occupancy and colour of one method against one re-voxelization.
#[derive(Clone, Debug, Serialize)]
pub struct AgreementRow {
    /// Animation time, seconds.
    pub time_s: f32,
    /// Which objects: `skinned`, `rigid` or `all`.
    pub objects: String,
    /// The voxelizer of the caches and of the reference: `conservative` or `thin`.
    pub voxelizer: String,
    /// `nearest` or `8-neighbour`.
    pub filter: String,
    /// Occupancy threshold (voxels of covered volume).
    pub threshold: f32,
    /// Voxels of the re-voxelization.
    pub reference_voxels: u64,
    /// Intersection over union of the occupied voxels.
    pub iou: f64,
    /// Reference voxels the transform left empty, as a fraction of the reference.
    pub missing_fraction: f64,
    /// Voxels the transform occupied that the reference does not, as a fraction of it.
    pub extra_fraction: f64,
    /// Mean absolute difference of linear RGB (mean of the channels) over shared voxels.
    pub colour_error: f64,
}

/// One method's cone-traced images against the ray-traced references of the posed mesh.
#[derive(Clone, Debug, Serialize)]
pub struct ImageRow {
    /// Animation time, seconds.
    pub time_s: f32,
    /// `conservative` or `thin`.
    pub voxelizer: String,
    /// `transform, nearest`, `transform, 8-neighbour` or `re-voxelized`.
    pub method: String,
    /// AO: MSE against the ray-traced AO (8-bit sRGB).
    pub ao_mse: f64,
    /// AO SSIM.
    pub ao_ssim: f64,
    /// Indirect light: MSE against the one-bounce path tracer.
    pub indirect_mse: f64,
    /// Indirect SSIM.
    pub indirect_ssim: f64,
    /// AO: MSE against the re-voxelized octree's cone-traced AO (0 for that row itself).
    pub ao_mse_revoxelized: f64,
    /// AO SSIM against the re-voxelized octree's AO.
    pub ao_ssim_revoxelized: f64,
    /// Indirect light: MSE against the re-voxelized octree's cone-traced indirect light.
    pub indirect_mse_revoxelized: f64,
    /// Indirect SSIM against the re-voxelized octree's.
    pub indirect_ssim_revoxelized: f64,
}

/// Occupancy of one rigid object at an exact rotation against its re-voxelization.
#[derive(Clone, Debug, Serialize)]
pub struct RotationRow {
    /// The rotation: `45° about x`, …
    pub rotation: String,
    /// The voxelizer of the cache and of the reference.
    pub voxelizer: String,
    /// `nearest` or `8-neighbour`.
    pub filter: String,
    /// Voxels of the re-voxelization.
    pub reference_voxels: u64,
    /// Intersection over union.
    pub iou: f64,
    /// Missing, as a fraction of the reference (the holes of nearest sampling).
    pub missing_fraction: f64,
    /// Extra, as a fraction of the reference.
    pub extra_fraction: f64,
}

/// What the images part leaves for the report: labelled AO images of one time.
pub struct ImageSet {
    /// `(label, image)` pairs: the reference first.
    pub images: Vec<(String, Srgb8Image)>,
}

pub(crate) fn mode_name(m: Mode) -> &'static str {
    match m {
        Mode::Conservative => "conservative",
        Mode::Thin => "thin",
        Mode::Solid => "solid",
    }
}

/// Occupied voxels (coordinates → linear colour).
type Occupancy = HashMap<UVec3, Vec3>;

fn occupancy_of_leaves(leaves: &[(u64, AveragePayload)]) -> Occupancy {
    leaves.iter().map(|(c, p)| (morton::decode(*c), p.color())).collect()
}

fn occupancy_of_records(map: &BrickMap<AverageRecord>) -> Occupancy {
    map.iter().map(|(c, r)| (c, r.color())).collect()
}

/// IoU, missing and extra fractions, colour error of `a` against reference `b`.
fn compare(a: &Occupancy, b: &Occupancy) -> (f64, f64, f64, f64) {
    let mut shared = 0usize;
    let mut colour = 0.0f64;
    for (c, ca) in a {
        if let Some(cb) = b.get(c) {
            shared += 1;
            colour += ((*ca - *cb).abs().element_sum() / 3.0) as f64;
        }
    }
    let union = a.len() + b.len() - shared;
    let reference = b.len().max(1) as f64;
    (
        shared as f64 / union.max(1) as f64,
        (b.len() - shared) as f64 / reference,
        (a.len() - shared) as f64 / reference,
        if shared > 0 { colour / shared as f64 } else { f64::NAN },
    )
}

/// The octree of `world`'s static voxels and `moving` re-voxelized voxels (whole voxels).
fn revoxelized_octree(
    world: &DynamicWorld,
    records: &BrickMap<AverageRecord>,
    build: &BuildOptions,
) -> Result<Octree<AveragePayload>, Error> {
    let moving = WorldSums::from_static(&world.grid, records.iter().map(|(c, r)| (c, *r)))?;
    let (leaves, _) = moving.merge(&world.statics).resolve(0.5)?;
    Ok(Octree::from_morton_sorted(world.grid, leaves, build)?)
}

/// Settings of the agreement part.
pub struct AgreementSettings<'a> {
    /// Times to measure.
    pub times: &'a [f32],
    /// Occupancy thresholds.
    pub thresholds: &'a [f32],
    /// Where records come from (caches and references alike).
    pub records: RecordSource,
    /// Image side (pixels, width; height ¾ of it).
    pub image_width: u32,
    /// Reference rays per pixel.
    pub spp: u32,
    /// AO radius, world units.
    pub ao_radius: f32,
    /// The octree's build options.
    pub build: BuildOptions,
}

/// What the agreement part measured.
pub struct Agreement {
    /// Occupancy and colour rows.
    pub rows: Vec<AgreementRow>,
    /// Image rows.
    pub images: Vec<ImageRow>,
    /// The AO images, one set per time.
    pub sets: Vec<ImageSet>,
}

/// The agreement rows, image rows and image sets of `prepared` (one per voxelizer, same
/// scene), at every time.
pub fn run(
    prepared: &[(Mode, Prepared)],
    s: &AgreementSettings,
    say: &dyn Fn(&str),
) -> Result<Agreement, Error> {
    let (mut rows, mut image_rows, mut sets) = (Vec::new(), Vec::new(), Vec::new());
    let first = &prepared[0].1;
    let light = super::setup::cone_light(first.ds.scene.light());
    let trace = voxlod_cone::TraceOptions { ao_radius: s.ao_radius, ..Default::default() };
    for &time in s.times {
        say(&format!("agreement at t = {time} s: references"));
        let pose = first.ds.pose(time)?;
        let posed = first.ds.posed_scene(&pose)?;
        let placements = first.ds.placements(&pose)?;
        let g = posed.geometry();
        let bvh = Bvh::new(&g)?;
        let camera = posed.default_camera()?;
        let (w, h) = (s.image_width, (s.image_width * 3 / 4).max(1));
        let gb = ground_truth::gbuffer(&posed, &g, &bvh, &camera, w, h)?;
        let opts = indirect::Options { spp: s.spp, seed: 0, ao_radius: s.ao_radius };
        let ao_ref = gray(&gb, &indirect::ambient_occlusion(&posed, &g, &bvh, &gb, &opts)?);
        let ind_ref = colour(&gb, &indirect::indirect_diffuse(&posed, &g, &bvh, &gb, &opts)?);
        let mut set =
            ImageSet { images: vec![(format!("t={time} ray-traced AO"), ao_ref.clone())] };
        for (mode, p) in prepared {
            say(&format!("agreement at t = {time} s: {} voxels", mode_name(*mode)));
            let vname = mode_name(*mode).to_string();
            for (class, wanted) in [("skinned", Some(true)), ("rigid", Some(false)), ("all", None)]
            {
                let picked: Vec<usize> = (0..p.ds.objects.len())
                    .filter(|&o| {
                        let skinned = matches!(p.ds.objects[o].kind, ObjectKind::Skinned { .. });
                        wanted.is_none_or(|w| w == skinned)
                    })
                    .collect();
                if picked.is_empty() {
                    continue;
                }
                let meshes: Vec<usize> =
                    picked.iter().flat_map(|&o| p.ds.objects[o].meshes.iter().copied()).collect();
                let geometry = geometry_of(&posed, &meshes);
                let reference = revoxelize(&posed, &geometry, &p.grid, *mode, s.records)?;
                let b = occupancy_of_records(&reference.records);
                let objects: Vec<(&VoxelCache, &Placement)> =
                    picked.iter().map(|&o| (&p.caches[o], &placements[o])).collect();
                for filter in [Filter::Nearest, Filter::EightNeighbour] {
                    for &threshold in s.thresholds {
                        let options = FrameOptions {
                            filter,
                            occupancy_threshold: threshold,
                            ..Default::default()
                        };
                        let (leaves, _) = p.moving_only.leaves(&objects, &options)?;
                        let (iou, missing, extra, colour_error) =
                            compare(&occupancy_of_leaves(&leaves), &b);
                        rows.push(AgreementRow {
                            time_s: time,
                            objects: class.into(),
                            voxelizer: vname.clone(),
                            filter: filter.name().into(),
                            threshold,
                            reference_voxels: b.len() as u64,
                            iou,
                            missing_fraction: missing,
                            extra_fraction: extra,
                            colour_error,
                        });
                    }
                }
                if class != "all" {
                    continue;
                }
                // Images: the whole world, every moving object, one octree per method.
                let all: Vec<(&VoxelCache, &Placement)> =
                    p.caches.iter().zip(&placements).collect();
                let mut octrees: Vec<(String, Octree<AveragePayload>)> = Vec::new();
                for filter in [Filter::Nearest, Filter::EightNeighbour] {
                    let options = FrameOptions { filter, build: s.build, ..Default::default() };
                    let (tree, _) = p.world.octree(&all, &options)?;
                    octrees.push((format!("transform, {}", filter.name()), tree));
                }
                octrees.push((
                    "re-voxelized".into(),
                    revoxelized_octree(&p.world, &reference.records, &s.build)?,
                ));
                let mut traced = Vec::with_capacity(octrees.len());
                for (method, tree) in &octrees {
                    let (ao, e) = inject_and_trace(tree, &light, &gb, trace)?;
                    traced.push((method, gray(&gb, &ao), colour(&gb, &e)));
                }
                // The re-voxelized octree's images (the last) are the second reference.
                let (_, ao_revox, ind_revox) = traced.last().cloned().expect("three octrees");
                for (method, ao_img, ind_img) in traced {
                    image_rows.push(ImageRow {
                        time_s: time,
                        voxelizer: vname.clone(),
                        method: method.clone(),
                        ao_mse: voxlod_eval::mse(&ao_img, &ao_ref)?,
                        ao_ssim: voxlod_eval::ssim(&ao_img, &ao_ref)?,
                        indirect_mse: voxlod_eval::mse(&ind_img, &ind_ref)?,
                        indirect_ssim: voxlod_eval::ssim(&ind_img, &ind_ref)?,
                        ao_mse_revoxelized: voxlod_eval::mse(&ao_img, &ao_revox)?,
                        ao_ssim_revoxelized: voxlod_eval::ssim(&ao_img, &ao_revox)?,
                        indirect_mse_revoxelized: voxlod_eval::mse(&ind_img, &ind_revox)?,
                        indirect_ssim_revoxelized: voxlod_eval::ssim(&ind_img, &ind_revox)?,
                    });
                    set.images.push((format!("{} {method}", mode_name(*mode)), ao_img));
                }
            }
        }
        sets.push(set);
    }
    Ok(Agreement { rows, images: image_rows, sets })
}

/// The rotations measured: exactly 45° about each axis, and two others.
pub fn rotations() -> Vec<(String, DQuat)> {
    let q = |axis: DVec3, deg: f64| DQuat::from_axis_angle(axis.normalize(), deg.to_radians());
    vec![
        ("45° about x".into(), q(DVec3::X, 45.0)),
        ("45° about y".into(), q(DVec3::Y, 45.0)),
        ("45° about z".into(), q(DVec3::Z, 45.0)),
        ("22.5° about y".into(), q(DVec3::Y, 22.5)),
        ("30° about (1,1,1)".into(), q(DVec3::ONE, 30.0)),
    ]
}

/// Occupancy of the first rigid object of each prepared scene at [`rotations`] (about its
/// centre, in place), against the re-voxelization of its mesh turned the same way.
pub fn rotation_rows(
    prepared: &[(Mode, Prepared)],
    options: &CacheOptions,
    say: &dyn Fn(&str),
) -> Result<Vec<RotationRow>, Error> {
    let mut rows = Vec::new();
    for (mode, p) in prepared {
        let Some(o) = p.ds.objects.iter().position(|o| matches!(o.kind, ObjectKind::Rigid { .. }))
        else {
            continue;
        };
        let ObjectKind::Rigid { node } = p.ds.objects[o].kind else { continue };
        say(&format!("rotations of '{}' ({})", p.ds.objects[o].name, mode_name(*mode)));
        let rest = p.ds.scene.nodes[node].world.as_dmat4();
        let (g, _) = p.ds.object_geometry(&p.ds.objects[o])?;
        let (lo, hi) = g.bounds().ok_or_else(|| Error::NothingToMeasure {
            scene: p.ds.scene.name.clone(),
            why: "the rigid object has no triangles".into(),
        })?;
        let centre = (lo + hi).as_dvec3() * 0.5;
        for (name, q) in rotations() {
            // Object space → world: turn about the object's centre, then its rest placement.
            let m = rest
                * DMat4::from_translation(centre)
                * DMat4::from_quat(q)
                * DMat4::from_translation(-centre);
            let mut turned = g.clone();
            for v in &mut turned.positions {
                *v = m.transform_point3(v.as_dvec3()).as_vec3();
            }
            let rotated = glam::DMat3::from_mat4(m);
            for n in &mut turned.normals {
                *n = (rotated * n.as_dvec3()).normalize_or_zero().as_vec3();
            }
            let reference = revoxelize(&p.ds.scene, &turned, &p.grid, *mode, options.records)?;
            let b = occupancy_of_records(&reference.records);
            let placement = Placement::Rigid(m);
            for filter in [Filter::Nearest, Filter::EightNeighbour] {
                let opts = FrameOptions { filter, ..Default::default() };
                let (leaves, _) = p.moving_only.leaves(&[(&p.caches[o], &placement)], &opts)?;
                let (iou, missing, extra, _) = compare(&occupancy_of_leaves(&leaves), &b);
                rows.push(RotationRow {
                    rotation: name.clone(),
                    voxelizer: mode_name(*mode).into(),
                    filter: filter.name().into(),
                    reference_voxels: b.len() as u64,
                    iou,
                    missing_fraction: missing,
                    extra_fraction: extra,
                });
            }
        }
    }
    Ok(rows)
}
