//! Measures each of the authors' choices ([`AuthorsChoices`]) against ours on one scene: every
//! toggle alone, paired over the same views, with MSE and SSIM against a ground truth, beside
//! the spread of the two random sources (the precompute's sampling lines and the pixel
//! pattern) for scale.
//!
//! `cargo run --release -p voxlod-studies --example authors_choices -- [SCENE] [RES] [VIEWS] [SPP]`
//! (defaults `builtin:bunny 64 4 256`); the image side equals the resolution.

use std::time::Instant;

use glam::Vec3;
use voxlod_cpu::appearance::averages::{self, AveragesGrid, AveragesNormal};
use voxlod_cpu::appearance::line_sampler::SamplingContext;
use voxlod_cpu::appearance::precompute::{PrecomputeOptions, precompute};
use voxlod_cpu::appearance::subgrid::DirectionalRule;
use voxlod_cpu::appearance::virtual_mesh::{self, ShadingFallback, VirtualMeshGrid};
use voxlod_cpu::appearance::{Appearance, AppearanceGrid, AuthorsChoices, FaceSamples, sggx};
use voxlod_cpu::raycast::Bvh;
use voxlod_cpu::render::filtered::{self, FrameCache, PixelPattern, VjkChord};
use voxlod_cpu::render::ground_truth;
use voxlod_cpu::voxelize::{self, Mode};
use voxlod_eval::compare;
use voxlod_format::GridSpec;
use voxlod_format::records::{AverageRecord, SggxRecord, VirtualMeshRecord};
use voxlod_scene::{Camera, Srgb8Image};
use voxlod_studies::views::orbit_views;

type Res<T> = Result<T, Box<dyn std::error::Error>>;

/// Per-view (MSE, SSIM).
type Scores = Vec<(f64, f64)>;

/// Per-view MSE and SSIM of `app` rendered with `choices`' render options.
fn score(
    app: &dyn Appearance,
    choices: &AuthorsChoices,
    scene: &voxlod_scene::Scene,
    views: &[Camera],
    truths: &[Srgb8Image],
    size: u32,
) -> Res<Scores> {
    let plain = filtered::Options {
        width: size,
        height: size,
        ambient: Vec3::splat(0.1),
        ..Default::default()
    };
    let options = choices.render(plain);
    let light = scene.light();
    let mut out = Vec::new();
    for (camera, truth) in views.iter().zip(truths) {
        let mut cache = FrameCache::new(app)?;
        let image = filtered::render(&mut cache, camera, &light, scene.background, &options)?;
        let m = compare(&image.to_srgb8(), truth)?;
        out.push((m.mse, m.ssim));
    }
    Ok(out)
}

/// The three grids of one precompute seed.
struct Grids {
    averages: AppearanceGrid<AverageRecord>,
    vjk: AppearanceGrid<SggxRecord>,
    vmesh: AppearanceGrid<VirtualMeshRecord>,
}

fn grids(ctx: &SamplingContext<'_>, seed: u32) -> Res<Grids> {
    let opts = PrecomputeOptions { rays: 150, seed };
    Ok(Grids {
        averages: precompute(ctx, &opts, averages::fit)?,
        vjk: precompute(ctx, &opts, sggx::fit)?,
        vmesh: precompute(ctx, &opts, virtual_mesh::fit)?,
    })
}

fn mean(v: &[f64]) -> f64 {
    v.iter().sum::<f64>() / v.len() as f64
}

fn main() -> Res<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let spec = args.first().map_or("builtin:bunny", |s| s.as_str()).to_string();
    let res: u32 = args.get(1).map_or(Ok(64), |s| s.parse())?;
    let nviews: usize = args.get(2).map_or(Ok(4), |s| s.parse())?;
    let spp: u32 = args.get(3).map_or(Ok(256), |s| s.parse())?;
    let start = Instant::now();
    let scene = voxlod_studies::scenes::load(&spec)?;
    let geometry = scene.geometry();
    let bvh = Bvh::new(&geometry)?;
    let (lo, hi) = scene.bounds()?;
    let views = orbit_views(scene.default_camera()?, (lo + hi) * 0.5, nviews);
    let gt = ground_truth::Options {
        width: res,
        height: res,
        spp,
        ambient: Vec3::splat(0.1),
        ..Default::default()
    };
    let truths: Vec<Srgb8Image> = views
        .iter()
        .map(|c| Ok(ground_truth::render(&scene, &geometry, &bvh, c, &gt)?.image.to_srgb8()))
        .collect::<Res<_>>()?;
    eprintln!("ground truth {res}² × {nviews} views at {spp} spp: {:.1?}", start.elapsed());

    let grid = GridSpec::fit(lo.as_dvec3(), hi.as_dvec3(), res)?;
    let vox = voxelize::voxelize(
        &geometry,
        &grid,
        &voxelize::Options { mode: Mode::Conservative, ..Default::default() },
    )?;
    let ctx = SamplingContext::new(&scene, &geometry, &vox)?;
    let t = Instant::now();
    let g = [grids(&ctx, 0)?, grids(&ctx, 1)?];
    eprintln!(
        "{} voxels, precompute (2 seeds × 3 methods): {:.1?}",
        ctx.voxel_count(),
        t.elapsed()
    );

    let ours = AuthorsChoices::default();
    let s = |app: &dyn Appearance, c: &AuthorsChoices| score(app, c, &scene, &views, &truths, res);
    let averages = |seed: usize, normal| AveragesGrid { grid: g[seed].averages.clone(), normal };
    let vmesh = |seed: usize, c: &AuthorsChoices| {
        VirtualMeshGrid::with_params(g[seed].vmesh.clone(), c.virtual_mesh(Default::default()))
    };
    // (method, toggle, baseline scores, toggled scores)
    let mut rows: Vec<(&str, String, Scores, Scores)> = Vec::new();

    let avg = s(&averages(0, AveragesNormal::TowardViewer), &ours)?;
    let stored = s(&averages(0, AveragesNormal::AsStored), &ours)?;
    rows.push(("Averages", "normal as stored (e)".into(), avg.clone(), stored));
    let avg_seed1 = s(&averages(1, AveragesNormal::TowardViewer), &ours)?;
    rows.push(("Averages", "precompute seed 1".into(), avg.clone(), avg_seed1));
    for seed in [0, 1] {
        let c = AuthorsChoices { pattern: PixelPattern::Jittered { seed }, ..ours };
        let j = s(&averages(0, AveragesNormal::TowardViewer), &c)?;
        rows.push(("Averages", format!("jittered pattern seed {seed}"), avg.clone(), j));
    }

    let vjk = s(&g[0].vjk, &ours)?;
    for chord in [VjkChord::CachedChord, VjkChord::CachedAlpha] {
        let c = AuthorsChoices { vjk_chord: chord, ..ours };
        rows.push(("[VJK21]", format!("{chord:?} (d)"), vjk.clone(), s(&g[0].vjk, &c)?));
    }
    rows.push(("[VJK21]", "precompute seed 1".into(), vjk.clone(), s(&g[1].vjk, &ours)?));
    for seed in [0, 1] {
        let c = AuthorsChoices { pattern: PixelPattern::Jittered { seed }, ..ours };
        rows.push((
            "[VJK21]",
            format!("jittered pattern seed {seed}"),
            vjk.clone(),
            s(&g[0].vjk, &c)?,
        ));
    }

    let vm = s(&vmesh(0, &ours), &ours)?;
    for rule in [DirectionalRule::Circles, DirectionalRule::Authors] {
        let c = AuthorsChoices { opacity_rule: rule, ..ours };
        let note = if rule == DirectionalRule::Authors { " (a)" } else { "" };
        rows.push((
            "virtual mesh",
            format!("rule {rule:?}{note}"),
            vm.clone(),
            s(&vmesh(0, &c), &c)?,
        ));
    }
    for seed in [0, 1] {
        let c = AuthorsChoices { face_samples: FaceSamples::Random { seed }, ..ours };
        rows.push((
            "virtual mesh",
            format!("40 random samples, seed {seed} (b)"),
            vm.clone(),
            s(&vmesh(0, &c), &c)?,
        ));
    }
    let c = AuthorsChoices { fallback: ShadingFallback::Unshaded, ..ours };
    rows.push(("virtual mesh", "unshaded fallback (c)".into(), vm.clone(), s(&vmesh(0, &c), &c)?));
    rows.push((
        "virtual mesh",
        "precompute seed 1".into(),
        vm.clone(),
        s(&vmesh(1, &ours), &ours)?,
    ));
    for seed in [0, 1] {
        let c = AuthorsChoices { pattern: PixelPattern::Jittered { seed }, ..ours };
        rows.push((
            "virtual mesh",
            format!("jittered pattern seed {seed}"),
            vm.clone(),
            s(&vmesh(0, &c), &c)?,
        ));
    }
    let all = AuthorsChoices::authors();
    rows.push((
        "virtual mesh",
        "all authors' choices".into(),
        vm.clone(),
        s(&vmesh(0, &all), &all)?,
    ));

    println!(
        "| method | toggle | MSE ours → toggled | ΔMSE per view (min..max) | SSIM ours → toggled | ΔSSIM per view (min..max) |"
    );
    println!("|---|---|---|---|---|---|");
    for (method, toggle, base, new) in &rows {
        let dm: Vec<f64> = base.iter().zip(new).map(|(a, b)| b.0 - a.0).collect();
        let ds: Vec<f64> = base.iter().zip(new).map(|(a, b)| b.1 - a.1).collect();
        let lo_hi = |v: &[f64]| {
            let (lo, hi) = v.iter().fold((f64::MAX, f64::MIN), |(l, h), &x| (l.min(x), h.max(x)));
            format!("{lo:+.2e}..{hi:+.2e}")
        };
        let m = |v: &[(f64, f64)], k: usize| {
            mean(&v.iter().map(|p| if k == 0 { p.0 } else { p.1 }).collect::<Vec<_>>())
        };
        println!(
            "| {method} | {toggle} | {:.3e} → {:.3e} | {} | {:.4} → {:.4} | {} |",
            m(base, 0),
            m(new, 0),
            lo_hi(&dm),
            m(base, 1),
            m(new, 1),
            lo_hi(&ds)
        );
    }
    eprintln!("total {:.1?}", start.elapsed());
    Ok(())
}
