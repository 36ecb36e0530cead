//! Materials and textures (`voxlod_gpu::material`, what the ground truth samples at each hit)
//! against voxlod-scene's `Material::sample` / `Texture::sample`, on random textures (sizes
//! from 1×1 to 256×1 and 1×33, random RGBA8 texels, sRGB or linear, every pair of wrap modes)
//! and materials (opaque, mask with a random cutoff, blend; base colours up to 1.2 so the
//! albedo clamp is exercised), at UVs drawn to hit every branch of the exact addressing:
//! uniform in [−4, 4], texel centres and edges ± 1 ULP, tiny magnitudes down to subnormals,
//! large ones up to 2^30, and NaN/±∞.
//!
//! Bound: **every channel of the texture sample within 2^-21 of the CPU's** (albedo: 2^-20,
//! it is multiplied by a base colour ≤ 1.2), and the same mask decision unless the CPU's alpha
//! is within that bound of the cutoff. Why: decoding (tables) and addressing (integer emulation
//! of the CPU's f64) are bit for bit, so only the three lerps `a·(1−s) + b·s` can differ, by
//! whether the compiler fuses a multiply-add: ≤ 2^-24 per lerp of values in [0, 1], ≤ 2^-22
//! after three; the bound leaves a factor 2. The note counts the bit-identical samples.
//! UVs with |uv·size| ≥ 2^52 (here 1e30 and 3e38), where the kernel does not emulate the f64
//! ties, are reported apart and not bounded.
//!
//! Control, on every backend: the same queries against textures shifted by one texel along u
//! must exceed the bound (the check can fail).

use std::sync::Arc;

use glam::{Vec2, Vec4};
use voxlod_gpu::material::MaterialKernel;
use voxlod_scene::{AlphaMode, Material, Sampler, Scene, Texture, TextureRef, WrapMode};

use crate::harness::{Executor, Measure};

const TEXTURE_BOUND: f32 = 1.0 / (1 << 21) as f32;
const ALBEDO_BOUND: f32 = 1.0 / (1 << 20) as f32;

struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        // splitmix64
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }
    fn unit(&mut self) -> f32 {
        (self.next() >> 40) as f32 / (1u64 << 24) as f32
    }
    fn below(&mut self, n: u64) -> u64 {
        self.next() % n
    }
}

fn scene(rng: &mut Rng) -> Scene {
    let sizes = [(1, 1), (3, 5), (7, 2), (16, 16), (256, 1), (1, 33), (5, 5), (2, 9), (64, 3)];
    let wraps = [WrapMode::Repeat, WrapMode::ClampToEdge, WrapMode::MirroredRepeat];
    let mut textures = Vec::new();
    let mut materials = Vec::new();
    for (i, &(w, h)) in sizes.iter().enumerate() {
        let texels: Vec<[u8; 4]> =
            (0..w * h).map(|_| rng.next().to_le_bytes()[..4].try_into().unwrap()).collect();
        textures.push(Texture {
            name: format!("t{i}"),
            width: w,
            height: h,
            texels: Arc::from(texels),
            srgb: i % 2 == 0,
            sampler: Sampler { wrap_u: wraps[i % 3], wrap_v: wraps[(i / 3) % 3] },
        });
        for mode in 0..3 {
            let alpha_mode = match mode {
                0 => AlphaMode::Opaque,
                1 => AlphaMode::Mask { cutoff: rng.unit() },
                _ => AlphaMode::Blend,
            };
            let c = Vec4::new(rng.unit(), rng.unit(), rng.unit(), rng.unit()) * 1.2;
            materials.push(Material {
                name: format!("m{i}.{mode}"),
                base_color: c,
                base_color_texture: Some(TextureRef { texture: i }),
                alpha_mode,
                ..Material::default()
            });
        }
    }
    materials.push(Material::diffuse("untextured", glam::Vec3::new(0.3, 1.5, -0.1)));
    Scene { materials, textures, ..Default::default() }
}

fn coordinate(rng: &mut Rng, n: u32) -> f32 {
    let sign = if rng.below(2) == 0 { 1.0 } else { -1.0 };
    match rng.below(6) {
        0 | 1 => rng.unit() * 8.0 - 4.0,
        2 => {
            // a texel centre or edge, nudged by an ULP or not
            let k = rng.below(4 * n as u64 + 4) as f32 - 2.0;
            let x = k / (2 * n) as f32;
            match rng.below(3) {
                0 => x.next_up(),
                1 => x.next_down(),
                _ => x,
            }
        }
        3 => sign * (1.0 + rng.unit()) * 2f32.powi(-(rng.below(130) as i32) - 1),
        4 => sign * f32::from_bits(rng.below(1 << 23) as u32 + 1), // subnormal
        _ => sign * (1.0 + rng.unit()) * 2f32.powi(rng.below(30) as i32),
    }
}

fn queries(scene: &Scene, rng: &mut Rng) -> Vec<(u32, Vec2)> {
    let mut q = Vec::new();
    for _ in 0..20_000 {
        let m = rng.below(scene.materials.len() as u64) as u32;
        let n = scene.materials[m as usize].base_color_texture.map_or((1, 1), |r| {
            (scene.textures[r.texture].width, scene.textures[r.texture].height)
        });
        q.push((m, Vec2::new(coordinate(rng, n.0), coordinate(rng, n.1))));
    }
    for m in 0..scene.materials.len() as u32 {
        for uv in [
            Vec2::ZERO,
            Vec2::new(-0.0, 0.0),
            Vec2::new(f32::NAN, 0.3),
            Vec2::new(0.3, f32::INFINITY),
            Vec2::new(f32::NEG_INFINITY, 0.7),
        ] {
            q.push((m, uv));
        }
    }
    q
}

/// Beyond this |uv·size| the kernel does not emulate the CPU's f64 ties.
fn beyond_exact(scene: &Scene, m: u32, uv: Vec2) -> bool {
    let Some(r) = scene.materials[m as usize].base_color_texture else { return false };
    let t = &scene.textures[r.texture];
    (uv.x as f64 * t.width as f64).abs() >= 2f64.powi(52)
        || (uv.y as f64 * t.height as f64).abs() >= 2f64.powi(52)
}

struct Errors {
    texture: f32,
    albedo: f32,
    mask_flips_far: usize,
    mask_flips_near: usize,
    identical: usize,
}

fn compare(scene: &Scene, q: &[(u32, Vec2)], actual: &[(Vec4, Vec4)]) -> Errors {
    let mut e =
        Errors { texture: 0.0, albedo: 0.0, mask_flips_far: 0, mask_flips_near: 0, identical: 0 };
    for (&(m, uv), &(tex, sample)) in q.iter().zip(actual) {
        let mat = &scene.materials[m as usize];
        let expected_tex =
            mat.base_color_texture.map_or(Vec4::ONE, |r| scene.textures[r.texture].sample(uv));
        let s = mat.sample(&scene.textures, uv);
        if tex.to_array().map(f32::to_bits) == expected_tex.to_array().map(f32::to_bits) {
            e.identical += 1;
        }
        e.texture = e.texture.max((tex - expected_tex).abs().max_element());
        e.albedo = e.albedo.max((sample.truncate() - s.albedo).abs().max_element());
        match mat.alpha_mode {
            AlphaMode::Mask { cutoff } => {
                if sample.w != s.alpha {
                    let a = mat.base_color.w * expected_tex.w;
                    if (a - cutoff).abs() <= TEXTURE_BOUND {
                        e.mask_flips_near += 1;
                    } else {
                        e.mask_flips_far += 1;
                    }
                }
            }
            _ => e.albedo = e.albedo.max((sample.w - s.alpha).abs()),
        }
    }
    e
}

/// Every texture shifted by one texel along u (texel x takes texel x + 1's value).
fn shifted(scene: &Scene) -> Scene {
    let mut s = scene.clone();
    for t in &mut s.textures {
        let (w, h) = (t.width as usize, t.height as usize);
        let texels: Vec<[u8; 4]> =
            (0..w * h).map(|i| t.texels[(i / w) * w + (i % w + 1) % w]).collect();
        t.texels = Arc::from(texels);
    }
    s
}

fn evaluate(
    backend: &Executor,
    scene: &Scene,
    q: &[(u32, Vec2)],
) -> Result<Vec<(Vec4, Vec4)>, String> {
    match backend {
        Executor::Cpu => Ok(q
            .iter()
            .map(|&(m, uv)| {
                let mat = &scene.materials[m as usize];
                let t = mat
                    .base_color_texture
                    .map_or(Vec4::ONE, |r| scene.textures[r.texture].sample(uv));
                let s = mat.sample(&scene.textures, uv);
                (t, s.albedo.extend(s.alpha))
            })
            .collect()),
        Executor::Gpu(ctx) => {
            let k = MaterialKernel::new(ctx).map_err(|e| e.to_string())?;
            let out = k.eval(scene, q).map_err(|e| e.to_string())?;
            Ok(out.into_iter().map(|p| (p.texture, p.sample)).collect())
        }
    }
}

pub fn exact(backend: &Executor) -> Result<Measure, String> {
    let mut rng = Rng(0x5eed_7e47);
    let scene = scene(&mut rng);
    let all = queries(&scene, &mut rng);
    let (far, q): (Vec<_>, Vec<_>) =
        all.iter().copied().partition(|&(m, uv)| beyond_exact(&scene, m, uv));
    let actual = evaluate(backend, &scene, &q)?;
    let e = compare(&scene, &q, &actual);
    let far_actual = evaluate(backend, &scene, &far)?;
    let far_e = compare(&scene, &far, &far_actual);
    // Control: textures shifted by one texel, against the unshifted reference.
    let control = evaluate(backend, &shifted(&scene), &q)?;
    let c = compare(&scene, &q, &control);
    let pass = e.texture <= TEXTURE_BOUND
        && e.albedo <= ALBEDO_BOUND
        && e.mask_flips_far == 0
        && c.texture > TEXTURE_BOUND;
    let note = format!(
        "{} queries on {} textures / {} materials: worst texture error {:.2e} (bound {:.2e}), \
         albedo/alpha {:.2e} (bound {:.2e}), {} bit-identical texture samples, mask flips: {} \
         far from the cutoff (bound 0), {} within the bound of it; |uv·size| ≥ 2^52 (unbounded): \
         {} queries, worst {:.2e}; control (textures shifted one texel): worst {:.3} (must exceed \
         the bound)",
        q.len(),
        scene.textures.len(),
        scene.materials.len(),
        e.texture,
        TEXTURE_BOUND,
        e.albedo,
        ALBEDO_BOUND,
        e.identical,
        e.mask_flips_far,
        e.mask_flips_near,
        far.len(),
        far_e.texture,
        c.texture,
    );
    Ok(Measure {
        max_error: e.texture.max(e.albedo / 2.0) as f64,
        bound: TEXTURE_BOUND as f64,
        pass,
        note,
    })
}
