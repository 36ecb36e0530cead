//! Solid voxelization tests: the closed-cube regression, the open-mesh rule, and parity against
//! an independent winding-number oracle.

use std::collections::HashSet;

use glam::{DVec3, UVec3, Vec3};

use crate::voxelize::lattice::{self, Lattice};
use crate::voxelize::tests::{blob, cube, fitted, grid, options};
use crate::voxelize::{Mode, voxelize};

#[test]
fn closed_cube_solid_is_exactly_n_cubed_wherever_its_faces_sit() {
    // Regression: N×N×N, not N×N×(N−1), for faces on voxel boundaries, through voxel centres
    // (half-voxel offsets) and anywhere between.
    for n in [1, 2, 3, 5] {
        for offset in [
            Vec3::splat(1.0),
            Vec3::splat(1.5),
            Vec3::new(1.25, 2.5, 1.0),
            Vec3::new(1.0 / 3.0, 2.75, 1.5),
        ] {
            let g = cube(offset, n as f32, &[]);
            for lists in [false, true] {
                let v = voxelize(&g, &grid(9), &options(Mode::Solid, lists)).unwrap();
                assert_eq!(v.voxels.len(), n * n * n, "n = {n}, offset {offset}");
                assert_eq!(v.boundary_edges, Some(0));
                // The first centre i + ½ at or past the lower face.
                let lo = (offset - 0.5).ceil().as_uvec3();
                assert!(
                    v.voxels.coords().all(|c| c.cmpge(lo).all() && c.cmplt(lo + n as u32).all())
                );
            }
        }
    }
}

#[test]
fn open_box_solid_uses_the_majority_rule() {
    // A cube missing one face is not closed (its rim: 4 boundary edges); the majority of the
    // three axis parities still gives exactly its interior, for every missing face, where the
    // z parity alone would fill the columns above the bottom to the top of the grid.
    let n = 4;
    for face in 0..6 {
        let g = cube(Vec3::splat(2.0), n as f32, &[face]);
        let v = voxelize(&g, &grid(10), &options(Mode::Solid, false)).unwrap();
        assert_eq!(v.boundary_edges, Some(4), "face {face}");
        assert!(!v.is_closed());
        assert_eq!(v.voxels.len(), n * n * n, "face {face}");
        assert!(
            v.voxels
                .coords()
                .all(|c| c.cmpge(UVec3::splat(2)).all() && c.cmplt(UVec3::splat(6)).all())
        );
    }
}

/// Winding number of the point `p` with respect to the triangles `tris` (Van Oosterom &
/// Strackee solid angles), in `f64`.
fn winding(tris: &[[DVec3; 3]], p: DVec3) -> f64 {
    let total: f64 = tris
        .iter()
        .map(|t| {
            let [a, b, c] = t.map(|v| v - p);
            let (la, lb, lc) = (a.length(), b.length(), c.length());
            let num = a.dot(b.cross(c));
            let den = la * lb * lc + a.dot(b) * lc + b.dot(c) * la + c.dot(a) * lb;
            2.0 * num.atan2(den)
        })
        .sum();
    total / (4.0 * std::f64::consts::PI)
}

#[test]
fn solid_blob_matches_the_winding_number_and_lists_match_conservative() {
    let g = blob(6, 0.35);
    let grid = fitted(&g, 14);
    let lattice = Lattice::new(&g, &grid).unwrap();
    let tris: Vec<[DVec3; 3]> =
        g.indices.iter().map(|t| t.map(|i| lattice.vertex(i).unwrap().as_dvec3())).collect();
    let v = voxelize(&g, &grid, &options(Mode::Solid, true)).unwrap();
    assert!(v.is_closed());
    let solid: HashSet<UVec3> = v.voxels.coords().collect();
    let mut inside = 0;
    for z in 0..grid.dims.z {
        for y in 0..grid.dims.y {
            for x in 0..grid.dims.x {
                let c = UVec3::new(x, y, z);
                let w = winding(&tris, (c.as_dvec3() + 0.5) * lattice::VOXEL as f64);
                assert!((w - w.round()).abs() < 0.25, "centre {c} too close to the surface: {w}");
                assert_eq!(solid.contains(&c), w.round() != 0.0, "voxel {c}, winding {w}");
                inside += (w.round() != 0.0) as usize;
            }
        }
    }
    assert!(inside > 100, "{inside}");
    // Lists: exactly the conservative lists of the solid voxels; interior voxels empty.
    let cons = voxelize(&g, &grid, &options(Mode::Conservative, true)).unwrap();
    for (i, c) in v.voxels.coords().enumerate() {
        let expected = cons.voxels.index_of(c).map(|j| cons.triangles_of(j)).unwrap_or(&[]);
        assert_eq!(v.triangles_of(i), expected, "voxel {c}");
    }
    let listed: usize = v.voxels.values().iter().map(|r| r.count as usize).sum();
    assert_eq!(listed, v.triangles.len());
}
