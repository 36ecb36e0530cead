//! Ground-truth images of a scene's views, rendered once per image side and shared by every
//! representation scored against them.

use glam::Vec3;

use crate::Error;
use crate::backend::SceneGpu;
use crate::report::Config;

/// Ground-truth images of one scene's views, rendered once per image side and kept.
pub(crate) struct GroundTruths<'a> {
    scene: &'a voxlod_scene::Scene,
    geometry: &'a voxlod_scene::Geometry,
    bvh: &'a voxlod_cpu::raycast::Bvh,
    views: &'a [voxlod_scene::Camera],
    spp: u32,
    ambient: Vec3,
    label: &'a str,
    gpu: Option<&'a SceneGpu<'a>>,
    by_size: Vec<(u32, Vec<voxlod_scene::Srgb8Image>)>,
}

impl<'a> GroundTruths<'a> {
    /// An empty set for `views` of `scene`.
    pub(crate) fn new(
        scene: &'a voxlod_scene::Scene,
        geometry: &'a voxlod_scene::Geometry,
        bvh: &'a voxlod_cpu::raycast::Bvh,
        views: &'a [voxlod_scene::Camera],
        config: &Config,
        label: &'a str,
        gpu: Option<&'a SceneGpu<'a>>,
    ) -> Self {
        let (spp, ambient) = (config.gt_spp, config.ambient);
        Self { scene, geometry, bvh, views, spp, ambient, label, gpu, by_size: Vec::new() }
    }

    /// Keeps images rendered elsewhere (seed 0) for side `size`.
    pub(crate) fn insert(&mut self, size: u32, images: Vec<voxlod_scene::Srgb8Image>) {
        self.by_size.push((size, images));
    }

    /// The seed-0 ground truth of every view at `size`², rendered on first use (on the GPU when
    /// the scene was uploaded to one).
    pub(crate) fn get(
        &mut self,
        size: u32,
        progress: &(dyn Fn(&str) + Sync),
    ) -> Result<&[voxlod_scene::Srgb8Image], Error> {
        if let Some(i) = self.by_size.iter().position(|(s, _)| *s == size) {
            return Ok(&self.by_size[i].1);
        }
        let options = voxlod_cpu::render::ground_truth::Options {
            width: size,
            height: size,
            spp: self.spp,
            seed: 0,
            ambient: self.ambient,
            shadows: true,
            light_filter: None,
        };
        let mut images = Vec::new();
        for (i, camera) in self.views.iter().enumerate() {
            progress(&format!(
                "{}: ground truth {size}², view {}/{}",
                self.label,
                i + 1,
                self.views.len()
            ));
            let gt = match self.gpu {
                Some(gpu) => gpu.ground_truth(camera, &options)?,
                None => voxlod_cpu::render::ground_truth::render(
                    self.scene,
                    self.geometry,
                    self.bvh,
                    camera,
                    &options,
                )?,
            };
            images.push(gt.image.to_srgb8());
        }
        self.by_size.push((size, images));
        Ok(&self.by_size.last().expect("just pushed").1)
    }
}

/// A seed-0 ground truth, its render time, and the MSE of an independent second seed against
/// it (8-bit sRGB): half of that estimates the truth's own error.
pub(crate) struct SeededTruth {
    /// The seed-0 render.
    pub(crate) truth: voxlod_cpu::render::ground_truth::GroundTruth,
    /// Its image in 8-bit sRGB.
    pub(crate) srgb8: voxlod_scene::Srgb8Image,
    /// Seed-0 render time, ms.
    pub(crate) ms: f64,
    /// MSE of seed 1 against seed 0.
    pub(crate) seed_mse: f64,
}

/// Renders the ground truth of `camera` with `options` at seeds 0 and 1 (`options.seed` is
/// ignored) and compares them.
pub(crate) fn seeded_truth(
    scene: &voxlod_scene::Scene,
    geometry: &voxlod_scene::Geometry,
    bvh: &voxlod_cpu::raycast::Bvh,
    camera: &voxlod_scene::Camera,
    options: &voxlod_cpu::render::ground_truth::Options,
) -> Result<SeededTruth, Error> {
    use voxlod_cpu::render::ground_truth::{Options, render};
    let t = std::time::Instant::now();
    let truth = render(scene, geometry, bvh, camera, &Options { seed: 0, ..*options })?;
    let ms = crate::spread::ms(t.elapsed());
    let srgb8 = truth.image.to_srgb8();
    let second = render(scene, geometry, bvh, camera, &Options { seed: 1, ..*options })?;
    let seed_mse = voxlod_eval::mse(&second.image.to_srgb8(), &srgb8)?;
    Ok(SeededTruth { truth, srgb8, ms, seed_mse })
}
