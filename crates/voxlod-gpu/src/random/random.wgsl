// The counter-based RNG of voxlod-cpu's random.rs, bit for bit: PCG3D (Jarzynski & Olano
// 2020) on u32 arithmetic, which WGSL defines as wrapping, like Rust's wrapping_* calls.

fn pcg3d(x: u32, y: u32, z: u32) -> vec3<u32> {
    var v = vec3<u32>(x, y, z) * 1664525u + 1013904223u;
    v.x += v.y * v.z;
    v.y += v.z * v.x;
    v.z += v.x * v.y;
    v ^= v >> vec3<u32>(16u);
    v.x += v.y * v.z;
    v.y += v.z * v.x;
    v.z += v.x * v.y;
    return v;
}

fn rand_u32(id: u32, sample: u32, dim: u32) -> u32 {
    return pcg3d(id, sample, dim).x;
}

// A float in [0, 1) with 24 random bits: exact (a 24-bit integer times 2^-24).
fn rand_f32(id: u32, sample: u32, dim: u32) -> f32 {
    return f32(rand_u32(id, sample, dim) >> 8u) * (1.0 / 16777216.0);
}
