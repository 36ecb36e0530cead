//! Transmittance shadow maps (Eisemann and Décoret 2006, §3.1): slicemaps seen from the light,
//! and the ray-traced transmittance they approximate.
//!
//! # The maps
//! Opaque and semi-transparent triangles go into separate maps, as in the paper: the opaque
//! ones into a standard shadow map (the nearest opaque depth per column, here the range of a
//! locally sliced map with one slice), the semi-transparent ones (leaves) into a slicemap with
//! local slicing. A directional light gets one orthographic map enclosing the scene's bounds; a
//! point light six perspective maps, the faces of a cube around it (90° each), so that a light
//! inside the scene sees every direction.
//!
//! # The lookup
//! A point `p` is moved toward the light by `bias` (world units: shadow maps need one against
//! self-shadowing) and located in its map. Behind the nearest opaque depth it receives nothing;
//! otherwise it counts the occupied slices nearer the light than its own
//! ([`Slicemap::count_nearer`]: the bits below its slice) and receives `(1 − σ)^n`, every
//! semi-transparent layer attenuating the light by the same factor `σ`. A point outside every
//! map (beyond the bounds the maps enclose) is fully lit.
//!
//! # The reference
//! [`RayTracedTransmittance`] casts the segment from `p` (started `epsilon` toward the light)
//! to the light through the whole geometry and counts every semi-transparent triangle it
//! crosses, or returns 0 when an opaque one blocks it: the exact `(1 − σ)^crossings` the map
//! approximates. Both implement [`LightFilter`], so the ground-truth renderer shades a scene
//! with either.

use glam::{DVec3, Vec3};
use voxlod_scene::{Geometry, Light};

use super::{Coverage, Faces, Options, Projection, SliceCamera, Slicemap, Slicing};
use crate::raycast::Bvh;
use crate::render::ground_truth::LightFilter;
use crate::{Error, Result};

/// Options of [`TransmittanceShadowMap::build`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ShadowOptions {
    /// Columns per side of each map.
    pub size: u32,
    /// Slices of the semi-transparent map, 1..=512.
    pub slices: u32,
    /// Slicing of the semi-transparent map (the paper: local).
    pub slicing: Slicing,
    /// Coverage rule of both maps.
    pub coverage: Coverage,
    /// Attenuation `σ` of one semi-transparent layer, in [0, 1].
    pub sigma: f32,
    /// Distance a point is moved toward the light before the lookup (world units, ≥ 0).
    pub bias: f64,
}

impl Default for ShadowOptions {
    fn default() -> Self {
        ShadowOptions {
            size: 512,
            slices: 96,
            slicing: Slicing::Local,
            coverage: Coverage::Standard,
            sigma: 0.3,
            bias: 0.0,
        }
    }
}

/// The maps of one light direction: opaque depth and semi-transparent layers.
#[derive(Clone, Debug, PartialEq)]
pub struct ShadowFace {
    /// Nearest opaque depth per column (a one-slice local map: its ranges), if any opaque
    /// triangle is in view.
    pub opaque: Slicemap,
    /// The semi-transparent layers.
    pub layers: Slicemap,
}

/// Where the maps look from.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Source {
    Directional,
    Point(DVec3),
}

/// Transmittance shadow maps of one light (module docs).
#[derive(Clone, Debug, PartialEq)]
pub struct TransmittanceShadowMap {
    source: Source,
    /// One face (directional light) or six (point light: +x, −x, +y, −y, +z, −z).
    pub faces: Vec<ShadowFace>,
    /// The options used.
    pub options: ShadowOptions,
}

/// The cameras of a light's maps for a scene within `[lo, hi]`.
fn cameras(light: &Light, lo: DVec3, hi: DVec3, size: u32) -> (Source, Vec<SliceCamera>) {
    match *light {
        Light::Directional { to_light, .. } => {
            let cam = SliceCamera::enclosing_orthographic(-to_light.as_dvec3(), lo, hi, size);
            (Source::Directional, vec![cam])
        }
        Light::Point { position, .. } => {
            let p = position.as_dvec3();
            // Far enough for the farthest corner of the bounds; near a small fraction of it.
            let far = (0..8)
                .map(|i| {
                    let c = DVec3::new(
                        if i & 1 == 0 { lo.x } else { hi.x },
                        if i & 2 == 0 { lo.y } else { hi.y },
                        if i & 4 == 0 { lo.z } else { hi.z },
                    );
                    (c - p).abs().max_element()
                })
                .fold(0.0, f64::max)
                .max(1e-9);
            let near = far * 1e-4;
            let faces = [
                (DVec3::X, DVec3::NEG_Y),
                (DVec3::NEG_X, DVec3::NEG_Y),
                (DVec3::Y, DVec3::Z),
                (DVec3::NEG_Y, DVec3::NEG_Z),
                (DVec3::Z, DVec3::NEG_Y),
                (DVec3::NEG_Z, DVec3::NEG_Y),
            ];
            let cams = faces
                .iter()
                .map(|&(forward, up)| SliceCamera {
                    eye: p,
                    forward,
                    up,
                    projection: Projection::Perspective { fov_y_deg: 90.0 },
                    width: size,
                    height: size,
                    near,
                    far: far * 1.001,
                })
                .collect();
            (Source::Point(p), cams)
        }
    }
}

impl TransmittanceShadowMap {
    /// Builds the maps of `light` for `geometry`, whose triangle `t` is semi-transparent when
    /// `transmissive(t)`, with `build` making each slicemap (the CPU reference
    /// [`super::build`], or a GPU renderer). Errors on invalid options, geometry or light, or
    /// what `build` returns.
    pub fn build_with<E: From<Error>>(
        geometry: &Geometry,
        transmissive: impl Fn(usize) -> bool,
        light: &Light,
        options: &ShadowOptions,
        mut build: impl FnMut(&Geometry, &SliceCamera, &Options) -> std::result::Result<Slicemap, E>,
    ) -> std::result::Result<Self, E> {
        let o = *options;
        if !((0.0..=1.0).contains(&o.sigma) && o.bias >= 0.0 && o.bias.is_finite()) {
            return Err(Error::InvalidParameter {
                name: "shadow options",
                value: format!("sigma {} bias {}", o.sigma, o.bias),
                reason: "sigma in [0, 1] and a finite bias ≥ 0".into(),
            }
            .into());
        }
        let light = light.validated().map_err(Error::from)?;
        let Some((lo, hi)) = geometry.bounds() else {
            return Err(Error::InvalidParameter {
                name: "shadow geometry",
                value: "no triangles".into(),
                reason: "a shadow map needs geometry to bound".into(),
            }
            .into());
        };
        let (mut opaque, mut layers) = (geometry.clone(), geometry.clone());
        opaque.indices.clear();
        layers.indices.clear();
        for (t, &idx) in geometry.indices.iter().enumerate() {
            if transmissive(t) { &mut layers } else { &mut opaque }.indices.push(idx);
        }
        let (source, cams) = cameras(&light, lo.as_dvec3(), hi.as_dvec3(), o.size);
        let depth = Options {
            slices: 1,
            slicing: Slicing::Local,
            coverage: o.coverage,
            faces: Faces::All,
            ..Options::default()
        };
        let slices =
            Options { slices: o.slices, slicing: o.slicing, coverage: o.coverage, ..depth };
        let mut faces = Vec::with_capacity(cams.len());
        for cam in &cams {
            faces.push(ShadowFace {
                opaque: build(&opaque, cam, &depth)?,
                layers: build(&layers, cam, &slices)?,
            });
        }
        Ok(Self { source, faces, options: o })
    }

    /// [`TransmittanceShadowMap::build_with`] with the CPU reference.
    pub fn build(
        geometry: &Geometry,
        transmissive: impl Fn(usize) -> bool,
        light: &Light,
        options: &ShadowOptions,
    ) -> Result<Self> {
        Self::build_with(geometry, transmissive, light, options, super::build)
    }

    /// The face whose map holds world point `p`, and the direction toward the light there.
    fn face(&self, p: DVec3) -> (usize, DVec3) {
        match self.source {
            Source::Directional => (0, -self.faces[0].layers.camera.frame().forward),
            Source::Point(l) => {
                let d = p - l;
                let a = d.abs();
                let face = if a.x >= a.y && a.x >= a.z {
                    if d.x >= 0.0 { 0 } else { 1 }
                } else if a.y >= a.z {
                    if d.y >= 0.0 { 2 } else { 3 }
                } else if d.z >= 0.0 {
                    4
                } else {
                    5
                };
                (face, (-d).normalize_or_zero())
            }
        }
    }

    /// Whether an opaque triangle hides `p` from the light, and the semi-transparent layers
    /// between them (module docs); `None` outside every map.
    pub fn lookup(&self, p: DVec3) -> Option<(bool, u32)> {
        let (face, to_light) = self.face(p);
        let f = &self.faces[face];
        let q = p + to_light * self.options.bias;
        let at = f.layers.locate(q)?;
        let blocked = f.opaque.range(at.x, at.y).is_some_and(|(near, _)| at.d > near);
        Some((blocked, f.layers.count_nearer(0, at.x, at.y, at.d)))
    }

    /// `(1 − σ)^n`, or 0 behind an opaque occluder, 1 outside the maps.
    pub fn transmittance_at(&self, p: DVec3) -> f32 {
        match self.lookup(p) {
            None => 1.0,
            Some((true, _)) => 0.0,
            Some((false, n)) => (1.0 - self.options.sigma).powi(n as i32),
        }
    }

    /// Bytes of all maps' bits and ranges.
    pub fn memory_bytes(&self) -> u64 {
        let map = |m: &Slicemap| {
            m.bits.len() as u64 * 4 + m.ranges.as_ref().map_or(0, |r| r.len() as u64 * 8)
        };
        self.faces.iter().map(|f| map(&f.opaque) + map(&f.layers)).sum()
    }
}

impl LightFilter for TransmittanceShadowMap {
    fn transmittance(&self, p: Vec3) -> f32 {
        self.transmittance_at(p.as_dvec3())
    }
}

/// The exact transmittance the maps approximate, by ray casting (module docs).
pub struct RayTracedTransmittance<'a> {
    bvh: &'a Bvh,
    transmissive: Vec<bool>,
    light: Light,
    sigma: f32,
    epsilon: f32,
}

impl<'a> RayTracedTransmittance<'a> {
    /// The reference for `geometry` (with `bvh` built over it), triangle `t` semi-transparent
    /// when `transmissive(t)`; segments start `epsilon` (world units) from the point.
    pub fn new(
        geometry: &Geometry,
        bvh: &'a Bvh,
        transmissive: impl Fn(usize) -> bool,
        light: &Light,
        sigma: f32,
        epsilon: f32,
    ) -> Result<Self> {
        if bvh.triangle_count() != geometry.triangle_count() {
            return Err(Error::InvalidParameter {
                name: "bvh",
                value: format!("{} triangles", bvh.triangle_count()),
                reason: format!("the geometry has {} triangles", geometry.triangle_count()),
            });
        }
        let transmissive = (0..geometry.triangle_count()).map(transmissive).collect();
        Ok(Self { bvh, transmissive, light: light.validated()?, sigma, epsilon })
    }

    /// Whether an opaque triangle blocks the segment from `p` to the light, and the
    /// semi-transparent triangles it crosses.
    pub fn crossings(&self, p: Vec3) -> (bool, u32) {
        let s = self.light.sample(p);
        let origin = p + s.to_light * self.epsilon;
        let t_max = if s.distance.is_finite() { s.distance - self.epsilon } else { f32::INFINITY };
        let (mut blocked, mut n) = (false, 0);
        if t_max > 0.0 {
            self.bvh.occluded_filtered(origin, s.to_light, t_max, |h| {
                if self.transmissive[h.triangle as usize] {
                    n += 1;
                    false
                } else {
                    blocked = true;
                    true
                }
            });
        }
        (blocked, n)
    }
}

impl LightFilter for RayTracedTransmittance<'_> {
    fn transmittance(&self, p: Vec3) -> f32 {
        match self.crossings(p) {
            (true, _) => 0.0,
            (false, n) => (1.0 - self.sigma).powi(n as i32),
        }
    }
}

/// The length of the ray `origin + t·dir` (`dir` unit, `t > t_min`) inside a closed mesh: the
/// sum of the intervals from an entering hit (geometric normal against the ray) to the next
/// leaving one, every hit counted once (hits at the same `t` with the same orientation are one:
/// a ray through a shared edge or vertex).
pub fn traversed_length(
    bvh: &Bvh,
    geometry: &Geometry,
    origin: Vec3,
    dir: Vec3,
    t_min: f32,
) -> f32 {
    let mut hits: Vec<(f32, i32)> = Vec::new();
    bvh.occluded_filtered(origin, dir, f32::INFINITY, |h| {
        if h.t > t_min {
            let [a, b, c] = geometry.triangle(h.triangle as usize);
            let n = (b - a).cross(c - a);
            let s = n.dot(dir);
            if s != 0.0 {
                hits.push((h.t, if s < 0.0 { 1 } else { -1 }));
            }
        }
        false
    });
    hits.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
    hits.dedup_by(|a, b| a.1 == b.1 && (a.0 - b.0).abs() <= 1e-6 * a.0.abs().max(1.0));
    let (mut depth, mut inside_from, mut length) = (0i32, 0.0f32, 0.0f32);
    for (t, s) in hits {
        if depth <= 0 && depth + s > 0 {
            inside_from = t;
        } else if depth > 0 && depth + s <= 0 {
            length += t - inside_from;
        }
        depth += s;
    }
    length
}

#[cfg(test)]
mod tests;
