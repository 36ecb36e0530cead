//! The light-leaking experiment: a wall of known thickness between a lit floor and a receiver
//! that sees only the wall's unlit face, so every bit of light the cones gather is leaked.

use glam::{UVec3, Vec3};
use serde::Serialize;
use voxlod_cone::{ConeTracer, Light, RadiancePayload, Shadows, TraceOptions, inject};
use voxlod_format::GridSpec;
use voxlod_octree::{AveragePayload, BuildOptions, Directional, Octree};

use crate::Error;

/// One light-leaking measurement.
#[derive(Clone, Debug, Serialize)]
pub struct LeakRow {
    /// Octree depth (grid of 2^depth voxels over the unit cube).
    pub depth: u32,
    /// Wall thickness in voxels (1/32 of the scene).
    pub wall_voxels: u32,
    /// "isotropic" or "directional".
    pub option: String,
    /// Step fraction.
    pub step: f32,
    /// Receiver's `E/π` with the wall divided by without it (truth: 0).
    pub leak: f64,
}

/// The wall scene over the unit cube at `2^depth` voxels: a floor (y = 0 layer) on `x < ½`,
/// lit from straight above, and a wall `x ∈ [½, ½ + 1/32)` across the whole cube (if `wall`);
/// its faces are vertical, so unlit. The receiver at `(¾, ¼, ½)` faces −x: it sees only the
/// wall's unlit face (truth 0), or the lit floor without the wall.
fn wall_scene(depth: u32, wall: bool) -> Result<Octree<AveragePayload>, Error> {
    let n = 1u32 << depth;
    let grid = GridSpec::new(glam::DVec3::ZERO, 1.0 / n as f64, UVec3::splat(n))?;
    let thick = (n / 32).max(1);
    let mut v = Vec::new();
    for x in 0..n / 2 {
        for z in 0..n {
            v.push((UVec3::new(x, 0, z), AveragePayload::new(Vec3::ONE, Vec3::Y, 1.0)));
        }
    }
    if wall {
        for x in n / 2..n / 2 + thick {
            let normal = if x == n / 2 { Vec3::NEG_X } else { Vec3::X };
            for y in 0..n {
                for z in 0..n {
                    v.push((UVec3::new(x, y, z), AveragePayload::new(Vec3::ONE, normal, 1.0)));
                }
            }
        }
    }
    Ok(Octree::build(grid, v, &BuildOptions { depth: Some(depth), dense_log2: 4.min(depth) })?)
}

/// The receiver's leak ratio at each octree depth and step, both opacity pre-filters.
pub(super) fn leak_experiment(depths: &[u32], steps: &[f32]) -> Result<Vec<LeakRow>, Error> {
    let light =
        Light::Directional { to_light: Vec3::Y, irradiance: Vec3::splat(std::f32::consts::PI) };
    let p = Vec3::new(0.75, 0.25, 0.5);
    let mut rows = Vec::new();
    for &depth in depths {
        let with = wall_scene(depth, true)?;
        let without = wall_scene(depth, false)?;
        for &step in steps {
            let o = TraceOptions { step_factor: step, ..TraceOptions::default() };
            let e = |t: &Octree<AveragePayload>, directional: bool| -> Result<f64, Error> {
                Ok(if directional {
                    let r: Octree<Directional<RadiancePayload>> =
                        inject(t, &light, &Shadows::None)?;
                    ConeTracer::new(&r, o)?.diffuse(p, Vec3::NEG_X).x as f64
                } else {
                    let r: Octree<RadiancePayload> = inject(t, &light, &Shadows::None)?;
                    ConeTracer::new(&r, o)?.diffuse(p, Vec3::NEG_X).x as f64
                })
            };
            for (name, directional) in [("isotropic", false), ("directional", true)] {
                let open = e(&without, directional)?;
                let leak = if open > 0.0 { e(&with, directional)? / open } else { f64::NAN };
                rows.push(LeakRow {
                    depth,
                    wall_voxels: ((1u32 << depth) / 32).max(1),
                    option: name.into(),
                    step,
                    leak,
                });
            }
        }
    }
    Ok(rows)
}
