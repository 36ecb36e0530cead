//! Solid voxelization: a voxel is set iff its **centre** is inside the mesh.
//!
//! # Closed meshes: exact parity
//! For each column of voxel centres along an axis `w`, every triangle whose projection (onto
//! the plane of the other two axes) contains the column counts one crossing at its plane's
//! height `w*`, flipping the parity of the centres with `w_c ≥ w*`. All of it is integer
//! arithmetic on the lattice (centres are lattice points since `F ≥ 1`):
//! - **Point in projected triangle** ([`column_inside`]) uses a top-left fill rule: a centre
//!   exactly on a projected edge belongs to the triangle iff the edge, oriented
//!   counter-clockwise, points down (`e_b < 0`) or points along `+a` (`e_b = 0, e_a > 0`). That
//!   is the exact test for the centre moved by an infinitesimal `(ε, ε²)`, so an edge or vertex
//!   shared by several triangles is counted exactly once, and triangles seen edge-on
//!   (`n_w = 0`) never count.
//! - **The crossing** ([`first_above`]) counts for centres with `w_c ≥ w*` (the centre moved by
//!   an infinitesimal `+√ε` along `w`), so faces through centres are half-open like the grid's
//!   `[i, i+1)` convention.
//!
//! Together the centre is tested at an infinitesimally perturbed position that lies on no
//! triangle, so the parity is exact for every closed mesh: an axis-aligned cube spanning
//! exactly `N` voxels gives `N³` voxels wherever its faces sit (on voxel boundaries, through
//! centres, anywhere).
//!
//! # When is a mesh closed?
//! Parity is exact when every edge is shared by an **even** number of triangles (orientation is
//! irrelevant to parity). Edges are identified by their snapped end points (not by vertex
//! index, so meshes with split vertices at seams count as closed); zero-area triangles are left
//! out (they cross nothing), as are triangles that cannot influence the grid. A **boundary
//! edge** is one used an odd number of times; [`Voxelization::boundary_edges`] reports their
//! number (`Some(0)`: closed).
//!
//! # Meshes that are not closed: majority of three parities
//! With boundary edges, the parity along one axis can leak through a hole (an open box missing
//! its top face fills its column up to the grid's top along `z`). Then the parities along `x`,
//! `y` and `z` are all computed and a voxel is set iff **at least two** say inside. Where the
//! mesh is closed around the centre all three agree; a hole corrupts only the rays that pass
//! through it, so a box missing one face still voxelizes exactly to its interior.
//!
//! # Triangle lists
//! A solid voxel's list holds the triangles whose conservative test overlaps it (the surface
//! voxels of the solid); interior voxels have empty lists. A conservative surface voxel whose
//! centre is outside is not part of the solid, and its triangles are not listed.

use glam::{I64Vec3, IVec3, UVec3};
use rayon::prelude::*;
use voxlod_format::morton;
use voxlod_scene::Geometry;

use super::budget::{self, result_bytes};
use super::lattice::{HALF_VOXEL, Lattice, Reach, VOXEL, voxel_span};
use super::overlap::normal;
use super::pairs::{self, bits_for, code_bits, par_emit};
use super::sort::Key;
use super::surface::brick_map;
use super::{Options, TriangleRange, Voxelization};
use crate::Result;

const V: i64 = VOXEL as i64;
const H: i64 = HALF_VOXEL as i64;

/// Whether the column of centres `q = (q_a, q_b)` (lattice coordinates in the plane dropping
/// axis `w`, with `a = w+1`, `b = w+2` mod 3) lies in the projection of `tri`, under the
/// top-left rule of the module docs. Always false for triangles seen edge-on. Widths: edge
/// functions `< 2^62` (`i64`).
pub fn column_inside(tri: &[IVec3; 3], w: usize, qa: i64, qb: i64) -> bool {
    let (a, b) = ((w + 1) % 3, (w + 2) % 3);
    let s = normal(tri)[w].signum();
    if s == 0 {
        return false;
    }
    let v = tri.map(|p| p.as_i64vec3());
    (0..3).all(|i| {
        let (ea, eb) = (s * (v[(i + 1) % 3][a] - v[i][a]), s * (v[(i + 1) % 3][b] - v[i][b]));
        let f = ea * (qb - v[i][b]) - eb * (qa - v[i][a]);
        f > 0 || (f == 0 && (eb < 0 || (eb == 0 && ea > 0)))
    })
}

/// The first voxel index `k` along `w` whose centre `k·V + V/2` is at or above the plane of
/// `tri` at the column `(q_a, q_b)` — `⌈(s·R + |n_w|·(v0_w − V/2)) / (|n_w|·V)⌉` with
/// `R = −n_a(q_a − v0_a) − n_b(q_b − v0_b)`, `s = sign(n_w)`. Requires `n_w ≠ 0`. `i128`.
pub fn first_above(tri: &[IVec3; 3], w: usize, qa: i64, qb: i64) -> i64 {
    let (a, b) = ((w + 1) % 3, (w + 2) % 3);
    let n = normal(tri);
    let v0 = tri[0].as_i64vec3();
    let r = -(n[a] as i128) * (qa - v0[a]) as i128 - n[b] as i128 * (qb - v0[b]) as i128;
    let num = n[w].signum() as i128 * r + n[w].abs() as i128 * (v0[w] - H) as i128;
    let k = -(-num).div_euclid(n[w].abs() as i128 * V as i128);
    k.clamp(i64::MIN as i128, i64::MAX as i128) as i64
}

/// Inside/outside parity of every voxel centre along axis `w`: one bit per voxel, columns of
/// `dims[w]` bits padded to whole words.
struct Parity {
    w: usize,
    dims: UVec3,
    words_per_column: usize,
    words: Vec<u64>,
}

impl Parity {
    fn bytes(dims: UVec3, w: usize) -> u64 {
        let columns = dims[(w + 1) % 3] as u64 * dims[(w + 2) % 3] as u64;
        columns * (dims[w] as u64).div_ceil(64) * 8
    }

    fn new(live: &[[IVec3; 3]], dims: UVec3, w: usize) -> Self {
        let (a, b) = ((w + 1) % 3, (w + 2) % 3);
        let chunks: Vec<Vec<u64>> = live
            .par_chunks(1024)
            .map(|chunk| {
                let mut out = Vec::new();
                for tri in chunk.iter().filter(|t| normal(t)[w] != 0) {
                    let lo = tri[0].min(tri[1]).min(tri[2]).as_i64vec3();
                    let hi = tri[0].max(tri[1]).max(tri[2]).as_i64vec3();
                    // Columns whose centre lies in the projected bounding box.
                    let range = |k: usize| {
                        let first = -(-(lo[k] - H)).div_euclid(V);
                        let last = (hi[k] - H).div_euclid(V);
                        (first.max(0), last.min(dims[k] as i64 - 1))
                    };
                    let ((a0, a1), (b0, b1)) = (range(a), range(b));
                    for ib in b0..=b1 {
                        for ia in a0..=a1 {
                            let (qa, qb) = (ia * V + H, ib * V + H);
                            if column_inside(tri, w, qa, qb) {
                                let k = first_above(tri, w, qa, qb).max(0);
                                if k < dims[w] as i64 {
                                    let column = ib as u64 * dims[a] as u64 + ia as u64;
                                    out.push(column << 21 | k as u64);
                                }
                            }
                        }
                    }
                }
                out
            })
            .collect();
        let mut events = chunks.concat();
        events.par_sort_unstable();
        let words_per_column = (dims[w] as usize).div_ceil(64);
        let columns = dims[a] as usize * dims[b] as usize;
        let mut words = vec![0u64; columns * words_per_column];
        let end = dims[w] as u64;
        // Flip [k, end) of the column at each crossing: pairs of crossings bound inside runs.
        for group in events.chunk_by(|x, y| x >> 21 == y >> 21) {
            let column =
                &mut words[(group[0] >> 21) as usize * words_per_column..][..words_per_column];
            let ks: Vec<u64> = group.iter().map(|e| e & ((1 << 21) - 1)).collect();
            for run in ks.chunks(2) {
                set_range(column, run[0], run.get(1).copied().unwrap_or(end));
            }
        }
        Self { w, dims, words_per_column, words }
    }

    #[inline]
    fn get(&self, c: UVec3) -> bool {
        let (a, b) = ((self.w + 1) % 3, (self.w + 2) % 3);
        let column = c[b] as usize * self.dims[a] as usize + c[a] as usize;
        let k = c[self.w] as usize;
        self.words[column * self.words_per_column + k / 64] >> (k % 64) & 1 == 1
    }
}

/// Sets bits `[from, to)` of a column.
fn set_range(words: &mut [u64], from: u64, to: u64) {
    let mut k = from;
    while k < to {
        let bit = k % 64;
        let n = (64 - bit).min(to - k);
        let mask = if n == 64 { u64::MAX } else { ((1u64 << n) - 1) << bit };
        words[(k / 64) as usize] |= mask;
        k += n;
    }
}

/// Number of edges (by snapped end points) used an odd number of times.
pub fn boundary_edges(live: &[[IVec3; 3]]) -> u64 {
    let mut edges: Vec<[i32; 6]> = live
        .par_iter()
        .flat_map_iter(|t| {
            (0..3).map(move |i| {
                let (p, q) = (t[i].to_array(), t[(i + 1) % 3].to_array());
                let (p, q) = if p <= q { (p, q) } else { (q, p) };
                [p[0], p[1], p[2], q[0], q[1], q[2]]
            })
        })
        .collect();
    edges.par_sort_unstable();
    edges.chunk_by(|x, y| x == y).filter(|g| g.len() % 2 == 1).count() as u64
}

/// Solid voxelization of `geometry` on `lattice`.
pub fn voxelize(geometry: &Geometry, lattice: &Lattice, options: &Options) -> Result<Voxelization> {
    let grid = *lattice.grid();
    let dims = grid.dims;
    let survey = budget::survey(geometry, lattice, Reach::Solid, false)?;
    let live: Vec<[IVec3; 3]> = par_emit(geometry, lattice, Reach::Solid, |_, tri, out| {
        if normal(tri) != I64Vec3::ZERO && Reach::Solid.reaches_snapped(tri, dims) {
            out.push(*tri);
        }
    })?;
    // Every inside centre lies within the bounding box of the live triangles.
    let (lo, hi) = live.iter().fold((IVec3::MAX, IVec3::MIN), |(lo, hi), t| {
        (lo.min(t[0].min(t[1]).min(t[2])), hi.max(t[0].max(t[1]).max(t[2])))
    });
    let region = (0..3).map(|k| voxel_span(lo[k], hi[k])).collect::<Vec<_>>();
    let region_lo = UVec3::from_array([0, 1, 2].map(|k| region[k].0.max(0) as u32));
    let region_hi =
        UVec3::from_array([0, 1, 2].map(|k| (region[k].1 + 1).clamp(0, dims[k] as i32) as u32));
    let region_voxels = if live.is_empty() {
        0
    } else {
        (region_hi.saturating_sub(region_lo)).as_u64vec3().element_product()
    };
    let tri_bits = bits_for(geometry.indices.len() as u64);
    let wide = code_bits(dims) + tri_bits > 64;
    let lists = if options.triangle_lists {
        survey.pairs.saturating_mul(if wide { 36 } else { 20 })
    } else {
        0
    };
    let bytes = (lattice.memory_bytes() as u64)
        .saturating_add(live.len() as u64 * (36 + 72))
        .saturating_add((0..3).map(|w| Parity::bytes(dims, w)).sum())
        .saturating_add(survey.pairs.saturating_mul(16))
        .saturating_add(result_bytes(region_voxels, dims))
        .saturating_add(lists);
    budget::check(dims, bytes, options.memory_limit_bytes)?;

    let boundary = boundary_edges(&live);
    let parities: Vec<Parity> = if boundary == 0 {
        vec![Parity::new(&live, dims, 2)]
    } else {
        (0..3).into_par_iter().map(|w| Parity::new(&live, dims, w)).collect()
    };
    let inside = |c: UVec3| match parities.as_slice() {
        [z] => z.get(c),
        all => all.iter().filter(|p| p.get(c)).count() >= 2,
    };
    let codes = inside_codes(region_lo, region_hi, &inside);
    let (voxels, triangles) = if !options.triangle_lists {
        (codes.into_iter().map(|c| (c, TriangleRange::default())).collect(), Vec::new())
    } else if wide {
        with_lists::<u128>(geometry, lattice, tri_bits, codes, &inside)?
    } else {
        with_lists::<u64>(geometry, lattice, tri_bits, codes, &inside)?
    };
    Ok(Voxelization {
        grid,
        mode: options.mode,
        voxels: brick_map(dims, voxels)?,
        triangles,
        boundary_edges: Some(boundary),
    })
}

/// Morton codes of the inside voxels of the box `[lo, hi)`, in Morton order.
fn inside_codes(lo: UVec3, hi: UVec3, inside: &(impl Fn(UVec3) -> bool + Sync)) -> Vec<u64> {
    if lo.cmpge(hi).any() {
        return Vec::new();
    }
    let (b0, b1) = (lo / 8, (hi + 7) / 8);
    let mut bricks: Vec<u64> = (b0.z..b1.z)
        .flat_map(|z| {
            (b0.y..b1.y)
                .flat_map(move |y| (b0.x..b1.x).map(move |x| morton::encode(UVec3::new(x, y, z))))
        })
        .collect();
    bricks.par_sort_unstable();
    let per_brick: Vec<Vec<u64>> = bricks
        .par_iter()
        .map(|&brick| {
            (0..512u64)
                .map(|local| brick << 9 | local)
                .filter(|&code| {
                    let c = morton::decode(code);
                    c.cmpge(lo).all() && c.cmplt(hi).all() && inside(c)
                })
                .collect()
        })
        .collect();
    per_brick.concat()
}

/// Solid voxels in Morton order with their ranges, and the triangle ids.
type Lists = (Vec<(u64, TriangleRange)>, Vec<u32>);

/// Attaches the conservative triangle lists to the solid voxels `codes` (Morton order).
fn with_lists<K: Key>(
    geometry: &Geometry,
    lattice: &Lattice,
    tri_bits: u32,
    codes: Vec<u64>,
    inside: &(impl Fn(UVec3) -> bool + Sync),
) -> Result<Lists> {
    let keys = pairs::sorted_keys::<K>(geometry, lattice, false, tri_bits)?;
    let (surface, triangles) = pairs::group(&keys, tri_bits, |code| inside(morton::decode(code)));
    drop(keys);
    let mut surface = surface.into_iter().peekable();
    let mut offset = 0;
    let voxels = codes
        .into_iter()
        .map(|code| match surface.next_if(|s| s.0 == code) {
            Some(s) => {
                offset = s.1.first + s.1.count;
                s
            }
            None => (code, TriangleRange { first: offset, count: 0 }),
        })
        .collect();
    debug_assert!(surface.next().is_none(), "a listed voxel is not solid");
    Ok((voxels, triangles))
}

#[cfg(test)]
mod tests;
