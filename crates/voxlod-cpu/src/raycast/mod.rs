//! BVH ray casting of a [`Geometry`]: closest hit ([`Bvh::intersect`], and
//! [`Bvh::intersect_packet`] for four coherent camera rays at once) and any hit
//! ([`Bvh::occluded`]), each with an optional per-hit filter for alpha-masked and
//! alpha-blended materials, plus the shadow-ray origin rule ([`offset_origin`]).
//!
//! The acceleration structure is obvhs's compressed wide BVH8 (CWBVH), built by PLOC with the
//! preset [`Bvh::DEFAULT_PARAMS`]. Triangles are copied into BVH order, three vertices per SIMD
//! lane group, and intersected with a watertight test (Woop, Benthin & Wald 2013: no cracks
//! along shared edges, at any scale; see `triangle.rs`). Traversal is our own explicit-stack
//! loop over the CWBVH with its child boxes decompressed to `f32` (`traverse.rs`), the shape
//! the WGSL mirror takes; the GPU gets obvhs's compressed nodes ([`Bvh::cwbvh`]).
//!
//! Results do not depend on the tree: among hits at equal `t` the lowest triangle id wins, so
//! the closest hit is the brute-force answer bit for bit, whatever the preset, the thread
//! count, the traversal order, single rays or packets.

mod packet;
mod traverse;
mod triangle;

#[cfg(test)]
mod tests;

use std::time::Duration;

use glam::{Vec3, Vec3A};
use obvhs::BvhBuildParams;
use obvhs::cwbvh::CwBvh;
use obvhs::cwbvh::builder::build_cwbvh_from_tris;
use voxlod_scene::Geometry;

use crate::{Error, Result};
use traverse::{BoxRay, STACK_SIZE, Visit, WideNode};
use triangle::{ShearedRay, SoaTriangle};

/// The closest intersection along a ray.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    /// Ray parameter of the hit: `origin + t·dir` (a distance when `dir` is a unit vector).
    pub t: f32,
    /// Index of the triangle in the [`Geometry`] the BVH was built from.
    pub triangle: u32,
    /// Barycentric weight of vertex 1 (see [`Geometry::interpolate`]).
    pub u: f32,
    /// Barycentric weight of vertex 2; vertex 0 gets `1 − u − v`.
    pub v: f32,
}

/// A CWBVH over the triangles of one [`Geometry`], with the triangles in BVH order.
#[derive(Clone, Debug)]
pub struct Bvh {
    cwbvh: CwBvh,
    /// `cwbvh.nodes` with `f32` child boxes, what the CPU traverses.
    nodes: Vec<WideNode>,
    /// Triangles in `cwbvh.primitive_indices` order (a triangle split by the builder's spatial
    /// pre-splits appears once per reference).
    triangles: Vec<SoaTriangle>,
    /// Original triangle id of each entry of `triangles`.
    ids: Vec<u32>,
    /// Bounds of all triangles (min, max): rays that miss them skip the traversal.
    bounds: (Vec3, Vec3),
    triangle_count: usize,
    build_time: Duration,
}

impl Bvh {
    /// The build preset: obvhs's `slow_build` (PLOC with spatial pre-splits and more
    /// reinsertion). It traces fastest of obvhs's presets in every view `benches/raycast.rs`
    /// measures (the bunny framed and close up, the forest framed), for about twice the build
    /// time of `medium_build`; the ground truth casts hundreds of millions of rays per image, so
    /// tracing dominates. Where builds dominate (a BVH rebuilt per frame), pass a faster preset
    /// to [`Bvh::with_params`]. `VOXLOD_BENCH_PRESETS=1 cargo bench -p voxlod-cpu --bench
    /// raycast` prints the build and trace times of every preset.
    pub const DEFAULT_PARAMS: BvhBuildParams = BvhBuildParams::slow_build();

    /// Builds the BVH with [`Bvh::DEFAULT_PARAMS`].
    ///
    /// Errors on a non-finite vertex of a triangle or an index out of range; a geometry without
    /// triangles gives a BVH that nothing hits.
    pub fn new(geometry: &Geometry) -> Result<Self> {
        Self::with_params(geometry, Self::DEFAULT_PARAMS)
    }

    /// Builds the BVH with explicit obvhs build parameters.
    pub fn with_params(geometry: &Geometry, params: BvhBuildParams) -> Result<Self> {
        validate(geometry)?;
        let n = geometry.triangle_count();
        let start = std::time::Instant::now();
        if n == 0 {
            return Ok(Self {
                cwbvh: CwBvh::default(),
                nodes: Vec::new(),
                triangles: Vec::new(),
                ids: Vec::new(),
                bounds: (Vec3::ZERO, Vec3::ZERO),
                triangle_count: 0,
                build_time: start.elapsed(),
            });
        }
        let tris: Vec<obvhs::triangle::Triangle> = (0..n)
            .map(|t| {
                let [a, b, c] = geometry.triangle(t).map(Vec3A::from);
                obvhs::triangle::Triangle { v0: a, v1: b, v2: c }
            })
            .collect();
        let mut core_time = Duration::ZERO;
        let cwbvh = build_cwbvh_from_tris(&tris, params, &mut core_time);
        let ids = cwbvh.primitive_indices.clone();
        let triangles =
            ids.iter().map(|&i| SoaTriangle::new(geometry.triangle(i as usize))).collect();
        let depth = depth(&cwbvh);
        if depth >= STACK_SIZE {
            return Err(Error::InvalidParameter {
                name: "geometry",
                value: format!("{n} triangles"),
                reason: format!(
                    "its BVH is {depth} levels deep, over the traversal stack of {STACK_SIZE}"
                ),
            });
        }
        let nodes = WideNode::decompress(&cwbvh);
        let bounds = geometry.bounds().unwrap_or((Vec3::ZERO, Vec3::ZERO));
        Ok(Self {
            cwbvh,
            nodes,
            triangles,
            ids,
            bounds,
            triangle_count: n,
            build_time: start.elapsed(),
        })
    }

    /// Number of triangles of the geometry the BVH was built from.
    pub fn triangle_count(&self) -> usize {
        self.triangle_count
    }

    /// Wall time of the build (validation and triangle copies included).
    pub fn build_time(&self) -> Duration {
        self.build_time
    }

    /// The underlying obvhs CWBVH (nodes and primitive order), for uploading to a GPU.
    pub fn cwbvh(&self) -> &CwBvh {
        &self.cwbvh
    }

    /// The closest hit with `t_min ≤ t ≤ t_max`, or `None`. `dir` need not be normalized (`t`
    /// is then in units of `dir`); `t_min` below 0 counts as 0; a non-finite or zero
    /// `origin`/`dir`, or a NaN bound, hits nothing.
    #[inline]
    pub fn intersect(&self, origin: Vec3, dir: Vec3, t_min: f32, t_max: f32) -> Option<Hit> {
        self.intersect_filtered(origin, dir, t_min, t_max, |_| true)
    }

    /// [`Bvh::intersect`] where `accept` may discard a candidate hit (alpha testing): the
    /// result is the closest hit `accept` keeps. `accept` sees each candidate at most once per
    /// BVH reference and must be a pure function of the hit for the result to be deterministic.
    #[inline]
    pub fn intersect_filtered(
        &self,
        origin: Vec3,
        dir: Vec3,
        t_min: f32,
        t_max: f32,
        accept: impl FnMut(&Hit) -> bool,
    ) -> Option<Hit> {
        if !valid_ray(origin, dir) || t_min.is_nan() || t_max.is_nan() {
            return None;
        }
        let t_min = t_min.max(0.0);
        if t_min > t_max {
            return None;
        }
        let box_ray = BoxRay::new(origin, dir);
        if !box_ray.overlaps(self.bounds, t_min, t_max) {
            return None;
        }
        let tri_ray = ShearedRay::new(origin, dir);
        match tri_ray.kz {
            0 => self.closest::<0>(&box_ray, &tri_ray, t_min, t_max, accept),
            1 => self.closest::<1>(&box_ray, &tri_ray, t_min, t_max, accept),
            _ => self.closest::<2>(&box_ray, &tri_ray, t_min, t_max, accept),
        }
    }

    #[inline(always)]
    fn closest<const KZ: usize>(
        &self,
        box_ray: &BoxRay,
        tri_ray: &ShearedRay,
        t_min: f32,
        t_max: f32,
        mut accept: impl FnMut(&Hit) -> bool,
    ) -> Option<Hit> {
        let mut best: Option<Hit> = None;
        let mut limit = t_max;
        traverse::traverse(&self.nodes, box_ray, t_min, &mut limit, |slot, limit| {
            let slot = slot as usize;
            if let Some(h) = tri_ray.intersect::<KZ>(&self.triangles[slot], t_min, *limit) {
                let triangle = self.ids[slot];
                let closer = match best {
                    None => true,
                    Some(b) => h.t < b.t || (h.t == b.t && triangle < b.triangle),
                };
                let hit = Hit { t: h.t, triangle, u: h.u, v: h.v };
                if closer && accept(&hit) {
                    best = Some(hit);
                    *limit = h.t;
                }
            }
            Visit::Continue
        });
        best
    }

    /// Whether anything is hit with `0 < t < t_max` (a shadow ray toward a light at distance
    /// `t_max`, or `f32::INFINITY`). Consistent with [`Bvh::intersect`]: true exactly when a
    /// closest hit exists in that open range.
    #[inline]
    pub fn occluded(&self, origin: Vec3, dir: Vec3, t_max: f32) -> bool {
        self.occluded_filtered(origin, dir, t_max, |_| true)
    }

    /// [`Bvh::occluded`] where `accept` may discard a blocker (alpha testing). The barycentrics
    /// of the hits it sees are exact; their `t` is too, but hits are not visited in order.
    #[inline]
    pub fn occluded_filtered(
        &self,
        origin: Vec3,
        dir: Vec3,
        t_max: f32,
        accept: impl FnMut(&Hit) -> bool,
    ) -> bool {
        if !valid_ray(origin, dir) || t_max.is_nan() || t_max <= 0.0 {
            return false;
        }
        let box_ray = BoxRay::new(origin, dir);
        if !box_ray.overlaps(self.bounds, 0.0, t_max) {
            return false;
        }
        let tri_ray = ShearedRay::new(origin, dir);
        match tri_ray.kz {
            0 => self.any::<0>(&box_ray, &tri_ray, t_max, accept),
            1 => self.any::<1>(&box_ray, &tri_ray, t_max, accept),
            _ => self.any::<2>(&box_ray, &tri_ray, t_max, accept),
        }
    }

    #[inline(always)]
    fn any<const KZ: usize>(
        &self,
        box_ray: &BoxRay,
        tri_ray: &ShearedRay,
        t_max: f32,
        mut accept: impl FnMut(&Hit) -> bool,
    ) -> bool {
        let mut limit = t_max;
        let mut blocked = false;
        traverse::traverse(&self.nodes, box_ray, 0.0, &mut limit, |slot, _| {
            let slot = slot as usize;
            match tri_ray.intersect::<KZ>(&self.triangles[slot], 0.0, t_max) {
                Some(h) if h.t > 0.0 && h.t < t_max => {
                    let hit = Hit { t: h.t, triangle: self.ids[slot], u: h.u, v: h.v };
                    if accept(&hit) {
                        blocked = true;
                        return Visit::Stop;
                    }
                    Visit::Continue
                }
                _ => Visit::Continue,
            }
        });
        blocked
    }
}

/// The origin of a secondary ray (shadow, AO, bounce) leaving the surface of `triangle` at
/// `point` toward `dir`, where `point` was reached by a ray arriving from the side `to_viewer`
/// points to (for a camera hit, `eye − point`; for a bounce, minus the incoming direction).
/// The origin is moved off every surface `point` lies on, so that no face through `point` is
/// reported at `t ≈ 0`.
///
/// Rule, with `n` the unit geometric normal of `triangle` on the side `dir` points to, `v` the
/// unit `to_viewer`, `c = n · v` and `ε = 2⁻¹⁶ · max |vertex coordinate|` of the triangle:
/// - `c ≥ 1/64` (the point was seen from `dir`'s side): `point + v · ε / c`, i.e. back along
///   the ray that found the point, to `ε` above the triangle's own plane. That segment is free
///   space (the point was the ray's first hit), so the origin is in front of *every* face
///   through the point: a point on an edge or a corner (a camera ray landing exactly on the
///   seam of a room's floor and wall) also lies on the adjacent faces, and moving along `n`
///   alone would slide it within them — or, in a sharp concave wedge, through them. Rays that
///   leave into an adjacent face then hit it at a small `t > 0`, rays that leave away from it
///   miss it: the value at the seam is the limit from the visible side.
/// - otherwise (no viewer, a view within 0.9° of the plane, or `dir` on the far side):
///   `point + n · ε`, off the triangle's own plane only.
///
/// Why `ε`: a hit point interpolated from barycentrics is off the plane by a few ULPs of the
/// largest vertex coordinate (≈ 2⁻²² of it), and the watertight test translates vertices to
/// the origin with the same relative error, so `ε` has a margin of about 64×; it scales with the
/// coordinates, so a scene scaled by 10⁻⁴ or 10⁵ shadows the same. The price is that blockers
/// closer than `ε` (at most `64 ε` along `v`) are missed. A degenerate triangle (no normal)
/// uses `dir` for `n`. The WGSL mirror (voxlod-gpu's ground truth) is the same arithmetic in
/// the same order.
pub fn offset_origin(
    geometry: &Geometry,
    triangle: u32,
    point: Vec3,
    dir: Vec3,
    to_viewer: Vec3,
) -> Vec3 {
    let [a, b, c] = geometry.triangle(triangle as usize);
    let n = (b - a).cross(c - a);
    let scale = a.abs().max(b.abs()).max(c.abs()).max_element();
    let eps = scale * (1.0 / 65_536.0);
    let n = match n.try_normalize() {
        Some(n) => {
            if n.dot(dir) >= 0.0 {
                n
            } else {
                -n
            }
        }
        None => dir.normalize_or_zero(),
    };
    let v = to_viewer.normalize_or_zero();
    let c = n.dot(v);
    if c >= 1.0 / 64.0 { point + v * (eps / c) } else { point + n * eps }
}

fn valid_ray(origin: Vec3, dir: Vec3) -> bool {
    origin.is_finite() && dir.is_finite() && dir != Vec3::ZERO
}

/// Checks what the BVH reads: indices in range, finite referenced vertices. (Normals, UVs and
/// materials are the renderers' business.)
fn validate(g: &Geometry) -> Result<()> {
    let n = g.positions.len();
    for (t, tri) in g.indices.iter().enumerate() {
        for &i in tri {
            let Some(p) = g.positions.get(i as usize) else {
                return Err(voxlod_scene::Error::IndexOutOfRange {
                    mesh: "geometry".into(),
                    triangle: t,
                    index: i,
                    vertex_count: n,
                }
                .into());
            };
            if !p.is_finite() {
                return Err(voxlod_scene::Error::NonFinite {
                    mesh: "geometry".into(),
                    attribute: "position",
                    vertex: i as usize,
                    value: p.to_array(),
                }
                .into());
            }
        }
    }
    Ok(())
}

/// Depth of the CWBVH in nodes (the traversal stack needs one entry per level).
fn depth(bvh: &CwBvh) -> usize {
    if bvh.nodes.is_empty() {
        return 0;
    }
    let mut max = 0;
    let mut todo = vec![(0u32, 1usize)];
    while let Some((i, d)) = todo.pop() {
        max = max.max(d);
        let node = &bvh.nodes[i as usize];
        for ch in 0..8 {
            if node.imask & (1 << ch) != 0 {
                todo.push((node.child_node_index(ch), d + 1));
            }
        }
    }
    max
}
