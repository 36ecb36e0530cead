//! Scene-level tests of [`voxelize`]: regressions other voxelizers got wrong, extremes (scale,
//! degenerate input, bad input, memory), and the voxelizers against the per-voxel reference.

use std::collections::{HashMap, HashSet};

use glam::{DVec3, IVec3, UVec3, Vec3};
use voxlod_format::GridSpec;
use voxlod_scene::Geometry;

use super::lattice::Lattice;
use super::overlap::{box_overlap, diamond_overlap};
use super::*;
use crate::random::rand_f32;

pub fn options(mode: Mode, triangle_lists: bool) -> Options {
    Options { mode, triangle_lists, ..Options::default() }
}

pub fn grid(n: u32) -> GridSpec {
    GridSpec::new(DVec3::ZERO, 1.0, UVec3::splat(n)).unwrap()
}

fn geometry(positions: Vec<Vec3>, indices: Vec<[u32; 3]>) -> Geometry {
    Geometry { positions, indices, ..Default::default() }
}

/// An axis-aligned cube `[lo, lo + size]`, outward triangles; faces `skip` left out; every
/// face with its own four vertices (so closedness must be judged by position, not index).
pub fn cube(lo: Vec3, size: f32, skip: &[usize]) -> Geometry {
    let mut g = Geometry::default();
    for face in (0..6).filter(|f| !skip.contains(f)) {
        let (axis, side) = (face / 2, face % 2);
        let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
        let corner = |a: f32, b: f32| {
            let mut p = Vec3::ZERO;
            p[axis] = side as f32;
            p[u] = a;
            p[v] = b;
            lo + p * size
        };
        let base = g.positions.len() as u32;
        g.positions.extend([
            corner(0.0, 0.0),
            corner(1.0, 0.0),
            corner(1.0, 1.0),
            corner(0.0, 1.0),
        ]);
        let quad = if side == 1 { [[0, 1, 2], [0, 2, 3]] } else { [[0, 2, 1], [0, 3, 2]] };
        g.indices.extend(quad.map(|t| t.map(|i| base + i)));
    }
    g
}

/// A closed sphere-like mesh from the octahedron's surface lattice (`8·n²` triangles), radius
/// jittered by `bumps` (0 for a sphere) except at the six axis points, vertices rounded to
/// multiples of 2⁻¹², so that its bounds are exactly `[-1, 1]³`.
pub fn blob(n: i32, bumps: f32) -> Geometry {
    let mut index: HashMap<IVec3, u32> = HashMap::new();
    let mut g = Geometry::default();
    let mut vertex = |q: IVec3, g: &mut Geometry| {
        *index.entry(q).or_insert_with(|| {
            let id = g.positions.len() as u32;
            let axis = q.abs().max_element() == n;
            let r = if axis { 1.0 } else { 1.0 - bumps * rand_f32(id, 0, 0) };
            let p = q.as_vec3().normalize() * r;
            g.positions.push((p * 4096.0).round() / 4096.0);
            id
        })
    };
    for octant in 0..8 {
        let s = IVec3::new(1 - 2 * (octant & 1), 1 - (octant & 2), 1 - (octant & 4) / 2);
        let at = |i: i32, j: i32| IVec3::new(i, j, n - i - j) * s;
        let flip = s.x * s.y * s.z < 0;
        for i in 0..n {
            for j in 0..n - i {
                let mut tris = vec![[at(i, j), at(i + 1, j), at(i, j + 1)]];
                if i + j < n - 1 {
                    tris.push([at(i + 1, j), at(i + 1, j + 1), at(i, j + 1)]);
                }
                for mut t in tris {
                    if flip {
                        t.swap(1, 2);
                    }
                    let t = t.map(|q| vertex(q, &mut g));
                    g.indices.push(t);
                }
            }
        }
    }
    g
}

fn scaled(g: &Geometry, s: f64) -> Geometry {
    let positions = g.positions.iter().map(|p| (p.as_dvec3() * s).as_vec3()).collect();
    Geometry { positions, indices: g.indices.clone(), ..Default::default() }
}

pub fn fitted(g: &Geometry, res: u32) -> GridSpec {
    let (lo, hi) = g.bounds().unwrap();
    GridSpec::fit(lo.as_dvec3(), hi.as_dvec3(), res).unwrap()
}

fn coords(v: &Voxelization) -> Vec<UVec3> {
    v.voxels.coords().collect()
}

#[test]
fn surface_voxelizers_equal_the_reference_with_lists() {
    let g = blob(5, 0.3);
    let grid = fitted(&g, 11);
    let lattice = Lattice::new(&g, &grid).unwrap();
    let tris: Vec<[IVec3; 3]> =
        g.indices.iter().map(|t| t.map(|i| lattice.vertex(i).unwrap())).collect();
    for (mode, test) in
        [(Mode::Conservative, box_overlap as fn(&_, _) -> bool), (Mode::Thin, diamond_overlap)]
    {
        let v = voxelize(&g, &grid, &options(mode, true)).unwrap();
        v.voxels.validate().unwrap();
        let mut expected = Vec::new();
        for z in 0..grid.dims.z {
            for y in 0..grid.dims.y {
                for x in 0..grid.dims.x {
                    let c = UVec3::new(x, y, z);
                    let list: Vec<u32> = (0..tris.len() as u32)
                        .filter(|&t| test(&tris[t as usize], c.as_ivec3()))
                        .collect();
                    if !list.is_empty() {
                        expected.push((voxlod_format::morton::encode(c), c, list));
                    }
                }
            }
        }
        expected.sort_by_key(|e| e.0);
        assert_eq!(v.voxels.len(), expected.len(), "{mode:?}");
        for (i, (_, c, list)) in expected.iter().enumerate() {
            assert_eq!(v.voxels.coord_of(i), *c);
            assert_eq!(v.triangles_of(i), list.as_slice(), "{mode:?} voxel {c}");
        }
        // Occupancy alone: the same voxels, empty ranges.
        let occ = voxelize(&g, &grid, &options(mode, false)).unwrap();
        assert_eq!(coords(&occ), coords(&v));
        assert!(occ.triangles.is_empty() && occ.voxels.values().iter().all(|r| r.count == 0));
    }
}

#[test]
fn dense_and_sparse_occupancy_paths_agree() {
    let g = blob(6, 0.2);
    let grid = fitted(&g, 20);
    let lattice = Lattice::new(&g, &grid).unwrap();
    for thin in [false, true] {
        let dense: Vec<u64> = pairs::dense_bits(&g, &lattice, thin).unwrap().codes().collect();
        assert_eq!(dense, pairs::sorted_codes(&g, &lattice, thin).unwrap());
        assert!(!dense.is_empty() && dense.windows(2).all(|w| w[0] < w[1]));
    }
}

#[test]
fn plane_on_a_voxel_boundary_fills_both_layers() {
    // Regression (axis-aligned thin planes, faces on voxel boundaries): a quad over the whole
    // grid at z = 5 exactly overlaps the full layers 4 and 5 — no missing voxel.
    let n = 9.0;
    let g = geometry(
        vec![
            Vec3::new(0.0, 0.0, 5.0),
            Vec3::new(n, 0.0, 5.0),
            Vec3::new(n, n, 5.0),
            Vec3::new(0.0, n, 5.0),
        ],
        vec![[0, 1, 2], [0, 2, 3]],
    );
    for mode in [Mode::Conservative, Mode::Thin] {
        let v = voxelize(&g, &grid(9), &options(mode, true)).unwrap();
        let set: HashSet<UVec3> = v.voxels.coords().collect();
        assert_eq!(set.len(), 2 * 81, "{mode:?}");
        assert!((0..9).all(|x| {
            (0..9).all(|y| set.contains(&UVec3::new(x, y, 4)) && set.contains(&UVec3::new(x, y, 5)))
        }));
    }
}

/// Voxel centres above the plane `z = a·x + b·y + c` reachable from voxel (0, 0, 0) through
/// 6-connected unset voxels.
fn leaks(set: &HashSet<UVec3>, n: u32, plane: impl Fn(f64, f64) -> f64) -> usize {
    let mut seen = HashSet::from([UVec3::ZERO]);
    let mut stack = vec![UVec3::ZERO];
    let mut leaks = 0;
    while let Some(c) = stack.pop() {
        let centre = c.as_dvec3() + 0.5;
        leaks += (centre.z > plane(centre.x, centre.y)) as usize;
        for d in [IVec3::X, IVec3::Y, IVec3::Z, -IVec3::X, -IVec3::Y, -IVec3::Z] {
            let q = c.as_ivec3() + d;
            if q.cmpge(IVec3::ZERO).all() && q.cmplt(IVec3::splat(n as i32)).all() {
                let q = q.as_uvec3();
                if !set.contains(&q) && seen.insert(q) {
                    stack.push(q);
                }
            }
        }
    }
    leaks
}

#[test]
fn thin_is_6_separating_and_thinner_than_conservative() {
    let n = 24;
    let plane = |x: f64, y: f64| 0.31 * x + 0.17 * y + 3.3;
    let corner = |x: f32, y: f32| Vec3::new(x, y, plane(x as f64, y as f64) as f32);
    let g = geometry(
        vec![corner(-1.0, -1.0), corner(25.0, -1.0), corner(25.0, 25.0), corner(-1.0, 25.0)],
        vec![[0, 1, 2], [0, 2, 3]],
    );
    let thin = voxelize(&g, &grid(n), &options(Mode::Thin, false)).unwrap();
    let cons = voxelize(&g, &grid(n), &options(Mode::Conservative, false)).unwrap();
    let thin_set: HashSet<UVec3> = thin.voxels.coords().collect();
    let cons_set: HashSet<UVec3> = cons.voxels.coords().collect();
    assert!(thin_set.is_subset(&cons_set));
    assert!(thin_set.len() < cons_set.len() * 3 / 4, "{} vs {}", thin_set.len(), cons_set.len());
    assert_eq!(leaks(&thin_set, n, plane), 0, "a 6-connected path crosses the thin surface");
    // The check can fail: punch out the thin voxels of one column and the fill leaks up it.
    let mut holed = thin_set.clone();
    holed.retain(|c| c.x != 12 || c.y != 12);
    assert!(holed.len() < thin_set.len() && leaks(&holed, n, plane) > 0);
}

#[test]
fn scaling_the_scene_does_not_change_occupancy() {
    // A bumpy closed mesh with bounds exactly [-1, 1]³, scaled by 1e-4 and 1e5 with the grid
    // fitted to its bounds; and a mesh off the 2^-12 grid scaled by exact powers of two.
    let g = blob(8, 0.3);
    for res in [32, 64, 128] {
        for mode in [Mode::Conservative, Mode::Thin, Mode::Solid] {
            let reference = coords(&voxelize(&g, &fitted(&g, res), &options(mode, false)).unwrap());
            assert!(!reference.is_empty());
            for s in [1e-4, 1e5] {
                let h = scaled(&g, s);
                let got = coords(&voxelize(&h, &fitted(&h, res), &options(mode, false)).unwrap());
                assert!(
                    got == reference,
                    "{mode:?} at {res}³ scaled by {s}: {} vs {} voxels",
                    got.len(),
                    reference.len()
                );
            }
        }
    }
    let mut g = blob(7, 0.3);
    for (i, p) in g.positions.iter_mut().enumerate() {
        *p +=
            Vec3::new(rand_f32(i as u32, 1, 0), rand_f32(i as u32, 1, 1), rand_f32(i as u32, 1, 2))
                * 1e-3;
    }
    for res in [37, 50] {
        for mode in [Mode::Conservative, Mode::Thin, Mode::Solid] {
            let reference = coords(&voxelize(&g, &fitted(&g, res), &options(mode, false)).unwrap());
            for s in [2f64.powi(-14), 2f64.powi(17)] {
                let h = scaled(&g, s);
                let got = coords(&voxelize(&h, &fitted(&h, res), &options(mode, false)).unwrap());
                assert!(got == reference, "{mode:?} at {res} scaled by {s}");
            }
        }
    }
}

#[test]
fn degenerate_and_needle_triangles() {
    let p = [
        Vec3::new(0.5, 0.5, 0.5),
        Vec3::new(3.5, 0.5, 0.5),
        Vec3::new(2.0, 0.5, 0.5),
        Vec3::new(0.1, 0.2, 0.3),
        Vec3::new(7.7, 6.9, 7.3),
        Vec3::new(7.7, 6.9, 7.301),
    ];
    // A collinear triangle (a segment through voxel centres), a point on the face between two
    // voxels (it touches both), a needle.
    let g = geometry(p.to_vec(), vec![[0, 1, 2], [2, 2, 2], [3, 4, 5]]);
    let v = voxelize(&g, &grid(8), &options(Mode::Conservative, true)).unwrap();
    let lists: HashMap<UVec3, Vec<u32>> =
        v.voxels.coords().enumerate().map(|(i, c)| (c, v.triangles_of(i).to_vec())).collect();
    let segment: Vec<UVec3> =
        lists.iter().filter(|(_, l)| l.contains(&0)).map(|(c, _)| *c).collect();
    assert_eq!(segment.len(), 4);
    assert!(segment.iter().all(|c| c.y == 0 && c.z == 0 && c.x < 4));
    assert_eq!(lists.iter().filter(|(_, l)| l.contains(&1)).count(), 2);
    let needle = lists.iter().filter(|(_, l)| l.contains(&2)).count();
    assert!((8..8 * 8).contains(&needle), "{needle}");
    // Zero-area triangles cross nothing: solid ignores them, and they are no boundary edges.
    let mut g = cube(Vec3::splat(2.0), 3.0, &[]);
    g.positions.extend([Vec3::splat(2.0), Vec3::splat(3.5), Vec3::splat(5.0)]);
    g.indices.push([24, 25, 26]);
    let v = voxelize(&g, &grid(8), &options(Mode::Solid, false)).unwrap();
    assert_eq!((v.voxels.len(), v.boundary_edges), (27, Some(0)));
}

#[test]
fn empty_geometry_gives_an_empty_voxelization() {
    for mode in [Mode::Conservative, Mode::Thin, Mode::Solid] {
        for g in [Geometry::default(), geometry(vec![Vec3::splat(50.0); 3], vec![[0, 1, 2]])] {
            let v = voxelize(&g, &grid(8), &options(mode, true)).unwrap();
            assert!(v.voxels.is_empty() && v.triangles.is_empty());
            assert_eq!(v.boundary_edges, (mode == Mode::Solid).then_some(0));
        }
    }
}

#[test]
fn bad_input_gives_errors_that_name_it() {
    let tri = |p: Vec3| geometry(vec![Vec3::ONE, Vec3::new(2.0, 1.0, 1.0), p], vec![[0, 1, 2]]);
    for mode in [Mode::Conservative, Mode::Solid] {
        let err = voxelize(&tri(Vec3::new(f32::NAN, 0.0, 0.0)), &grid(4), &options(mode, true));
        let err = err.unwrap_err().to_string();
        assert!(err.contains("vertex 2") && err.contains("not finite"), "{err}");
        let err =
            voxelize(&tri(Vec3::new(1.0, f32::INFINITY, 0.0)), &grid(4), &options(mode, true));
        assert!(err.unwrap_err().to_string().contains("vertex 2"));
        // A triangle reaching into the grid from 1e30 is refused, never clamped.
        let err = voxelize(&tri(Vec3::new(1e30, 1.0, 1.0)), &grid(4), &options(mode, true));
        let err = err.unwrap_err().to_string();
        assert!(err.contains("triangle = 0") && err.contains("vertex 2"), "{err}");
        let mut g = tri(Vec3::ONE);
        g.indices.push([0, 1, 3]);
        let err = voxelize(&g, &grid(4), &options(mode, true)).unwrap_err().to_string();
        assert!(err.contains("triangle 1") && err.contains("vertex 3"), "{err}");
    }
    // A triangle at 1e30 entirely outside the grid is culled.
    let far = geometry(
        vec![Vec3::splat(1e30), Vec3::new(1e30, 0.0, 1e30), Vec3::splat(2e30)],
        vec![[0, 1, 2]],
    );
    assert!(voxelize(&far, &grid(4), &Options::default()).unwrap().voxels.is_empty());
}

#[test]
fn grids_too_large_are_refused_with_the_estimate() {
    let big = GridSpec::new(DVec3::ZERO, 1.0, UVec3::new(1 << 21, 1, 1)).unwrap();
    let g = cube(Vec3::ONE, 1.0, &[]);
    let err = voxelize(&g, &big, &Options::default()).unwrap_err();
    assert!(
        matches!(err, crate::Error::Format(voxlod_format::Error::GridTooLarge { .. })),
        "{err}"
    );
    // A plane across a 2^20 × 2^20 grid: about 2^41 voxels, far over the default 8 GiB.
    let n = (1 << 20) as f32;
    let plane =
        geometry(vec![Vec3::ZERO, Vec3::new(n, 0.0, 0.0), Vec3::new(0.0, n, 0.0)], vec![[0, 1, 2]]);
    let huge = GridSpec::new(DVec3::ZERO, 1.0, UVec3::new(1 << 20, 1 << 20, 1)).unwrap();
    for mode in [Mode::Conservative, Mode::Thin, Mode::Solid] {
        for lists in [false, true] {
            match voxelize(&plane, &huge, &options(mode, lists)) {
                Err(crate::Error::OutOfMemory { dims, estimated_bytes, limit_bytes }) => {
                    assert_eq!(dims, [1 << 20, 1 << 20, 1]);
                    assert!(estimated_bytes > 1 << 40 && limit_bytes == 8 << 30);
                }
                other => panic!("{mode:?}: expected OutOfMemory, got {other:?}"),
            }
        }
    }
    // The same guard under a small explicit limit on an ordinary grid.
    let small = Options { memory_limit_bytes: 1000, ..Options::default() };
    assert!(matches!(voxelize(&g, &grid(8), &small), Err(crate::Error::OutOfMemory { .. })));
}
