//! The volume kernels beyond the scenes: random particle clouds (property rows), extreme
//! inputs, the controls that must break the bounds, and bad input the CPU refuses.

use glam::Vec3;
use voxlod_cpu::raycast::Bvh;
use voxlod_cpu::volume::binning::bin_brute_force;
use voxlod_cpu::volume::march::{render, render_front_to_back};
use voxlod_cpu::volume::{self, Attenuation, BuildSettings, MarchOptions};
use voxlod_scene::Camera;
use voxlod_scene::particles::{ColorMode, DisplacedSphere};
use voxlod_scene::procedural::Rng;

use crate::harness::{Executor, Measure};

use super::{
    FRAME_BOUND, binning, camera_outside, cases, cloud, compare, depth, exact_bins, floor, frame,
    kernels, map, reference_frame, spec,
};

pub fn property(backend: &Executor) -> Result<Measure, String> {
    let k = kernels(backend)?;
    let map = map();
    let cases = std::env::var("PROPTEST_CASES").ok().and_then(|s| s.parse().ok()).unwrap_or(8u64);
    let lights = [
        Vec3::X,
        Vec3::NEG_Y,
        Vec3::Z,
        Vec3::Y,
        Vec3::new(1.0, 1.0, 1.0),
        Vec3::new(-1.0, 1.0, 0.0),
        Vec3::new(1.0, -1.0, -1.0),
    ];
    let (mut out, mut bins) = (Vec::new(), Vec::new());
    for case in 0..cases {
        let mut r = Rng::stream(0x766f6c, &[case]);
        let n = 20 + r.below(200) as usize;
        let mut s = cloud(n, 1000 + case, r.range(0.5, 10.0));
        for p in s.iter_mut().filter(|_| r.below(5) == 0) {
            p.color_mode = ColorMode::DisplacementAo as u32;
        }
        let light = lights[r.below(lights.len() as u32) as usize];
        let (kk, m) = (2 + r.below(3), [2, 4, 8][r.below(3) as usize]);
        let spec = spec(light, kk, m);
        let binned = binning(&k, &s, &spec)?;
        bins.push(exact_bins(&format!("case {case}"), &binned.bins, &bin_brute_force(&s, &spec)));
        let inside = r.below(3) == 0;
        let camera = if inside {
            let eye = Vec3::new(r.range(-0.5, 0.5), r.range(-0.5, 0.5), r.range(-0.5, 0.5));
            Camera::look_at(
                eye,
                eye + Vec3::new(r.range(-1.0, 1.0), r.range(-1.0, 1.0), 1.0),
                Vec3::Y,
                75.0,
            )
        } else {
            let dir = Vec3::new(r.range(-1.0, 1.0), r.range(-1.0, 1.0), r.range(-1.0, 1.0));
            let dir = if dir.length() < 0.1 { Vec3::Z } else { dir };
            Camera::framing(dir, Vec3::ZERO, r.range(1.0, 2.5), 50.0)
        };
        let attenuation =
            if r.below(2) == 0 { Attenuation::Chapter } else { Attenuation::BeerLambert };
        let settings = BuildSettings { attenuation, ..Default::default() };
        let options = MarchOptions { width: 32, height: 24, step: r.range(0.5, 1.5) };
        let want = reference_frame(&s, &map, &spec, &settings, &camera, &options, None)?;
        let got = match &k {
            None => {
                let view = camera.frame(options.width, options.height);
                let v = volume::build(&s, &map, &spec, &settings, Some(&view), None)
                    .map_err(|e| e.to_string())?;
                render_front_to_back(&v, &camera, &options, None).map_err(|e| e.to_string())?
            }
            Some(_) => frame(&k, &s, &map, &spec, &settings, &camera, &options, None)?,
        };
        let name = format!("volume-property-{case}{}", if inside { "-inside" } else { "" });
        out.push(compare(&name, &got, &want, FRAME_BOUND));
    }
    out.extend(bins);
    Ok(Measure::combine(&out))
}

/// The extremes of the CPU's own tests: density 0 and 10⁶, particles outside the volume or
/// larger than it, no particles, under axis and diagonal lights: bins exact, frames within the
/// frame bound, every image finite.
pub fn extremes(backend: &Executor) -> Result<Measure, String> {
    let k = kernels(backend)?;
    let map = map();
    let one = |c: Vec3, inner: f32, amplitude: f32, density: f32| DisplacedSphere {
        center: c,
        inner,
        amplitude,
        color: Vec3::new(0.9, 0.7, 0.5),
        color_outer: Vec3::splat(0.3),
        density,
        rot_cos: 1.0,
        rot_sin: 0.0,
        color_mode: 0,
        flags: 0,
    };
    let dense_centre = one(Vec3::ZERO, 0.3, 0.1, 1e6);
    let cases: Vec<(&str, Vec<DisplacedSphere>)> = vec![
        ("density 0", cloud(50, 8, 0.0)),
        ("density 1e6", {
            let mut c = cloud(50, 8, 1e6);
            c.push(dense_centre);
            c
        }),
        ("outside", vec![one(Vec3::splat(30.0), 1.0, 0.5, 1.0)]),
        ("larger than the volume", vec![one(Vec3::ZERO, 40.0, 10.0, 0.5), dense_centre]),
        ("empty", Vec::new()),
    ];
    let cameras = [
        Camera::look_at(Vec3::new(0.5, 2.5, 3.0), Vec3::ZERO, Vec3::Y, 50.0),
        Camera::look_at(Vec3::new(0.01, 0.02, 0.03), Vec3::new(1.0, 0.0, 0.0), Vec3::Y, 60.0),
    ];
    let options = MarchOptions { width: 24, height: 20, step: 1.0 };
    let mut images = Vec::new();
    let mut bins = Vec::new();
    for to_light in [Vec3::Y, Vec3::NEG_Z, Vec3::ONE] {
        let spec = spec(to_light, 2, 6);
        for (name, s) in &cases {
            let got = binning(&k, s, &spec)?;
            bins.push(exact_bins(name, &got.bins, &bin_brute_force(s, &spec)));
            for (ci, camera) in cameras.iter().enumerate() {
                for att in [Attenuation::Chapter, Attenuation::BeerLambert, Attenuation::Exact] {
                    let settings = BuildSettings { attenuation: att, ..Default::default() };
                    let want = reference_frame(s, &map, &spec, &settings, camera, &options, None)?;
                    let got = frame(&k, s, &map, &spec, &settings, camera, &options, None)?;
                    if !got.pixels.iter().all(|p| p.is_finite()) {
                        return Err(format!(
                            "{name}, camera {ci}, {}: non-finite pixels",
                            att.name()
                        ));
                    }
                    let label = format!("volume-extreme-{}-{ci}", name.replace(' ', "-"));
                    images.push(compare(&label, &got, &want, FRAME_BOUND));
                }
            }
        }
    }
    let mut m = Measure::combine(&images);
    let b = Measure::combine(&bins);
    m.pass &= b.pass;
    m.note = format!(
        "{} frames, worst {:.3e} of pixels over the bound; {} binnings{}",
        images.len(),
        m.max_error,
        bins.len(),
        if b.pass { " exact".to_string() } else { format!(": {}", b.note) }
    );
    Ok(m)
}

/// The checks above can fail: a frame with 20 % denser particles is beyond the frame bound,
/// a bin list with one particle dropped is not exact, and a frame built without the mesh's
/// shadow (light from below the floor) is beyond the frame bound.
pub fn control(backend: &Executor) -> Result<Measure, String> {
    let k = kernels(backend)?;
    let map = map();
    let (n, seed, light, kk, m, density) = cases()[0];
    let s = cloud(n, seed, density);
    let spec = spec(light, kk, m);
    let settings = BuildSettings::default();
    let camera = camera_outside();
    let options = MarchOptions { width: 48, height: 40, step: 1.0 };
    let want = reference_frame(&s, &map, &spec, &settings, &camera, &options, None)?;
    let denser: Vec<DisplacedSphere> =
        s.iter().map(|p| DisplacedSphere { density: p.density * 1.2, ..*p }).collect();
    let got = match &k {
        None => reference_frame(&denser, &map, &spec, &settings, &camera, &options, None)?,
        Some(_) => frame(&k, &denser, &map, &spec, &settings, &camera, &options, None)?,
    };
    let image = compare("volume-control", &got, &want, FRAME_BOUND);
    let mut bins = binning(&k, &s, &spec)?.bins;
    if let Some(b) = bins.iter_mut().find(|b| b.particles.len() > 1) {
        b.particles.pop();
    }
    let exact = exact_bins("one particle dropped", &bins, &bin_brute_force(&s, &spec));
    // The mesh's shadow matters: case 2 (light from below the floor) without it.
    let (n, seed, light, kk, m, density) = cases()[2];
    let (s, spec) = (cloud(n, seed, density), self::spec(light, kk, m));
    let g = floor();
    let bvh = Bvh::new(&g).map_err(|e| e.to_string())?;
    let d = depth(&bvh, &camera, &options);
    let mesh = Some((&g, &bvh, d.as_slice()));
    let want = reference_frame(&s, &map, &spec, &settings, &camera, &options, mesh)?;
    let unshadowed: Vec<f32> = d.clone();
    let got = match &k {
        None => {
            let view = camera.frame(options.width, options.height);
            let v = volume::build(&s, &map, &spec, &settings, Some(&view), None)
                .map_err(|e| e.to_string())?;
            render(&v, &camera, &options, Some(&unshadowed)).map_err(|e| e.to_string())?
        }
        Some(k) => {
            let (img, _, _) = k
                .frame(&s, &map, &spec, &settings, None, &camera, &options, Some(&unshadowed))
                .map_err(|e| e.to_string())?;
            img
        }
    };
    let shadow = compare("volume-control-shadow", &got, &want, FRAME_BOUND);
    let pass = !image.pass && !exact.pass && !shadow.pass;
    Ok(Measure {
        max_error: image.max_error,
        bound: image.bound,
        pass,
        note: format!(
            "must fail all: denser frame {} ({}); dropped particle {} ({}); no mesh shadow {} ({})",
            if image.pass { "PASSED" } else { "failed" },
            image.note,
            if exact.pass { "PASSED" } else { "failed" },
            exact.note,
            if shadow.pass { "PASSED" } else { "failed" },
            shadow.note
        ),
    })
}

/// Bad input gets the CPU path's errors through the GPU entry points.
pub fn errors(backend: &Executor) -> Result<Measure, String> {
    let Some(k) = kernels(backend)? else {
        return Ok(Measure { max_error: 0.0, bound: 0.0, pass: true, note: "GPU only".into() });
    };
    let map = map();
    let spec = spec(Vec3::Y, 2, 4);
    let settings = BuildSettings::default();
    let mut s = cloud(10, 4, 1.0);
    s[3].inner = f32::NAN;
    let cpu = volume::build(&s, &map, &spec, &settings, None, None).unwrap_err().to_string();
    let gpu = k.build(&s, &map, &spec, &settings, None, None).unwrap_err().to_string();
    let s = cloud(50, 4, 1.0);
    let tight = BuildSettings { max_bytes: 1000, ..settings };
    let cpu_oom = volume::build(&s, &map, &spec, &tight, None, None).unwrap_err().to_string();
    let gpu_oom = k.build(&s, &map, &spec, &tight, None, None).unwrap_err().to_string();
    let v = k.build(&s, &map, &spec, &settings, None, None).map_err(|e| e.to_string())?;
    let cam = camera_outside();
    let bad = MarchOptions { width: 8, height: 8, step: 0.0 };
    let cv = volume::build(&s, &map, &spec, &settings, None, None).map_err(|e| e.to_string())?;
    let cpu_step = render(&cv, &cam, &bad, None).unwrap_err().to_string();
    let gpu_step = k.render(&v, &cam, &bad, None).unwrap_err().to_string();
    let ok = MarchOptions { width: 8, height: 8, step: 1.0 };
    let cpu_depth = render(&cv, &cam, &ok, Some(&[1.0; 3])).unwrap_err().to_string();
    let gpu_depth = k.render(&v, &cam, &ok, Some(&[1.0; 3])).unwrap_err().to_string();
    let pairs = [(cpu, gpu), (cpu_oom, gpu_oom), (cpu_step, gpu_step), (cpu_depth, gpu_depth)];
    let differ: Vec<String> = pairs
        .iter()
        .filter(|(a, b)| a != b)
        .map(|(a, b)| format!("cpu {a:?} vs gpu {b:?}"))
        .collect();
    Ok(Measure {
        max_error: differ.len() as f64,
        bound: 0.0,
        pass: differ.is_empty(),
        note: if differ.is_empty() {
            "NaN radius, memory budget, march step, depth length: the CPU's errors".into()
        } else {
            differ.join("; ")
        },
    })
}
