//! The counter-based RNG: PCG3D and the 24-bit float, **exact** (integer arithmetic).
//!
//! Oracle: PCG3D written here independently in `u64` arithmetic reduced mod 2^32 (not the
//! wrapping `u32` calls of voxlod-cpu), on counters at the edges (0, 1, 2^31, 2^32 − 1, the
//! stream keys of seeds 0..4) and on 4096 pseudo-random ones. Error: the number of counters
//! whose four words (`pcg3d` × 3, `rand_f32` bits) differ; bound 0.

use voxlod_cpu::random::{pcg3d, rand_f32};
use voxlod_cpu::render::pixel_samples::Streams;
use voxlod_gpu::random::RandomKernel;

use crate::harness::{Executor, Measure};

fn oracle(c: [u32; 3]) -> [u32; 4] {
    const M: u64 = 0xffff_ffff;
    let mut v = c.map(|x| (x as u64 * 1_664_525 + 1_013_904_223) & M);
    let mix = |v: &mut [u64; 3]| {
        v[0] = (v[0] + v[1] * v[2]) & M;
        v[1] = (v[1] + v[2] * v[0]) & M;
        v[2] = (v[2] + v[0] * v[1]) & M;
    };
    mix(&mut v);
    for x in &mut v {
        *x ^= *x >> 16;
    }
    mix(&mut v);
    let f = (v[0] >> 8) as f64 / 16_777_216.0;
    [v[0] as u32, v[1] as u32, v[2] as u32, (f as f32).to_bits()]
}

fn counters() -> Vec<[u32; 3]> {
    let edges = [0, 1, 2, 0x5EED, 1 << 31, u32::MAX - 1, u32::MAX];
    let mut out = Vec::new();
    for &a in &edges {
        for &b in &edges {
            for &c in &edges {
                out.push([a, b, c]);
            }
        }
    }
    for seed in 0..4 {
        let s = Streams::new(seed);
        for key in [s.jitter_x, s.jitter_y, s.alpha_primary, s.alpha_shadow] {
            out.push([seed, 7, key]);
        }
    }
    let mut x = 0x9E37_79B9u32;
    for _ in 0..4096 {
        let mut next = || {
            x ^= x << 13;
            x ^= x >> 17;
            x ^= x << 5;
            x
        };
        out.push([next(), next(), next()]);
    }
    out
}

pub fn exact(backend: &Executor) -> Result<Measure, String> {
    let inputs = counters();
    let actual: Vec<[u32; 4]> = match backend {
        Executor::Cpu => inputs
            .iter()
            .map(|&[a, b, c]| {
                let v = pcg3d(a, b, c);
                [v[0], v[1], v[2], rand_f32(a, b, c).to_bits()]
            })
            .collect(),
        Executor::Gpu(ctx) => {
            RandomKernel::new(ctx).and_then(|k| k.eval(&inputs)).map_err(|e| e.to_string())?
        }
    };
    let wrong: Vec<usize> = (0..inputs.len()).filter(|&i| actual[i] != oracle(inputs[i])).collect();
    let mut note = format!("{} counters", inputs.len());
    if let Some(&i) = wrong.first() {
        note += &format!(
            "; first wrong: {:?} gave {:?}, oracle {:?}",
            inputs[i],
            actual[i],
            oracle(inputs[i])
        );
    }
    Ok(Measure { max_error: wrong.len() as f64, bound: 0.0, pass: wrong.is_empty(), note })
}
