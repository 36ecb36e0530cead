//! The per-voxel ray sampler (HPG 2023 §3.2; design note §1): random lines through a voxel,
//! hit-tested against the voxel's own triangle list and booked into [`VoxelSamples`].
//!
//! # Rules (each has a unit test below)
//! - **Lines.** Ray `i` of voxel `v` draws its direction uniformly on the sphere from
//!   `rand_f32(v, i, base + 0..2)`; then a point uniform over the voxel's projection along it,
//!   exactly and without rejection ([`choose_face`]): face axis `k` with probability
//!   `|d_k| / Σ|d|` (dimension `base + 2`), the face the line *enters* through (`min` if
//!   `d_k > 0`, `max` otherwise), and a uniform point on it (dimensions `base + 3`, `base + 4`,
//!   shifted by half a random step into the open interval (0, 1) so that no line starts on a
//!   voxel edge). The faces' projections tile the hexagon, so these are the isotropic random
//!   lines through the voxel: mean chord 2/3 voxel units (Cauchy).
//! - **Voxel id and seed.** `v` is the voxel's linear index `x + X·(y + Y·z)` (wrapping to
//!   `u32`), so a voxel draws the same lines in any voxelization of the same grid;
//!   `base = 8·seed` (wrapping), so seeds draw disjoint dimensions and seed 0 uses the design
//!   note's dimensions 0..4 literally.
//! - **Hits.** The whole line (`t ∈ ℝ`, origin at the entry point) is intersected with the
//!   voxel's triangles in voxel-local coordinates: `t` from the triangle's plane, then the
//!   barycentrics of `entry + t·d` from two barycentric planes (all set up in `f64` per voxel),
//!   which stays accurate near the voxel for triangles much larger than it; edges count as
//!   inside (`u, v ≥ 0`, `u + v ≤ 1`). The closest hit is the smallest `t`, i.e. the ray
//!   starts at infinity. Ties in `t` go to the lowest triangle id, as in the BVH. Degenerate
//!   triangles and lines in a triangle's plane never hit.
//! - **Alpha.** As the ground truth (`render/surface.rs`): `Opaque` hits always count; `Mask`
//!   hits count where the material's alpha at the hit's UV is > 0 (i.e. ≥ cutoff); `Blend` hits
//!   on triangle `t` count when `rand_f32(v, i, blend_key ^ t) < alpha`, with the precompute's
//!   own key `blend_key = rand_u32(seed, 4, 0x5EED)` (the ground truth's keys are purposes
//!   0..3 of the same formula).
//! - **Cases.** The line is *occluded* when a closest hit exists at all: inside or outside the
//!   voxel, front- or back-facing. The hit is *inside* when its point `entry + t·d` lies in the
//!   **closed** voxel box, the grid's tie rule; on an axis-aligned triangle the point's
//!   coordinate along that axis is the triangle's own, so a triangle lying on a voxel face is
//!   exactly on the box (inside). It is *front-facing* when the world-space geometric normal
//!   `(b−a)×(c−a)` satisfies `n_g·d < 0`, or always on double-sided materials,
//!   whose shading normal is then flipped when `n_g·d > 0`, exactly as the ground truth flips
//!   it. Only an inside, front-facing closest hit is a [`SurfaceSample`] (case (a)): the
//!   interpolated shading normal, and the albedo, specular level (mean of the specular colour)
//!   and exponent of `scene.material_sample(material, uv)`, the ground truth's material
//!   evaluation.
//!
//! # How
//! The geometry and voxelization are checked once in [`SamplingContext::new`]. A voxel is then
//! sampled in three passes over its lines: the lines ([`LineBatch`]), their closest hits with
//! the triangle loop outside and the line loop inside (`hits.rs`), both branch-free where no
//! alpha filter runs so that the compiler vectorizes them (8 lines per instruction on x86-64
//! CPUs with AVX2, chosen at run time; IEEE arithmetic without contraction gives the same bits
//! as the portable loop, tested), and the booking of each line. Nothing is allocated once the
//! per-thread buffers and the caller's [`VoxelSamples`] have grown.

use std::cell::RefCell;

use glam::{UVec3, Vec3};
use voxlod_format::GridSpec;
use voxlod_scene::{AlphaMode, Geometry, Scene};

use super::voxel_samples::{RaySample, SurfaceSample, VoxelSamples};
use crate::random::rand_f32;
use crate::voxelize::Voxelization;
use crate::{Error, Result};
use hits::{HitBatch, LocalTriangle};
pub use lines::{
    LineBatch, blend_key, choose_face, chord, dimension_base, entry_point, sample_line,
    sin_cos_turns, uniform_direction,
};

mod hits;
mod lines;

/// How a material's alpha filters hits (as in the ground truth).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Coverage {
    Opaque,
    Mask,
    Blend,
}

/// Per-material facts the sampler reads per hit.
#[derive(Clone, Copy, Debug)]
struct MaterialRule {
    coverage: Coverage,
    double_sided: bool,
}

/// Per-thread buffers of [`SamplingContext::sample_voxel`]: grown once, never freed.
#[derive(Default)]
struct Scratch {
    /// The current voxel's triangles.
    tris: Vec<LocalTriangle>,
    /// Its lines.
    lines: LineBatch,
    /// Their closest hits.
    hits: HitBatch,
}

thread_local! {
    static SCRATCH: RefCell<Scratch> = RefCell::new(Scratch::default());
}

/// What [`VoxelSamples`] are drawn from: a scene, its flattened geometry and its voxelization
/// with triangle lists, checked once, plus a seed (0 unless [`SamplingContext::with_seed`]).
#[derive(Clone, Debug)]
pub struct SamplingContext<'a> {
    scene: &'a Scene,
    geometry: &'a Geometry,
    vox: &'a Voxelization,
    /// Coordinate of each voxel of `vox.voxels`, in its (Morton) order.
    coords: Vec<UVec3>,
    rules: Vec<MaterialRule>,
    specular: bool,
    seed: u32,
}

/// An [`Error::InvalidParameter`] about the voxelization.
fn bad_voxelization(value: String, reason: String) -> Error {
    Error::InvalidParameter { name: "voxelization", value, reason }
}

impl<'a> SamplingContext<'a> {
    /// Checks that the three belong together and precomputes what sampling reads: every
    /// attribute array of `geometry` matches its vertices and triangles, vertex and material
    /// indices are in range, every vertex is finite, the voxelization's brick map matches its
    /// valid grid, it kept triangle lists (unless it has no voxels) and every list entry names a
    /// triangle of `geometry`. Each failure is an error naming what and where.
    pub fn new(scene: &'a Scene, geometry: &'a Geometry, vox: &'a Voxelization) -> Result<Self> {
        check_geometry(scene, geometry)?;
        vox.grid.validate()?;
        if vox.voxels.dims() != vox.grid.dims {
            return Err(bad_voxelization(
                format!("brick map of {} voxels", vox.voxels.dims()),
                format!("its grid has {} voxels", vox.grid.dims),
            ));
        }
        let listed: u64 = vox.voxels.values().iter().map(|r| r.count as u64).sum();
        if vox.triangles.is_empty() && listed > 0 {
            return Err(bad_voxelization(
                format!("{} voxels without triangle lists", vox.voxels.len()),
                "ray sampling needs triangle lists (voxelize with triangle_lists: true)".into(),
            ));
        }
        if let Some(r) = vox
            .voxels
            .values()
            .iter()
            .find(|r| r.first as u64 + r.count as u64 > vox.triangles.len() as u64)
        {
            return Err(bad_voxelization(
                format!("triangle range {r:?}"),
                format!("the list holds {} entries", vox.triangles.len()),
            ));
        }
        let n = geometry.triangle_count();
        if let Some(&t) = vox.triangles.iter().find(|&&t| t as usize >= n) {
            return Err(bad_voxelization(
                format!("triangle {t}"),
                format!("the geometry has {n} triangles"),
            ));
        }
        let rules: Vec<MaterialRule> = scene
            .materials
            .iter()
            .map(|m| MaterialRule {
                coverage: match m.alpha_mode {
                    AlphaMode::Opaque => Coverage::Opaque,
                    AlphaMode::Mask { .. } => Coverage::Mask,
                    AlphaMode::Blend => Coverage::Blend,
                },
                double_sided: m.double_sided,
            })
            .collect();
        Ok(Self {
            scene,
            geometry,
            vox,
            coords: vox.voxels.coords().collect(),
            specular: scene.materials.iter().any(|m| m.is_specular()),
            rules,
            seed: 0,
        })
    }

    /// The same context drawing with `seed` (module docs: seeds draw disjoint dimensions).
    pub fn with_seed(mut self, seed: u32) -> Self {
        self.seed = seed;
        self
    }

    /// The seed [`SamplingContext::sample_voxel`] draws with.
    pub fn seed(&self) -> u32 {
        self.seed
    }

    /// The scene.
    pub fn scene(&self) -> &'a Scene {
        self.scene
    }

    /// The voxelization whose voxels are sampled.
    pub fn voxelization(&self) -> &'a Voxelization {
        self.vox
    }

    /// The grid.
    pub fn grid(&self) -> &'a GridSpec {
        &self.vox.grid
    }

    /// Number of voxels (indices `0..voxel_count()`, the voxelization's Morton order).
    pub fn voxel_count(&self) -> usize {
        self.coords.len()
    }

    /// Coordinate of voxel `index`.
    pub fn coord(&self, index: usize) -> UVec3 {
        self.coords[index]
    }

    /// Whether any material of the scene has a specular lobe (then the records need their
    /// specular side records).
    pub fn has_specular(&self) -> bool {
        self.specular
    }

    /// The random id of voxel `index`: its linear index `x + X·(y + Y·z)`, wrapping to `u32`.
    pub fn voxel_id(&self, index: usize) -> u32 {
        let c = self.coords[index];
        let d = self.vox.grid.dims;
        c.x.wrapping_add(d.x.wrapping_mul(c.y.wrapping_add(d.y.wrapping_mul(c.z))))
    }

    /// Replaces `out`'s lines with rays `first_ray .. first_ray + count` of voxel `index` (into
    /// the voxelization's voxels), drawn with the context's seed. Rays of different indices are
    /// independent, so rays `R..R+H` are held out from rays `0..R`; a ray's content does not
    /// depend on which others are drawn with it. `out`'s buffer is reused.
    ///
    /// # Panics
    /// If `index ≥ voxel_count()`.
    pub fn sample_voxel(&self, index: usize, first_ray: u32, count: u32, out: &mut VoxelSamples) {
        self.sample_voxel_seeded(index, self.seed, first_ray, count, out);
    }

    /// [`SamplingContext::sample_voxel`] with an explicit seed instead of the context's.
    ///
    /// # Panics
    /// If `index ≥ voxel_count()`.
    pub fn sample_voxel_seeded(
        &self,
        index: usize,
        seed: u32,
        first_ray: u32,
        count: u32,
        out: &mut VoxelSamples,
    ) {
        let id = self.voxel_id(index);
        let base = dimension_base(seed);
        let key = blend_key(seed);
        out.rays.clear();
        out.rays.reserve(count as usize);
        SCRATCH.with(|scratch| {
            let Scratch { tris, lines, hits } = &mut *scratch.borrow_mut();
            self.load_triangles(index, tris);
            // Three passes, the first two vectorized: the lines, their closest hits (triangles
            // outside, lines inside), then the booking of each line.
            lines.fill(id, first_ray, count, base);
            hits.closest(tris, lines, |tri, j, u, v| {
                self.accepts(tri, u, v, id, first_ray.wrapping_add(j as u32), key)
            });
            let ([dx, dy, dz], [ex, ey, ez]) = (&lines.dir, &lines.entry);
            out.rays.extend((0..count as usize).map(|j| {
                let mut r = RaySample {
                    dir: Vec3::new(dx[j], dy[j], dz[j]),
                    entry: Vec3::new(ex[j], ey[j], ez[j]),
                    chord: lines.chord[j],
                    occluded: false,
                    surface: None,
                };
                if let Some(tri) = tris.get(hits.k[j] as usize) {
                    self.book(tri, &mut r, hits.t[j], hits.u[j], hits.v[j]);
                }
                r
            }));
        });
    }

    /// Fills `tris` with voxel `index`'s triangles in voxel-local coordinates (computed in
    /// `f64` from the grid's origin and voxel size, then rounded).
    fn load_triangles(&self, index: usize, tris: &mut Vec<LocalTriangle>) {
        let grid = &self.vox.grid;
        let min = grid.voxel_min(self.coords[index]);
        let inv = 1.0 / grid.voxel_size;
        let local = |p: Vec3| (p.as_dvec3() - min) * inv;
        tris.clear();
        for &t in self.vox.triangles_of(index) {
            let [a, b, c] = self.geometry.triangle(t as usize);
            let material = self.geometry.materials[t as usize];
            let (la, lb, lc) = (local(a), local(b), local(c));
            let (e1, e2) = (lb - la, lc - la);
            let big_n = e1.cross(e2);
            let area2 = big_n.length_squared();
            if area2.is_nan() || area2 <= 0.0 {
                continue; // degenerate: never hit
            }
            // p − a = u·e1 + v·e2 on the plane ⇒ u = (p−a)·(e2×N)/|N|², v = (p−a)·(N×e1)/|N|².
            let bu = e2.cross(big_n) / area2;
            let bv = big_n.cross(e1) / area2;
            let n = big_n / area2.sqrt();
            let (fa, fb, fc) = (la.as_vec3(), lb.as_vec3(), lc.as_vec3());
            let flat =
                (0..3).filter(|&j| fa[j] == fb[j] && fa[j] == fc[j]).fold(0u8, |m, j| m | 1 << j);
            tris.push(LocalTriangle {
                a: fa,
                n: n.as_vec3(),
                offset: n.dot(la) as f32,
                bu: bu.as_vec3(),
                cu: -bu.dot(la) as f32,
                bv: bv.as_vec3(),
                cv: -bv.dot(la) as f32,
                flat,
                alpha: self.rules[material as usize].coverage != Coverage::Opaque,
                normal: (b - a).cross(c - a),
                triangle: t,
                material,
            });
        }
    }

    /// Whether a hit on `tri` at barycentrics `(u, v)` counts for ray `ray` of voxel `id`
    /// (module docs: alpha).
    #[inline]
    fn accepts(&self, tri: &LocalTriangle, u: f32, v: f32, id: u32, ray: u32, key: u32) -> bool {
        let rule = self.rules[tri.material as usize].coverage;
        if rule == Coverage::Opaque {
            return true;
        }
        let (_, uv) = self.geometry.interpolate(tri.triangle as usize, u, v);
        let alpha = self.scene.material_sample(tri.material, uv).alpha;
        match rule {
            Coverage::Blend => rand_f32(id, ray, key ^ tri.triangle) < alpha,
            _ => alpha > 0.0,
        }
    }

    /// Books into `r` its closest hit: `tri` at `t` with barycentrics `(u, v)`.
    #[inline]
    fn book(&self, tri: &LocalTriangle, r: &mut RaySample, t: f32, u: f32, v: f32) {
        let (d, entry) = (r.dir, r.entry);
        r.occluded = true;
        let mut point = entry + d * t;
        for j in 0..3 {
            if tri.flat >> j & 1 == 1 {
                point[j] = tri.a[j]; // exact on axis-aligned triangles (voxel-face ties)
            }
        }
        if !(point.cmpge(Vec3::ZERO).all() && point.cmple(Vec3::ONE).all()) {
            return; // case (b): occludes, outside the voxel
        }
        let rule = self.rules[tri.material as usize];
        let facing = tri.normal.dot(d);
        if !(rule.double_sided || facing < 0.0) {
            return; // back-facing: occludes, no normal
        }
        let (mut normal, uv) = self.geometry.interpolate(tri.triangle as usize, u, v);
        if rule.double_sided && facing > 0.0 {
            normal = -normal;
        }
        let m = self.scene.material_sample(tri.material, uv);
        r.surface = Some(SurfaceSample {
            point,
            normal,
            albedo: m.albedo,
            specular: (m.specular.x + m.specular.y + m.specular.z) * (1.0 / 3.0),
            shininess: m.shininess,
        });
    }
}

/// Checks that `geometry` can be sampled and shaded with `scene`'s materials: the ground
/// truth's checks (one normal and UV per vertex, one material per triangle, indices in range),
/// plus finite vertices.
fn check_geometry(scene: &Scene, geometry: &Geometry) -> Result<()> {
    crate::render::surface::check_geometry(scene, geometry)?;
    if let Some(i) = geometry.positions.iter().position(|p| !p.is_finite()) {
        return Err(Error::InvalidParameter {
            name: "geometry",
            value: format!("vertex {i} at {}", geometry.positions[i]),
            reason: "vertex positions must be finite".into(),
        });
    }
    Ok(())
}

#[cfg(test)]
mod tests;
