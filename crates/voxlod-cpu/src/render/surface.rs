//! What a camera ray of the ground truth finds: [`MeshTracer`] traces a ray through the BVH
//! with the materials' alpha honoured, reconstructs the surface point (position, shading and
//! geometric normals, material sample), and shades it with one shadow ray and [`shade`].
//!
//! Alpha rules (camera and shadow rays alike):
//! - `Opaque`: every hit counts; no filter runs for a scene without other materials.
//! - `Mask { cutoff }`: a hit counts where the material's alpha at the hit's UV is ≥ `cutoff`.
//! - `Blend`: alpha is stochastic coverage: a hit on triangle `t` counts when
//!   `rand_f32(pixel, sample, key ^ t) < alpha`, with separate keys for camera and shadow rays
//!   ([`Streams`]), so averaging many samples gives `alpha·surface + (1 − alpha)·behind` and
//!   alpha-blended blockers transmit `1 − alpha` of the light.

use glam::Vec3;
use voxlod_scene::{AlphaMode, Geometry, Light, MaterialSample, Scene};

use super::pixel_samples::Streams;
use crate::random::rand_f32;
use crate::raycast::{Bvh, Hit, offset_origin};
use crate::shading::shade;
use crate::{Error, Result};

/// An extra transmittance toward the light, per shading point: what lies between a surface
/// point and the light that the mesh's shadow ray does not see, such as a participating
/// medium (the procedural volume's shadow on the scene, [`crate::volume::Volume`] implements
/// it with [`crate::volume::Volume::transmittance_to_light`]).
///
/// Closures `Fn(Vec3) -> f32 + Sync` implement it.
pub trait LightFilter: Sync {
    /// Transmittance in [0, 1] of the light reaching world point `p` (1: unfiltered). The
    /// renderer clamps it into [0, 1] and reads NaN as 0.
    fn transmittance(&self, p: Vec3) -> f32;
}

impl<F: Fn(Vec3) -> f32 + Sync> LightFilter for F {
    #[inline]
    fn transmittance(&self, p: Vec3) -> f32 {
        self(p)
    }
}

/// A surface point seen by a camera ray.
#[derive(Clone, Copy, Debug)]
pub(crate) struct SurfacePoint {
    /// The hit.
    pub hit: Hit,
    /// World position, interpolated from the triangle's vertices.
    pub position: Vec3,
    /// Unit shading normal, flipped toward the viewer on double-sided materials.
    pub normal: Vec3,
    /// The material at the hit.
    pub material: MaterialSample,
}

/// The lighting switches of a render.
#[derive(Clone, Copy)]
pub(crate) struct Lighting<'f> {
    /// Whether to trace shadow rays.
    pub shadows: bool,
    /// Ambient term of `shade`.
    pub ambient: Vec3,
    /// Extra transmittance toward the light, multiplying the shadow ray's visibility.
    pub filter: Option<&'f dyn LightFilter>,
}

/// How a material's alpha filters hits.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Coverage {
    Opaque,
    Mask,
    Blend,
}

/// A scene ready for tracing: its geometry, BVH, light and per-material alpha rule.
pub(crate) struct MeshTracer<'a> {
    pub scene: &'a Scene,
    pub geometry: &'a Geometry,
    pub bvh: &'a Bvh,
    pub light: Light,
    coverage: Vec<Coverage>,
    any_alpha: bool,
}

impl<'a> MeshTracer<'a> {
    /// Checks that the three belong together (same triangle count, one normal and UV per
    /// vertex, material indices in range, a valid light) and precomputes the alpha rules.
    pub fn new(scene: &'a Scene, geometry: &'a Geometry, bvh: &'a Bvh) -> Result<Self> {
        if bvh.triangle_count() != geometry.triangle_count() {
            return Err(Error::InvalidParameter {
                name: "bvh",
                value: format!("{} triangles", bvh.triangle_count()),
                reason: format!("the geometry has {} triangles", geometry.triangle_count()),
            });
        }
        check_geometry(scene, geometry)?;
        let coverage: Vec<Coverage> = scene
            .materials
            .iter()
            .map(|m| match m.alpha_mode {
                AlphaMode::Opaque => Coverage::Opaque,
                AlphaMode::Mask { .. } => Coverage::Mask,
                AlphaMode::Blend => Coverage::Blend,
            })
            .collect();
        let any_alpha = coverage.iter().any(|&c| c != Coverage::Opaque);
        let light = scene.light().validated()?;
        Ok(Self { scene, geometry, bvh, light, coverage, any_alpha })
    }

    /// Whether `hit` counts for the ray of `(pixel, sample)` whose alpha key is `key`.
    #[inline]
    fn accepts(&self, hit: &Hit, pixel: u32, sample: u32, key: u32) -> bool {
        let material = self.geometry.materials[hit.triangle as usize];
        let rule = self.coverage[material as usize];
        if rule == Coverage::Opaque {
            return true;
        }
        let (_, uv) = self.geometry.interpolate(hit.triangle as usize, hit.u, hit.v);
        let alpha = self.scene.material_sample(material, uv).alpha;
        match rule {
            Coverage::Blend => rand_f32(pixel, sample, key ^ hit.triangle) < alpha,
            _ => alpha > 0.0,
        }
    }

    /// The surface a camera ray `eye + t·dir` sees, if any.
    #[inline]
    pub fn trace(
        &self,
        eye: Vec3,
        dir: Vec3,
        pixel: u32,
        sample: u32,
        streams: &Streams,
    ) -> Option<SurfacePoint> {
        let hit = if self.any_alpha {
            let key = streams.alpha_primary;
            self.bvh.intersect_filtered(eye, dir, 0.0, f32::INFINITY, |h| {
                self.accepts(h, pixel, sample, key)
            })
        } else {
            self.bvh.intersect(eye, dir, 0.0, f32::INFINITY)
        }?;
        Some(self.surface(hit, dir))
    }

    /// [`MeshTracer::trace`] for samples `sample .. sample + 4` of `pixel` at once, as a ray
    /// packet: the same answers, faster.
    #[inline]
    pub fn trace4(
        &self,
        eye: Vec3,
        dirs: &[Vec3; 4],
        pixel: u32,
        sample: u32,
        streams: &Streams,
    ) -> [Option<SurfacePoint>; 4] {
        let hits = if self.any_alpha {
            let key = streams.alpha_primary;
            self.bvh.intersect_packet_filtered(eye, dirs, 0.0, f32::INFINITY, |lane, h| {
                self.accepts(h, pixel, sample + lane as u32, key)
            })
        } else {
            self.bvh.intersect_packet(eye, dirs, 0.0, f32::INFINITY)
        };
        let s = |l: usize| hits[l].map(|h| self.surface(h, dirs[l]));
        [s(0), s(1), s(2), s(3)]
    }

    /// The surface point of `hit` seen along `dir`.
    #[inline]
    fn surface(&self, hit: Hit, dir: Vec3) -> SurfacePoint {
        let t = hit.triangle as usize;
        let [a, b, c] = self.geometry.triangle(t);
        let position = a * (1.0 - hit.u - hit.v) + b * hit.u + c * hit.v;
        let (mut normal, uv) = self.geometry.interpolate(t, hit.u, hit.v);
        let material_index = self.geometry.materials[t];
        let material = self.scene.material_sample(material_index, uv);
        if self.scene.materials[material_index as usize].double_sided
            && (b - a).cross(c - a).dot(dir) > 0.0
        {
            normal = -normal;
        }
        SurfacePoint { hit, position, normal, material }
    }

    /// Outgoing radiance toward the camera ray `dir` at `s`: one light, one shadow ray (from
    /// the offset origin of [`offset_origin`]) when `shadows` is on and the light is above the
    /// shading normal's horizon, the light filter's transmittance at `s.position` (clamped into
    /// [0, 1], NaN as 0) where the light is above the horizon and not blocked, and [`shade`]
    /// with `ambient`.
    #[inline]
    pub fn radiance(
        &self,
        s: &SurfacePoint,
        dir: Vec3,
        pixel: u32,
        sample: u32,
        streams: &Streams,
        lighting: Lighting,
    ) -> Vec3 {
        let Lighting { shadows, ambient, filter } = lighting;
        let light = self.light.sample(s.position);
        let mut visibility = 1.0;
        if shadows && s.normal.dot(light.to_light) > 0.0 {
            let origin =
                offset_origin(self.geometry, s.hit.triangle, s.position, light.to_light, -dir);
            let t_max = match self.light {
                Light::Directional { .. } => f32::INFINITY,
                Light::Point { position, .. } => (position - origin).length(),
            };
            let key = streams.alpha_shadow;
            let blocked = if self.any_alpha {
                self.bvh.occluded_filtered(origin, light.to_light, t_max, |h| {
                    self.accepts(h, pixel, sample, key)
                })
            } else {
                self.bvh.occluded(origin, light.to_light, t_max)
            };
            if blocked {
                visibility = 0.0;
            }
        }
        if let Some(filter) = filter
            && visibility > 0.0
            && s.normal.dot(light.to_light) > 0.0
        {
            let t = filter.transmittance(s.position);
            // Into [0, 1], NaN (not ≥ 0) as 0 (`clamp` would keep the NaN).
            visibility *= if t >= 0.0 { t.min(1.0) } else { 0.0 };
        }
        shade(&s.material, s.normal, -dir, &light, visibility, ambient)
    }
}

/// Checks that `geometry` can be shaded with `scene`'s materials: one normal and UV per vertex,
/// vertex indices in range, one material per triangle, material indices in range.
pub(crate) fn check_geometry(scene: &Scene, geometry: &Geometry) -> Result<()> {
    let n = geometry.positions.len();
    if geometry.normals.len() != n
        || geometry.uvs.len() != n
        || geometry.materials.len() != geometry.indices.len()
    {
        return Err(Error::InvalidParameter {
            name: "geometry",
            value: format!(
                "{n} positions, {} normals, {} uvs, {} triangles, {} materials",
                geometry.normals.len(),
                geometry.uvs.len(),
                geometry.indices.len(),
                geometry.materials.len()
            ),
            reason: "normals and uvs need one entry per position, materials one per triangle"
                .into(),
        });
    }
    if let Some(&i) = geometry.indices.iter().flatten().find(|&&i| i as usize >= n) {
        return Err(Error::InvalidParameter {
            name: "geometry",
            value: format!("vertex index {i}"),
            reason: format!("the geometry has {n} vertices"),
        });
    }
    if let Some(&m) = geometry.materials.iter().find(|&&m| m as usize >= scene.materials.len()) {
        return Err(voxlod_scene::Error::DanglingReference {
            what: "material",
            index: m as usize,
            count: scene.materials.len(),
            by: "a triangle of the geometry".into(),
        }
        .into());
    }
    Ok(())
}
