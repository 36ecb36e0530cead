//! The filtered-appearance comparison of one scene with both Adaptive selectors and the
//! predictor check, on the CPU:
//!
//! `cargo run --release -p voxlod-studies --example adaptive_selectors -- SCENE RES VIEWS SPP
//! HELDOUT_TAUS IMAGE_TAUS SAMPLES [area]` (thresholds comma-separated, e.g.
//! `builtin:bunny 64 3 128 0.1,0.2 0.02,0.05 200`; `area`: Adaptive's virtual mesh scales its
//! opacity by the projected area). Prints the tables as Markdown.

use std::time::Duration;

use voxlod_cpu::appearance::virtual_mesh::VirtualMeshParams;
use voxlod_studies::backend::Backend;
use voxlod_studies::filtered::FilteredConfig;
use voxlod_studies::report::{self, Config, SceneCase};

fn list(s: &str) -> Vec<f32> {
    s.split(',').filter(|t| !t.is_empty()).map(|t| t.parse().expect("a threshold")).collect()
}

fn main() {
    let a: Vec<String> = std::env::args().skip(1).collect();
    let arg = |i: usize, default: &str| a.get(i).cloned().unwrap_or_else(|| default.into());
    let scene = arg(0, "builtin:bunny");
    let res: u32 = arg(1, "64").parse().expect("a resolution");
    let filtered = FilteredConfig {
        resolutions: vec![res],
        higher_image: None,
        thresholds: list(&arg(4, "0.1,0.2,0.3")),
        image_thresholds: list(&arg(5, "0.02,0.05")),
        contribution_samples: arg(6, "200").parse().expect("a sample count"),
        adaptive_vmesh: VirtualMeshParams {
            projected_area: arg(7, "plain") == "area",
            ..Default::default()
        },
        ..FilteredConfig::quick()
    };
    let config = Config {
        scenes: vec![SceneCase::new(&scene, "scene")],
        resolutions: vec![res],
        image_size: res,
        gt_spp: arg(3, "128").parse().expect("rays per pixel"),
        views: arg(2, "3").parse().expect("a view count"),
        section_budget: Duration::MAX,
        filtered: Some(filtered),
        volume: None,
        cone: None,
        command: format!(
            "cargo run --release -p voxlod-studies --example adaptive_selectors -- {}",
            a.join(" ")
        ),
        ..Config::quick()
    };
    let progress = |m: &str| eprintln!("{m}");
    let outcome = report::run(&config, Backend::Cpu, &progress).expect("the comparison");
    for s in &outcome.scenes {
        if let Some(f) = &s.filtered {
            for t in f.tables(&s.label).expect("tables") {
                println!("\n{}", t.to_markdown());
            }
        }
    }
    println!("\nwall time {:.1} s", outcome.elapsed.as_secs_f64());
}
