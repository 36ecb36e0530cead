//! The cone benchmarks' scene, shared by `benches/cone.rs` and `examples/cone_work.rs`: a
//! closed 64³ room (1-voxel walls, floor, ceiling) with a 16³ block in it, and the shading
//! points of a pinhole camera inside it.

use glam::{DVec3, UVec3, Vec3};
use rayon::prelude::*;
use voxlod_cone::{Cone, March, trace};
use voxlod_format::GridSpec;
use voxlod_octree::{AveragePayload, BuildOptions, Octree};

pub const EYE: Vec3 = Vec3::new(32.0, 40.0, 60.0);

pub const N: u32 = 64;

pub fn room() -> Octree<AveragePayload> {
    let mut v = Vec::new();
    for x in 0..N {
        for y in 0..N {
            for z in 0..N {
                let wall = [x, y, z].iter().any(|&c| c == 0 || c == N - 1);
                let block = (24..40).contains(&x) && y < 17 && (24..40).contains(&z);
                if !(wall || block) {
                    continue;
                }
                let c = Vec3::new(x as f32, y as f32, z as f32) - (N as f32 - 1.0) * 0.5;
                let n = if block {
                    Vec3::Y
                } else {
                    // inward normal of the nearest wall
                    let a = c.abs();
                    if a.x >= a.y && a.x >= a.z {
                        Vec3::new(-c.x.signum(), 0.0, 0.0)
                    } else if a.y >= a.z {
                        Vec3::new(0.0, -c.y.signum(), 0.0)
                    } else {
                        Vec3::new(0.0, 0.0, -c.z.signum())
                    }
                };
                let albedo = if x == 0 { Vec3::new(0.8, 0.1, 0.1) } else { Vec3::splat(0.7) };
                v.push((UVec3::new(x, y, z), AveragePayload::new(albedo, n, 1.0)));
            }
        }
    }
    let grid = GridSpec::new(DVec3::ZERO, 1.0, UVec3::splat(N)).unwrap();
    Octree::build(grid, v, &BuildOptions::default()).unwrap()
}

/// Shading points of a `w × h` pinhole camera inside the room (first level-0 hit of each ray).
pub fn shading_points(geometry: &Octree<AveragePayload>, w: u32, h: u32) -> Vec<(Vec3, Vec3)> {
    let eye = EYE;
    let target = Vec3::new(32.0, 16.0, 32.0);
    let f = (target - eye).normalize();
    let r = f.cross(Vec3::Y).normalize();
    let u = r.cross(f);
    let tan = 35f32.to_radians().tan();
    (0..w * h)
        .into_par_iter()
        .map(|i| {
            let (x, y) = ((i % w) as f32 + 0.5, (i / w) as f32 + 0.5);
            let sx = (2.0 * x / w as f32 - 1.0) * tan * w as f32 / h as f32;
            let sy = (1.0 - 2.0 * y / h as f32) * tan;
            let dir = (f + r * sx + u * sy).normalize();
            let march = March {
                start_voxels: 0.0,
                step_factor: 0.5,
                max_distance: f32::INFINITY,
                opacity_cutoff: 0.5,
                ao: None,
            };
            let hit = trace(geometry, &Cone { apex: eye, dir, aperture: 0.0 }, &march);
            // The march stops half a step past where opacity reached 0.5: step back a voxel.
            let t = (hit.steps as f32) * 0.5 - 1.0;
            let p = eye + dir * t;
            let n = geometry.sample(p, 1.0).normal();
            (p, if n == Vec3::ZERO { -dir } else { n })
        })
        .collect()
}
