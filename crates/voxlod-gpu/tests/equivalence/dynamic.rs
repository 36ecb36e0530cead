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

/// The CPU's leaves and sums of `placed` (moving voxels blended, statics merged).
fn cpu_blend(c: &Case, placed: &[Placed], filter: Filter) -> (Leaves, Vec<(u64, CellSums)>) {
    let records: Vec<AverageRecord> =
        c.caches.iter().flat_map(|x| x.records.iter().copied()).collect();
    let (moving, _) = blend(
        &c.world.grid,
        &[BlendInput { placed, records: &records }],
        filter,
        c.world.statics.len() as u64,
    )
    .unwrap();
    let sums = moving.merge(&c.world.statics);
    let (leaves, _) = sums.resolve(FrameOptions::default().occupancy_threshold).unwrap();
    let min = (FrameOptions::default().occupancy_threshold as f64 * 262_144.0).ceil() as u64;
    let kept = sums
        .codes
        .iter()
        .zip(&sums.sums)
        .filter(|(_, s)| s.weight >= min.max(1) && s.alpha > 0)
        .map(|(&c, &s)| (c, s))
        .collect();
    (leaves, kept)
}

/// Blend: the CPU's moved voxels blended on the GPU, exact; plus the control.
pub fn blend_scenes(backend: &Executor) -> Result<Measure, String> {
    let k = kernels(backend)?;
    let e = |e: voxlod_gpu::Error| e.to_string();
    let (mut differ, mut worst_payload, mut leaves_total, mut control_differ) =
        (0u64, 0.0f64, 0, 0u64);
    let mut first = String::new();
    for c in cases() {
        let up = match &k {
            Some(k) => Some(k.upload(&c.world, &c.caches).map_err(e)?),
            None => None,
        };
        for filter in FILTERS {
            let options = FrameOptions { filter, ..FrameOptions::default() };
            let placed = cpu_placed(c, &frames(c, &options), filter);
            let (want_leaves, want_sums) = cpu_blend(c, &placed, filter);
            leaves_total += want_leaves.len();
            let run = |placed: &[Placed]| -> Result<Blended, String> {
                match (&k, &up) {
                    (Some(k), Some(up)) => {
                        let buf = k.upload_placed(placed).map_err(e)?;
                        let leaves =
                            k.blend(up, &buf, filter, options.occupancy_threshold).map_err(e)?;
                        let (coords, payload, sums) = k.read_leaves(&leaves).map_err(e)?;
                        Ok((coords.into_iter().map(morton::encode).collect(), payload, sums))
                    }
                    _ => {
                        // The CPU row: the brute-force 128-bit sum of every contribution.
                        let oracle = brute_force(c, placed, filter);
                        let (leaves, _) = cpu_blend(c, placed, filter);
                        let codes = leaves.iter().map(|l| l.0).collect();
                        let sums = leaves.iter().map(|l| oracle[&l.0]).collect();
                        Ok((codes, leaves.iter().map(|l| l.1).collect(), sums))
                    }
                }
            };
            let (codes, payload, sums) = run(&placed)?;
            let want_codes: Vec<u64> = want_leaves.iter().map(|l| l.0).collect();
            let mut bad = 0u64;
            if codes != want_codes {
                bad += codes.len().abs_diff(want_codes.len()) as u64
                    + codes.iter().zip(&want_codes).filter(|(a, b)| a != b).count() as u64;
            }
            for ((s, (_, w)), (p, (_, wp))) in
                sums.iter().zip(&want_sums).zip(payload.iter().zip(&want_leaves))
            {
                let (a, b): (&[u32], &[u32]) = (
                    bytemuck::cast_slice(std::slice::from_ref(s)),
                    bytemuck::cast_slice(std::slice::from_ref(w)),
                );
                bad += a.iter().zip(b).filter(|(x, y)| x != y).count() as u64;
                worst_payload = worst_payload.max(p.max_abs_diff(wp) as f64);
            }
            if bad > 0 && first.is_empty() {
                first = format!("{} {}: {bad} differ", c.name, filter.name());
            }
            differ += bad;
            // Control: one voxel's fraction moved by a sixty-fourth must change the sums.
            if filter == Filter::EightNeighbour {
                let mut perturbed = placed.clone();
                if let Some(p) = perturbed.iter_mut().find(|p| p.status == 0 && p.frac & 0xff < 64)
                {
                    p.frac += 1;
                }
                let (_, _, sums) = run(&perturbed)?;
                let changed = sums.len() != want_sums.len()
                    || sums.iter().zip(&want_sums).any(|(a, (_, b))| a != b);
                control_differ += u64::from(changed);
            }
        }
    }
    let controls = cases().len() as u64;
    let pass = differ == 0 && worst_payload <= PAYLOAD && control_differ == controls;
    Ok(Measure {
        max_error: differ as f64,
        bound: 0.0,
        pass,
        note: format!(
            "{leaves_total} leaves: {differ} codes/sum words differ{}; payloads within {worst_payload:.2e} (bound {PAYLOAD:e}); control (one fraction +1/64) caught {control_differ}/{controls}",
            if first.is_empty() { String::new() } else { format!(" ({first})") }
        ),
    })
}

fn brute_force(
    c: &Case,
    placed: &[Placed],
    filter: Filter,
) -> std::collections::BTreeMap<u64, CellSums> {
    let records: Vec<AverageRecord> =
        c.caches.iter().flat_map(|x| x.records.iter().copied()).collect();
    let mut out: std::collections::BTreeMap<u64, [i128; 8]> = Default::default();
    let table = voxlod_octree::dynamic::linear12_table();
    let g = &c.world.grid;
    for (p, r) in placed.iter().zip(&records) {
        if p.status != 0 {
            continue;
        }
        for k in 0..filter.corners() {
            let (cell, w) = voxlod_octree::dynamic::blend::corner(p, k, filter);
            if w == 0 || cell.min_element() < 0 || !cell.as_uvec3().cmplt(g.dims).all() {
                continue;
            }
            let e = out.entry(morton::encode(cell.as_uvec3())).or_default();
            let (w, a) = (w as i128, r.opacity as i128);
            e[0] += w;
            e[1] += w * a;
            for i in 0..3 {
                e[2 + i] += w * a * table[r.color[i] as usize] as i128;
                e[5 + i] += w * a * p.normal[i] as i128;
            }
        }
    }
    for (code, s) in c.world.statics.codes.iter().zip(&c.world.statics.sums) {
        let e = out.entry(*code).or_default();
        let v = [
            s.weight as i128,
            s.alpha as i128,
            s.color[0] as i128,
            s.color[1] as i128,
            s.color[2] as i128,
            s.normal[0] as i128,
            s.normal[1] as i128,
            s.normal[2] as i128,
        ];
        for i in 0..8 {
            e[i] += v[i];
        }
    }
    out.into_iter()
        .map(|(k, e)| {
            (
                k,
                CellSums {
                    weight: e[0] as u64,
                    alpha: e[1] as u64,
                    color: [e[2] as u64, e[3] as u64, e[4] as u64],
                    normal: [e[5] as i64, e[6] as i64, e[7] as i64],
                },
            )
        })
        .collect()
}

/// Entries of two flat octrees' topologies that differ.
fn topology_diff(a: &FlatOctree<AveragePayload>, e: &FlatOctree<AveragePayload>) -> u64 {
    let count = |x: usize, y: usize, d: usize| (x.abs_diff(y) + d) as u64;
    let mut bad = u64::from(a.depth != e.depth);
    bad += count(
        a.levels.len(),
        e.levels.len(),
        a.levels.iter().zip(&e.levels).filter(|(x, y)| x != y).count(),
    );
    bad += count(
        a.nodes.len(),
        e.nodes.len(),
        a.nodes.iter().zip(&e.nodes).filter(|(x, y)| x != y).count(),
    );
    bad += count(
        a.tiles.len(),
        e.tiles.len(),
        a.tiles.iter().zip(&e.tiles).filter(|(x, y)| x != y).count(),
    );
    for (l, lv) in e.levels.iter().enumerate() {
        for i in lv.first..lv.first + lv.count {
            for axis in 0..3 {
                bad += u64::from(a.neighbour(l as u32, i, axis) != e.neighbour(l as u32, i, axis));
            }
        }
    }
    bad
}

/// Rebuild: the GPU's octree from its own leaves against the CPU's from the CPU's leaves.
pub fn rebuild_scenes(backend: &Executor) -> Result<Measure, String> {
    let k = kernels(backend)?;
    let e = |e: voxlod_gpu::Error| e.to_string();
    let (mut differ, mut worst, mut control_caught, mut nodes) = (0u64, 0.0f64, 0u64, 0usize);
    let options = FrameOptions::default();
    let bound = PAYLOAD + 8.0 * 7.0 / (1u64 << 24) as f64;
    for c in cases() {
        let (cpu_leaves, _) = {
            let objects: Vec<(&VoxelCache, &Placement)> =
                c.caches.iter().zip(&c.placements).collect();
            c.world.leaves(&objects, &options).unwrap()
        };
        let cpu = FlatOctree::from_octree(
            &Octree::from_morton_sorted(c.world.grid, cpu_leaves.clone(), &options.build).unwrap(),
        )
        .unwrap();
        nodes += cpu.nodes.len();
        let got = match &k {
            None => {
                let voxels: Vec<(UVec3, AveragePayload)> =
                    cpu_leaves.iter().map(|(code, p)| (morton::decode(*code), *p)).collect();
                FlatOctree::build_level_by_level(c.world.grid, &voxels, &options.build)
                    .map_err(|e| e.to_string())?
            }
            Some(k) => {
                let up = k.upload(&c.world, &c.caches).map_err(e)?;
                let f = frames(c, &options);
                let placed = k.transform(&up, &f, options.filter).map_err(e)?;
                let leaves = k
                    .blend(&up, &placed, options.filter, options.occupancy_threshold)
                    .map_err(e)?;
                let octree = voxlod_gpu::octree::OctreeBuilder::new(k_ctx(backend)).map_err(e)?;
                let tree = octree
                    .build_device(
                        &c.world.grid,
                        &leaves.coords,
                        &leaves.payload,
                        leaves.count as usize,
                        &options.build,
                    )
                    .map_err(e)?;
                tree.read_back().map_err(e)?
            }
        };
        differ += topology_diff(&got, &cpu);
        if got.payload.len() == cpu.payload.len() {
            for (a, b) in got.payload.iter().zip(&cpu.payload) {
                worst = worst.max(a.max_abs_diff(b) as f64);
            }
        }
        // Control: the CPU octree without its first leaf must differ.
        let mut fewer = cpu_leaves;
        fewer.remove(0);
        let dropped = FlatOctree::from_octree(
            &Octree::from_morton_sorted(c.world.grid, fewer, &options.build).unwrap(),
        )
        .unwrap();
        let payload_moved = got.payload.len() != dropped.payload.len()
            || got
                .payload
                .iter()
                .zip(&dropped.payload)
                .any(|(a, b)| a.max_abs_diff(b) as f64 > bound);
        control_caught += u64::from(topology_diff(&got, &dropped) > 0 || payload_moved);
    }
    let controls = cases().len() as u64;
    Ok(Measure {
        max_error: differ as f64,
        bound: 0.0,
        pass: differ == 0 && worst <= bound && control_caught == controls,
        note: format!(
            "{nodes} nodes: {differ} topology entries differ; payloads within {worst:.2e} (bound {bound:.2e}); control (one leaf dropped) caught {control_caught}/{controls}"
        ),
    })
}

fn k_ctx<'a>(backend: &Executor<'a>) -> &'a voxlod_gpu::Context {
    match backend {
        Executor::Gpu(ctx) => ctx,
        Executor::Cpu => unreachable!("GPU rows only"),
    }
}

/// Per-value relative errors (absolute below 1) tallied against [`BOUND`] and [`HARD`].
#[derive(Default)]
struct Tally {
    values: usize,
    over: usize,
    worst: f64,
}

impl Tally {
    fn add(&mut self, got: f32, want: f32) {
        let d = (got as f64 - want as f64).abs() / (want.abs() as f64).max(1.0);
        self.values += 1;
        self.worst = self.worst.max(d);
        self.over += usize::from(d > BOUND);
    }
    fn passes(&self) -> bool {
        self.worst <= HARD && (self.values - self.over) as f64 >= FRACTION * self.values as f64
    }
    fn note(&self) -> String {
        format!("{} values, {} over {BOUND:e}, worst {:.2e}", self.values, self.over, self.worst)
    }
}

/// The CPU's injected radiance per leaf (Morton order), for shadows `shadows`.
fn cpu_injected(c: &Case, shadows: &Shadows) -> Vec<[f32; 4]> {
    let options = FrameOptions::default();
    let objects: Vec<(&VoxelCache, &Placement)> = c.caches.iter().zip(&c.placements).collect();
    let (geometry, _) = c.world.octree(&objects, &options).unwrap();
    let radiance: Octree<RadiancePayload> = inject(&geometry, &c.light, shadows).unwrap();
    let level = radiance.level(0);
    level
        .payload
        .iter()
        .filter(|p| p.opacity > 0.0)
        .map(|p| [p.radiance_alpha[0], p.radiance_alpha[1], p.radiance_alpha[2], p.opacity])
        .collect()
}

/// Inject: the GPU's radiance per leaf against the CPU's; plus the control.
pub fn inject_scenes(backend: &Executor) -> Result<Measure, String> {
    let k = kernels(backend)?;
    let e = |e: voxlod_gpu::Error| e.to_string();
    let (mut tally, mut control) = (Tally::default(), Tally::default());
    for c in cases() {
        let want = cpu_injected(c, &Shadows::MARCH);
        let perturbed =
            cpu_injected(c, &Shadows::March { offset_voxels: 1.5, step_factor: 0.5 * 1.05 });
        let got: Vec<[f32; 4]> = match &k {
            None => {
                // The CPU row: without shadows, the injection is the Lambert formula per leaf.
                let objects: Vec<(&VoxelCache, &Placement)> =
                    c.caches.iter().zip(&c.placements).collect();
                let (geometry, _) = c.world.octree(&objects, &FrameOptions::default()).unwrap();
                let unshadowed = cpu_injected(c, &Shadows::None);
                let leaves = voxlod_cone::occupied_leaves(&geometry);
                for ((cell, p), r) in leaves.iter().zip(&unshadowed) {
                    let centre = c.world.grid.voxel_center(*cell).as_vec3();
                    let (l, irr, _) = c.light.at(centre).unwrap();
                    let n = p.normal();
                    let ndl = if n == Vec3::ZERO { 0.5 } else { n.dot(l).max(0.0) };
                    let expected = p.color() * std::f32::consts::FRAC_1_PI * irr * ndl * p.opacity;
                    for i in 0..3 {
                        tally.add(r[i], expected[i]);
                    }
                }
                continue;
            }
            Some(k) => {
                let up = k.upload(&c.world, &c.caches).map_err(e)?;
                let options = FrameOptions::default();
                let frame = k
                    .frame(&up, &c.caches, &c.placements, &options, &c.light, &Shadows::MARCH)
                    .map_err(e)?;
                let raw: Vec<AveragePayload> = bytemuck::pod_collect_to_vec(
                    &k_ctx(backend)
                        .read(
                            &frame.injected,
                            frame.leaves.count * size_of::<AveragePayload>() as u64,
                        )
                        .map_err(e)?,
                );
                raw.iter()
                    .map(|p| [p.color_alpha[0], p.color_alpha[1], p.color_alpha[2], p.opacity])
                    .collect()
            }
        };
        if got.len() != want.len() {
            return Err(format!("{}: {} leaves, expected {}", c.name, got.len(), want.len()));
        }
        for (g, (w, p)) in got.iter().zip(want.iter().zip(&perturbed)) {
            for i in 0..4 {
                tally.add(g[i], w[i]);
                control.add(g[i], p[i]);
            }
        }
    }
    let caught = !control.passes() || matches!(backend, Executor::Cpu);
    Ok(Measure {
        max_error: tally.worst,
        bound: BOUND,
        pass: tally.passes() && caught,
        note: format!(
            "{}; control (step ×1.05): {} → {}",
            tally.note(),
            control.note(),
            if matches!(backend, Executor::Cpu) {
                "n/a on the CPU row"
            } else if caught {
                "caught"
            } else {
                "NOT caught"
            }
        ),
    })
}

/// Frame: the whole frame on the device, cone traced, against the CPU pipeline and tracer.
pub fn frame_scenes(backend: &Executor) -> Result<Measure, String> {
    let k = kernels(backend)?;
    let e = |e: voxlod_gpu::Error| e.to_string();
    let c = &cases()[0];
    let options = FrameOptions::default();
    let trace = TraceOptions { ao_radius: 1.0, ..TraceOptions::default() };
    let query = ConeQuery { ambient_occlusion: true, diffuse: true, specular: false };
    let mut pipeline: FramePipeline<RadiancePayload> =
        FramePipeline::new(&c.world, &c.caches, options, c.light, Shadows::MARCH);
    let (_, radiance, _) = pipeline.frame(&c.placements).map_err(|e| e.to_string())?;
    let tracer = ConeTracer::new(radiance, trace).map_err(|e| e.to_string())?;
    let want: Vec<_> = c.points.iter().map(|p| reference(&tracer, p, query)).collect();
    let got = match &k {
        None => {
            // The CPU row: the pipeline equals the composition of its steps, bit for bit.
            let objects: Vec<(&VoxelCache, &Placement)> =
                c.caches.iter().zip(&c.placements).collect();
            let (geometry, _) = c.world.octree(&objects, &options).unwrap();
            let r: Octree<RadiancePayload> = inject(&geometry, &c.light, &Shadows::MARCH).unwrap();
            let t = ConeTracer::new(&r, trace).unwrap();
            c.points.iter().map(|p| reference(&t, p, query)).collect::<Vec<_>>()
        }
        Some(k) => {
            let up = k.upload(&c.world, &c.caches).map_err(e)?;
            let frame = k
                .frame(&up, &c.caches, &c.placements, &options, &c.light, &Shadows::MARCH)
                .map_err(e)?;
            k.trace(&frame, &trace, query, &c.points, c.width).map_err(e)?
        }
    };
    let mut tally = Tally::default();
    for (g, w) in got.iter().zip(&want) {
        tally.add(g.ao, w.ao);
        for i in 0..3 {
            tally.add(g.diffuse[i], w.diffuse[i]);
        }
    }
    let hits = c.points.iter().filter(|p| p.normal != Vec3::ZERO).count();
    Ok(Measure {
        max_error: tally.worst,
        bound: BOUND,
        pass: tally.passes() && got.len() == want.len(),
        note: format!("{} ({hits} shading points on the posed crowd)", tally.note()),
    })
}
