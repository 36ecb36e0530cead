//! Subdivision of triangle meshes, so that triangle size relative to a voxel becomes a variable
//! one can set: [`midpoint`] splits every triangle into four and keeps the surface; [`loop_`]
//! (Loop 1987) splits the same way and smooths it towards a C² limit surface.
//!
//! Scene specs take two parameters for it (builtins, embedded models and files alike, see
//! [`Subdivision::take_from_pairs`]): `subdivide=N` (levels, 0..=[`MAX_LEVELS`]) and
//! `subdivision=midpoint|loop` (default `midpoint`).
//!
//! # Midpoint
//! Each triangle `a b c` becomes `a m_ab m_ca`, `m_ab b m_bc`, `m_ca m_bc c` and
//! `m_ab m_bc m_ca`, where `m_xy` is one new vertex per edge (identified by its two vertex
//! indices): a shared edge is split once, so a mesh without gaps keeps none. Positions, UVs and
//! normals of `m_xy` are the averages of the edge's end points (normals renormalized), so the
//! surface, its texture mapping and its interpolated shading normals are unchanged up to the
//! `f32` rounding of `(a + b) / 2` — none when the end points lie on a dyadic lattice fine
//! enough. Where two triangles share an edge by position but not by vertex index (a seam of
//! UVs or normals, the faces of a flat-shaded box), each gets its own midpoint vertex at the
//! same, bit-identical position.
//!
//! # Loop
//! The topology is that of the mesh **welded by position** (vertices with bit-identical
//! positions are one, so UV and normal seams do not tear the surface); attributes stay per
//! corner: each original vertex keeps its UV, an edge's new vertex gets the average of the UVs
//! of the corners it splits (UVs are interpolated linearly). Positions (Loop 1987; vertex
//! classification of Hoppe et al. 1994):
//! - an edge shared by exactly two triangles, with opposite vertices `c`, `d`, gets
//!   `3/8 (a + b) + 1/8 (c + d)`; any other edge — a boundary (one triangle) or a
//!   **non-manifold edge (three or more triangles), which is treated as a crease** rather
//!   than refused — is a crease edge and gets its midpoint;
//! - a vertex on no crease edge or on one (a dart) moves to `(1 − nβ) v + β Σ neighbours` with
//!   Loop's `β(n) = (5/8 − (3/8 + 1/4 cos 2π/n)²) / n` ([`loop_beta`]; Warren 1995's simpler
//!   `3/(8n)` is [`warren_beta`]); a vertex on two crease edges follows the cubic B-spline of
//!   the crease, `3/4 v + 1/8 (a + b)`; a vertex on three or more (a corner) stays put.
//!
//! Boundaries therefore converge to cubic B-spline curves that depend on the boundary vertices
//! alone, so two meshes sharing a boundary stay joined. [`loop_limit_positions`] gives the limit
//! positions of a mesh's vertices (the limit masks of the rules above). Normals of the result
//! are recomputed: area-weighted over the welded topology, so all copies of a welded vertex share
//! one normal. Degenerate edges (both ends at one position) are left out of the topology.
//!
//! # Limits and errors
//! The result of [`Subdivision::apply`] may have at most [`MAX_SUBDIVIDED_TRIANGLES`]
//! triangles: a larger request is an [`Error::InvalidParameter`] naming the scene, the level
//! and the count, before anything is allocated. Skinned meshes are refused (their joint
//! weights would need a rule of their own); a mesh's vertex count must stay below 2³².
//!
//! # References
//! - Loop 1987, "Smooth Subdivision Surfaces Based on Triangles", M.S. thesis, University of
//!   Utah (§3: the rules and β; §4: limit positions).
//! - Warren 1995, "Subdivision Methods for Geometric Design", Rice University (the β = 3/(8n)
//!   variant).
//! - Hoppe, DeRose, Duchamp, Halstead, Jin, McDonald, Schweitzer and Stuetzle 1994,
//!   "Piecewise Smooth Surface Reconstruction", SIGGRAPH (§3: crease, dart and corner
//!   vertices; their modified crease-edge masks next to corners are not used here).
//!
//! ```
//! use glam::Vec3;
//! use voxlod_scene::procedural::primitives::cube;
//! use voxlod_scene::subdivide::{Scheme, subdivide_mesh};
//!
//! let c = cube(Vec3::splat(-1.0), Vec3::splat(1.0));
//! let fine = subdivide_mesh(&c, Scheme::Midpoint, 2)?;
//! assert_eq!(fine.triangle_count(), 12 * 16);
//! let smooth = subdivide_mesh(&c, Scheme::Loop, 2)?;
//! // Loop rounds the cube: its corners (the first vertices) move inside.
//! assert!(smooth.positions[..24].iter().all(|p| p.abs().max_element() < 0.9));
//! # Ok::<(), voxlod_scene::Error>(())
//! ```

use std::collections::HashMap;

use glam::Vec3;

use crate::procedural::ParamInfo;
use crate::procedural::rng::sin_cos_turns;
use crate::{Error, Mesh, Result, Scene};

/// The most triangles a subdivided scene may have (the procedural scenes' limit,
/// [`crate::procedural::MAX_TRIANGLES`]).
pub const MAX_SUBDIVIDED_TRIANGLES: u64 = crate::procedural::MAX_TRIANGLES;

/// The most subdivision levels a spec may ask for (each multiplies the triangles by four).
pub const MAX_LEVELS: u32 = 8;

/// The spec parameters every scene takes for subdivision, as `voxlod scenes` lists them.
pub const PARAMS: &[ParamInfo] = &[
    ParamInfo {
        name: "subdivide",
        default: Some("0"),
        description: "subdivision levels, 0..=8: each splits every triangle into 4",
    },
    ParamInfo {
        name: "subdivision",
        default: Some("midpoint"),
        description: "midpoint (keeps the surface) or loop (Loop 1987, smooths it); needs subdivide",
    },
];

/// A subdivision scheme.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum Scheme {
    /// 1-to-4 split at edge midpoints: the surface is unchanged ([`midpoint`]).
    #[default]
    Midpoint,
    /// Loop 1987 smooth subdivision ([`loop_`]).
    Loop,
}

impl Scheme {
    /// The name a spec uses: `midpoint` or `loop`.
    pub fn name(self) -> &'static str {
        match self {
            Scheme::Midpoint => "midpoint",
            Scheme::Loop => "loop",
        }
    }
}

/// `levels` rounds of one [`Scheme`], as a spec's `subdivide=N&subdivision=…` asks.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct Subdivision {
    /// Levels, 0..=[`MAX_LEVELS`] (0: unchanged).
    pub levels: u32,
    /// The scheme.
    pub scheme: Scheme,
}

impl Subdivision {
    /// Removes the keys `subdivide` and `subdivision` from a spec's `(key, value)` pairs and
    /// returns what they ask for (`None` when neither is given). `scene` names the scene in
    /// errors: a key given twice, a level that is not an integer in 0..=[`MAX_LEVELS`], a scheme
    /// other than `midpoint` or `loop`, or `subdivision` without `subdivide`.
    pub fn take_from_pairs(scene: &str, pairs: &mut Vec<(&str, &str)>) -> Result<Option<Self>> {
        let invalid = |key: &str, value: &str, reason: &str| Error::InvalidParameter {
            name: format!("{scene}.{key}"),
            value: value.into(),
            reason: reason.into(),
        };
        let mut levels = None;
        let mut scheme = None;
        for &(key, value) in pairs.iter() {
            match key {
                "subdivide" => {
                    if levels.is_some() {
                        return Err(invalid(key, value, "given more than once"));
                    }
                    let n: u32 =
                        value.trim().parse().ok().filter(|n| *n <= MAX_LEVELS).ok_or_else(
                            || {
                                invalid(
                                    key,
                                    value,
                                    &format!("expected an integer in 0..={MAX_LEVELS} (levels)"),
                                )
                            },
                        )?;
                    levels = Some(n);
                }
                "subdivision" => {
                    if scheme.is_some() {
                        return Err(invalid(key, value, "given more than once"));
                    }
                    scheme = Some(match value.trim() {
                        "midpoint" => Scheme::Midpoint,
                        "loop" => Scheme::Loop,
                        _ => return Err(invalid(key, value, "expected midpoint or loop")),
                    });
                }
                _ => {}
            }
        }
        pairs.retain(|&(k, _)| k != "subdivide" && k != "subdivision");
        match (levels, scheme) {
            (None, None) => Ok(None),
            (None, Some(s)) => {
                Err(invalid("subdivision", s.name(), "needs subdivide=N (the number of levels)"))
            }
            (Some(levels), scheme) => Ok(Some(Self { levels, scheme: scheme.unwrap_or_default() })),
        }
    }

    /// Triangles after subdividing `triangles` (saturating at `u64::MAX`).
    pub fn triangle_count(&self, triangles: u64) -> u64 {
        triangles.saturating_mul(4u64.saturating_pow(self.levels))
    }

    /// Subdivides every mesh of `scene` (materials, lights, camera and the rest unchanged).
    /// Refuses, naming the scene and the counts, a result over [`MAX_SUBDIVIDED_TRIANGLES`].
    pub fn apply(&self, mut scene: Scene) -> Result<Scene> {
        if self.levels == 0 {
            return Ok(scene);
        }
        let before = scene.triangle_count() as u64;
        let after = self.triangle_count(before);
        if after > MAX_SUBDIVIDED_TRIANGLES {
            return Err(Error::InvalidParameter {
                name: format!("scene '{}': subdivide", scene.name),
                value: self.levels.to_string(),
                reason: format!(
                    "{before} triangles × 4^{} = {after} triangles, over the limit of \
                     {MAX_SUBDIVIDED_TRIANGLES}; lower subdivide",
                    self.levels
                ),
            });
        }
        for mesh in &mut scene.meshes {
            *mesh = subdivide_mesh(mesh, self.scheme, self.levels)?;
        }
        Ok(scene)
    }
}

/// `levels` rounds of `scheme` on one mesh (a copy of it for 0 levels).
pub fn subdivide_mesh(mesh: &Mesh, scheme: Scheme, levels: u32) -> Result<Mesh> {
    let mut out = mesh.clone();
    for _ in 0..levels {
        out = match scheme {
            Scheme::Midpoint => midpoint(&out)?,
            Scheme::Loop => loop_(&out)?,
        };
    }
    Ok(out)
}

/// Checks what both schemes need: no skin, and room for the new vertices in `u32` indices.
fn check(mesh: &Mesh) -> Result<()> {
    let invalid = |value: String, reason: &str| Error::InvalidParameter {
        name: format!("mesh '{}': subdivision", mesh.name),
        value,
        reason: reason.into(),
    };
    if mesh.skin.is_some() {
        return Err(invalid("skinned".into(), "skinned meshes are not subdivided"));
    }
    // At most one new vertex per edge, three edges per triangle.
    let vertices = mesh.positions.len() as u64 + 3 * mesh.indices.len() as u64;
    if vertices > u32::MAX as u64 {
        return Err(invalid(
            format!("{vertices} vertices"),
            "the result would need more than 2^32 − 1 vertices",
        ));
    }
    mesh.validate()
}

/// New vertex ids of a triangle's three edges (`ab`, `bc`, `ca`), creating them in order of first
/// appearance: the one place both schemes number their edge vertices.
struct EdgeVertices {
    ids: HashMap<(u32, u32), u32>,
    /// `(lo, hi)` original vertex indices of every new vertex, in id order from `first`.
    ends: Vec<(u32, u32)>,
    first: u32,
}

impl EdgeVertices {
    fn new(first: u32, triangles: usize) -> Self {
        let edges = triangles * 3 / 2 + 16;
        Self { ids: HashMap::with_capacity(edges), ends: Vec::with_capacity(edges), first }
    }

    fn of(&mut self, tri: [u32; 3]) -> [u32; 3] {
        let mut m = [0; 3];
        for e in 0..3 {
            let (a, b) = (tri[e], tri[(e + 1) % 3]);
            let key = (a.min(b), a.max(b));
            let next = self.first + self.ends.len() as u32;
            m[e] = *self.ids.entry(key).or_insert_with(|| {
                self.ends.push(key);
                next
            });
        }
        m
    }
}

/// The four triangles of the 1-to-4 split of `t` with edge vertices `m` (`ab`, `bc`, `ca`).
#[inline]
fn split(t: [u32; 3], m: [u32; 3]) -> [[u32; 3]; 4] {
    [[t[0], m[0], m[2]], [m[0], t[1], m[1]], [m[2], m[1], t[2]], [m[0], m[1], m[2]]]
}

/// Splits every triangle into four at its edge midpoints (see the module docs): `4·T`
/// triangles, the original vertices first (same indices), then one vertex per edge.
pub fn midpoint(mesh: &Mesh) -> Result<Mesh> {
    check(mesh)?;
    let n = mesh.positions.len();
    let mut edges = EdgeVertices::new(n as u32, mesh.indices.len());
    let mut indices = Vec::with_capacity(4 * mesh.indices.len());
    for &t in &mesh.indices {
        indices.extend(split(t, edges.of(t)));
    }
    let mut out = Mesh { indices, ..mesh.clone() };
    let extra = edges.ends.len();
    out.positions.reserve(extra);
    out.normals.reserve(extra);
    out.uvs.reserve(if mesh.uvs.is_empty() { 0 } else { extra });
    for &(a, b) in &edges.ends {
        let (a, b) = (a as usize, b as usize);
        let p = (mesh.positions[a] + mesh.positions[b]) * 0.5;
        out.positions.push(p);
        // Opposite normals (a fold) average to nothing: keep the first end's.
        let n = (mesh.normals[a] + mesh.normals[b]).try_normalize().unwrap_or(mesh.normals[a]);
        out.normals.push(n);
        if !mesh.uvs.is_empty() {
            out.uvs.push((mesh.uvs[a] + mesh.uvs[b]) * 0.5);
        }
    }
    Ok(out)
}

/// Position bits with −0 folded into +0, the welding key.
#[inline]
fn weld_key(p: Vec3) -> [u32; 3] {
    (p + Vec3::ZERO).to_array().map(f32::to_bits)
}

/// The mesh welded by position: for every vertex its welded id, and the welded positions.
fn weld(positions: &[Vec3]) -> (Vec<u32>, Vec<Vec3>) {
    let mut ids: HashMap<[u32; 3], u32> = HashMap::with_capacity(positions.len());
    let mut unique = Vec::with_capacity(positions.len());
    let map = positions
        .iter()
        .map(|&p| {
            *ids.entry(weld_key(p)).or_insert_with(|| {
                unique.push(p);
                unique.len() as u32 - 1
            })
        })
        .collect();
    (map, unique)
}

/// Loop's vertex weight `β(n) = (5/8 − (3/8 + 1/4 cos 2π/n)²) / n` (Loop 1987, §3): 1/16 at the
/// regular valence 6. `n ≥ 1`.
pub fn loop_beta(n: u32) -> f32 {
    let (_, c) = sin_cos_turns(1.0 / n as f32);
    let t = 0.375 + 0.25 * c;
    (0.625 - t * t) / n as f32
}

/// Warren 1995's vertex weight: `3/16` at valence 3, `3/(8n)` otherwise (1/16 at valence 6).
pub fn warren_beta(n: u32) -> f32 {
    if n == 3 { 3.0 / 16.0 } else { 3.0 / (8.0 * n as f32) }
}

/// The welded topology Loop's rules read.
struct Topology {
    /// Welded id of every vertex.
    weld: Vec<u32>,
    /// Welded positions.
    points: Vec<Vec3>,
    /// Welded edges `(lo, hi)` in order of first appearance, with their triangle count and the
    /// welded opposite vertices of their first two triangles.
    edges: Vec<WeldedEdge>,
    edge_index: HashMap<(u32, u32), u32>,
    /// Per welded vertex: neighbour count and sum, crease-neighbour count and sum.
    valence: Vec<u32>,
    neighbour_sum: Vec<Vec3>,
    creases: Vec<u32>,
    crease_sum: Vec<Vec3>,
}

struct WeldedEdge {
    ends: (u32, u32),
    triangles: u32,
    opposite: [u32; 2],
}

impl WeldedEdge {
    fn is_crease(&self) -> bool {
        self.triangles != 2
    }
}

impl Topology {
    fn new(mesh: &Mesh) -> Self {
        let (weld, points) = weld(&mesh.positions);
        let mut edges: Vec<WeldedEdge> = Vec::with_capacity(mesh.indices.len() * 3 / 2 + 16);
        let mut edge_index = HashMap::with_capacity(mesh.indices.len() * 3 / 2 + 16);
        for t in &mesh.indices {
            let w = t.map(|i| weld[i as usize]);
            for e in 0..3 {
                let (a, b, c) = (w[e], w[(e + 1) % 3], w[(e + 2) % 3]);
                if a == b {
                    continue;
                }
                let key = (a.min(b), a.max(b));
                let next = edges.len() as u32;
                let k = *edge_index.entry(key).or_insert(next) as usize;
                if k == edges.len() {
                    edges.push(WeldedEdge { ends: key, triangles: 0, opposite: [c; 2] });
                }
                let edge = &mut edges[k];
                if edge.triangles < 2 {
                    edge.opposite[edge.triangles as usize] = c;
                }
                edge.triangles += 1;
            }
        }
        let n = points.len();
        let (mut valence, mut neighbour_sum) = (vec![0u32; n], vec![Vec3::ZERO; n]);
        let (mut creases, mut crease_sum) = (vec![0u32; n], vec![Vec3::ZERO; n]);
        for e in &edges {
            let (a, b) = (e.ends.0 as usize, e.ends.1 as usize);
            for (v, other) in [(a, b), (b, a)] {
                valence[v] += 1;
                neighbour_sum[v] += points[other];
                if e.is_crease() {
                    creases[v] += 1;
                    crease_sum[v] += points[other];
                }
            }
        }
        Self { weld, points, edges, edge_index, valence, neighbour_sum, creases, crease_sum }
    }

    /// The new position of welded vertex `v` (Loop's even rule, with creases and corners).
    fn vertex_point(&self, v: usize) -> Vec3 {
        let p = self.points[v];
        match self.creases[v] {
            0 | 1 => {
                let n = self.valence[v];
                if n == 0 {
                    return p;
                }
                let beta = loop_beta(n);
                p * (1.0 - n as f32 * beta) + self.neighbour_sum[v] * beta
            }
            2 => p * 0.75 + self.crease_sum[v] * 0.125,
            _ => p,
        }
    }

    /// The limit position of welded vertex `v` (Loop 1987, §4; the cubic B-spline's on creases).
    fn limit_point(&self, v: usize) -> Vec3 {
        let p = self.points[v];
        match self.creases[v] {
            0 | 1 => {
                let n = self.valence[v];
                if n == 0 {
                    return p;
                }
                let chi = 1.0 / (3.0 / (8.0 * loop_beta(n)) + n as f32);
                p * (1.0 - n as f32 * chi) + self.neighbour_sum[v] * chi
            }
            2 => p * (2.0 / 3.0) + self.crease_sum[v] * (1.0 / 6.0),
            _ => p,
        }
    }

    /// The new position on welded edge `e` (Loop's odd rule; crease edges at their midpoint).
    fn edge_point(&self, e: &WeldedEdge) -> Vec3 {
        let (a, b) = (self.points[e.ends.0 as usize], self.points[e.ends.1 as usize]);
        if e.is_crease() {
            return (a + b) * 0.5;
        }
        let [c, d] = e.opposite.map(|i| self.points[i as usize]);
        (a + b) * 0.375 + (c + d) * 0.125
    }
}

/// One level of Loop subdivision (see the module docs): `4·T` triangles, the original
/// vertices first (same indices, moved by the vertex rule), then one vertex per edge (by vertex
/// index, so a UV seam gets two vertices at one position); normals recomputed.
pub fn loop_(mesh: &Mesh) -> Result<Mesh> {
    check(mesh)?;
    let topo = Topology::new(mesh);
    let vertex_points: Vec<Vec3> = (0..topo.points.len()).map(|v| topo.vertex_point(v)).collect();
    let n = mesh.positions.len();
    let mut edges = EdgeVertices::new(n as u32, mesh.indices.len());
    let mut indices = Vec::with_capacity(4 * mesh.indices.len());
    for &t in &mesh.indices {
        indices.extend(split(t, edges.of(t)));
    }
    let total = n + edges.ends.len();
    let mut positions = Vec::with_capacity(total);
    // Welded id of every new vertex: old welded vertices keep theirs, edge points follow them.
    let mut welded = Vec::with_capacity(total);
    positions.extend(topo.weld.iter().map(|&w| vertex_points[w as usize]));
    welded.extend_from_slice(&topo.weld);
    let edge_points: Vec<Vec3> = topo.edges.iter().map(|e| topo.edge_point(e)).collect();
    let base = topo.points.len() as u32;
    let mut uvs = Vec::with_capacity(if mesh.uvs.is_empty() { 0 } else { total });
    uvs.extend_from_slice(&mesh.uvs);
    for &(a, b) in &edges.ends {
        let (wa, wb) = (topo.weld[a as usize], topo.weld[b as usize]);
        if wa == wb {
            // A degenerate edge: its point is its (single) end's.
            positions.push(vertex_points[wa as usize]);
            welded.push(wa);
        } else {
            let k = topo.edge_index[&(wa.min(wb), wa.max(wb))];
            positions.push(edge_points[k as usize]);
            welded.push(base + k);
        }
        if !mesh.uvs.is_empty() {
            uvs.push((mesh.uvs[a as usize] + mesh.uvs[b as usize]) * 0.5);
        }
    }
    // Area-weighted normals over the welded topology, shared by every copy of a welded vertex.
    let mut acc = vec![Vec3::ZERO; base as usize + topo.edges.len()];
    for t in &indices {
        let [a, b, c] = t.map(|i| positions[i as usize]);
        let face = (b - a).cross(c - a);
        for &i in t {
            acc[welded[i as usize] as usize] += face;
        }
    }
    let normals =
        welded.iter().map(|&w| acc[w as usize].try_normalize().unwrap_or(Vec3::Z)).collect();
    Ok(Mesh { positions, normals, uvs, indices, ..mesh.clone() })
}

/// The Loop limit position of every vertex of `mesh` (copies of a welded vertex share theirs):
/// where infinitely many rounds of [`loop_`] take it. Vertices on no or one crease edge use
/// Loop's limit mask `(1 − nχ) v + χ Σ neighbours`, `χ = 1 / (3/(8β) + n)`; vertices on two
/// crease edges the cubic B-spline's `(1/6, 2/3, 1/6)`; corners stay.
pub fn loop_limit_positions(mesh: &Mesh) -> Vec<Vec3> {
    let topo = Topology::new(mesh);
    let limits: Vec<Vec3> = (0..topo.points.len()).map(|v| topo.limit_point(v)).collect();
    topo.weld.iter().map(|&w| limits[w as usize]).collect()
}

#[cfg(test)]
mod tests;
