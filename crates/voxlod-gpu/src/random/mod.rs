//! The counter-based RNG on the GPU: [`WGSL`] is voxlod-cpu's [`voxlod_cpu::random`] (PCG3D and
//! the 24-bit float) in WGSL, included by every kernel that draws random numbers, so that both
//! backends draw the same numbers. Integer arithmetic: equal bit for bit, which
//! [`RandomKernel`] lets the equivalence suite check on each adapter.
//!
//! On a real GPU PCG3D is 9 multiply-adds and 3 shifts per call, no memory traffic: free next
//! to the ray traversal that consumes it.

use crate::{Context, Result};

/// The WGSL functions `pcg3d`, `rand_u32` and `rand_f32`.
pub const WGSL: &str = include_str!("random.wgsl");

/// The test kernel: [`WGSL`] followed by an entry point evaluating it on a list of counters.
pub const KERNEL_WGSL: &str = concat!(include_str!("random.wgsl"), include_str!("kernel.wgsl"));

/// The test kernel's parameters (mirrors WGSL `Params`).
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
pub struct GpuRandomParams {
    /// `x` = number of counters.
    pub counts: [u32; 4],
}

/// One result of [`RandomKernel::eval`]: `pcg3d(id, sample, dim)` and the bits of
/// `rand_f32(id, sample, dim)`.
pub type RandomOutput = [u32; 4];

/// The RNG evaluated on the GPU, compiled for one [`Context`].
pub struct RandomKernel<'a> {
    ctx: &'a Context,
    pipeline: wgpu::ComputePipeline,
}

impl<'a> RandomKernel<'a> {
    /// Compiles the kernel.
    pub fn new(ctx: &'a Context) -> Result<Self> {
        Ok(Self { ctx, pipeline: ctx.pipeline("random", KERNEL_WGSL)? })
    }

    /// `[pcg3d(c)[0], pcg3d(c)[1], pcg3d(c)[2], rand_f32(c).to_bits()]` for every counter
    /// `c = (id, sample, dim)`.
    pub fn eval(&self, counters: &[[u32; 3]]) -> Result<Vec<RandomOutput>> {
        let ctx = self.ctx;
        if counters.is_empty() {
            return Ok(Vec::new());
        }
        let inputs: Vec<[u32; 4]> = counters.iter().map(|c| [c[0], c[1], c[2], 0]).collect();
        let n = inputs.len() as u64;
        let params = GpuRandomParams { counts: [n as u32, 0, 0, 0] };
        if n > u32::MAX as u64 {
            return Err(crate::Error::TooLarge {
                what: "counters",
                requested: n,
                limit: u32::MAX as u64,
            });
        }
        let uniform = ctx.uniform("random params", bytemuck::bytes_of(&params))?;
        let input = ctx.storage_init("random counters", bytemuck::cast_slice(&inputs))?;
        let bytes = n * 16;
        let output = ctx.storage_zeroed("random outputs", bytes)?;
        let (x, y) = ctx.dispatch_size("random workgroups", n.div_ceil(64))?;
        let buffers = [&uniform, &input, &output];
        ctx.dispatch("drawing random numbers", &self.pipeline, &buffers, (x, y))?;
        Ok(bytemuck::cast_slice(&ctx.read(&output, bytes)?).to_vec())
    }
}

#[cfg(test)]
mod tests {
    use std::mem::offset_of;

    use super::*;
    use crate::layout::assert_mirrors;

    #[test]
    fn random_types_mirror_their_wgsl() {
        assert_mirrors(
            KERNEL_WGSL,
            "Params",
            size_of::<GpuRandomParams>(),
            &[("counts", offset_of!(GpuRandomParams, counts))],
        );
    }
}
