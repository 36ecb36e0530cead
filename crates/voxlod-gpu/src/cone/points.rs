//! Host-side shading inputs and results: [`ShadingPoint`] (from a G-buffer) and its upload
//! record, [`ConeQuery`], [`ConeShade`], and the CPU reference of one point.

use glam::Vec3;
use voxlod_cone::{ConeMedium, ConeTracer};
use voxlod_cpu::render::ground_truth::GBuffer;

use super::params::GpuPoint;

/// A shading point: what a G-buffer texel gives the tracer.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ShadingPoint {
    /// World position.
    pub position: Vec3,
    /// Surface normal (need not be unit; zero or non-finite: no cones).
    pub normal: Vec3,
    /// Direction toward the viewer, for the specular cone (need not be unit).
    pub to_viewer: Vec3,
    /// Glossiness in \[0, 1\] (clamped; NaN → 0) for the specular aperture.
    pub glossiness: f32,
}

impl ShadingPoint {
    /// The shading points of a G-buffer seen from `eye`, with one glossiness for all: a miss
    /// (triangle `u32::MAX`) gets a zero normal, so no cones (AO 1, no radiance), as
    /// `voxlod cone` treats misses.
    pub fn from_gbuffer(gb: &GBuffer, eye: Vec3, glossiness: f32) -> Vec<Self> {
        gb.texels
            .iter()
            .map(|t| {
                if t.triangle == u32::MAX {
                    ShadingPoint::default()
                } else {
                    ShadingPoint {
                        position: t.position,
                        normal: t.normal,
                        to_viewer: eye - t.position,
                        glossiness,
                    }
                }
            })
            .collect()
    }

    pub(super) fn gpu(&self) -> GpuPoint {
        let ok = self.position.is_finite() && self.normal.try_normalize().is_some();
        let view = self.to_viewer.try_normalize().is_some();
        let g = if self.glossiness.is_nan() { 0.0 } else { self.glossiness.clamp(0.0, 1.0) };
        let keep = |v: Vec3, k: bool| if k { v.to_array() } else { [0.0; 3] };
        GpuPoint {
            position: keep(self.position, ok),
            glossiness: g,
            normal: keep(self.normal, ok),
            flags: u32::from(ok) | if view { 2 } else { 0 },
            to_viewer: keep(self.to_viewer, view),
            pad: 0,
        }
    }
}

/// Which cones to trace.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ConeQuery {
    /// Ambient occlusion from the diffuse cones.
    pub ambient_occlusion: bool,
    /// Diffuse indirect light `E/π` from the same cones.
    pub diffuse: bool,
    /// The specular cone.
    pub specular: bool,
}

impl ConeQuery {
    /// Everything.
    pub const ALL: Self = Self { ambient_occlusion: true, diffuse: true, specular: true };
    pub(super) fn bits(self) -> u32 {
        u32::from(self.ambient_occlusion)
            | if self.diffuse { 2 } else { 0 }
            | if self.specular { 4 } else { 0 }
    }
}

/// What one shading point gathered.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ConeShade {
    /// Ambient occlusion in \[0, 1\] (1 when not asked for, or no cones).
    pub ao: f32,
    /// `E/π` from the diffuse cones (what their marches gathered, also when only AO is asked
    /// for, as [`ConeTracer::ao_and_diffuse`] returns it).
    pub diffuse: Vec3,
    /// Radiance along the specular cone (zero when not asked for).
    pub specular: Vec3,
    /// The specular cone's accumulated opacity.
    pub specular_opacity: f32,
    /// Octree samples of the diffuse cones.
    pub diffuse_steps: u32,
    /// Octree samples of the specular cone.
    pub specular_steps: u32,
}

/// The CPU reference of one shading point: exactly what the kernel computes, through
/// [`ConeTracer`] ([`ConeTracer::ao_and_diffuse`] when AO or diffuse is asked for,
/// [`ConeTracer::specular`] when specular is).
pub fn reference<M: ConeMedium>(
    tracer: &ConeTracer<'_, M>,
    point: &ShadingPoint,
    query: ConeQuery,
) -> ConeShade {
    let mut out = ConeShade { ao: 1.0, ..ConeShade::default() };
    let (p, n) = (point.position, point.normal);
    if query.ambient_occlusion || query.diffuse {
        let (ao, e, steps) = tracer.ao_and_diffuse(p, n, query.ambient_occlusion, query.diffuse);
        (out.ao, out.diffuse, out.diffuse_steps) = (ao, e, steps);
    }
    if query.specular {
        let r = tracer.specular(p, n, point.to_viewer, point.glossiness);
        (out.specular, out.specular_opacity, out.specular_steps) = (r.radiance, r.opacity, r.steps);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn unusable_shading_inputs_are_flagged_not_uploaded() {
        let good = ShadingPoint {
            position: Vec3::ONE,
            normal: Vec3::Y * 3.0,
            to_viewer: Vec3::Z,
            glossiness: f32::NAN,
        };
        let g = good.gpu();
        assert_eq!((g.flags, g.glossiness), (3, 0.0));
        let nan = ShadingPoint { position: Vec3::NAN, ..good }.gpu();
        assert_eq!((nan.flags, nan.position), (2, [0.0; 3]));
        let zero = ShadingPoint { normal: Vec3::ZERO, to_viewer: Vec3::ZERO, ..good }.gpu();
        assert_eq!(zero.flags, 0);
        assert_eq!(ShadingPoint { glossiness: 7.0, ..good }.gpu().glossiness, 1.0);
    }
}
