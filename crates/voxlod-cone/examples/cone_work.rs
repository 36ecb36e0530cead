//! A fixed amount of cone-tracing work on the scene of `benches/cone.rs`, for counting
//! instructions (`perf stat -e instructions:u`), which, unlike criterion's wall-clock figures,
//! does not depend on the machine's load:
//!
//! `RAYON_NUM_THREADS=1 perf stat -e instructions:u target/release/examples/cone_work [what]`
//!
//! `what`: `setup` (build, inject, shading points only), `diffuse` (plus one pass of AO + 6
//! diffuse cones at 160×90, the `cone/diffuse` bench's work), `frame` (plus one 320×180 frame of
//! 6 diffuse + 1 specular cones, the `frame/320x180` bench's work), `frame1280` (the same at
//! 1280×720, the frame size of Yalçıner and Sahillioğlu's timings). Subtract `setup` from the
//! others. Prints the cone steps and a checksum of the results (bit-identical code gives the
//! same checksum).

#[path = "../benches/common/mod.rs"]
mod common;

use common::{EYE, room, shading_points};
use glam::Vec3;
use rayon::prelude::*;
use voxlod_cone::{ConeTracer, Light, RadiancePayload, Shadows, TraceOptions, inject};
use voxlod_octree::Octree;

/// Checksum of the exact bits of some results, in order.
fn checksum(v: impl IntoIterator<Item = f32>) -> u64 {
    v.into_iter().fold(0u64, |h, x| h.wrapping_mul(0x100_0000_01b3) ^ u64::from(x.to_bits()))
}

fn main() {
    let what = std::env::args().nth(1).unwrap_or_else(|| "frame".into());
    let geometry = room();
    let light =
        Light::Directional { to_light: Vec3::new(0.3, 1.0, 0.2), irradiance: Vec3::splat(3.0) };
    let radiance: Octree<RadiancePayload> = inject(&geometry, &light, &Shadows::MARCH).unwrap();
    let tracer =
        ConeTracer::new(&radiance, TraceOptions { ao_radius: 8.0, ..Default::default() }).unwrap();
    match what.as_str() {
        "setup" => {}
        "diffuse" => {
            let small = shading_points(&geometry, 160, 90);
            let r: Vec<_> =
                small.par_iter().map(|&(p, n)| tracer.ao_and_diffuse(p, n, true, true)).collect();
            let steps: u64 = r.iter().map(|x| x.2 as u64).sum();
            let sum = checksum(r.iter().flat_map(|(ao, d, _)| [*ao, d.x, d.y, d.z]));
            println!("diffuse 160x90: {steps} cone steps, checksum {sum:016x}");
        }
        "frame" | "frame1280" => {
            let (w, h) = if what == "frame" { (320, 180) } else { (1280, 720) };
            let points = shading_points(&geometry, w, h);
            let r: Vec<Vec3> = points
                .par_iter()
                .map(|&(p, n)| {
                    let (_, d, _) = tracer.ao_and_diffuse(p, n, false, true);
                    d + tracer.specular(p, n, (EYE - p).normalize(), 0.5).radiance
                })
                .collect();
            println!(
                "frame {w}x{h}: checksum {:016x}",
                checksum(r.iter().flat_map(|v| v.to_array()))
            );
        }
        other => panic!("unknown work {other:?}: setup, diffuse, frame or frame1280"),
    }
}
