//! Command-line definitions (clap) of the `voxlod` tool.

pub mod parse;

use std::path::PathBuf;

use clap::{Args, Parser, Subcommand, ValueEnum};

/// voxlod: voxelize triangle scenes, render them as voxels and as meshes, and measure the
/// difference. With no command, runs the default experiment and writes out/report.md.
#[derive(Debug, Parser)]
#[command(name = "voxlod", version, about, long_about = None)]
pub struct Cli {
    /// Worker threads (default: all cores).
    #[arg(long, global = true)]
    pub threads: Option<usize>,
    /// No progress bars.
    #[arg(long, short, global = true)]
    pub quiet: bool,
    /// What to do (default: `report`).
    #[command(subcommand)]
    pub command: Option<Command>,
}

/// Subcommands.
#[derive(Debug, Subcommand)]
pub enum Command {
    /// Run the default experiment on the embedded scenes and write a report (the default).
    Report(ReportArgs),
    /// Voxelize a scene into a .vxl or .binvox file.
    Voxelize(VoxelizeArgs),
    /// Export a scene (voxelized and filtered with the Averages fit), a .vxl file or a
    /// procedural volume's density to MagicaVoxel .vox, Mitsuba 3 .vol or NanoVDB .nvdb.
    Export(ExportArgs),
    /// Render the ground truth of a scene (mesh ray casting) to a PNG.
    Render(RenderArgs),
    /// Compare two images: MSE, PSNR, SSIM on 8-bit sRGB.
    CompareImages(CompareArgs),
    /// Measure every filtered-appearance representation of a scene against its ground truth:
    /// error, memory, precompute and render time, as tables, plots and an image grid
    /// (`--setup paper`: under the HPG 2023 paper's conditions, with paired intervals).
    Compare(CompareSceneArgs),
    /// Ablate the paper setup of the filtered-appearance comparison: one deviation at a time,
    /// each method's change with a paired bootstrap interval, and which method renders best.
    Ablation(AblationArgs),
    /// Voxel cone tracing on a sparse voxel octree: AO and one-bounce indirect light against
    /// ray-traced references, over cone count × aperture × octree depth × step, and light leaking.
    Cone(ConeArgs),
    /// Dynamic scenes by voxel transformation: an animated scene's moving objects voxelized
    /// once and moved every frame (nearest, 8-neighbour; rigid, skinned), against
    /// re-voxelizing them — agreement, exact rotations, flicker, time per frame against object
    /// count — and a frame sequence through the whole pipeline on either backend.
    Dynamic(DynamicArgs),
    /// Heitz–Neyret surface statistics with coverage masks against alpha blending over
    /// distance: error against the mesh, silhouettes, colour at grazing angles, cost, bytes per
    /// node.
    HeitzNeyret(HeitzNeyretArgs),
    /// Describe a file: .vxl, .binvox, .obj, .gltf, .glb or an image.
    Info(InfoArgs),
    /// Import voxels from MagicaVoxel .vox (occupancy and palette colours; rotated and
    /// translated models placed) or Mitsuba 3 .vol (density → opacity, albedo) into a .vxl of
    /// Averages records.
    Import(ImportArgs),
    /// Render a procedural volume preset (smoke, explosion, clouds) over a small mesh scene
    /// with metavoxels, and measure its trade: attenuation models against the exact reference,
    /// time and memory per metavoxel size.
    Volume(VolumeArgs),
    /// Slicemaps (bitmask voxelization by rasterization, Eisemann and Décoret 2006) of a scene:
    /// holes against the exact voxelizers, transmittance shadow maps against ray-traced
    /// transmittance, the traversed volume for refraction against ray-cast intervals; images
    /// and error tables.
    Slicemap(SlicemapArgs),
    /// List the builtin scenes and their parameters.
    Scenes,
}

/// `voxlod report`.
#[derive(Debug, Args)]
pub struct ReportArgs {
    /// Paper-scale settings: 128³ and 256³, 1024 rays per pixel (takes much longer).
    #[arg(long)]
    pub full: bool,
    /// Output directory (keep in sync with `Default`).
    #[arg(short, long, default_value = "out")]
    pub output: PathBuf,
    /// Print the summary as JSON instead of tables.
    #[arg(long)]
    pub json: bool,
    /// Where the images with a GPU kernel are rendered (gpu: the ground truth and every
    /// representation's rows; each row says which backend rendered it).
    #[arg(long, value_enum, default_value_t = BackendArg::Cpu)]
    pub backend: BackendArg,
    /// Add a turntable of N frames (1..=3600) to each scene section: the ground truth beside
    /// the voxel baseline and Averages from an orbiting camera, as an animated PNG (off by
    /// default: it costs more than a tenth of the default run).
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u16).range(1..=3600))]
    pub turntable: Option<u16>,
}

impl Default for ReportArgs {
    /// What `voxlod` with no command runs: the same defaults as `voxlod report`.
    fn default() -> Self {
        Self {
            full: false,
            output: PathBuf::from("out"),
            json: false,
            backend: BackendArg::Cpu,
            turntable: None,
        }
    }
}

/// Where a command's kernel runs.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum BackendArg {
    /// The CPU reference (rayon).
    Cpu,
    /// The wgpu backend on the adapter `VOXLOD_ADAPTER` selects (default: a discrete GPU
    /// first); no adapter is an error, never a silent fall-back to the CPU.
    Gpu,
}

/// Voxelization mode.
#[derive(Debug, Clone, Copy, ValueEnum)]
pub enum ModeArg {
    /// Every voxel a triangle touches.
    Conservative,
    /// 6-separating thin surface.
    Thin,
    /// Interior of a closed mesh.
    Solid,
}

/// `voxlod voxelize`.
#[derive(Debug, Args)]
pub struct VoxelizeArgs {
    /// A scene file (.obj, .gltf, .glb) or `builtin:NAME[?key=value&...]`.
    pub scene: String,
    /// Voxels along the longest axis of the scene's bounds.
    #[arg(long, default_value_t = 128)]
    pub res: u32,
    /// Which voxels to set.
    #[arg(long, value_enum, default_value_t = ModeArg::Conservative)]
    pub mode: ModeArg,
    /// Where to voxelize (gpu: conservative and thin modes; the same voxels as the CPU).
    #[arg(long, value_enum, default_value_t = BackendArg::Cpu)]
    pub backend: BackendArg,
    /// Output file: .vxl (voxlod container) or .binvox.
    #[arg(short, long)]
    pub output: PathBuf,
    /// Print a JSON summary.
    #[arg(long)]
    pub json: bool,
}

/// `voxlod export`.
#[derive(Debug, Args)]
pub struct ExportArgs {
    /// A scene file (.obj, .gltf, .glb) or `builtin:NAME[?key=value&...]`, voxelized and
    /// filtered on the way; a .vxl file of Averages or occupancy records; or `volume:PRESET`
    /// (smoke, explosion, clouds), the density of a procedural volume's particles sampled on
    /// a world-aligned cube of --res³ voxels (.vol and .nvdb only).
    pub input: String,
    /// Output file: .vox (MagicaVoxel: occupancy and a 255-colour palette), .vol (Mitsuba 3:
    /// density, with the albedo beside it as NAME.albedo.vol) or .nvdb (NanoVDB: a `density`
    /// float fog volume and a `color` Vec3f grid in one file).
    #[arg(short, long, value_parser = parse::export_output)]
    pub output: ExportOutput,
    /// Voxels along the longest axis of the scene's bounds (scene inputs), or along each axis
    /// of the volume's cube (volume inputs, at most 4096).
    #[arg(long, default_value_t = 128, value_parser = clap::value_parser!(u32).range(1..=2_097_152))]
    pub res: u32,
    /// Sampling lines per voxel of the Averages fit (scene inputs).
    #[arg(long, default_value_t = 64, value_parser = clap::value_parser!(u32).range(1..))]
    pub rays: u32,
    /// Print a JSON summary.
    #[arg(long)]
    pub json: bool,
}

/// An export's output file and the format its extension names.
#[derive(Clone, Debug)]
pub struct ExportOutput {
    /// The file.
    pub path: PathBuf,
    /// Its format.
    pub format: ExportFormat,
}

/// The formats `voxlod export` writes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ExportFormat {
    /// MagicaVoxel `.vox`.
    Vox,
    /// Mitsuba 3 `.vol`.
    Vol,
    /// NanoVDB `.nvdb`.
    Nvdb,
}

/// `voxlod render`.
#[derive(Debug, Args)]
pub struct RenderArgs {
    /// A scene file (.obj, .gltf, .glb) or `builtin:NAME[?key=value&...]`.
    pub scene: String,
    /// Camera `eye=X,Y,Z;target=X,Y,Z[;up=X,Y,Z][;fov=DEG]` in world coordinates (default: the
    /// scene's own or one framing its bounds).
    #[arg(long)]
    pub camera: Option<String>,
    /// Light `dir=X,Y,Z[;irradiance=E]` (toward the light) or `point=X,Y,Z[;intensity=I]`
    /// (world coordinates, like the camera's).
    #[arg(long, value_parser = parse::light_arg)]
    pub light: Option<parse::LightSpec>,
    /// Rays per pixel.
    #[arg(long, default_value_t = 64, value_parser = clap::value_parser!(u32).range(1..))]
    pub spp: u32,
    /// Image size WIDTHxHEIGHT.
    #[arg(long, default_value = "512x512", value_parser = parse::size_arg)]
    pub size: (u32, u32),
    /// Seed of the pixel sampling pattern.
    #[arg(long, default_value_t = 0)]
    pub seed: u32,
    /// Output PNG.
    #[arg(short, long)]
    pub output: PathBuf,
    /// Also write the G-buffer (depth, normal, albedo PNGs) next to the output.
    #[arg(long)]
    pub gbuffer: bool,
    /// Where to render (gpu: every material — textured, alpha-masked, alpha-blended; equal to
    /// the CPU's image within the equivalence suite's bound).
    #[arg(long, value_enum, default_value_t = BackendArg::Cpu)]
    pub backend: BackendArg,
    /// Print a JSON summary.
    #[arg(long)]
    pub json: bool,
    /// Also render a turntable of N frames (1..=3600): the camera orbiting the scene, each frame
    /// the ground truth beside the voxel baseline and Averages (panels of --size at --spp), as
    /// an animated PNG in a report written to `<output stem>-turntable/` next to the output.
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u16).range(1..=3600))]
    pub turntable: Option<u16>,
    /// Voxels along the longest axis of the turntable's voxel panels.
    #[arg(long, default_value_t = 64, value_parser = clap::value_parser!(u32).range(1..=4096))]
    pub turntable_res: u32,
    /// Sampling lines per voxel of the turntable's Averages records.
    #[arg(long, default_value_t = 64, value_parser = clap::value_parser!(u32).range(1..))]
    pub turntable_rays: u32,
    /// How long each turntable frame shows, in milliseconds.
    #[arg(long, default_value_t = 100, value_parser = clap::value_parser!(u16).range(1..))]
    pub turntable_ms: u16,
}

/// `voxlod compare`.
#[derive(Debug, Args)]
pub struct CompareSceneArgs {
    /// A scene file (.obj, .gltf, .glb) or `builtin:NAME[?key=value&...]`; with `--setup
    /// paper` also a paper scene's name (`voxlod compare --setup paper --help` lists them) or
    /// `paper` for all of them.
    pub scene: String,
    /// The conditions: voxlod's default comparison, or the HPG 2023 paper's (white background,
    /// sun and point light, image side = resolution, 1024 rays per pixel, paired intervals over
    /// views × seeds).
    #[arg(long, value_enum, default_value_t = SetupArg::Default)]
    pub setup: SetupArg,
    /// Voxel resolutions (voxels along the longest axis, 1..=4096), comma-separated.
    #[arg(long, default_value = "128,256", value_delimiter = ',', num_args = 1..,
          value_parser = clap::value_parser!(u32).range(1..=4096))]
    pub res: Vec<u32>,
    /// The higher image side rendered besides the one equal to each resolution (0: none; the
    /// default setup only).
    #[arg(long, default_value_t = 512, value_parser = clap::value_parser!(u32).range(0..=8192))]
    pub image: u32,
    /// Rays per pixel of the ground truth (default: 256, 1024 with `--setup paper`).
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..))]
    pub spp: Option<u32>,
    /// Viewpoints (the scene's camera orbited about the vertical axis).
    #[arg(long, default_value_t = 4, value_parser = parse::at_least_one)]
    pub views: usize,
    /// Sampling rays per voxel.
    #[arg(long, default_value_t = 150, value_parser = clap::value_parser!(u32).range(1..))]
    pub rays: u32,
    /// Adaptive thresholds (finite, ≥ 0), comma-separated.
    #[arg(long, default_value = "0.1,0.2,0.3", value_delimiter = ',',
          value_parser = parse::non_negative_f32)]
    pub thresholds: Vec<f32>,
    /// With `--setup paper`: Adaptive thresholds of the image-error selector, comma-separated.
    #[arg(long, default_value = "0.01,0.02", value_delimiter = ',',
          value_parser = parse::non_negative_f32)]
    pub image_thresholds: Vec<f32>,
    #[command(flatten)]
    pub paper: PaperArgs,
    /// With `--setup paper`: also the rays-per-voxel sweep (`--sweep-rays`), the 2×2-downsample
    /// experiment and the single-threaded precompute beside the paper's Table 2.
    #[arg(long)]
    pub extras: bool,
    /// Rays per voxel of the `--extras` sweep, comma-separated.
    #[arg(long, default_value = "50,150,500", value_delimiter = ',',
          value_parser = clap::value_parser!(u32).range(1..))]
    pub sweep_rays: Vec<u32>,
    /// Where to render the images that have a GPU kernel (gpu: the ground truth — every
    /// material, textures and alpha included —, the baseline, Averages and [VJK21], the virtual
    /// mesh and Adaptive). Every row says which backend rendered it. The paper setup runs on
    /// the CPU.
    #[arg(long, value_enum, default_value_t = BackendArg::Cpu)]
    pub backend: BackendArg,
    /// Output directory.
    #[arg(short, long, default_value = "out/compare")]
    pub output: PathBuf,
    /// Print the rows as JSON instead of tables.
    #[arg(long)]
    pub json: bool,
}

/// The conditions of `voxlod compare`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum SetupArg {
    /// voxlod's comparison: the scene's light and background, a second image side.
    Default,
    /// The HPG 2023 paper's conditions.
    Paper,
}

/// Options of the paper setup (`voxlod compare --setup paper`, `voxlod ablation`).
#[derive(Debug, Args)]
pub struct PaperArgs {
    /// Seeds of the precompute's sampling lines (paired samples = views × seeds).
    #[arg(long, default_value_t = 2, value_parser = clap::value_parser!(u32).range(1..=16))]
    pub seeds: u32,
    /// The coarse-mesh counterpart of a scene given as a spec (paper scenes have their own).
    #[arg(long)]
    pub coarse: Option<String>,
    /// Directory of cached ground truths (default: $XDG_CACHE_HOME/voxlod/ground-truth, else
    /// ~/.cache/voxlod/ground-truth).
    #[arg(long, conflicts_with = "no_cache")]
    pub cache: Option<PathBuf>,
    /// Render every ground truth, read and write no cache.
    #[arg(long)]
    pub no_cache: bool,
}

/// `voxlod ablation`.
#[derive(Debug, Args)]
pub struct AblationArgs {
    /// A paper scene's name, `paper` for all of them, or a scene spec.
    pub scene: String,
    /// Voxel resolutions (= image sides), comma-separated.
    #[arg(long, default_value = "128", value_delimiter = ',', num_args = 1..,
          value_parser = clap::value_parser!(u32).range(11..=1024))]
    pub res: Vec<u32>,
    /// The deviations to run (default: all), comma-separated.
    #[arg(long, value_enum, value_delimiter = ',', num_args = 1..)]
    pub toggles: Vec<ToggleArg>,
    /// Rays per pixel of the ground truth.
    #[arg(long, default_value_t = 1024, value_parser = clap::value_parser!(u32).range(1..))]
    pub spp: u32,
    /// Viewpoints.
    #[arg(long, default_value_t = 4, value_parser = parse::at_least_one)]
    pub views: usize,
    /// Sampling rays per voxel.
    #[arg(long, default_value_t = 150, value_parser = clap::value_parser!(u32).range(1..))]
    pub rays: u32,
    /// Adaptive thresholds (finite, ≥ 0), comma-separated.
    #[arg(long, default_value = "0.1", value_delimiter = ',',
          value_parser = parse::non_negative_f32)]
    pub thresholds: Vec<f32>,
    /// Adaptive thresholds of the image-error selector (finite, ≥ 0), comma-separated.
    #[arg(long, default_value = "0.01,0.02", value_delimiter = ',',
          value_parser = parse::non_negative_f32)]
    pub image_thresholds: Vec<f32>,
    #[command(flatten)]
    pub paper: PaperArgs,
    /// Output directory.
    #[arg(short, long, default_value = "out/ablation")]
    pub output: PathBuf,
    /// Print the result as JSON instead of tables.
    #[arg(long)]
    pub json: bool,
}

/// A deviation from the paper setup.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum ToggleArg {
    /// The scene's coarse mesh.
    CoarseMesh,
    /// The red background of the paper's Fig. 10.
    RedBackground,
    /// The scene's own background.
    SceneBackground,
    /// The sun alone.
    SunOnly,
    /// voxlod's line-sampled directional opacity.
    LinesOpacity,
    /// The paper text's normalized circles.
    CirclesOpacity,
    /// voxlod's 16 fixed samples per visible face.
    FixedFaceSamples,
    /// voxlod's stored-normals shading fallback.
    StoredNormalsFallback,
    /// voxlod's exact per-ray [VJK21] chord.
    PerRayChord,
    /// voxlod's Averages normal flipped toward the viewer.
    FlippedAveragesNormal,
    /// voxlod's fixed pixel pattern.
    FixedPixelPattern,
    /// All of voxlod's choices at once.
    AllOurs,
    /// Scores on images cropped to the ground truth's coverage.
    Crop,
}

/// `voxlod cone`.
#[derive(Debug, Args)]
pub struct ConeArgs {
    /// A scene file (.obj, .gltf, .glb) or `builtin:NAME[?key=value&...]`.
    pub scene: String,
    /// Voxel resolutions (voxels along the longest axis, powers of two in 4..=1024; octree
    /// depth = log2), comma-separated.
    #[arg(long, default_value = "32,64", value_delimiter = ',', value_parser = parse::octree_resolution)]
    pub res: Vec<u32>,
    /// Diffuse cone counts (1..=1024), comma-separated.
    #[arg(long, default_value = "1,6,16", value_delimiter = ',',
          value_parser = clap::value_parser!(u32).range(1..=1024))]
    pub cones: Vec<u32>,
    /// Full cone apertures in degrees, in [0, 180), comma-separated.
    #[arg(long, default_value = "15,30,60", value_delimiter = ',',
          value_parser = parse::f32_in(0.0, 180.0, true))]
    pub apertures: Vec<f32>,
    /// Step lengths as fractions of the cone diameter, in [0.05, 4], comma-separated.
    #[arg(long, default_value = "0.5,1", value_delimiter = ',',
          value_parser = parse::f32_in(0.05, 4.0, false))]
    pub steps: Vec<f32>,
    /// Image side in pixels (1..=2048).
    #[arg(long, default_value_t = 64, value_parser = clap::value_parser!(u32).range(1..=2048))]
    pub size: u32,
    /// Where the cones of the sweep are traced: cpu (rayon, the reference) or gpu (the wgpu
    /// kernel, on the adapter `VOXLOD_ADAPTER` selects; no adapter is an error). The G-buffer,
    /// references, octrees, leak experiment and LOD section stay on the CPU.
    #[arg(long, value_enum, default_value_t = BackendArg::Cpu)]
    pub backend: BackendArg,
    /// Rays per pixel of the ray-traced references.
    #[arg(long, default_value_t = 256, value_parser = clap::value_parser!(u32).range(1..))]
    pub spp: u32,
    /// AO radius as a fraction of the scene's bounding-box diagonal (finite, > 0).
    #[arg(long, default_value_t = 0.1, value_parser = parse::positive_f32)]
    pub ao_radius: f32,
    /// Primary visibility with level of detail by distance: the scene rendered by one
    /// pixel-wide cone per pixel through its Averages octree ("none" skips it).
    #[arg(long, default_value = "builtin:forest")]
    pub lod_scene: String,
    /// Voxels along the longest axis of the LOD scene's octree (a power of two, 4..=1024).
    #[arg(long, default_value_t = 256, value_parser = parse::octree_resolution)]
    pub lod_res: u32,
    /// Image side of the LOD renders, pixels (1..=2048).
    #[arg(long, default_value_t = 128, value_parser = clap::value_parser!(u32).range(1..=2048))]
    pub lod_size: u32,
    /// LOD biases (footprint multipliers in [0, 64]; 0 = always the finest level, the
    /// reference march), comma-separated.
    #[arg(long, default_value = "0,0.5,1,2,4", value_delimiter = ',',
          value_parser = parse::f32_in(0.0, 64.0, false))]
    pub lod_bias: Vec<f32>,
    /// Step of the LOD march as a fraction of the footprint diameter, in [0.05, 4].
    #[arg(long, default_value_t = 0.5, value_parser = parse::f32_in(0.05, 4.0, false))]
    pub lod_step: f32,
    /// Moves the LOD scene's default camera away from its target by this factor (> 0).
    #[arg(long, default_value_t = 1.0, value_parser = parse::positive_f32)]
    pub lod_zoom_out: f32,
    /// Rays per pixel of the LOD scene's ground-truth mesh render.
    #[arg(long, default_value_t = 64, value_parser = clap::value_parser!(u32).range(1..))]
    pub lod_spp: u32,
    /// Output directory.
    #[arg(short, long, default_value = "out/cone")]
    pub output: PathBuf,
    /// Print the rows as JSON instead of tables.
    #[arg(long)]
    pub json: bool,
}

/// `voxlod dynamic`.
#[derive(Debug, Args)]
pub struct DynamicArgs {
    /// An animated scene: a .gltf/.glb file with an animation, or `builtin:crowd[?...]`.
    #[arg(default_value = "builtin:crowd?walkers=4&rigid=4")]
    pub scene: String,
    /// The study's larger settings: six times, thresholds ¼ and ½, 256-ray references,
    /// scaling up to 256 walkers (takes much longer).
    #[arg(long)]
    pub full: bool,
    /// World voxel edge in world units (> 0; the crowd's walkers are 1.85 tall).
    #[arg(long, default_value_t = 0.05, value_parser = parse::positive_f32)]
    pub voxel: f32,
    /// Animation times to measure, seconds, comma-separated (default: the preset's).
    #[arg(long, value_delimiter = ',', value_parser = parse::non_negative_f32)]
    pub times: Vec<f32>,
    /// Walker counts of the scaling part (1..=256), comma-separated; "0" skips it.
    #[arg(long, value_delimiter = ',', value_parser = clap::value_parser!(u32).range(0..=256))]
    pub walkers: Vec<u32>,
    /// Frames of the sequence rendered through the pipeline (0..=256).
    #[arg(long, value_parser = clap::value_parser!(u32).range(0..=256))]
    pub frames: Option<u32>,
    /// Image width in pixels (8..=1024; height ¾ of it).
    #[arg(long, value_parser = clap::value_parser!(u32).range(8..=1024))]
    pub width: Option<u32>,
    /// Rays per pixel of the ray-traced references.
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..))]
    pub spp: Option<u32>,
    /// Skip the rotations and the stability parts.
    #[arg(long)]
    pub no_extras: bool,
    /// Where the frame sequence (and the scaling part's GPU column) runs: cpu (the reference)
    /// or gpu (the whole frame on the device, on the adapter `VOXLOD_ADAPTER` selects; no
    /// adapter is an error).
    #[arg(long, value_enum, default_value_t = BackendArg::Cpu)]
    pub backend: BackendArg,
    /// Output directory.
    #[arg(short, long, default_value = "out/dynamic")]
    pub output: PathBuf,
    /// Print the rows as JSON instead of tables.
    #[arg(long)]
    pub json: bool,
}

/// `voxlod heitz-neyret`.
#[derive(Debug, Args)]
pub struct HeitzNeyretArgs {
    /// The report's settings (256³, 256² pixels, zooms 1–16, 256 rays per pixel, 150 lines per
    /// voxel, 3 timed runs); without it the quick preset (128³, 128², zooms 1, 2, 4, 8, 64 rays
    /// per pixel, 64 lines per voxel, 3 timed runs).
    #[arg(long)]
    pub full: bool,
    /// Scene specs (default: the preset's bumpy sphere, bumpy specular sphere, bunny and
    /// forest). A `builtin:bumpy-*` scene gets the grazing-colour measure (its macro-surface is
    /// a sphere); `builtin:forest`, `island` and `blinds` are marked outside the model's domain.
    pub scenes: Vec<String>,
    /// Voxels along the longest axis (a power of two in 8..=1024); default: the preset's.
    #[arg(long, value_parser = parse::octree_resolution)]
    pub res: Option<u32>,
    /// Image side in pixels (8..=2048); default: the preset's.
    #[arg(long, value_parser = clap::value_parser!(u32).range(8..=2048))]
    pub size: Option<u32>,
    /// Camera distance factors from the default framing (≥ 0.5), comma-separated.
    #[arg(long, value_delimiter = ',', value_parser = parse::f32_in(0.5, 1e6, false))]
    pub zooms: Vec<f32>,
    /// Rays per pixel of the ground truth; default: the preset's.
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..))]
    pub spp: Option<u32>,
    /// Sampling lines per voxel for the records (1..=4096); default: the preset's.
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=4096))]
    pub rays: Option<u32>,
    /// Timed renders per method and zoom (1..=16); default: the preset's.
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=16))]
    pub repeats: Option<u32>,
    /// Skip the depth-of-field measure.
    #[arg(long)]
    pub no_dof: bool,
    /// Where the coverage-mask renders also run (gpu: voxlod-gpu's differential kernel, timed
    /// and compared with the CPU image; every other render stays on the CPU).
    #[arg(long, value_enum, default_value_t = BackendArg::Cpu)]
    pub backend: BackendArg,
    /// Output directory.
    #[arg(short, long, default_value = "out/heitz-neyret")]
    pub output: PathBuf,
    /// Print the result as JSON instead of tables.
    #[arg(long)]
    pub json: bool,
}

/// `voxlod volume`.
#[derive(Debug, Args)]
pub struct VolumeArgs {
    /// Preset: smoke, explosion or clouds.
    #[arg(value_parser = clap::builder::PossibleValuesParser::new(voxlod::studies::volume::PRESETS))]
    pub preset: String,
    /// Particles (0: the preset's default: smoke 10000, explosion 4000, clouds 3000).
    #[arg(long, default_value_t = 0)]
    pub particles: usize,
    /// Voxels per axis of the volume; every metavoxel size must divide it.
    #[arg(long, default_value_t = 128)]
    pub res: u32,
    /// Metavoxel sizes M measured (≥ 1), comma-separated.
    #[arg(long, default_value = "8,16,32,64", value_delimiter = ',',
          value_parser = clap::value_parser!(u32).range(1..))]
    pub m: Vec<u32>,
    /// Image side in pixels (1..=4096).
    #[arg(long, default_value_t = 256, value_parser = clap::value_parser!(u32).range(1..=4096))]
    pub image: u32,
    /// Rays per pixel of the mesh's ground truth.
    #[arg(long, default_value_t = 16, value_parser = clap::value_parser!(u32).range(1..))]
    pub spp: u32,
    /// Where to build and march the volume (gpu: the four voxlod-gpu volume kernels, equal to
    /// the CPU within the equivalence suite's bounds; the mesh's ground truth stays on the
    /// CPU).
    #[arg(long, value_enum, default_value_t = BackendArg::Cpu)]
    pub backend: BackendArg,
    /// Output directory.
    #[arg(short, long, default_value = "out/volume")]
    pub output: PathBuf,
    /// Print the rows as JSON instead of tables.
    #[arg(long)]
    pub json: bool,
}

/// `voxlod slicemap`.
#[derive(Debug, Args)]
pub struct SlicemapArgs {
    /// Scene for every part: an .obj/.gltf/.glb file or builtin:NAME[?KEY=VALUE&...]
    /// (`voxlod scenes`). Without it, the preset's scenes: holes on the bunny and a forest
    /// (with `--full`, also the engine), shadows on the forest's leaves, refraction through the
    /// closed bunny.
    pub scene: Option<String>,
    /// Paper-scale settings: 512² maps, up to 512 slices, larger images, three timed runs.
    #[arg(long)]
    pub full: bool,
    /// Parts to run, comma-separated.
    #[arg(long, default_value = "holes,shadows,refraction", value_delimiter = ',',
          value_parser = clap::builder::PossibleValuesParser::new(["holes", "shadows", "refraction"]))]
    pub parts: Vec<String>,
    /// Slice counts (1..=512) of the perspective maps and of the refraction's front/back maps,
    /// comma-separated (default: the preset's).
    #[arg(long, value_delimiter = ',', value_parser = clap::value_parser!(u32).range(1..=512))]
    pub slices: Vec<u32>,
    /// Width in pixels of the shadow and refraction images (1..=4096; default: the preset's).
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=4096))]
    pub image: Option<u32>,
    /// Voxels along the longest side of the grid the aligned maps are compared in (1..=512;
    /// default: the preset's).
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=512))]
    pub res: Option<u32>,
    /// Columns per side of the perspective maps and of the light's maps (1..=4096; default:
    /// the preset's). With it, the shadow maps are measured at this size for every slice
    /// count of `--slices` (or 32, 96, 512).
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=4096))]
    pub map_size: Option<u32>,
    /// Substring of the names of semi-transparent materials for the shadow maps (when none
    /// matches, every triangle is a semi-transparent layer).
    #[arg(long, default_value = "leaves")]
    pub transmissive: String,
    /// Attenuation σ of one semi-transparent layer, in [0, 1].
    #[arg(long, default_value_t = 0.3, value_parser = parse::f32_in(0.0, 1.0, false))]
    pub sigma: f32,
    /// Where the slicemaps are also built, for their time (gpu: voxlod-gpu's render pipeline;
    /// every measured number comes from the CPU reference, which the equivalence suite shows
    /// equal).
    #[arg(long, value_enum, default_value_t = BackendArg::Cpu)]
    pub backend: BackendArg,
    /// Output directory.
    #[arg(short, long, default_value = "out/slicemap")]
    pub output: PathBuf,
    /// Print the rows as JSON instead of tables.
    #[arg(long)]
    pub json: bool,
}

/// `voxlod compare-images`.
#[derive(Debug, Args)]
pub struct CompareArgs {
    /// Reference image.
    pub a: PathBuf,
    /// Test image.
    pub b: PathBuf,
    /// Print JSON.
    #[arg(long)]
    pub json: bool,
}

/// `voxlod info`.
#[derive(Debug, Args)]
pub struct InfoArgs {
    /// The file.
    pub file: PathBuf,
    /// Print JSON.
    #[arg(long)]
    pub json: bool,
}

/// `voxlod import`.
#[derive(Debug, Args)]
pub struct ImportArgs {
    /// A MagicaVoxel .vox file or a Mitsuba 3 .vol density grid (one channel, extinction per
    /// world unit).
    #[arg(value_parser = parse::import_input)]
    pub input: ImportInput,
    /// Output .vxl file (Averages records: colour, opacity; or, with --f32, linear RGB and
    /// opacity as four f32).
    #[arg(short, long, value_parser = parse::vxl_output)]
    pub output: PathBuf,
    /// Edge of a voxel in world units (.vox only: the file stores whole voxels; a .vol's box
    /// and cell count set it).
    #[arg(long, value_parser = parse::positive_f64)]
    pub voxel_size: Option<f64>,
    /// The albedo grid of a .vol (three channels, same cells and box; default: NAME.albedo.vol
    /// beside NAME.vol if it exists, else grey).
    #[arg(long)]
    pub albedo: Option<PathBuf>,
    /// .vol only: store linear RGB and opacity as four f32 per voxel (record `4f32`) instead of
    /// quantized Averages records.
    #[arg(long)]
    pub f32: bool,
    /// Print a JSON summary.
    #[arg(long)]
    pub json: bool,
}

/// An import's input file and the format its extension names.
#[derive(Clone, Debug)]
pub struct ImportInput {
    /// The file.
    pub path: PathBuf,
    /// Its format.
    pub format: ImportFormat,
}

/// The formats `voxlod import` reads.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ImportFormat {
    /// MagicaVoxel `.vox`.
    Vox,
    /// Mitsuba 3 `.vol`.
    Vol,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn no_command_means_report_with_the_report_defaults() {
        let explicit = Cli::parse_from(["voxlod", "report"]);
        let Some(Command::Report(args)) = explicit.command else { panic!("parsed a report") };
        let default = ReportArgs::default();
        assert_eq!(
            (args.full, &args.output, args.json),
            (default.full, &default.output, default.json)
        );
        assert!(Cli::parse_from(["voxlod"]).command.is_none());
    }
}
