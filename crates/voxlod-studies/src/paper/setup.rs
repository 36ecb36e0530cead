//! What every variant of a scene shares: the scene loaded once with its views, and per
//! variant its lights, background, ground truths (through the cache) and crop boxes.

use glam::Vec3;
use voxlod_cpu::appearance::{Appearance, AuthorsChoices};
use voxlod_cpu::raycast::Bvh;
use voxlod_cpu::render::{filtered, ground_truth};
use voxlod_scene::{Camera, Geometry, Image, Light, Scene, Srgb8Image};

use super::{PaperConfig, TruthCache, Variant, cache, lighting};
use crate::Error;
use crate::views::orbit_views;

/// A scene loaded once, with its BVH and views.
pub(super) struct Loaded {
    pub spec: String,
    pub scene: Scene,
    pub geometry: Geometry,
    pub bvh: Bvh,
    pub views: Vec<Camera>,
}

/// One variant's conditions: its scene (background), lights, references and crop boxes.
pub(super) struct Setup {
    pub scene: Scene,
    pub lights: Vec<Light>,
    /// Seed-0 ground truth per view, 8-bit sRGB.
    pub references: Vec<Srgb8Image>,
    pub crops: Vec<Crop>,
    /// Half the seed-1 against seed-0 MSE, mean over views.
    pub truth_error: f64,
}

impl Loaded {
    pub fn new(spec: &str, views: usize) -> Result<Self, Error> {
        let scene = crate::scenes::load(spec)?;
        let geometry = scene.geometry();
        let bvh = Bvh::new(&geometry)?;
        let (lo, hi) = scene.bounds()?;
        let views = orbit_views(scene.default_camera()?, (lo + hi) * 0.5, views);
        Ok(Self { spec: spec.into(), scene, geometry, bvh, views })
    }

    /// The ground truths of `v` at `size`² (seeds 0 and 1 per view, from the cache or rendered
    /// into it).
    pub fn truths(
        &self,
        v: &Variant,
        size: u32,
        config: &PaperConfig,
        cache: &TruthCache,
        progress: &dyn Fn(&str),
    ) -> Result<Setup, Error> {
        let mut scene = self.scene.clone();
        scene.background = v.background.colour(&self.scene);
        let lights = v.lighting.lights(&scene, &self.views[0])?;
        let (mut references, mut crops, mut noise) = (Vec::new(), Vec::new(), 0.0);
        for (i, camera) in self.views.iter().enumerate() {
            let truth = |seed: u32| -> Result<Image, Error> {
                progress(&format!(
                    "{size}²: ground truth ({}, {}), view {}/{}, seed {seed}",
                    v.lighting.name(),
                    v.background.name(),
                    i + 1,
                    self.views.len()
                ));
                let key = cache::TruthInputs {
                    spec: &self.spec,
                    scene: &scene,
                    camera,
                    lights: &lights,
                    ambient: config.ambient,
                    size,
                    spp: config.gt_spp,
                    seed,
                }
                .key();
                cache.get_or_render(&key, || {
                    let options = |ambient| ground_truth::Options {
                        width: size,
                        height: size,
                        spp: config.gt_spp,
                        seed,
                        ambient,
                        shadows: true,
                        light_filter: None,
                    };
                    lighting::superpose(&lights, config.ambient, scene.background, |l, a, b| {
                        let mut s = scene.clone();
                        (s.lights, s.background) = (vec![*l], b);
                        let gt = ground_truth::render(
                            &s,
                            &self.geometry,
                            &self.bvh,
                            camera,
                            &options(a),
                        )?;
                        Ok(gt.image)
                    })
                })
            };
            let seed0 = truth(0)?;
            let seed1 = truth(1)?.to_srgb8();
            let reference = seed0.to_srgb8();
            noise += voxlod_eval::mse(&seed1, &reference)? * 0.5;
            crops.push(if v.crop { Crop::of_coverage(&seed0) } else { Crop::whole(&seed0) });
            references.push(reference);
        }
        let truth_error = noise / self.views.len() as f64;
        Ok(Setup { scene, lights, references, crops, truth_error })
    }
}

/// Renders `grid` from `camera` under `lights`, linear.
pub(super) fn render_linear(
    grid: &dyn Appearance,
    camera: &Camera,
    lights: &[Light],
    background: Vec3,
    ambient: Vec3,
    choices: &AuthorsChoices,
    size: u32,
) -> Result<Image, Error> {
    let mut cache = filtered::FrameCache::new(grid)?;
    lighting::superpose(lights, ambient, background, |l, a, b| {
        let options = choices.render(filtered::Options {
            width: size,
            height: size,
            ambient: a,
            shadows: true,
            ..Default::default()
        });
        Ok(filtered::render(&mut cache, camera, l, b, &options)?)
    })
}

/// Renders `grid` from `camera` under `lights`, 8-bit sRGB.
pub(super) fn render(
    grid: &dyn Appearance,
    camera: &Camera,
    lights: &[voxlod_scene::Light],
    background: Vec3,
    ambient: Vec3,
    choices: &AuthorsChoices,
    size: u32,
) -> Result<Srgb8Image, Error> {
    Ok(render_linear(grid, camera, lights, background, ambient, choices, size)?.to_srgb8())
}

/// The part of an image that is scored.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Crop {
    /// Left column.
    pub x: u32,
    /// Top row.
    pub y: u32,
    /// Width.
    pub width: u32,
    /// Height.
    pub height: u32,
}

impl Crop {
    /// The whole of `image`.
    pub fn whole(image: &Image) -> Self {
        Self { x: 0, y: 0, width: image.width, height: image.height }
    }

    /// The bounding box of the pixels of `image` with any coverage (alpha > 0), grown by one
    /// pixel, then to at least the SSIM window per side where the image allows; the whole image
    /// when nothing is covered.
    pub fn of_coverage(image: &Image) -> Self {
        let (mut x0, mut y0, mut x1, mut y1) = (u32::MAX, u32::MAX, 0, 0);
        for y in 0..image.height {
            for x in 0..image.width {
                if image.get(x, y).w > 0.0 {
                    (x0, y0, x1, y1) = (x0.min(x), y0.min(y), x1.max(x), y1.max(y));
                }
            }
        }
        if x0 == u32::MAX {
            return Self::whole(image);
        }
        let grow = |lo: u32, hi: u32, side: u32| -> (u32, u32) {
            let (mut lo, mut hi) = (lo.saturating_sub(1), (hi + 1).min(side - 1));
            let min = voxlod_eval::ssim::SSIM_WINDOW.min(side);
            while hi - lo + 1 < min {
                lo = lo.saturating_sub(1);
                if hi - lo + 1 < min && hi + 1 < side {
                    hi += 1;
                }
            }
            (lo, hi - lo + 1)
        };
        let (x, width) = grow(x0, x1, image.width);
        let (y, height) = grow(y0, y1, image.height);
        Self { x, y, width, height }
    }

    /// The cropped copy of `image`.
    pub fn apply(&self, image: &Srgb8Image) -> Srgb8Image {
        let mut pixels = Vec::with_capacity(self.width as usize * self.height as usize);
        for y in self.y..self.y + self.height {
            let row = (y * image.width) as usize;
            pixels.extend_from_slice(&image.pixels[row + self.x as usize..][..self.width as usize]);
        }
        Srgb8Image { width: self.width, height: self.height, pixels }
    }
}
