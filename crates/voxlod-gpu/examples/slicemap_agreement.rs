//! Slicemaps of larger scenes on the GPU path against the CPU reference, bit for bit: the
//! embedded bunny (3 674 triangles) and engine (121 496), and a 200 k-triangle forest, at 512²
//! (perspective) and 777² (orthographic) columns, standard and conservative coverage, uniform
//! and local slicing, front/back layers. Prints, per map, the bits set, the bits that differ,
//! the columns covered on each side and the local ranges that differ; exits with status 1 on
//! any difference. The equivalence suite checks small scenes with a boundary tolerance; this
//! checks what the tolerance allows does not happen on large ones (on lavapipe: nothing
//! differs).
//!
//! `cargo run --release -p voxlod-gpu --example slicemap_agreement`

use std::path::Path;
use std::process::ExitCode;

use glam::Vec3;
use voxlod_cpu::voxelize::slicemap::{self as cpu, Coverage, Faces, Options, SliceCamera, Slicing};
use voxlod_scene::procedural::forest::{ForestParams, forest};
use voxlod_scene::{Camera, Geometry, Scene};

fn asset(path: &str) -> Geometry {
    let p = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets").join(path);
    Scene::load(&p).unwrap_or_else(|e| panic!("{}: {e}", p.display())).geometry()
}

fn main() -> ExitCode {
    let ctx = match voxlod_gpu::Context::new() {
        Ok(c) => c,
        Err(e) => {
            eprintln!("no adapter: {e}");
            return ExitCode::FAILURE;
        }
    };
    println!("adapter: {}", ctx.summary());
    let renderer = voxlod_gpu::slicemap::SlicemapRenderer::new(&ctx).expect("pipelines compile");
    let params =
        ForestParams { alpha_leaves: false, ..ForestParams::with_target_triangles(200_000) };
    let scenes = [
        ("bunny", asset("bunny/bunny.obj")),
        ("engine", asset("2CylinderEngine/2CylinderEngine.glb")),
        ("forest-200k", forest(&params).expect("forest").geometry()),
    ];
    let mut failed = false;
    for (name, g) in &scenes {
        let (lo, hi) = g.bounds().expect("triangles");
        let c = (lo + hi) * 0.5;
        let r = (hi - lo).length() * 0.5;
        let cam = Camera::framing(Vec3::new(0.45, 0.35, 1.0), c, r, 40.0);
        let d = (cam.eye - c).length() as f64;
        for perspective in [true, false] {
            let sc = if perspective {
                SliceCamera::from_camera(&cam, 512, 512, d - r as f64, d + r as f64)
            } else {
                let dir = (c - cam.eye).as_dvec3();
                SliceCamera::enclosing_orthographic(dir, lo.as_dvec3(), hi.as_dvec3(), 777)
            };
            for (slices, slicing, coverage) in [
                (512, Slicing::Local, Coverage::Standard),
                (96, Slicing::Uniform, Coverage::Standard),
                (512, Slicing::Uniform, Coverage::Conservative),
                (64, Slicing::Local, Coverage::Conservative),
            ] {
                let o = Options {
                    slices,
                    slicing,
                    coverage,
                    faces: Faces::Split,
                    ..Options::default()
                };
                let want = cpu::build(g, &sc, &o).expect("cpu map");
                let got = renderer.build(g, &sc, &o).expect("gpu map");
                let differ: u64 =
                    want.bits.iter().zip(&got.bits).map(|(a, b)| (a ^ b).count_ones() as u64).sum();
                let ranges = match (&want.ranges, &got.ranges) {
                    (Some(a), Some(b)) => a.iter().zip(b).filter(|(p, q)| p != q).count(),
                    _ => 0,
                };
                let (ca, cb) = (want.covered_columns(), got.covered_columns());
                failed |= differ > 0 || ranges > 0 || ca != cb;
                println!(
                    "{name} {} {slices} {slicing:?} {coverage:?}: {} bits set, {differ} differ; \
                     columns {ca} (cpu) {cb} (gpu); {ranges} ranges differ",
                    if perspective { "perspective 512²" } else { "orthographic 777²" },
                    want.occupied(),
                );
            }
        }
    }
    if failed { ExitCode::FAILURE } else { ExitCode::SUCCESS }
}
