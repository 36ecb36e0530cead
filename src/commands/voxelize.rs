//! `voxlod voxelize`.

use std::time::Instant;

use anyhow::{Context, Result, bail};
use voxlod::cpu::voxelize::{self, Mode};
use voxlod::format::{GridSpec, Occupancy, binvox, vxl};

use super::{Ui, backend, load_scene, print_json};
use crate::cli::{ModeArg, VoxelizeArgs};

#[derive(serde::Serialize)]
struct Summary {
    scene: String,
    triangles: usize,
    mode: &'static str,
    dims: [u32; 3],
    voxel_size: f64,
    origin: [f64; 3],
    scene_origin: [f64; 3],
    voxels: usize,
    bricks: usize,
    seconds: f64,
    backend: String,
    output: String,
}

/// Voxelizes a scene and writes a .vxl or .binvox file.
pub fn voxelize(ui: &Ui, args: VoxelizeArgs) -> Result<()> {
    let ext = args.output.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase);
    if !matches!(ext.as_deref(), Some("vxl" | "binvox")) {
        bail!("output {} must end in .vxl or .binvox", args.output.display());
    }
    let gpu = backend(args.backend)?;
    let backend_name = super::on(&gpu).describe();
    let spinner = ui.spinner();
    spinner.set_message(format!("loading {}", args.scene));
    let scene = load_scene(&args.scene)?;
    let geometry = scene.geometry();
    let (lo, hi) = scene.bounds()?;
    let grid = GridSpec::fit(lo.as_dvec3(), hi.as_dvec3(), args.res)
        .with_context(|| format!("fitting a {}³ grid to the scene", args.res))?;
    let (mode, mode_name) = match args.mode {
        ModeArg::Conservative => (Mode::Conservative, "conservative"),
        ModeArg::Thin => (Mode::Thin, "thin"),
        ModeArg::Solid => (Mode::Solid, "solid"),
    };
    spinner.set_message(format!(
        "voxelizing {} triangles into {}",
        geometry.triangle_count(),
        grid.dims
    ));
    let start = Instant::now();
    let occupancy = match &gpu {
        None => {
            let options = voxelize::Options { mode, triangle_lists: false, ..Default::default() };
            let vox = voxelize::voxelize(&geometry, &grid, &options).context("voxelizing")?;
            vox.voxels.map(|_| Occupancy)
        }
        Some(ctx) => {
            let kernel = voxlod::gpu::voxelize::Voxelizer::new(ctx)?;
            let options = voxlod::gpu::voxelize::VoxelizeOptions { mode, counts: false };
            let vox =
                kernel.voxelize(&geometry, &grid, &options).context("voxelizing on the GPU")?;
            vox.to_brick_map()?.map(|_| Occupancy)
        }
    };
    let seconds = start.elapsed().as_secs_f64();
    // The scene voxelizes in its local coordinates; files keep the grid's world origin in f64.
    let grid = GridSpec { origin: grid.origin + scene.origin, ..grid };
    spinner.set_message(format!("writing {}", args.output.display()));
    let written = if ext.as_deref() == Some("vxl") {
        let meta = [
            ("scene".to_string(), args.scene.clone()),
            ("mode".to_string(), mode_name.to_string()),
            ("triangles".to_string(), geometry.triangle_count().to_string()),
            ("generator".to_string(), format!("voxlod {}", env!("CARGO_PKG_VERSION"))),
        ];
        vxl::write(&args.output, &grid, &occupancy, &meta)
    } else {
        binvox::write(&args.output, &grid, &occupancy)
    };
    written.with_context(|| format!("writing {}", args.output.display()))?;
    spinner.finish_and_clear();
    let summary = Summary {
        scene: args.scene,
        triangles: geometry.triangle_count(),
        mode: mode_name,
        dims: grid.dims.to_array(),
        voxel_size: grid.voxel_size,
        origin: grid.origin.to_array(),
        scene_origin: scene.origin.to_array(),
        voxels: occupancy.len(),
        bricks: occupancy.bricks().len(),
        seconds,
        backend: backend_name,
        output: args.output.display().to_string(),
    };
    if args.json {
        return print_json("voxelize", &summary);
    }
    println!("backend: {}", summary.backend);
    println!(
        "{} ({} triangles) → {} voxels ({} mode) in a {}×{}×{} grid of {} bricks, {:.3} s → {}",
        summary.scene,
        summary.triangles,
        summary.voxels,
        summary.mode,
        summary.dims[0],
        summary.dims[1],
        summary.dims[2],
        summary.bricks,
        summary.seconds,
        summary.output
    );
    if scene.origin != glam::DVec3::ZERO {
        println!(
            "  re-centred: scene origin {}, grid origin {} (world coordinates, f64)",
            scene.origin, grid.origin
        );
    }
    Ok(())
}
