//! The oracle both backends answer to: independent `f64` sampling lines of each voxel (see
//! the parent module's docs).

use glam::{DVec3, Vec3};
use voxlod_cpu::appearance::line_sampler::{blend_key, dimension_base, sample_line};
use voxlod_cpu::appearance::voxel_samples::{RaySample, SurfaceSample, VoxelSamples};
use voxlod_cpu::appearance::{averages, subgrid};
use voxlod_cpu::random::rand_f32;
use voxlod_gpu::precompute::LineCase;
use voxlod_scene::{AlphaMode, Geometry, Scene};

use super::{Answer, Case};

/// Whether the oracle counts a hit at barycentrics `(u, v)` on triangle `tri` of material
/// `material` for line `ray` of voxel `id` (the sampler's alpha rules, on `scene`'s materials:
/// `Mask` where the alpha at the interpolated UV is > 0, `Blend` where the line's blend number
/// is below it).
#[allow(clippy::too_many_arguments)]
pub(super) fn oracle_accepts(
    scene: &Scene,
    geometry: &Geometry,
    tri: u32,
    u: f64,
    v: f64,
    id: u32,
    ray: u32,
    seed: u32,
) -> bool {
    let material = geometry.materials[tri as usize];
    let mode = scene.materials[material as usize].alpha_mode;
    if mode == AlphaMode::Opaque {
        return true;
    }
    let (_, uv) = geometry.interpolate(tri as usize, u as f32, v as f32);
    let alpha = scene.material_sample(material, uv).alpha;
    match mode {
        AlphaMode::Blend => rand_f32(id, ray, blend_key(seed) ^ tri) < alpha,
        _ => alpha > 0.0,
    }
}

/// The oracle's lines of one voxel (module docs), with `scene`'s materials.
pub(super) fn oracle_voxel(
    c: &Case,
    scene: &Scene,
    i: usize,
    seed: u32,
) -> (VoxelSamples, Vec<(LineCase, u32)>) {
    let grid = &c.vox.grid;
    let coord = c.vox.voxels.coords().nth(i).expect("voxel");
    let min = grid.voxel_min(coord);
    let inv = 1.0 / grid.voxel_size;
    let local = |p: Vec3| (p.as_dvec3() - min) * inv;
    let d = grid.dims;
    let id =
        coord.x.wrapping_add(d.x.wrapping_mul(coord.y.wrapping_add(d.y.wrapping_mul(coord.z))));
    let tris: Vec<_> = c
        .vox
        .triangles_of(i)
        .iter()
        .filter_map(|&t| {
            let [a, b, cc] = c.geometry.triangle(t as usize);
            let (la, lb, lc) = (local(a), local(b), local(cc));
            let (e1, e2) = (lb - la, lc - la);
            let area2 = e1.cross(e2).length_squared();
            (area2 > 0.0).then_some((t, la, lb, lc, (b - a).cross(cc - a).as_dvec3()))
        })
        .collect();
    let mut samples = VoxelSamples::default();
    let mut cases = Vec::new();
    for r in 0..c.opts.rays {
        let (dir, entry, chord) = sample_line(id, r, dimension_base(seed));
        let (e, dd) = (entry.as_dvec3(), dir.as_dvec3());
        let mut best: Option<(f64, f64, f64, usize)> = None;
        for (k, &(tri, a, b, cc, _)) in tris.iter().enumerate() {
            let (e1, e2) = (b - a, cc - a);
            let p = dd.cross(e2);
            let det = e1.dot(p);
            if det == 0.0 {
                continue;
            }
            let inv_det = 1.0 / det;
            let tv = e - a;
            let u = tv.dot(p) * inv_det;
            let q = tv.cross(e1);
            let v = dd.dot(q) * inv_det;
            let t = e2.dot(q) * inv_det;
            // The closest accepted hit: a hit the alpha rejects does not occlude.
            if u >= 0.0
                && v >= 0.0
                && u + v <= 1.0
                && best.is_none_or(|bt| t < bt.0)
                && oracle_accepts(scene, &c.geometry, tri, u, v, id, r, seed)
            {
                best = Some((t, u, v, k));
            }
        }
        let mut ray = RaySample { dir, entry, chord, occluded: false, surface: None };
        let mut result = (LineCase::Miss, u32::MAX);
        if let Some((t, u, v, k)) = best {
            let (tri, a, b, cc, ng) = tris[k];
            ray.occluded = true;
            result = (LineCase::Occluded, tri);
            let mut p = e + dd * t;
            // The voxel-face tie rule is defined on the f32 local vertices (a triangle within
            // f32 rounding of a voxel face lies on it): applied here the same way.
            let (fa, fb, fc) = (a.as_vec3(), b.as_vec3(), cc.as_vec3());
            for j in 0..3 {
                if fa[j] == fb[j] && fa[j] == fc[j] {
                    p[j] = fa[j] as f64;
                }
            }
            let inside = p.cmpge(DVec3::ZERO).all() && p.cmple(DVec3::ONE).all();
            let material = c.geometry.materials[tri as usize];
            let ds = scene.materials[material as usize].double_sided;
            let facing = ng.dot(dd);
            if inside && (ds || facing < 0.0) {
                let (mut normal, uv) = c.geometry.interpolate(tri as usize, u as f32, v as f32);
                if ds && facing > 0.0 {
                    normal = -normal;
                }
                let m = scene.material_sample(material, uv);
                ray.surface = Some(SurfaceSample {
                    point: p.as_vec3(),
                    normal,
                    albedo: m.albedo,
                    specular: (m.specular.x + m.specular.y + m.specular.z) * (1.0 / 3.0),
                    shininess: m.shininess,
                });
                result.0 = LineCase::Surface;
            }
        }
        samples.rays.push(ray);
        cases.push(result);
    }
    (samples, cases)
}

/// The oracle's answer for `c` with `scene`'s materials (the case's own, or a control's
/// perturbed ones).
pub(super) fn oracle(c: &Case, scene: &Scene) -> Answer {
    let n = c.vox.voxels.len();
    let mut out =
        Answer { lines: Vec::new(), records: Vec::new(), subgrids: Vec::new(), line_bits: None };
    for i in 0..n {
        let (s, cases) = oracle_voxel(c, scene, i, c.opts.seed);
        out.records.push(averages::fit(&s));
        out.subgrids.push(subgrid::build(&s));
        out.lines.push(cases);
    }
    out
}
