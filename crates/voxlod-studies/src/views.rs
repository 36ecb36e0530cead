//! Viewpoints: the scene's camera orbited about a vertical axis through the scene.

use glam::{Quat, Vec3};
use voxlod_scene::Camera;

/// `n` cameras: `base`, then `n − 1` copies orbited about the vertical axis through `pivot` at
/// equal angles, each looking at `pivot`, at the same height and horizontal distance. The pivot
/// is the point of `base`'s view ray closest to `center` (the scene's bounds centre), so the
/// orbit stays on the scene even when a scene camera looks at it from far away or off-centre.
pub fn orbit_views(base: Camera, center: Vec3, n: usize) -> Vec<Camera> {
    let n = n.max(1);
    let forward = (base.target - base.eye).normalize();
    let pivot = base.eye + forward * (center - base.eye).dot(forward).max(0.0);
    (0..n)
        .map(|k| {
            if k == 0 {
                return base;
            }
            let q = Quat::from_rotation_y(std::f32::consts::TAU * k as f32 / n as f32);
            let eye = pivot + q * (base.eye - pivot);
            let up = if (pivot - eye).normalize().cross(Vec3::Y).length() < 1e-3 {
                Vec3::Z
            } else {
                Vec3::Y
            };
            Camera { eye, target: pivot, up, ..base }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn orbit_keeps_distance_and_looks_at_the_scene() {
        let base =
            Camera::look_at(Vec3::new(1.0, 2.0, 5.0), Vec3::new(1.0, 2.0, 4.0), Vec3::Y, 40.0);
        // The camera looks along -z at height 2; the scene's centre is at the origin.
        let views = orbit_views(base, Vec3::ZERO, 4);
        assert_eq!(views.len(), 4);
        assert_eq!(views[0], base);
        let pivot = Vec3::new(1.0, 2.0, 0.0);
        for v in &views[1..] {
            assert!((v.target - pivot).length() < 1e-5, "{}", v.target);
            assert!(((v.eye - pivot).length() - 5.0).abs() < 1e-4);
            assert!((v.eye.y - 2.0).abs() < 1e-5);
            v.validate().unwrap();
        }
        assert!((views[2].eye - Vec3::new(1.0, 2.0, -5.0)).length() < 1e-4, "{}", views[2].eye);
    }
}
