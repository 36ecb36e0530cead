//! Lists the wgpu adapters voxlod-gpu can use and the one `Context::new` picks
//! (`VOXLOD_ADAPTER` = an index or a name substring overrides the default preference).
//! Exits with status 1 when there is none. `cargo xtask test` runs this first.

use std::process::ExitCode;

fn main() -> ExitCode {
    let found = voxlod_gpu::adapters();
    println!("GPU adapters found: {}", found.len());
    for a in &found {
        println!("  {a}");
    }
    if found.is_empty() {
        eprintln!("!!!!!!!! NO GPU ADAPTER FOUND !!!!!!!!");
        eprintln!(
            "the GPU kernels cannot run or be checked; on Linux without a GPU install Mesa's"
        );
        eprintln!("lavapipe (apt-get install mesa-vulkan-drivers)");
        return ExitCode::FAILURE;
    }
    match voxlod_gpu::Context::new() {
        Ok(ctx) => {
            println!("using: {}", ctx.summary());
            let l = ctx.limits();
            println!(
                "  limits: storage binding {} B, buffer {} B, workgroups per dimension {}",
                l.max_storage_buffer_binding_size,
                l.max_buffer_size,
                l.max_compute_workgroups_per_dimension
            );
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("cannot open the selected adapter: {e}");
            ExitCode::FAILURE
        }
    }
}
