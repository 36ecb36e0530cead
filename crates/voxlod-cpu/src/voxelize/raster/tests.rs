//! The rasterizer must emit exactly the voxels the per-voxel reference accepts, once each.

use glam::{I64Vec3, IVec3, UVec3};
use proptest::prelude::*;

use super::*;
use crate::voxelize::overlap::{box_overlap, diamond_overlap};

/// Every voxel of a `dims` grid the reference accepts, in the rasterizer's sorted order.
fn reference(tri: &[IVec3; 3], thin: bool, dims: UVec3) -> Vec<UVec3> {
    let test = if thin { diamond_overlap } else { box_overlap };
    let mut out = Vec::new();
    for z in 0..dims.z {
        for y in 0..dims.y {
            for x in 0..dims.x {
                let c = UVec3::new(x, y, z);
                if test(tri, c.as_ivec3()) {
                    out.push(c);
                }
            }
        }
    }
    out
}

fn sorted(mut v: Vec<UVec3>) -> Vec<UVec3> {
    v.sort_by_key(|c| (c.z, c.y, c.x));
    v
}

fn check(tri: [IVec3; 3], dims: UVec3) -> Result<(), TestCaseError> {
    for thin in [false, true] {
        let got = voxels(&tri, thin, dims);
        let n = got.len();
        let got = sorted(got);
        prop_assert!(got.windows(2).all(|w| w[0] != w[1]), "duplicate voxel");
        prop_assert_eq!(n, got.len());
        prop_assert_eq!(got, reference(&tri, thin, dims), "thin = {} tri = {:?}", thin, tri);
    }
    Ok(())
}

fn coord(ties: bool, range: i32) -> BoxedStrategy<i32> {
    if ties {
        (-4..(range / HALF_VOXEL) + 4).prop_map(|k| k * HALF_VOXEL).boxed()
    } else {
        (-2 * VOXEL..range + 2 * VOXEL).boxed()
    }
}

fn triangle(range: i32) -> impl Strategy<Value = [IVec3; 3]> {
    (any::<bool>(), 0..5u8).prop_flat_map(move |(ties, shape)| {
        let v = move || {
            (coord(ties, range), coord(ties, range), coord(ties, range)).prop_map(IVec3::from)
        };
        (v(), v(), v()).prop_map(move |(a, b, c)| match shape {
            0 => [a, b, b * 2 - a],
            1 => [a, a, a],
            2 => [a, a, c],
            _ => [a, b, c],
        })
    })
}

proptest! {
    #[test]
    fn small_triangles_match_the_reference(
        tri in triangle(6 * VOXEL), dims in (1u32..7, 1u32..7, 1u32..7)
    ) {
        check(tri, UVec3::new(dims.0, dims.1, dims.2))?;
    }

    #[test]
    fn large_triangles_match_the_reference(tri in triangle(24 * VOXEL)) {
        // Bounding boxes many voxels deep along the dominant axis: the plane interval is
        // computed by division instead of scanned.
        check(tri, UVec3::new(22, 20, 24))?;
    }
}

#[test]
fn ground_plane_covers_its_columns_once() {
    // A 64×64-voxel quad at y = 10.5 voxels: exactly one layer.
    let (n, y) = (64 * VOXEL, 10 * VOXEL + HALF_VOXEL);
    let quad = [
        [IVec3::new(0, y, 0), IVec3::new(n, y, 0), IVec3::new(n, y, n)],
        [IVec3::new(0, y, 0), IVec3::new(n, y, n), IVec3::new(0, y, n)],
    ];
    let dims = UVec3::new(64, 32, 64);
    for thin in [false, true] {
        let mut all: Vec<UVec3> = quad.iter().flat_map(|t| voxels(t, thin, dims)).collect();
        all.sort_by_key(|c| (c.z, c.y, c.x));
        all.dedup();
        assert_eq!(all.len(), 64 * 64);
        assert!(all.iter().all(|c| c.y == 10));
    }
}

#[test]
fn culled_and_clipped_triangles() {
    let dims = UVec3::splat(4);
    // Entirely outside: nothing.
    let out =
        [IVec3::splat(-3 * VOXEL), IVec3::splat(-2 * VOXEL), IVec3::new(-VOXEL - 1, 0, -VOXEL - 1)];
    assert!(voxels(&out, false, dims).is_empty());
    // Touching the grid's far face from outside: the last layer (closed boxes).
    let v = 4 * VOXEL;
    let face = [IVec3::new(v, 0, 0), IVec3::new(v, v, 0), IVec3::new(v, 0, v)];
    let got = voxels(&face, false, dims);
    assert!(!got.is_empty() && got.iter().all(|c| c.x == 3));
    assert_eq!(got, reference(&face, false, dims));
}

#[test]
fn huge_triangles_take_the_wide_path_and_match_the_reference() {
    // Extents over SMALL_EXTENT (512 voxels): the plane test runs in i128, and the tilt makes
    // the working-axis range deep enough to be divided out rather than scanned.
    let v = VOXEL;
    let dims = UVec3::new(600, 14, 580);
    for tri in [
        [
            IVec3::new(-3 * v, v, 0),
            IVec3::new(600 * v, 13 * v + 7, 40 * v),
            IVec3::new(17, 2 * v + 99, 579 * v),
        ],
        [
            IVec3::new(0, 0, 0),
            IVec3::new(599 * v + 3, 14 * v, 0),
            IVec3::new(0, 7 * v + 1, 580 * v),
        ],
    ] {
        assert!((tri[1] - tri[0]).abs().max_element() as i64 > SMALL_EXTENT);
        check(tri, dims).unwrap();
    }
}

/// The equivalence suite found `PlaneSpan::new` computing `n·VOXEL` in `i64`, which
/// overflows for triangles over ~2^19 voxels across (`|n| > 2^55`): a panic with overflow
/// checks, wrong voxels without. Triangles reaching the lattice's limit (`±COORD_LIMIT`, 2^21
/// voxels) through a small grid must match the per-voxel reference (`i128`).
#[test]
fn triangles_at_the_lattice_limit_match_the_reference() {
    // The triangle `(p + a, p + b, p − a − b)`: its centroid is `p`.
    let around = |p: IVec3, a: [i32; 3], b: [i32; 3]| {
        let (a, b) = (IVec3::from_array(a), IVec3::from_array(b));
        [p + a, p + b, p - a - b]
    };
    use crate::voxelize::lattice::COORD_LIMIT;
    let (l, v) = (COORD_LIMIT, VOXEL);
    let dims = UVec3::splat(14);
    for tri in [
        // The equivalence suite's "far" triangles, 1.5·10^6 voxels out.
        [
            IVec3::new(-384_000_000, 845, 1050),
            IVec3::new(2483, 307_200_000, 1408),
            IVec3::new(1331, 1562, 1856),
        ],
        [
            IVec3::new(794, 1075, -280_320_000),
            IVec3::new(357_120_000, 334_080_000, 2099),
            IVec3::new(1690, 563, 2330),
        ],
        // Vertices near the limit, centroid inside the grid, tilted: |n| near 2^59.
        around(
            IVec3::new(7 * v + 13, 6 * v + 99, 7 * v + 50),
            [l / 2, -l / 3 + 7, l / 2 - 1],
            [-l / 2 + 5, l / 2, l / 5],
        ),
        around(
            IVec3::new(3 * v, 11 * v + 1, 5 * v + 128),
            [l / 2 - 3, l / 2, -l / 2],
            [l / 3, -l / 2 + 9, l / 2],
        ),
    ] {
        let n = (tri[1] - tri[0]).as_i64vec3().cross((tri[2] - tri[0]).as_i64vec3());
        assert!(n.abs().max_element() > 1 << 55, "{n}");
        for thin in [false, true] {
            let got = sorted(voxels(&tri, thin, dims));
            let want = reference(&tri, thin, dims);
            assert!(!want.is_empty(), "the triangle must reach the grid: {tri:?}");
            assert_eq!(got, want, "thin = {thin}, tri = {tri:?}");
        }
    }
}

proptest! {
    #[test]
    fn plane_span_widths_agree(
        tri in triangle(40 * VOXEL),
        i in -2i64..45, j in -2i64..45, k in -2i64..45,
        o in (-3i64..3, -3i64..3, -3i64..3),
    ) {
        let v = tri.map(|p| p.as_i64vec3());
        let n = (v[1] - v[0]).cross(v[2] - v[0]);
        prop_assume!(n.z != 0);
        let origin = I64Vec3::new(o.0, o.1, o.2);
        for thin in [false, true] {
            let (narrow, wide) = if thin {
                (PlaneSpan::<i64>::new::<true>(&v, n, origin), PlaneSpan::<i128>::new::<true>(&v, n, origin))
            } else {
                (PlaneSpan::<i64>::new::<false>(&v, n, origin), PlaneSpan::<i128>::new::<false>(&v, n, origin))
            };
            let (x, y) = (narrow.column(i, j), wide.column(i, j));
            prop_assert_eq!(x as i128, y);
            prop_assert_eq!(narrow.passes(x, k), wide.passes(y, k));
            prop_assert_eq!(narrow.range(x), wide.range(y));
            // The range is exactly the passing voxels.
            let (first, last) = wide.range(y);
            for kk in first - 2..=last + 2 {
                prop_assert_eq!(wide.passes(y, kk), (first..=last).contains(&kk));
            }
        }
    }
}
