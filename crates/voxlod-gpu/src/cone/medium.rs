//! The payloads the kernel marches through ([`GpuMedium`]): voxlod-cone's and voxlod-octree's
//! payload types converted to the kernel's isotropic or directional records.

use voxlod_cone::{ConeMedium, RadiancePayload};
use voxlod_octree::{AveragePayload, Directional};

use super::params::{GpuDirectionalRadiance, GpuRadiance};

/// A payload the kernel can march through (see the module docs for the list).
pub trait GpuMedium: ConeMedium {
    /// Whether it carries six directional opacities.
    const DIRECTIONAL: bool;
    /// The payloads as the kernel's buffer.
    fn gpu_bytes(payload: &[Self]) -> Vec<u8>;
}

fn isotropic(radiance_alpha: [f32; 3], opacity: f32) -> GpuRadiance {
    GpuRadiance { radiance_alpha, opacity }
}

fn directional(radiance_alpha: [f32; 3], opacity: f32, o: &[f32; 6]) -> GpuDirectionalRadiance {
    GpuDirectionalRadiance {
        radiance_alpha,
        opacity,
        plus: [o[0], o[2], o[4]],
        pad0: 0.0,
        minus: [o[1], o[3], o[5]],
        pad1: 0.0,
    }
}

impl GpuMedium for RadiancePayload {
    const DIRECTIONAL: bool = false;
    fn gpu_bytes(payload: &[Self]) -> Vec<u8> {
        let v: Vec<GpuRadiance> =
            payload.iter().map(|p| isotropic(p.radiance_alpha, p.opacity)).collect();
        bytemuck::cast_slice(&v).to_vec()
    }
}

impl GpuMedium for AveragePayload {
    const DIRECTIONAL: bool = false;
    fn gpu_bytes(payload: &[Self]) -> Vec<u8> {
        let v: Vec<GpuRadiance> = payload.iter().map(|p| isotropic([0.0; 3], p.opacity)).collect();
        bytemuck::cast_slice(&v).to_vec()
    }
}

impl GpuMedium for Directional<RadiancePayload> {
    const DIRECTIONAL: bool = true;
    fn gpu_bytes(payload: &[Self]) -> Vec<u8> {
        let v: Vec<GpuDirectionalRadiance> = payload
            .iter()
            .map(|p| directional(p.inner.radiance_alpha, p.inner.opacity, &p.opacity))
            .collect();
        bytemuck::cast_slice(&v).to_vec()
    }
}

impl GpuMedium for Directional<AveragePayload> {
    const DIRECTIONAL: bool = true;
    fn gpu_bytes(payload: &[Self]) -> Vec<u8> {
        let v: Vec<GpuDirectionalRadiance> =
            payload.iter().map(|p| directional([0.0; 3], p.inner.opacity, &p.opacity)).collect();
        bytemuck::cast_slice(&v).to_vec()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn directional_opacities_are_regrouped_plus_then_minus() {
        let d = directional([1.0, 2.0, 3.0], 0.5, &[0.1, 0.2, 0.3, 0.4, 0.5, 0.6]);
        assert_eq!((d.plus, d.minus), ([0.1, 0.3, 0.5], [0.2, 0.4, 0.6]));
    }
}
