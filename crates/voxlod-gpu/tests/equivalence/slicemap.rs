//! Slicemaps: the render pipeline against `voxlod_cpu::voxelize::slicemap::build`, and the
//! query kernels against the reference's queries.
//!
//! Tolerance, per map:
//! - **columns covered: exact** (the set of columns with a bit set, per layer), and local
//!   slicing's per-column ranges empty in the same columns and equal within `1e-6` of the
//!   depth span elsewhere;
//! - **slice bits: equal except at fragments within `1e-5` of a slice boundary** in normalized
//!   depth (`|z'·n − k| < 1e-5·n` for a boundary `k`, both slices beside it): every differing
//!   bit must be such a slice of such a fragment (the reference enumerates its fragments to
//!   know), and the differing bits must stay below 0.1 % of the fragments. The driver's `f32`
//!   arithmetic (fused multiply-adds, division) is not the reference's bit for bit.
//! - queries: inner voxels of the same map **exact**; occluder counts exact except for points
//!   within `1e-5` of a boundary.
//!
//! The reported error is the number of differences the tolerance does not explain (bound 0).
//! Controls that must fail: a standard GPU map against the conservative reference, and a GPU
//! map shifted by one slice.

use glam::{DVec3, UVec3, Vec3};
use proptest::prelude::*;
use proptest::test_runner::{Config, RngAlgorithm, TestRng, TestRunner};
use voxlod_cpu::random::rand_f32;
use voxlod_cpu::voxelize::slicemap::{
    self as cpu, Coverage, Faces, Options, Projection, SliceCamera, Slicemap, Slicing,
};
use voxlod_format::GridSpec;
use voxlod_gpu::slicemap::SlicemapRenderer;
use voxlod_gpu::slicemap::query::SlicemapQueries;
use voxlod_scene::{Camera, Geometry};

use crate::harness::{Executor, Measure};

/// Normalized-depth distance to a slice boundary within which a bit may differ.
const BOUNDARY: f32 = 1e-5;
/// Most differing bits, as a fraction of the fragments.
const MAX_FRACTION: f64 = 1e-3;

type Kernels<'a> = Option<(SlicemapRenderer<'a>, SlicemapQueries<'a>)>;

fn kernels<'a>(backend: &Executor<'a>) -> Result<Kernels<'a>, String> {
    match backend {
        Executor::Cpu => Ok(None),
        Executor::Gpu(ctx) => {
            let r = SlicemapRenderer::new(ctx).map_err(|e| e.to_string())?;
            let q = SlicemapQueries::new(ctx).map_err(|e| e.to_string())?;
            Ok(Some((r, q)))
        }
    }
}

fn build(k: &Kernels, g: &Geometry, cam: &SliceCamera, o: &Options) -> Result<Slicemap, String> {
    match k {
        None => cpu::build(g, cam, o).map_err(|e| e.to_string()),
        Some((r, _)) => r.build(g, cam, o).map_err(|e| e.to_string()),
    }
}

/// Per column and layer, the slices whose bit may differ: those beside a boundary within
/// [`BOUNDARY`] of a fragment's depth interval ends. Also returns the fragment count.
fn uncertain(want: &Slicemap, triangles: &[cpu::SliceTriangle]) -> (Vec<u32>, u64) {
    let (cam, o) = (&want.camera, &want.options);
    let n = o.slices;
    let k = o.words() as usize;
    let w = cam.width as usize;
    let columns = w * cam.height as usize;
    let mut mask = vec![0u32; want.bits.len()];
    let mut fragments = 0u64;
    for t in triangles {
        cpu::for_each_fragment(t, cam, o, |f| {
            let c = f.y as usize * w + f.x as usize;
            let Some((lo, hi)) = want.range(f.x, f.y) else { return };
            fragments += 1;
            let base = (f.layer as usize * columns + c) * k;
            for d in [f.d_lo, f.d_hi] {
                let z = if hi > lo { (d - lo) / (hi - lo) } else { 0.0 };
                let b = (z * n as f32).round();
                if (z * n as f32 - b).abs() < BOUNDARY * n as f32 {
                    for s in [b as i64 - 1, b as i64] {
                        if s >= 0 && s < n as i64 {
                            mask[base + s as usize / 32] |= 1 << (s % 32);
                        }
                    }
                }
            }
        });
    }
    (mask, fragments)
}

/// What differs between two maps of the same camera and options.
struct Diff {
    /// Differences no tolerance explains: columns covered, ranges, bits away from boundaries.
    unexplained: u64,
    /// Bits that differ at boundary fragments.
    tolerated: u64,
    fragments: u64,
    first: String,
}

fn diff(got: &Slicemap, want: &Slicemap, triangles: &[cpu::SliceTriangle]) -> Diff {
    let mut d = Diff { unexplained: 0, tolerated: 0, fragments: 0, first: String::new() };
    let note = |d: &mut Diff, s: String| {
        d.unexplained += 1;
        if d.first.is_empty() {
            d.first = s;
        }
    };
    if got.bits.len() != want.bits.len() {
        note(&mut d, format!("{} words, expected {}", got.bits.len(), want.bits.len()));
        return d;
    }
    let (cam, k) = (&want.camera, want.words() as usize);
    let layers = want.options.faces.layers();
    for l in 0..layers {
        for y in 0..cam.height {
            for x in 0..cam.width {
                let (a, b) = (got.column(l, x, y), want.column(l, x, y));
                if a.iter().any(|&v| v != 0) != b.iter().any(|&v| v != 0) {
                    note(&mut d, format!("coverage of column ({x}, {y}) layer {l}"));
                }
            }
        }
    }
    if let (Some(gr), Some(wr)) = (&got.ranges, &want.ranges) {
        let tol = 1e-6 * want.depth_span();
        for (i, (g, w)) in gr.iter().zip(wr).enumerate() {
            let (ge, we) = (g[0] > g[1], w[0] > w[1]);
            if ge != we || (!we && ((g[0] - w[0]).abs() > tol || (g[1] - w[1]).abs() > tol)) {
                note(&mut d, format!("range of column {i}: {g:?}, expected {w:?}"));
            }
        }
    }
    let (mask, fragments) = uncertain(want, triangles);
    d.fragments = fragments;
    for (i, (&g, &w)) in got.bits.iter().zip(&want.bits).enumerate() {
        let x = g ^ w;
        d.tolerated += (x & mask[i]).count_ones() as u64;
        if x & !mask[i] != 0 {
            let c = i / k;
            note(&mut d, format!("word {} of column {c}: {g:#x}, expected {w:#x}", i % k));
        }
    }
    d
}

fn check(name: &str, d: Diff) -> Measure {
    let fraction = d.tolerated as f64 / d.fragments.max(1) as f64;
    Measure {
        max_error: d.unexplained as f64,
        bound: 0.0,
        pass: d.unexplained == 0 && fraction <= MAX_FRACTION,
        note: format!(
            "{name}: {} unexplained{}; {} boundary bits / {} fragments ({:.2e} ≤ {MAX_FRACTION:.0e})",
            d.unexplained,
            if d.first.is_empty() { String::new() } else { format!(" (first: {})", d.first) },
            d.tolerated,
            d.fragments,
            fraction
        ),
    }
}

fn bunny() -> Geometry {
    let path =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets/bunny/bunny.obj");
    voxlod_scene::Scene::load(&path).expect("the bunny asset loads").geometry()
}

fn bunny_camera(g: &Geometry, width: u32, height: u32) -> SliceCamera {
    let (lo, hi) = g.bounds().unwrap();
    let c = (lo + hi) * 0.5;
    let r = (hi - lo).length() * 0.5;
    let cam = Camera::look_at(c + Vec3::new(0.6, 0.4, 1.0).normalize() * 3.0 * r, c, Vec3::Y, 45.0);
    SliceCamera::from_camera(&cam, width, height, (1.5 * r) as f64, (4.5 * r) as f64)
}

/// Triangles whose vertices lie on pixel centres and pixel edges of an aligned 16 × 16 map:
/// coverage ties everywhere (top-left rule), edge-on and zero-area triangles among them.
fn ties() -> (Geometry, SliceCamera) {
    let grid = GridSpec::new(DVec3::ZERO, 1.0, UVec3::splat(16)).unwrap();
    let cam = SliceCamera::aligned(&grid, 2).unwrap();
    let mut g = Geometry::default();
    let mut add = |v: [Vec3; 3]| {
        let b = g.positions.len() as u32;
        g.positions.extend(v);
        g.indices.push([b, b + 1, b + 2]);
    };
    for i in 0..40u32 {
        let r = |d: u32| rand_f32(i, 1, d);
        // Corners on the half-pixel lattice; depth inside the grid, away from its faces.
        let p = |a: f32, b: f32, z: f32| {
            Vec3::new((a * 32.0).round() / 2.0, (b * 32.0).round() / 2.0, 0.7 + z * 14.6)
        };
        add([p(r(0), r(1), r(2)), p(r(3), r(4), r(5)), p(r(6), r(7), r(8))]);
    }
    // Axis-aligned quads on pixel edges, a triangle seen edge-on, a point and a segment.
    for (x0, y0, x1, y1, z) in
        [(2.0, 2.0, 6.0, 6.0, 3.3), (6.0, 2.0, 9.0, 6.0, 3.3), (2.5, 8.5, 7.5, 12.5, 9.1)]
    {
        add([Vec3::new(x0, y0, z), Vec3::new(x1, y0, z), Vec3::new(x1, y1, z)]);
        add([Vec3::new(x0, y0, z), Vec3::new(x1, y1, z), Vec3::new(x0, y1, z)]);
    }
    add([Vec3::new(11.5, 3.0, 2.0), Vec3::new(11.5, 9.0, 2.0), Vec3::new(11.5, 3.0, 13.0)]);
    add([Vec3::new(13.3, 13.3, 5.0); 3]);
    add([Vec3::new(1.0, 14.25, 4.0), Vec3::new(9.0, 14.25, 12.0), Vec3::new(5.0, 14.25, 8.0)]);
    (g, cam)
}

/// 512 planes parallel to the image, one in the middle of each slice of a 2 × 2 orthographic
/// map between depths 0 and 512: every bit of every column set.
fn full_columns() -> (Geometry, SliceCamera) {
    let mut g = Geometry::default();
    for k in 0..512u32 {
        let z = 10.0 - (k as f32 + 0.5);
        let b = g.positions.len() as u32;
        g.positions.extend([
            Vec3::new(-1.0, -1.0, z),
            Vec3::new(6.0, -1.0, z),
            Vec3::new(-1.0, 6.0, z),
        ]);
        g.indices.push([b, b + 1, b + 2]);
    }
    let cam = SliceCamera {
        eye: DVec3::new(1.0, 1.0, 10.0),
        forward: DVec3::NEG_Z,
        up: DVec3::Y,
        projection: Projection::Orthographic { half_width: 1.0, half_height: 1.0 },
        width: 2,
        height: 2,
        near: 0.0,
        far: 512.0,
    };
    (g, cam)
}

/// A soup of triangles of all sizes around the origin, some far larger than the view (guard
/// band clipping) and some crossing the near plane.
fn soup(n: u32, seed: u32) -> Geometry {
    let mut g = Geometry::default();
    for t in 0..n {
        let r = |d: u32| rand_f32(seed.wrapping_add(t), 0, d) * 2.0 - 1.0;
        let size = [0.02, 0.2, 1.0, 40.0][(t % 4) as usize];
        let c = Vec3::new(r(0), r(1), r(2)) * 1.5;
        let b = g.positions.len() as u32;
        for v in 0..3 {
            g.positions.push(c + Vec3::new(r(3 + 3 * v), r(4 + 3 * v), r(5 + 3 * v)) * size);
        }
        g.indices.push([b, b + 1, b + 2]);
    }
    g
}

fn soup_camera(perspective: bool, width: u32, height: u32) -> SliceCamera {
    SliceCamera {
        eye: DVec3::new(0.3, 0.5, 5.0),
        forward: DVec3::new(-0.05, -0.1, -1.0),
        up: DVec3::Y,
        projection: if perspective {
            Projection::Perspective { fov_y_deg: 50.0 }
        } else {
            Projection::Orthographic { half_width: 2.2, half_height: 1.9 }
        },
        width,
        height,
        near: 2.0,
        far: 9.0,
    }
}

fn case(
    k: &Kernels,
    name: &str,
    g: &Geometry,
    cam: &SliceCamera,
    o: &Options,
) -> Result<(Measure, Slicemap), String> {
    let want = cpu::build(g, cam, o).map_err(|e| e.to_string())?;
    let got = build(k, g, cam, o)?;
    let prepared = cpu::prepare(g, cam).map_err(|e| e.to_string())?;
    Ok((check(name, diff(&got, &want, &prepared.triangles)), got))
}

fn opts(slices: u32, slicing: Slicing, coverage: Coverage, faces: Faces) -> Options {
    Options { slices, slicing, coverage, faces, ..Options::default() }
}

/// The render pipeline on fixed scenes: the bunny in perspective, tie-laden triangles in an
/// aligned map, a soup with clipping, in both coverage rules and both slicings; columns with
/// every bit set.
pub fn scenes(backend: &Executor) -> Result<Measure, String> {
    let k = kernels(backend)?;
    let bunny = bunny();
    let bcam = bunny_camera(&bunny, 96, 80);
    let (ties, tcam) = ties();
    let soup = soup(200, 11);
    use Coverage::{Conservative as C, Standard as S};
    use Faces::{All, Split};
    use Slicing::{Local as L, Uniform as U};
    let cases: Vec<(&str, &Geometry, SliceCamera, Options)> = vec![
        ("bunny U S 32", &bunny, bcam, opts(32, U, S, All)),
        ("bunny L S split 96", &bunny, bcam, opts(96, L, S, Split)),
        ("bunny U C 512", &bunny, bcam, opts(512, U, C, All)),
        ("bunny L C split 64", &bunny, bcam, opts(64, L, C, Split)),
        ("ties U S 16", &ties, tcam, opts(16, U, S, All)),
        ("ties U C 16", &ties, tcam, opts(16, U, C, Split)),
        ("ties L S 32", &ties, tcam, opts(32, L, S, All)),
        ("soup persp L S 128", &soup, soup_camera(true, 64, 48), opts(128, L, S, Split)),
        ("soup persp U C 32", &soup, soup_camera(true, 64, 48), opts(32, U, C, All)),
        ("soup ortho L C 40", &soup, soup_camera(false, 50, 61), opts(40, L, C, All)),
    ];
    let mut measures = Vec::new();
    for (name, g, cam, o) in &cases {
        measures.push(case(&k, name, g, cam, o)?.0);
    }
    // Every bit of every column set: the reference's columns are full, and so must the GPU's be.
    let (full, fcam) = full_columns();
    let (m, got) = case(&k, "512 slices, full columns", &full, &fcam, &opts(512, U, S, All))?;
    if got.bits.iter().any(|&w| w != u32::MAX) {
        return Err("512 planes: a column is not full".into());
    }
    measures.push(m);
    // The same soup in draws of 7 triangles (the batching path).
    let small = k.map(|(r, q)| (r.with_batch(7), q));
    let o = opts(64, Slicing::Local, Coverage::Conservative, Faces::Split);
    measures.push(case(&small, "soup in batches of 7", &soup, &soup_camera(true, 40, 30), &o)?.0);
    Ok(Measure::combine(&measures))
}

/// Random soups, cameras and options (a fixed-seed proptest run).
pub fn property(backend: &Executor) -> Result<Measure, String> {
    let k = kernels(backend)?;
    let config = Config { cases: 12, failure_persistence: None, ..Config::default() };
    let rng = TestRng::from_seed(RngAlgorithm::ChaCha, &[17; 32]);
    let mut runner = TestRunner::new_with_rng(config, rng);
    let worst = std::cell::RefCell::new(Vec::new());
    let strategy = (
        1u32..1000,
        any::<bool>(),
        8u32..70,
        8u32..70,
        1u32..=512,
        any::<bool>(),
        any::<bool>(),
        any::<bool>(),
    );
    let result = runner.run(&strategy, |(seed, persp, w, h, slices, local, cons, split)| {
        let g = soup(60, seed);
        let cam = soup_camera(persp, w, h);
        let o = opts(
            slices,
            if local { Slicing::Local } else { Slicing::Uniform },
            if cons { Coverage::Conservative } else { Coverage::Standard },
            if split { Faces::Split } else { Faces::All },
        );
        let name = format!("soup {seed} persp={persp} {w}×{h} {o:?}");
        let (m, _) = case(&k, &name, &g, &cam, &o).map_err(TestCaseError::fail)?;
        let pass = m.pass;
        worst.borrow_mut().push(m);
        prop_assert!(pass, "{}", worst.borrow().last().unwrap().note);
        Ok(())
    });
    let mut measures = worst.into_inner();
    if let Err(e) = result {
        measures.push(Measure {
            max_error: f64::INFINITY,
            bound: 0.0,
            pass: false,
            note: e.to_string(),
        });
    }
    let mut m = Measure::combine(&measures);
    m.note = format!("{} cases; {}", measures.len(), if m.pass { "all pass" } else { &m.note });
    Ok(m)
}

/// The query kernels on the backend's own maps: inner voxels exact, occluders exact except at
/// boundary points.
pub fn queries(backend: &Executor) -> Result<Measure, String> {
    let k = kernels(backend)?;
    let bunny = bunny();
    let cam = bunny_camera(&bunny, 64, 56);
    let mut bad = 0u64;
    let mut notes = Vec::new();
    for (slicing, slices) in [(Slicing::Local, 32), (Slicing::Uniform, 200)] {
        let o = opts(slices, slicing, Coverage::Standard, Faces::Split);
        let map = build(&k, &bunny, &cam, &o)?;
        let inner = match &k {
            None => (0..cam.height)
                .flat_map(|y| (0..cam.width).map(move |x| (x, y)))
                .map(|(x, y)| map.inner_voxels(x, y).unwrap())
                .collect(),
            Some((_, q)) => q.inner_voxels(&map).map_err(|e| e.to_string())?,
        };
        let mut diffs = 0;
        for y in 0..cam.height {
            for x in 0..cam.width {
                diffs +=
                    (inner[(y * cam.width + x) as usize] != map.inner_voxels(x, y).unwrap()) as u64;
            }
        }
        bad += diffs;
        // Points on a lattice through the bunny's bounds, some outside the map.
        let (lo, hi) = bunny.bounds().unwrap();
        let mut points = Vec::new();
        for i in 0..4000u32 {
            let t = Vec3::new(rand_f32(i, 2, 0), rand_f32(i, 2, 1), rand_f32(i, 2, 2)) * 1.4 - 0.2;
            points.push(map.locate((lo + (hi - lo) * t).as_dvec3()));
        }
        let want: Vec<Option<u32>> =
            points.iter().map(|p| p.map(|l| map.count_nearer(0, l.x, l.y, l.d))).collect();
        let got = match &k {
            None => want.clone(),
            Some((_, q)) => q.occluders(&map, &points).map_err(|e| e.to_string())?,
        };
        let mut boundary = 0;
        for ((g, w), p) in got.iter().zip(&want).zip(&points) {
            if g != w {
                let l = p.expect("both located");
                let (a, b) = map.range(l.x, l.y).unwrap_or((0.0, 1.0));
                let z = (l.d - a) / (b - a) * slices as f32;
                if (z - z.round()).abs() < BOUNDARY * slices as f32 {
                    boundary += 1;
                } else {
                    bad += 1;
                }
            }
        }
        notes.push(format!(
            "{slicing:?} {slices}: inner voxels {diffs} differ; {} points, {boundary} at boundaries",
            points.len()
        ));
    }
    Ok(Measure { max_error: bad as f64, bound: 0.0, pass: bad == 0, note: notes.join("; ") })
}

/// Controls that must fail: the comparison catches a wrong coverage rule and a shifted slice.
pub fn control(backend: &Executor) -> Result<Measure, String> {
    let k = kernels(backend)?;
    let bunny = bunny();
    let cam = bunny_camera(&bunny, 48, 40);
    let prepared = cpu::prepare(&bunny, &cam).map_err(|e| e.to_string())?;
    let standard = opts(32, Slicing::Uniform, Coverage::Standard, Faces::All);
    let got = build(&k, &bunny, &cam, &standard)?;
    let conservative =
        cpu::build(&bunny, &cam, &Options { coverage: Coverage::Conservative, ..standard })
            .map_err(|e| e.to_string())?;
    let wrong_rule =
        check("standard vs conservative", diff(&got, &conservative, &prepared.triangles));
    let want = cpu::build(&bunny, &cam, &standard).map_err(|e| e.to_string())?;
    let mut shifted = got.clone();
    for w in &mut shifted.bits {
        *w <<= 1;
    }
    let shift = check("shifted by a slice", diff(&shifted, &want, &prepared.triangles));
    let pass = !wrong_rule.pass && !shift.pass;
    Ok(Measure {
        max_error: wrong_rule.max_error.min(shift.max_error),
        bound: 0.0,
        pass,
        note: format!(
            "must fail both: {} [{}]; {} [{}]",
            if wrong_rule.pass { "PASSED" } else { "failed" },
            wrong_rule.note,
            if shift.pass { "PASSED" } else { "failed" },
            shift.note
        ),
    })
}
