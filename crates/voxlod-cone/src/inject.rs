//! Light injection: direct light, with shadows, into the leaves of a radiance octree, then
//! pre-filtered upward by the octree build ([`inject`]); and [`InjectionCache`], which skips
//! the work when neither the light nor the scene changed.
//!
//! # Leaf radiance
//! Each occupied leaf of the geometry octree (an [`AveragePayload`]: albedo, mean normal,
//! coverage) becomes a [`RadianceLeaf`] with the same opacity and the outgoing radiance
//! `albedo/π · E · max(n·l, 0) · V` — the Lambert term of voxlod-cpu's `shade()` (this crate
//! cannot call it: `cone` depends on `octree` and `format` only), assumed to leave the voxel
//! equally in every direction. A leaf whose weighted normals cancel (`n = 0`, both faces of a
//! thin double-sided wall) gets `max(n·l, 0) = ½`. `V` is the visibility, see [`Shadows`].

use std::collections::hash_map::DefaultHasher;
use std::hash::{Hash, Hasher};

use glam::{DVec3, Vec3};
use rayon::prelude::*;
use voxlod_octree::{AveragePayload, BuildOptions, Octree};

use crate::cone::{Cone, March, trace};
use crate::error::check;
use crate::medium::RadianceLeaf;
use crate::{Error, Result};

/// The light that is injected.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Light {
    /// A distant light: unit direction toward it and the irradiance it gives a surface facing it.
    Directional {
        /// Direction toward the light (normalized here).
        to_light: Vec3,
        /// Irradiance (linear RGB) on a surface facing the light.
        irradiance: Vec3,
    },
    /// A point light: `E = intensity / distance²`.
    Point {
        /// World position.
        position: Vec3,
        /// Radiant intensity (linear RGB).
        intensity: Vec3,
    },
}

impl Light {
    pub(crate) fn validate(&self) -> Result<()> {
        let (v, e) = match *self {
            Light::Directional { to_light, irradiance } => {
                check(
                    to_light.is_finite() && to_light.length() > 0.0,
                    "to_light",
                    to_light.length(),
                    "a finite non-zero direction",
                )?;
                (irradiance, "irradiance")
            }
            Light::Point { position, intensity } => {
                check(position.is_finite(), "light position", position.length(), "finite")?;
                (intensity, "intensity")
            }
        };
        check(
            v.is_finite() && v.min_element() >= 0.0,
            e,
            v.min_element(),
            "finite and >= 0 per channel",
        )
    }

    /// Unit direction toward the light from `p`, the irradiance there, and the distance to the
    /// light (infinite for a directional light). `None` at the light's own position.
    pub fn at(&self, p: Vec3) -> Option<(Vec3, Vec3, f32)> {
        match *self {
            Light::Directional { to_light, irradiance } => {
                Some((to_light.normalize(), irradiance, f32::INFINITY))
            }
            Light::Point { position, intensity } => {
                let d = position - p;
                let dist2 = d.length_squared();
                (dist2 > 0.0).then(|| (d / dist2.sqrt(), intensity / dist2, dist2.sqrt()))
            }
        }
    }

    fn hash_into(&self, h: &mut DefaultHasher) {
        let (tag, a, b) = match *self {
            Light::Directional { to_light, irradiance } => (0u8, to_light, irradiance),
            Light::Point { position, intensity } => (1u8, position, intensity),
        };
        tag.hash(h);
        for x in a.to_array().into_iter().chain(b.to_array()) {
            x.to_bits().hash(h);
        }
    }
}

/// How the visibility `V` of the light from each leaf is found.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Shadows<'a> {
    /// No shadows: `V = 1`.
    None,
    /// March the geometry octree itself toward the light: a ray (a cone of aperture 0, level 0,
    /// step `step_factor` voxels) from the leaf centre moved `offset_voxels` along the leaf's
    /// normal (and along the light direction when the normal is zero), aimed at the light from
    /// there and ending one voxel short of a point light (a voxel's trilinear support reaches
    /// one voxel from its centre, so geometry just behind the light would otherwise shadow
    /// it), `V = 1 − A` with `A` its accumulated opacity. Soft where the opacities are partial; its own leaks are the
    /// octree's.
    March {
        /// Start offset in voxels, ≥ 0 (1.5 as Brito et al. 2023's shadow rays skip voxels closer than
        /// 1.5 voxel sizes).
        offset_voxels: f32,
        /// Step in voxels, in \[0.05, 4\].
        step_factor: f32,
    },
    /// Visibilities computed by the caller (e.g. mesh or voxel shadow rays of voxlod-cpu), one
    /// per occupied leaf in the order of [`occupied_leaves`], each in \[0, 1\].
    PerLeaf(&'a [f32]),
}

impl Shadows<'_> {
    /// The default octree march: offset 1.5 voxels, step 0.5 voxel.
    pub const MARCH: Shadows<'static> = Shadows::March { offset_voxels: 1.5, step_factor: 0.5 };

    fn hash_into(&self, h: &mut DefaultHasher) {
        match *self {
            Shadows::None => 0u8.hash(h),
            Shadows::March { offset_voxels, step_factor } => {
                1u8.hash(h);
                offset_voxels.to_bits().hash(h);
                step_factor.to_bits().hash(h);
            }
            Shadows::PerLeaf(v) => {
                2u8.hash(h);
                v.iter().for_each(|x| x.to_bits().hash(h));
            }
        }
    }
}

/// The occupied leaves (opacity > 0) of `tree`: voxel coordinates and payloads, in storage
/// (Morton) order — the order of [`Shadows::PerLeaf`].
pub fn occupied_leaves(tree: &Octree<AveragePayload>) -> Vec<(glam::UVec3, AveragePayload)> {
    let level = tree.level(0);
    tree.node_coords(0)
        .into_iter()
        .zip(level.payload.iter().copied())
        .filter(|(_, p)| p.opacity > 0.0)
        .collect()
}

/// Injects `light` into the occupied leaves of `geometry` (module docs for the radiance) and
/// builds the radiance octree over the same grid, depth and dense levels, pre-filtered upward.
/// Errors on an invalid light or shadow parameter, or a visibility list that does not match.
pub fn inject<R: RadianceLeaf>(
    geometry: &Octree<AveragePayload>,
    light: &Light,
    shadows: &Shadows,
) -> Result<Octree<R>> {
    light.validate()?;
    let leaves = occupied_leaves(geometry);
    match *shadows {
        Shadows::None => {}
        Shadows::March { offset_voxels, step_factor } => {
            check(
                offset_voxels.is_finite() && offset_voxels >= 0.0,
                "offset_voxels",
                offset_voxels,
                "finite and >= 0",
            )?;
            check(
                (0.05..=4.0).contains(&step_factor),
                "shadow step_factor",
                step_factor,
                "in [0.05, 4]",
            )?;
        }
        Shadows::PerLeaf(v) => {
            if v.len() != leaves.len() {
                return Err(Error::VisibilityLength { given: v.len(), expected: leaves.len() });
            }
            if let Some(i) = v.iter().position(|x| !(0.0..=1.0).contains(x)) {
                return Err(Error::InvalidVisibility {
                    index: i,
                    voxel: leaves[i].0.to_array(),
                    value: v[i],
                });
            }
        }
    }
    let grid = *geometry.grid();
    let voxel = grid.voxel_size as f32;
    let radiance: Vec<_> = leaves
        .par_iter()
        .enumerate()
        .map(|(i, &(c, p))| {
            let centre = grid.voxel_center(c).as_vec3();
            let Some((l, e, _)) = light.at(centre) else {
                return (c, R::leaf(Vec3::ZERO, p.opacity));
            };
            let n = p.normal();
            let ndl = if n == Vec3::ZERO { 0.5 } else { n.dot(l).max(0.0) };
            if ndl <= 0.0 || e == Vec3::ZERO {
                return (c, R::leaf(Vec3::ZERO, p.opacity));
            }
            let v = match *shadows {
                Shadows::None => 1.0,
                Shadows::PerLeaf(v) => v[i],
                Shadows::March { offset_voxels, step_factor } => {
                    let side = if n == Vec3::ZERO { l } else { n };
                    let apex = centre + side * (offset_voxels * voxel);
                    // Aim from the apex, and stop one voxel short of the light (module docs):
                    // measured from the centre, the march overshot a point light by the offset
                    // and read the geometry behind it (a ceiling above the light).
                    let Some((dir, _, to_light)) = light.at(apex) else {
                        return (c, R::leaf(out_radiance(&p, e, ndl, 1.0), p.opacity));
                    };
                    let march = March {
                        start_voxels: 0.0,
                        step_factor,
                        max_distance: (to_light - voxel).max(0.0),
                        opacity_cutoff: 0.999,
                        ao: None,
                    };
                    1.0 - trace(geometry, &Cone { apex, dir, aperture: 0.0 }, &march).opacity
                }
            };
            (c, R::leaf(out_radiance(&p, e, ndl, v), p.opacity))
        })
        .collect();
    let options = BuildOptions {
        depth: Some(geometry.depth()),
        dense_log2: geometry.depth() - geometry.first_dense(),
    };
    Ok(Octree::build(grid, radiance, &options)?)
}

/// The injected outgoing radiance `albedo/π · E · max(n·l, 0) · V` (module docs).
fn out_radiance(p: &AveragePayload, e: Vec3, ndl: f32, v: f32) -> Vec3 {
    p.color() * std::f32::consts::FRAC_1_PI * e * (ndl * v)
}

/// Keeps the last radiance octree and re-injects only when the light, the shadow mode or the
/// geometry changed. The key hashes the light, the shadow parameters (every per-leaf
/// visibility), the grid and depth and every leaf payload of the geometry octree: O(leaves),
/// far less than an injection with shadow marches.
#[derive(Debug)]
pub struct InjectionCache<R> {
    key: Option<u64>,
    tree: Option<Octree<R>>,
    injections: u64,
}

impl<R> Default for InjectionCache<R> {
    fn default() -> Self {
        Self { key: None, tree: None, injections: 0 }
    }
}

impl<R: RadianceLeaf> InjectionCache<R> {
    /// An empty cache.
    pub fn new() -> Self {
        Self::default()
    }

    /// How many injections this cache has run.
    pub fn injections(&self) -> u64 {
        self.injections
    }

    /// The radiance octree for `geometry` lit by `light`: the cached one if the key matches,
    /// else a fresh [`inject`].
    pub fn get(
        &mut self,
        geometry: &Octree<AveragePayload>,
        light: &Light,
        shadows: &Shadows,
    ) -> Result<&Octree<R>> {
        let key = cache_key(geometry, light, shadows);
        if self.key != Some(key) || self.tree.is_none() {
            self.tree = Some(inject(geometry, light, shadows)?);
            self.key = Some(key);
            self.injections += 1;
        }
        Ok(self.tree.as_ref().expect("set above"))
    }
}

fn cache_key(geometry: &Octree<AveragePayload>, light: &Light, shadows: &Shadows) -> u64 {
    let mut h = DefaultHasher::new();
    light.hash_into(&mut h);
    shadows.hash_into(&mut h);
    let g = geometry.grid();
    let o: DVec3 = g.origin;
    for x in o.to_array().into_iter().chain([g.voxel_size]) {
        x.to_bits().hash(&mut h);
    }
    g.dims.to_array().hash(&mut h);
    geometry.depth().hash(&mut h);
    geometry.first_dense().hash(&mut h);
    let level = geometry.level(0);
    level.payload.len().hash(&mut h);
    for p in level.payload {
        let words: [f32; 7] = bytemuck_cast(p);
        words.iter().for_each(|x| x.to_bits().hash(&mut h));
    }
    // Leaves are identified by position too.
    geometry.node_codes(0).hash(&mut h);
    h.finish()
}

fn bytemuck_cast(p: &AveragePayload) -> [f32; 7] {
    let [r, g, b] = p.color_alpha;
    let [x, y, z] = p.normal_alpha;
    [r, g, b, x, y, z, p.opacity]
}
