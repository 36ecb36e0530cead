//! The one shading function of voxlod. The ground truth and every voxel renderer, on both
//! backends, call [`shade`] so that an error measures a representation, not a shading
//! difference.

use std::f32::consts::PI;

use glam::Vec3;
use voxlod_scene::{LightSample, MaterialSample};

/// Outgoing radiance at a surface point:
///
/// `albedo/π · E · max(n·l, 0) · visibility`
/// `+ specular · (s+8)/(8π) · max(n·h, 0)^s · E · max(n·l, 0) · visibility` (normalized
/// Blinn-Phong, only where `specular > 0`)
/// `+ albedo · ambient`
///
/// `n` is the unit shading normal (the caller flips it toward the viewer for double-sided
/// materials), `v` the unit direction toward the viewer, `light` the light seen from the point
/// and `visibility` its shadow-ray visibility in [0, 1]. The result is finite for any finite
/// input, including `n·l = 0` and `h = 0` (light exactly behind the viewer's mirror direction).
#[inline]
pub fn shade(
    m: &MaterialSample,
    n: Vec3,
    v: Vec3,
    light: &LightSample,
    visibility: f32,
    ambient: Vec3,
) -> Vec3 {
    let l = light.to_light;
    let ndl = n.dot(l).max(0.0);
    let direct = light.irradiance * (ndl * visibility);
    let mut radiance = m.albedo * (1.0 / PI) * direct + m.albedo * ambient;
    if m.specular.max_element() > 0.0 && ndl > 0.0 {
        let h = (l + v).normalize_or_zero();
        let ndh = n.dot(h).max(0.0);
        let norm = (m.shininess + 8.0) / (8.0 * PI);
        radiance += m.specular * (norm * ndh.powf(m.shininess)) * direct;
    }
    radiance
}

#[cfg(test)]
mod tests {
    use super::*;

    fn white() -> MaterialSample {
        MaterialSample { albedo: Vec3::ONE, alpha: 1.0, specular: Vec3::ZERO, shininess: 0.0 }
    }

    fn light(dir: Vec3) -> LightSample {
        LightSample {
            to_light: dir.normalize(),
            distance: f32::INFINITY,
            irradiance: Vec3::splat(PI),
        }
    }

    #[test]
    fn lambert_facing_light_is_albedo_times_irradiance_over_pi() {
        let r = shade(&white(), Vec3::Y, Vec3::Y, &light(Vec3::Y), 1.0, Vec3::ZERO);
        assert!((r - Vec3::ONE).abs().max_element() < 1e-6, "{r}");
        let r =
            shade(&white(), Vec3::Y, Vec3::Y, &light(Vec3::new(1.0, 1.0, 0.0)), 1.0, Vec3::ZERO);
        assert!((r.x - std::f32::consts::FRAC_1_SQRT_2).abs() < 1e-6);
        let r = shade(&white(), Vec3::Y, Vec3::Y, &light(Vec3::NEG_Y), 1.0, Vec3::splat(0.1));
        assert_eq!(r, Vec3::splat(0.1));
        let r = shade(&white(), Vec3::Y, Vec3::Y, &light(Vec3::Y), 0.0, Vec3::ZERO);
        assert_eq!(r, Vec3::ZERO);
    }

    #[test]
    fn specular_peaks_at_the_mirror_direction_and_stays_finite() {
        let m = MaterialSample { specular: Vec3::splat(0.5), shininess: 64.0, ..white() };
        let l = light(Vec3::new(1.0, 1.0, 0.0));
        let mirror = shade(&m, Vec3::Y, Vec3::new(-1.0, 1.0, 0.0).normalize(), &l, 1.0, Vec3::ZERO);
        let off = shade(&m, Vec3::Y, Vec3::new(1.0, 0.2, 0.0).normalize(), &l, 1.0, Vec3::ZERO);
        assert!(mirror.x > off.x * 2.0, "{mirror} vs {off}");
        // v = -l: the half vector is zero.
        let degenerate = shade(&m, Vec3::Y, -l.to_light, &l, 1.0, Vec3::ZERO);
        assert!(degenerate.is_finite());
        let huge = MaterialSample { shininess: 1e6, ..m };
        assert!(shade(&huge, Vec3::Y, Vec3::Y, &l, 1.0, Vec3::ZERO).is_finite());
    }
}
