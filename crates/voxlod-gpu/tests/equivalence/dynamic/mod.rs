//! Dynamic scenes by voxel transformation (`voxlod_gpu::dynamic`) against voxlod-octree's
//! `dynamic` module and voxlod-cone's `inject` / `ConeTracer`, on a small `builtin:crowd`
//! (two skinned walkers, a torus and a cube, the floor's static voxels) and a cube turned by
//! exactly 45° about each axis, under both filters.
//!
//! - **Transform**: every moved voxel (cell, fractions, normal, status) against the CPU's.
//!   Voxels whose cell or fraction differ must differ by one step and lie within
//!   [`BOUNDARY`] voxel of the boundary they crossed (the CPU's `f32` position against the
//!   integer, or the sixty-fourth, it is rounded to): fused multiply-adds and WGSL's division
//!   move positions by a few ULP of the object's extent. At most [`FRACTION_AT_BOUNDARY`] of
//!   the voxels may; a normal component may differ by one unit of snorm12. The CPU row checks
//!   the CPU transform against an `f64` oracle the same way. Control (must FAIL): the CPU's
//!   voxels with every object moved by 0.01 voxel.
//! - **Blend**: the CPU's moved voxels blended on the GPU give the CPU's world voxels and
//!   sums **exactly** (error: differing voxels or words), payloads within [`PAYLOAD`] (the GPU
//!   converts 64-bit sums to `f32` in `f32`, the CPU in `f64`). Control (must FAIL): one moved
//!   voxel's fraction changed by one sixty-fourth. The CPU row checks the CPU blend against a
//!   brute-force sum in 128-bit integers.
//! - **Rebuild**: the octree the GPU builds from its own leaves has the CPU's topology
//!   **exactly** (levels, nodes, tiles, neighbours); payloads within `PAYLOAD + 8·depth·2⁻²⁴`
//!   (depth 7 here). Control (must FAIL): the CPU octree with its first leaf dropped (its
//!   topology or its payloads must differ).
//! - **Inject**: radiance per leaf, relative error (absolute below 1) within [`BOUND`] for at
//!   least [`FRACTION`] of the leaves and within [`HARD`] for all — the shadow march is the
//!   cone kernel's, with its rounding (see the cone rows). Control (must FAIL): a CPU
//!   reference marched with a 5 % longer step.
//! - **Frame**: the whole frame on the device, then AO and `E/π` cone traced at the posed
//!   mesh's G-buffer points, against the CPU's [`FramePipeline`] and [`ConeTracer`]: the
//!   cone rows' bound (1e-3 for 99 % of the points, 0.05 for all).

use std::sync::OnceLock;

use glam::{DMat4, DQuat, DVec3, UVec3, Vec3};
use voxlod_cone::{
    ConeTracer, FramePipeline, Light, RadiancePayload, Shadows, TraceOptions, inject,
};
use voxlod_cpu::dynamic::{CacheOptions, DynamicScene, RecordSource, build_cache, static_voxels};
use voxlod_cpu::raycast::Bvh;
use voxlod_cpu::render::ground_truth;
use voxlod_format::records::AverageRecord;
use voxlod_format::{BrickMap, GridSpec, morton};
use voxlod_gpu::cone::{ConeQuery, ShadingPoint, reference};
use voxlod_gpu::dynamic::DynamicKernels;
use voxlod_octree::dynamic::{
    BlendInput, CellSums, DynamicWorld, Filter, FrameOptions, ObjectFrame, Placed, Placement,
    VoxelCache, blend, place, transform, unpack_position, voxel_matrix,
};
use voxlod_octree::{AveragePayload, FlatOctree, Octree, Payload};

use crate::harness::{Executor, Measure};

mod blended;
mod light;
mod rebuild;

pub use blended::blend_scenes;
pub use light::{frame_scenes, inject_scenes};
pub use rebuild::rebuild_scenes;

/// Largest distance (voxels) of a voxel whose cell or fraction differs from the boundary it
/// crossed.
pub const BOUNDARY: f64 = 1e-5;
/// Fraction of the voxels that may differ at a boundary.
pub const FRACTION_AT_BOUNDARY: f64 = 1e-3;
/// Payload components (magnitude ≤ 1) converted from exact sums.
pub const PAYLOAD: f64 = 1e-5;
/// Injected radiance and traced light: per-value bound for [`FRACTION`] of the values.
pub const BOUND: f64 = 1e-3;
/// Fraction that must be within [`BOUND`].
pub const FRACTION: f64 = 0.99;
/// Every value within this.
pub const HARD: f64 = 0.05;

/// One world with its objects and their placements for one frame.
struct Case {
    name: String,
    world: DynamicWorld,
    caches: Vec<VoxelCache>,
    placements: Vec<Placement>,
    /// The posed scene's G-buffer points for the frame row (crowd only), an image `width` wide.
    points: Vec<ShadingPoint>,
    width: u32,
    light: Light,
}

fn crowd() -> Case {
    let scene = voxlod_scene::procedural::from_spec("crowd?walkers=2&rigid=2&sides=8").unwrap();
    let ds = DynamicScene::new(scene, 0).unwrap();
    let (lo, hi) = ds.scene.bounds().unwrap();
    let grid = GridSpec::fit(
        lo.as_dvec3() - DVec3::new(0.5, 0.1, 0.5),
        hi.as_dvec3() + DVec3::new(0.5, 1.0, 0.5),
        96,
    )
    .unwrap();
    let options = CacheOptions { records: RecordSource::Pieces, ..Default::default() };
    let caches = (0..ds.objects.len())
        .map(|o| build_cache(&ds, o, grid.voxel_size, &options).unwrap())
        .collect();
    let world = DynamicWorld::new(grid, static_voxels(&ds, &grid, &options).unwrap()).unwrap();
    let pose = ds.pose(0.37).unwrap();
    let placements = ds.placements(&pose).unwrap();
    let posed = ds.posed_scene(&pose).unwrap();
    let g = posed.geometry();
    let bvh = Bvh::new(&g).unwrap();
    let camera = posed.default_camera().unwrap();
    let width = 48;
    let gb = ground_truth::gbuffer(&posed, &g, &bvh, &camera, width, 32).unwrap();
    let points = ShadingPoint::from_gbuffer(&gb, camera.eye, 0.5);
    let light = match posed.light() {
        voxlod_scene::Light::Directional { to_light, irradiance } => {
            Light::Directional { to_light, irradiance }
        }
        voxlod_scene::Light::Point { position, intensity } => Light::Point { position, intensity },
    };
    Case { name: "crowd 2+2, 96".into(), world, caches, placements, points, width, light }
}

/// A hollow 12³ cube of red voxels turned by exactly 45° about `axis` inside a 32³ world.
fn cube_45(axis: DVec3, name: &str) -> Case {
    let g = GridSpec::new(DVec3::ZERO, 1.0, UVec3::splat(12)).unwrap();
    let red = AverageRecord::new(Vec3::new(0.8, 0.2, 0.1), Vec3::Y, 1.0);
    let shell = (0..12u32)
        .flat_map(|x| (0..12u32).flat_map(move |y| (0..12u32).map(move |z| UVec3::new(x, y, z))))
        .filter(|c| c.min_element() == 0 || c.max_element() == 11)
        .map(|c| (c, AverageRecord { normal: [(c.x as i8) - 6, 40, 7], ..red }));
    let map = BrickMap::from_voxels(g.dims, shell).unwrap();
    let caches = vec![VoxelCache::rigid("cube", g, 1.0, &map).unwrap()];
    let m = DMat4::from_translation(DVec3::new(16.2, 15.7, 16.4))
        * DMat4::from_quat(DQuat::from_axis_angle(axis, std::f64::consts::FRAC_PI_4))
        * DMat4::from_translation(-DVec3::splat(6.0));
    let floor = (0..32u32).flat_map(|x| (0..32u32).map(move |z| (UVec3::new(x, 0, z), red)));
    let world =
        DynamicWorld::new(GridSpec::new(DVec3::ZERO, 1.0, UVec3::splat(32)).unwrap(), floor)
            .unwrap();
    Case {
        name: name.into(),
        world,
        caches,
        placements: vec![Placement::Rigid(m)],
        points: Vec::new(),
        width: 1,
        light: Light::Directional {
            to_light: Vec3::new(0.3, 1.0, 0.2),
            irradiance: Vec3::splat(3.0),
        },
    }
}

fn cases() -> &'static [Case] {
    static CASES: OnceLock<Vec<Case>> = OnceLock::new();
    CASES.get_or_init(|| {
        vec![
            crowd(),
            cube_45(DVec3::X, "cube 45° about x"),
            cube_45(DVec3::Y, "cube 45° about y"),
            cube_45(DVec3::Z, "cube 45° about z"),
        ]
    })
}

const FILTERS: [Filter; 2] = [Filter::Nearest, Filter::EightNeighbour];

fn frames(c: &Case, options: &FrameOptions) -> Vec<ObjectFrame> {
    c.caches
        .iter()
        .zip(&c.placements)
        .map(|(cache, p)| place(cache, p, &c.world.grid, options.rigidity_tolerance).unwrap())
        .collect()
}

fn cpu_placed(c: &Case, frames: &[ObjectFrame], filter: Filter) -> Vec<Placed> {
    c.caches.iter().zip(frames).flat_map(|(cache, f)| transform(cache, f, filter)).collect()
}

/// The CPU's `f32` position of every voxel (relative to its anchor), for boundary distances.
fn cpu_positions(c: &Case, frames: &[ObjectFrame]) -> Vec<[f32; 3]> {
    let mut out = Vec::new();
    for (cache, f) in c.caches.iter().zip(frames) {
        let skins = cache.skin.as_ref().map(|s| &s.voxels[..]);
        for v in 0..cache.len() {
            let m = voxel_matrix(&f.matrices, skins.map(|s| &s[v])).m;
            let i = unpack_position(cache.positions[v]).as_vec3();
            out.push(std::array::from_fn(|k| {
                ((m[k] * i.x + m[3 + k] * i.y) + m[6 + k] * i.z) + m[9 + k]
            }));
        }
    }
    out
}

/// Distance (voxels) from the boundary axis `k` of a voxel at `r` crossed to differ as
/// `a` and `b` do.
fn boundary_distance(r: f32, filter: Filter) -> f64 {
    let r = r as f64;
    match filter {
        Filter::Nearest => (r - r.round()).abs(),
        Filter::EightNeighbour => {
            let q = r - 0.5;
            let t = (q - q.floor()) * 64.0 + 0.5;
            (q - q.round()).abs().min((t - t.round()).abs() / 64.0)
        }
    }
}

/// Transform rows' tally over one comparison.
#[derive(Default)]
struct Transformed {
    voxels: usize,
    at_boundary: usize,
    worst_distance: f64,
    bad: Vec<String>,
}

impl Transformed {
    fn add(&mut self, name: &str, got: &[Placed], want: &[Placed], r: &[[f32; 3]], filter: Filter) {
        self.voxels += want.len();
        if got.len() != want.len() {
            self.bad.push(format!("{name}: {} voxels, expected {}", got.len(), want.len()));
            return;
        }
        for (v, (a, b)) in got.iter().zip(want).enumerate() {
            if a.status != b.status {
                self.bad.push(format!("{name} voxel {v}: status {} vs {}", a.status, b.status));
                continue;
            }
            if a.normal.iter().zip(&b.normal).any(|(x, y)| (x - y).abs() > 1) {
                self.bad.push(format!("{name} voxel {v}: normal {:?} vs {:?}", a.normal, b.normal));
            }
            let (fa, fb) = (a.fractions(), b.fractions());
            let mut crossed = false;
            for k in 0..3 {
                let dc = (a.cell[k] - b.cell[k]).abs();
                let df = (fa[k] as i32 - fb[k] as i32).abs();
                if dc == 0 && df == 0 {
                    continue;
                }
                let d = boundary_distance(r[v][k], filter);
                self.worst_distance = self.worst_distance.max(d);
                // One step: a cell moved by one (the fraction wrapping 64 ↔ 0 with it), or a
                // fraction by one.
                let one_step = (dc <= 1 && (df <= 1 || df == 64)) && d <= BOUNDARY;
                if !one_step {
                    self.bad.push(format!(
                        "{name} voxel {v} axis {k}: cell {:?}/{:?}, frac {fa:?}/{fb:?}, {d:.2e} from a boundary",
                        a.cell, b.cell
                    ));
                }
                crossed = true;
            }
            self.at_boundary += usize::from(crossed);
        }
    }

    fn measure(&self) -> Measure {
        let fraction = self.at_boundary as f64 / self.voxels.max(1) as f64;
        let pass = self.bad.is_empty() && fraction <= FRACTION_AT_BOUNDARY;
        Measure {
            max_error: self.worst_distance,
            bound: BOUNDARY,
            pass,
            note: format!(
                "{} voxels, {} at a boundary ({:.4} %, at most {} %){}",
                self.voxels,
                self.at_boundary,
                100.0 * fraction,
                100.0 * FRACTION_AT_BOUNDARY,
                self.bad
                    .first()
                    .map_or(String::new(), |b| format!("; {} bad, first: {b}", self.bad.len()))
            ),
        }
    }
}

fn kernels<'a>(backend: &Executor<'a>) -> Result<Option<DynamicKernels<'a>>, String> {
    match backend {
        Executor::Cpu => Ok(None),
        Executor::Gpu(ctx) => DynamicKernels::new(ctx).map(Some).map_err(|e| e.to_string()),
    }
}

/// Transform: GPU against CPU; the CPU row, CPU against an `f64` oracle.
pub fn transform_scenes(backend: &Executor) -> Result<Measure, String> {
    let k = kernels(backend)?;
    let e = |e: voxlod_gpu::Error| e.to_string();
    let mut tally = Transformed::default();
    let mut control = Transformed::default();
    for c in cases() {
        let up = match &k {
            Some(k) => Some(k.upload(&c.world, &c.caches).map_err(e)?),
            None => None,
        };
        for filter in FILTERS {
            let options = FrameOptions { filter, ..FrameOptions::default() };
            let f = frames(c, &options);
            let want = cpu_placed(c, &f, filter);
            let r = cpu_positions(c, &f);
            let got = match (&k, &up) {
                (Some(k), Some(up)) => {
                    let placed = k.transform(up, &f, filter).map_err(e)?;
                    k.read_placed(&placed, up.voxels).map_err(e)?
                }
                _ => oracle_placed(c, filter),
            };
            tally.add(&format!("{} {}", c.name, filter.name()), &got, &want, &r, filter);
            // Control: the CPU's voxels with every object moved by 0.01 voxel along x.
            let shift = DVec3::new(0.01 * c.world.grid.voxel_size, 0.0, 0.0);
            let moved: Vec<Placement> = c
                .placements
                .iter()
                .map(|p| match p {
                    Placement::Rigid(m) => Placement::Rigid(DMat4::from_translation(shift) * *m),
                    Placement::Skinned(j) => Placement::Skinned(
                        j.iter().map(|m| DMat4::from_translation(shift) * *m).collect(),
                    ),
                })
                .collect();
            let shifted = Case { placements: moved, ..c.shallow() };
            let fs = frames(&shifted, &options);
            control.add(
                "shifted",
                &got,
                &cpu_placed(&shifted, &fs, filter),
                &cpu_positions(&shifted, &fs),
                filter,
            );
        }
    }
    let mut m = tally.measure();
    let c = control.measure();
    m.pass &= !c.pass;
    m.note = format!(
        "{}; control (objects moved by 0.01 voxel): {} → {}",
        m.note,
        c.note,
        if c.pass { "NOT caught" } else { "caught" }
    );
    Ok(m)
}

impl Case {
    /// The same world and caches (cloned) with no shading points, for a perturbed placement.
    fn shallow(&self) -> Case {
        Case {
            name: self.name.clone(),
            world: self.world.clone(),
            caches: self.caches.clone(),
            placements: self.placements.clone(),
            points: Vec::new(),
            width: 1,
            light: self.light,
        }
    }
}

/// The `f64` oracle of the transform (rigid objects exactly; skinned ones by the `f64` blend
/// of their joint matrices with the unorm8 weights).
fn oracle_placed(c: &Case, filter: Filter) -> Vec<Placed> {
    let g = &c.world.grid;
    let mut out = Vec::new();
    for (cache, p) in c.caches.iter().zip(&c.placements) {
        for v in 0..cache.len() {
            let m: DMat4 = match (p, &cache.skin) {
                (Placement::Rigid(m), _) => *m,
                (Placement::Skinned(j), Some(s)) => {
                    let sk = s.voxels[v];
                    (0..4).fold(DMat4::ZERO, |acc, k| {
                        acc + j[sk.joints[k] as usize] * (sk.weights[k] as f64 / 255.0)
                    })
                }
                _ => unreachable!("placements match the caches"),
            };
            let i = unpack_position(cache.positions[v]).as_dvec3();
            let world = m.transform_point3(cache.grid.origin + (i + 0.5) * cache.grid.voxel_size);
            let r = (world - g.origin) / g.voxel_size;
            let n = voxlod_format::records::quant::decode_dir(cache.records[v].normal).as_dvec3();
            let moved = glam::DMat3::from_mat4(m) * n;
            let normal = voxlod_octree::dynamic::quantize_normal(
                moved.normalize_or_zero().as_vec3().to_array(),
            );
            let (cell, frac) = match filter {
                Filter::Nearest => (r.floor().as_ivec3(), 0),
                Filter::EightNeighbour => {
                    let q = r - 0.5;
                    let f =
                        ((q - q.floor()) * 64.0 + 0.5).floor().min(DVec3::splat(64.0)).as_uvec3();
                    (q.floor().as_ivec3(), f.x | f.y << 8 | f.z << 16)
                }
            };
            out.push(Placed { cell: cell.to_array(), frac, normal, status: 0 });
        }
    }
    out
}

/// Occupied world voxels (Morton code, leaf payload).
type Leaves = Vec<(u64, AveragePayload)>;
/// A blend's leaf codes, payloads and raw sums.
type Blended = (Vec<u64>, Vec<AveragePayload>, Vec<CellSums>);

/// The GPU context of a GPU executor (the rows that call it run only on one).
fn k_ctx<'a>(backend: &Executor<'a>) -> &'a voxlod_gpu::Context {
    match backend {
        Executor::Gpu(ctx) => ctx,
        Executor::Cpu => unreachable!("GPU rows only"),
    }
}
