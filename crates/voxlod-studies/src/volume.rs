//! The procedural-volume trade: a particle preset over a small mesh scene (ground and
//! a block), rendered with the metavoxel pipeline of `voxlod_cpu::volume`, measured two ways:
//!
//! - **Attenuation**: the chapter's `1/(1+d)` and Beer–Lambert `e^(−d)`, both marched one
//!   sample per voxel, against the exact reference (`Attenuation::Exact`): MSE/SSIM of the
//!   composited 8-bit sRGB images, and the time of each (build + march).
//! - **Metavoxel size** `M ∈ {8, 16, 32, 64}` at a fixed resolution (`K = res / M`): time per
//!   stage, peak heap during the build and march (with the tracking allocator), the bytes the
//!   sparse volume holds and those of a dense volume of the same resolution.
//!
//! The mesh is rendered once by the ground-truth renderer without the volume (the "mesh" image;
//! its G-buffer depth stops the eye rays and its BVH casts the scene's shadow on the volume),
//! and again per attenuation model with the built volume as its light filter
//! (`Volume::transmittance_to_light` multiplying each shading point's direct light: the
//! volume's shadow on the scene), under the march's composite.

use std::time::{Duration, Instant};

use glam::Vec3;
use serde::Serialize;
use voxlod_cpu::raycast::Bvh;
use voxlod_cpu::render::ground_truth;
use voxlod_cpu::volume::{self, Attenuation, BuildSettings, MarchOptions, VolumeSpec, march};
use voxlod_eval::ImageMetrics;
use voxlod_scene::particles::{
    CloudParams, ExplosionParams, ParticleSystem, SmokeParams, cloud_bank, explosion, smoke_column,
};
use voxlod_scene::procedural::primitives::{cube, quad};
use voxlod_scene::{Camera, Image, Light, Material, Scene};

use crate::backend::Backend;
use crate::{Error, alloc};

/// The particle presets of `voxlod volume`.
pub const PRESETS: [&str; 3] = ["smoke", "explosion", "clouds"];

/// What to run.
#[derive(Clone, Debug, PartialEq)]
pub struct VolumeConfig {
    /// `smoke`, `explosion` or `clouds`.
    pub preset: String,
    /// Particles (0: the preset's default).
    pub particles: usize,
    /// Voxels per axis of the volume (`K · M`); each `M` of `metavoxel_sizes` must divide it.
    pub resolution: u32,
    /// Metavoxel edges measured.
    pub metavoxel_sizes: Vec<u32>,
    /// Image side in pixels.
    pub image: u32,
    /// Rays per pixel of the mesh's ground truth.
    pub mesh_spp: u32,
}

impl VolumeConfig {
    /// Small and fast: 64³ voxels, M ∈ {8, 16, 32, 64}, 160×160 pixels, 2000 particles.
    pub fn quick(preset: &str) -> Self {
        Self {
            preset: preset.into(),
            particles: 2_000,
            resolution: 64,
            metavoxel_sizes: vec![8, 16, 32, 64],
            image: 160,
            mesh_spp: 4,
        }
    }

    /// Checks every field (named in the error).
    pub fn validate(&self) -> Result<(), Error> {
        let bad = |field: &'static str, value: String, expected: &'static str| {
            Err(Error::InvalidConfig { study: "volume", field, value, expected })
        };
        if !PRESETS.contains(&self.preset.as_str()) {
            return bad("preset", self.preset.clone(), "one of smoke, explosion, clouds");
        }
        if !(1..=1024).contains(&self.resolution) {
            return bad("resolution", self.resolution.to_string(), "in 1..=1024 voxels per axis");
        }
        if self.metavoxel_sizes.is_empty() {
            return bad("metavoxel_sizes", "[]".into(), "at least one metavoxel size");
        }
        for &m in &self.metavoxel_sizes {
            if m == 0 || !self.resolution.is_multiple_of(m) || self.resolution / m > 128 {
                return bad(
                    "metavoxel_sizes",
                    m.to_string(),
                    "a divisor of the resolution, with at most 128 metavoxels per axis",
                );
            }
        }
        if !(1..=4096).contains(&self.image) {
            return bad("image", self.image.to_string(), "an image side in 1..=4096");
        }
        if self.mesh_spp == 0 {
            return bad("mesh_spp", "0".into(), "at least 1 ray per pixel");
        }
        Ok(())
    }
}

/// One attenuation model against the reference.
#[derive(Clone, Debug, Serialize)]
pub struct AttenuationRow {
    /// Model name.
    pub model: String,
    /// Metrics of the composited image against the reference's.
    pub metrics: ImageMetrics,
    /// Build (bin, cull, fill, propagate) seconds.
    pub build_s: f64,
    /// March seconds.
    pub march_s: f64,
    /// Seconds of the mesh's ground-truth render with the volume's shadow (the light filter).
    pub shadowed_mesh_s: f64,
}

/// One metavoxel size.
#[derive(Clone, Debug, Serialize)]
pub struct SizeRow {
    /// `M`.
    pub metavoxel_edge: u32,
    /// `K`.
    pub metavoxels: u32,
    /// Occupied metavoxels, and those kept after culling.
    pub occupied: usize,
    /// Kept (filled and lit) metavoxels.
    pub kept: usize,
    /// Seconds per stage.
    pub binning_s: f64,
    /// Culling seconds.
    pub culling_s: f64,
    /// Fill seconds.
    pub fill_s: f64,
    /// Propagation seconds.
    pub propagation_s: f64,
    /// March seconds.
    pub march_s: f64,
    /// Heap bytes held at the peak of build + march (None without the tracking allocator).
    pub peak_bytes: Option<usize>,
    /// Bytes of the sparse volume.
    pub volume_bytes: u64,
    /// Bytes of a dense volume of the same resolution.
    pub dense_bytes: u64,
}

/// Everything measured, with the images.
#[derive(Clone, Debug, Serialize)]
pub struct VolumeResult {
    /// The preset.
    pub preset: String,
    /// Which backend built and marched the volume (`cpu (rayon)` or `gpu: <adapter>`).
    pub backend: String,
    /// Particles alive in the frame.
    pub particles: usize,
    /// Voxels per axis.
    pub resolution: u32,
    /// Image side.
    pub image: u32,
    /// Rays per pixel of the mesh's ground truth.
    pub mesh_spp: u32,
    /// Seconds of the mesh's ground-truth render without the volume's shadow.
    pub mesh_s: f64,
    /// Attenuation rows (chapter, Beer–Lambert), at `M = 32` or the closest measured.
    pub attenuation: Vec<AttenuationRow>,
    /// Metavoxel-size rows.
    pub sizes: Vec<SizeRow>,
    /// Mesh, reference, chapter, Beer–Lambert composites (not serialized).
    #[serde(skip)]
    pub images: Vec<(String, Image)>,
}

/// The preset's particles (count 0: the preset's default).
pub fn preset(name: &str, count: usize) -> Result<ParticleSystem, Error> {
    let pick = |default: usize| if count == 0 { default } else { count };
    let system = match name {
        "smoke" => smoke_column(&SmokeParams {
            count: pick(SmokeParams::default().count),
            ..Default::default()
        })?,
        "explosion" => explosion(&ExplosionParams {
            count: pick(ExplosionParams::default().count),
            ..Default::default()
        })?,
        "clouds" => cloud_bank(&CloudParams {
            count: pick(CloudParams::default().count),
            ..Default::default()
        })?,
        other => {
            return Err(voxlod_scene::Error::InvalidParameter {
                name: "volume preset".into(),
                value: other.into(),
                reason: format!("one of {}", PRESETS.join(", ")),
            }
            .into());
        }
    };
    Ok(system)
}

/// The mesh around the effect: a ground quad and a block beside the effect's bounds, the sun,
/// and a camera framing the effect from a little above.
fn stage(lo: Vec3, hi: Vec3) -> (Scene, Camera, Vec3) {
    let centre = (lo + hi) * 0.5;
    let size = (hi - lo).max_element();
    let to_light = Vec3::new(0.45, 0.85, 0.3).normalize();
    let g = 2.0 * size;
    let mut ground = quad(
        Vec3::new(centre.x - g, 0.0, centre.z + g),
        Vec3::new(2.0 * g, 0.0, 0.0),
        Vec3::new(0.0, 0.0, -2.0 * g),
        false,
    );
    ground.material = 0;
    let b = 0.15 * size;
    let mut block = cube(
        Vec3::new(hi.x, 0.0, centre.z - b),
        Vec3::new(hi.x + 2.0 * b, 2.0 * b + 0.2 * size, centre.z + b),
    );
    block.material = 1;
    let scene = Scene {
        name: "volume stage".into(),
        meshes: vec![ground, block],
        materials: vec![
            Material::diffuse("ground", Vec3::new(0.45, 0.42, 0.38)),
            Material::diffuse("block", Vec3::new(0.7, 0.25, 0.2)),
        ],
        lights: vec![Light::Directional { to_light, irradiance: Vec3::splat(3.0) }],
        background: Vec3::new(0.42, 0.60, 0.85),
        ..Default::default()
    };
    let camera = Camera::framing(Vec3::new(0.35, 0.25, 1.0), centre, 0.75 * size, 45.0);
    (scene, camera, to_light)
}

fn secs(d: Duration) -> f64 {
    d.as_secs_f64()
}

/// One volume built and marched: the volume (the light filter of the shadowed mesh), the
/// image, the build and march times, the stats and stage times, the volume's bytes.
struct Frame {
    volume: volume::Volume,
    image: Image,
    build: Duration,
    march: Duration,
    bytes: u64,
}

/// The backend that builds and marches: the CPU reference, or the GPU kernels
/// (`voxlod_gpu::volume`) with the mesh's BVH uploaded for the scene's shadow.
enum Builder<'a> {
    Cpu,
    Gpu(voxlod_gpu::volume::VolumeKernels<'a>, voxlod_gpu::raycast::GpuBvh),
}

impl Builder<'_> {
    /// Builds (with `view` culling, `bvh` shadowing) and marches one volume.
    #[allow(clippy::too_many_arguments)]
    fn frame(
        &self,
        spheres: &[voxlod_scene::particles::DisplacedSphere],
        map: &voxlod_scene::particles::DisplacementMap,
        spec: &VolumeSpec,
        settings: &BuildSettings,
        view: &voxlod_scene::camera::CameraFrame,
        bvh: &Bvh,
        camera: &Camera,
        options: &MarchOptions,
        depth: &[f32],
        read_back: bool,
    ) -> Result<Frame, Error> {
        match self {
            Builder::Gpu(k, gpu_bvh) => {
                let t = Instant::now();
                let v = k.build(spheres, map, spec, settings, Some(view), Some(gpu_bvh))?;
                let build = t.elapsed();
                let t = Instant::now();
                let image = k.render(&v, camera, options, Some(depth))?;
                let march = t.elapsed();
                let bytes = v.bytes();
                // The read-back (for the volume's shadow on the mesh) is not timed.
                let volume = if read_back {
                    k.read_volume(&v)?
                } else {
                    volume::Volume::from_parts(
                        *spec,
                        settings.attenuation,
                        Vec::new(),
                        v.stats,
                        v.times,
                    )?
                };
                Ok(Frame { volume, image, build, march, bytes })
            }
            Builder::Cpu => {
                let t = Instant::now();
                let v = volume::build(spheres, map, spec, settings, Some(view), Some(bvh))?;
                let build = t.elapsed();
                let t = Instant::now();
                let image = march::render(&v, camera, options, Some(depth))?;
                let march = t.elapsed();
                let bytes = v.bytes();
                Ok(Frame { volume: v, image, build, march, bytes })
            }
        }
    }
}

/// Runs the measurement, building and marching on `gpu` when given (the mesh's ground truth
/// stays on the CPU). Errors on an unknown preset, a
/// resolution not divisible by a metavoxel size, or any pipeline error.
pub fn run(
    config: &VolumeConfig,
    backend: Backend<'_>,
    progress: &dyn Fn(&str),
) -> Result<VolumeResult, Error> {
    config.validate()?;
    let bad = |name: &str, value: String, reason: &str| {
        Error::Scene(voxlod_scene::Error::InvalidParameter {
            name: name.into(),
            value,
            reason: reason.into(),
        })
    };
    progress("particles");
    let system = preset(&config.preset, config.particles)?;
    let spheres = system.at(system.time);
    let (lo, hi) = voxlod_scene::particles::bounds(&spheres)
        .ok_or_else(|| bad("preset", config.preset.clone(), "no particle alive"))?;
    let (scene, camera, to_light) = stage(lo, hi);
    progress("mesh ground truth");
    let geometry = scene.geometry();
    let bvh = Bvh::new(&geometry)?;
    let (w, h) = (config.image, config.image);
    let gt_options = ground_truth::Options {
        width: w,
        height: h,
        spp: config.mesh_spp,
        ambient: Vec3::splat(0.15),
        ..Default::default()
    };
    let t = Instant::now();
    let gt = ground_truth::render(&scene, &geometry, &bvh, &camera, &gt_options)?;
    let mesh_s = secs(t.elapsed());
    let depth: Vec<f32> = gt.gbuffer.texels.iter().map(|t| t.depth).collect();
    let frame = camera.frame(w, h);
    let march_options = MarchOptions { width: w, height: h, step: 1.0 };
    let map = &system.displacement;

    // Attenuation models at the size closest to the chapter's M = 32.
    let m_ref = *config.metavoxel_sizes.iter().min_by_key(|&&m| m.abs_diff(32)).unwrap_or(&32);
    let spec = VolumeSpec::fit(lo, hi, to_light, config.resolution / m_ref, m_ref)?;
    let builder = match backend {
        Backend::Cpu => Builder::Cpu,
        Backend::Gpu(ctx) => {
            progress("compiling the GPU volume kernels");
            let k = voxlod_gpu::volume::VolumeKernels::new(ctx)?;
            let gpu_bvh = voxlod_gpu::raycast::upload_bvh(ctx, &bvh, &geometry)?;
            Builder::Gpu(k, gpu_bvh)
        }
    };
    let backend_name = backend.describe();
    let mut images = vec![("mesh".to_string(), gt.image.clone())];
    let mut rendered = Vec::new();
    for att in [Attenuation::Exact, Attenuation::Chapter, Attenuation::BeerLambert] {
        progress(&format!("volume, {}", att.name()));
        let settings = BuildSettings { attenuation: att, ..Default::default() };
        let f = builder.frame(
            &spheres,
            map,
            &spec,
            &settings,
            &frame,
            &bvh,
            &camera,
            &march_options,
            &depth,
            true,
        )?;
        let (v, img) = (f.volume, f.image);
        let (build_s, march_s) = (secs(f.build), secs(f.march));
        // The volume's shadow on the mesh: the same render, the volume filtering the light.
        let t = Instant::now();
        let shadowed_options = ground_truth::Options { light_filter: Some(&v), ..gt_options };
        let shadowed = ground_truth::render(&scene, &geometry, &bvh, &camera, &shadowed_options)?;
        let shadowed_mesh_s = secs(t.elapsed());
        let composed = march::composite(&img, &shadowed.image)?;
        rendered.push((att, composed.to_srgb8(), build_s, march_s, shadowed_mesh_s));
        images.push((att.name().to_string(), composed));
    }
    let reference = rendered[0].1.clone();
    let attenuation = rendered
        .iter()
        .map(|(att, img, build_s, march_s, shadowed_mesh_s)| {
            Ok(AttenuationRow {
                model: att.name().into(),
                metrics: voxlod_eval::compare(img, &reference)?,
                build_s: *build_s,
                march_s: *march_s,
                shadowed_mesh_s: *shadowed_mesh_s,
            })
        })
        .collect::<Result<Vec<_>, Error>>()?;

    // Metavoxel sizes.
    let mut sizes = Vec::new();
    for &m in &config.metavoxel_sizes {
        progress(&format!("volume, M = {m}"));
        let spec = VolumeSpec::fit(lo, hi, to_light, config.resolution / m, m)?;
        let settings = BuildSettings::default();
        let (built, peak_bytes) = alloc::measure_peak(|| {
            builder.frame(
                &spheres,
                map,
                &spec,
                &settings,
                &frame,
                &bvh,
                &camera,
                &march_options,
                &depth,
                false,
            )
        });
        let f = built?;
        let (v, march_time) = (&f.volume, f.march);
        sizes.push(SizeRow {
            metavoxel_edge: m,
            metavoxels: spec.metavoxels,
            occupied: v.stats.occupied,
            kept: v.stats.kept,
            binning_s: secs(v.times.binning),
            culling_s: secs(v.times.culling),
            fill_s: secs(v.times.fill),
            propagation_s: secs(v.times.propagation),
            march_s: secs(march_time),
            peak_bytes,
            volume_bytes: f.bytes,
            dense_bytes: spec.dense_bytes(),
        });
    }
    Ok(VolumeResult {
        preset: config.preset.clone(),
        backend: backend_name,
        particles: spheres.len(),
        resolution: config.resolution,
        image: config.image,
        mesh_spp: config.mesh_spp,
        mesh_s,
        attenuation,
        sizes,
        images,
    })
}

impl VolumeResult {
    /// The two tables: attenuation models against the reference, and metavoxel sizes.
    pub fn tables(&self) -> Result<Vec<voxlod_eval::report::Table>, Error> {
        use voxlod_eval::report::{Cell, Column, NumberFormat as F, Table};
        let mut a = Table::new(
            format!(
                "{}: attenuation against the exact reference ({} particles, {}³ voxels, {}×{}; \
                 volume on {}; mesh ground truth at {} spp on the CPU: {:.3} s alone, 'shadowed \
                 mesh s' with the volume's shadow)",
                self.preset,
                self.particles,
                self.resolution,
                self.image,
                self.image,
                self.backend,
                self.mesh_spp,
                self.mesh_s
            ),
            vec![
                Column::text("model"),
                Column::number("MSE", F::Scientific(3)),
                Column::number("SSIM", F::Fixed(4)),
                Column::number("build s", F::Fixed(3)),
                Column::number("march s", F::Fixed(3)),
                Column::number("shadowed mesh s", F::Fixed(3)),
            ],
        );
        for r in &self.attenuation {
            a.push_row(vec![
                Cell::from(r.model.as_str()),
                r.metrics.mse.into(),
                r.metrics.ssim.into(),
                r.build_s.into(),
                r.march_s.into(),
                r.shadowed_mesh_s.into(),
            ])?;
        }
        let mut s = Table::new(
            format!(
                "{}: metavoxel size M (K = {} / M), exp(-d), on {}",
                self.preset, self.resolution, self.backend
            ),
            vec![
                Column::number("M", F::Integer),
                Column::number("K", F::Integer),
                Column::number("occupied", F::Integer),
                Column::number("kept", F::Integer),
                Column::number("binning s", F::Fixed(4)),
                Column::number("fill s", F::Fixed(4)),
                Column::number("propagation s", F::Fixed(4)),
                Column::number("march s", F::Fixed(4)),
                Column::number("peak MiB", F::Fixed(2)),
                Column::number("volume MiB", F::Fixed(2)),
                Column::number("dense MiB", F::Fixed(2)),
            ],
        );
        let mib = |b: f64| b / (1024.0 * 1024.0);
        for r in &self.sizes {
            s.push_row(vec![
                (r.metavoxel_edge as f64).into(),
                (r.metavoxels as f64).into(),
                (r.occupied as f64).into(),
                (r.kept as f64).into(),
                r.binning_s.into(),
                r.fill_s.into(),
                r.propagation_s.into(),
                r.march_s.into(),
                r.peak_bytes.map_or(Cell::Empty, |b| mib(b as f64).into()),
                mib(r.volume_bytes as f64).into(),
                mib(r.dense_bytes as f64).into(),
            ])?;
        }
        Ok(vec![a, s])
    }

    /// The images as one labelled grid.
    pub fn grid(&self) -> voxlod_eval::report::ImageGrid {
        use voxlod_eval::report::{ImageGrid, LabeledImage};
        let images =
            self.images.iter().map(|(l, i)| LabeledImage::new(l.clone(), i.to_srgb8())).collect();
        ImageGrid::new(self.images.len() as u32, images)
    }
}

impl VolumeResult {
    /// Appends the preset's section (heading, tables, images) to `report`.
    pub fn add_to_report(&self, report: &mut voxlod_eval::report::Report) -> Result<(), Error> {
        let result = self;
        report.heading(2, format!("Procedural volume: {}", result.preset));
        report.text(
            "Metavoxel pipeline (McNabb 2015, GPU Pro 6): binning, culling, fill, light \
             propagation, eye march in the over/under sort order, composited over the mesh render \
             (its depth stops the rays, its BVH shadows the volume, and the volume shadows it: the \
             mesh is rendered again with Volume::transmittance_to_light filtering each shading \
             point's direct light). Errors are of the composited 8-bit sRGB image against the \
             exact reference. Every image uses the same mesh rays (one seed) and the marches are \
             deterministic, so these errors carry no sampling noise: they are the models' own \
             differences from the exact march for this configuration. Times are wall-clock on \
             this machine, all cores.",
        );
        report.text(format!(
            "Volume built and marched on {}{}.",
            result.backend,
            if result.backend.starts_with("gpu") {
                " (the mesh's ground truth on the CPU; volume bytes are device bytes, peak MiB the \
             host heap)"
            } else {
                ""
            }
        ));
        report.text(format!(
        "Mesh ground truth ({}×{}, {} rays per pixel): {:.3} s without the volume's shadow; the \
         'shadowed mesh s' column is the same render with it, per model.",
        result.image, result.image, result.mesh_spp, result.mesh_s
    ));
        for t in result.tables()? {
            report.table(t);
        }
        report.images(
            format!("volume-{}", result.preset),
            "mesh alone, then the volume (and its shadow on the mesh) composited with the \
         reference, 1/(1+d) and exp(-d)",
            result.grid(),
        );
        Ok(())
    }
}
