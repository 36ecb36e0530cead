//! Where a study runs the work that has a GPU kernel ([`Backend`]), and the kernels of the
//! filtered-appearance studies on the GPU backend (`voxlod compare --backend gpu`): every
//! image — the ground truth, the baseline, Averages, \[VJK21\], the virtual-mesh rows (Lines,
//! Circles, Lines × area) and the Adaptive rows — is rendered by voxlod-gpu's kernels on one
//! adapter.
//! Every row says which backend rendered it, and which precomputed its records: Averages is
//! precomputed on the adapter too (`voxlod_gpu::precompute`, for every scene: textured,
//! alpha-masked and alpha-blended materials included), the other representations on the CPU.
//! Nothing falls back: a scene the GPU kernels cannot serve (textures over the device's
//! limits, say) is an error naming the scene.

use glam::{DVec3, UVec3, Vec3};
use voxlod_format::{BrickMap, GridSpec};
use voxlod_gpu::Context;
use voxlod_gpu::filtered::FilteredKernel;
use voxlod_gpu::ground_truth::{GpuScene, GroundTruthKernel};

use crate::Error;

/// Where a study runs the work that has a GPU kernel (each study says which work that is).
#[derive(Clone, Copy, Debug, Default)]
pub enum Backend<'a> {
    /// Everything on the CPU reference (the default).
    #[default]
    Cpu,
    /// The work with a GPU kernel on this adapter; everything else on the CPU.
    Gpu(&'a Context),
}

impl Backend<'_> {
    /// `cpu (rayon)` or `gpu: <adapter summary>` (the summary says when the adapter is a CPU
    /// implementation, whose timings are CPU timings).
    pub fn describe(&self) -> String {
        match self {
            Backend::Cpu => "cpu (rayon)".into(),
            Backend::Gpu(ctx) => format!("gpu: {}", ctx.summary()),
        }
    }
}

/// The adapter's name for table cells: its name without the driver's parenthesized details
/// (`llvmpipe`, not `llvmpipe (LLVM 15.0.7, 256 bits)`).
pub fn short_name(ctx: &Context) -> String {
    let name = &ctx.info().name;
    name.split(" (").next().unwrap_or(name).trim().to_string()
}

/// The GPU kernels, compiled once per run.
pub(crate) struct Kernels<'c> {
    /// Short adapter name (the rows' `backend`).
    pub name: String,
    /// Adapter summary for the report (index, name, backend, type; says when it is a CPU
    /// implementation).
    pub summary: String,
    /// Whether the adapter is a CPU implementation (its timings are CPU timings).
    pub is_cpu: bool,
    pub ground_truth: GroundTruthKernel<'c>,
    pub filtered: FilteredKernel<'c>,
    pub precompute: voxlod_gpu::precompute::Precomputer<'c>,
}

impl<'c> Kernels<'c> {
    /// Compiles the kernels for `ctx`.
    pub fn new(ctx: &'c Context) -> Result<Self, Error> {
        Ok(Self {
            name: short_name(ctx),
            summary: ctx.summary().to_string(),
            is_cpu: ctx.is_cpu(),
            ground_truth: GroundTruthKernel::new(ctx)?,
            filtered: FilteredKernel::new(ctx)?,
            precompute: voxlod_gpu::precompute::Precomputer::new(ctx)?,
        })
    }

    /// Uploads one scene for the ground-truth kernel; a scene it refuses is an error naming
    /// the scene.
    pub fn upload_scene(
        &'c self,
        scene: &voxlod_scene::Scene,
        geometry: &voxlod_scene::Geometry,
        bvh: &voxlod_cpu::raycast::Bvh,
        spec: &str,
    ) -> Result<SceneGpu<'c>, Error> {
        let uploaded = self
            .ground_truth
            .upload(scene, geometry, bvh)
            .map_err(|source| Error::GpuScene { scene: spec.to_string(), source })?;
        self.warm_up(&uploaded, scene)?;
        Ok(SceneGpu { kernels: self, scene: uploaded })
    }

    /// One 1×1 frame of each kernel, untimed: a driver may compile a pipeline on its first
    /// dispatch (lavapipe takes seconds), which is not the cost of a frame.
    fn warm_up(&self, uploaded: &GpuScene, scene: &voxlod_scene::Scene) -> Result<(), Error> {
        use voxlod_cpu::render::{baseline, ground_truth};
        let camera = voxlod_scene::Camera::look_at(Vec3::ZERO, Vec3::Z, Vec3::Y, 40.0);
        let options = ground_truth::Options { width: 1, height: 1, spp: 1, ..Default::default() };
        drop(self.ground_truth.render(uploaded, &camera, &options)?);
        let grid = GridSpec::new(DVec3::ONE, 1.0, UVec3::ONE)?;
        let empty = self.filtered.upload_baseline(&grid, &BrickMap::new(UVec3::ONE))?;
        let options = baseline::Options { width: 1, height: 1, ..Default::default() };
        let light = scene.light();
        drop(self.filtered.render_baseline(&empty, &camera, &light, Vec3::ZERO, &options)?);
        // The precompute on the scene in one voxel, one line.
        let geometry = scene.geometry();
        let (lo, hi) = scene.bounds()?;
        let grid = GridSpec::fit(lo.as_dvec3(), hi.as_dvec3(), 1)?;
        let vox = voxlod_cpu::voxelize::voxelize(&geometry, &grid, &Default::default())?;
        let opts = voxlod_cpu::appearance::precompute::PrecomputeOptions { rays: 1, seed: 0 };
        self.precompute.run(scene, &geometry, &vox, &opts, Default::default())?;
        Ok(())
    }
}

/// One scene uploaded for the ground-truth kernel, with the run's kernels.
pub(crate) struct SceneGpu<'c> {
    pub kernels: &'c Kernels<'c>,
    pub scene: GpuScene,
}

impl SceneGpu<'_> {
    /// The ground truth of the uploaded scene from `camera` (what the CPU reference returns,
    /// within the equivalence suite's bound).
    pub fn ground_truth(
        &self,
        camera: &voxlod_scene::Camera,
        options: &voxlod_cpu::render::ground_truth::Options,
    ) -> Result<voxlod_cpu::render::ground_truth::GroundTruth, Error> {
        Ok(self.kernels.ground_truth.render(&self.scene, camera, options)?)
    }
}
