//! Slicemap tests: both coverage rules against independent oracles, the depth that defines a
//! slice, slicing, layers, queries, the comparison with the exact voxelizers, and the extremes
//! (edge-on and zero-area triangles, 512 perspective slices, full columns, a light inside the
//! volume, a scene larger than the depth range).

use glam::{DVec2, DVec3, UVec3, Vec3};
use proptest::prelude::*;
use voxlod_format::GridSpec;
use voxlod_scene::Geometry;

use super::camera::{FRONT_FACING, SUBPIXEL};
use super::compare::{Agreement, DenseBits, aligned_voxels, merged_voxels};
use super::query::{count_below, inner_voxels};
use super::raster::{for_each_conservative, for_each_covered};
use super::*;
use crate::voxelize::{self as vox, Mode};

fn geometry(tris: &[[Vec3; 3]]) -> Geometry {
    let mut g = Geometry::default();
    for t in tris {
        let base = g.positions.len() as u32;
        g.positions.extend_from_slice(t);
        g.indices.push([base, base + 1, base + 2]);
    }
    g
}

/// A camera looking down −z from `z = 10` at the square `[0, n]²` (window x = world x,
/// window y = n − world y), depth from `near` to `far` in eye-space z.
fn ortho(n: u32, near: f64, far: f64) -> SliceCamera {
    SliceCamera {
        eye: DVec3::new(n as f64 * 0.5, n as f64 * 0.5, 10.0),
        forward: DVec3::NEG_Z,
        up: DVec3::Y,
        projection: Projection::Orthographic {
            half_width: n as f64 * 0.5,
            half_height: n as f64 * 0.5,
        },
        width: n,
        height: n,
        near,
        far,
    }
}

fn opts(slices: u32) -> Options {
    Options { slices, ..Options::default() }
}

fn tri(v: [(i64, i64); 3], q: [f32; 3]) -> SliceTriangle {
    let mut t = SliceTriangle {
        x0: v[0].0 as i32,
        y0: v[0].1 as i32,
        x1: v[1].0 as i32,
        y1: v[1].1 as i32,
        x2: v[2].0 as i32,
        y2: v[2].1 as i32,
        q0: q[0],
        q1: q[1],
        q2: q[2],
        ..Default::default()
    };
    let a = t.area2();
    if a != 0 {
        let (ax, ay) = ((v[1].0 - v[0].0) as f64, (v[1].1 - v[0].1) as f64);
        let (bx, by) = ((v[2].0 - v[0].0) as f64, (v[2].1 - v[0].1) as f64);
        let (qa, qb) = ((q[1] - q[0]) as f64, (q[2] - q[0]) as f64);
        let s = SUBPIXEL as f64 / a as f64;
        t.dqdx = ((qa * by - qb * ay) * s) as f32;
        t.dqdy = ((ax * qb - bx * qa) * s) as f32;
    }
    t
}

fn orient(a: (i64, i64), b: (i64, i64), p: (i64, i64)) -> i64 {
    (b.0 - a.0) * (p.1 - a.1) - (b.1 - a.1) * (p.0 - a.0)
}

/// Independent oracle of the standard rule: the centre on the inner side of every edge, and
/// on an edge only when that edge is a top edge (horizontal, third vertex below) or a left
/// edge (the third vertex to the right of the edge's line at its height).
fn covers_oracle(v: [(i64, i64); 3], x: i64, y: i64) -> bool {
    let p = (x * SUBPIXEL + SUBPIXEL / 2, y * SUBPIXEL + SUBPIXEL / 2);
    if orient(v[0], v[1], v[2]) == 0 {
        return false;
    }
    for i in 0..3 {
        let (a, b, c) = (v[i], v[(i + 1) % 3], v[(i + 2) % 3]);
        let (s, sc) = (orient(a, b, p), orient(a, b, c));
        if s != 0 && (s > 0) != (sc > 0) {
            return false;
        }
        if s == 0 {
            let top = a.1 == b.1 && c.1 > a.1;
            // x of the edge's line at c.y, compared with c.x, times (b.y − a.y).
            let dy = b.1 - a.1;
            let left = dy != 0 && {
                let lhs = c.0 * dy;
                let rhs = a.0 * dy + (b.0 - a.0) * (c.1 - a.1);
                if dy > 0 { lhs > rhs } else { lhs < rhs }
            };
            if !(top || left) {
                return false;
            }
        }
    }
    true
}

fn on_segment(a: (i64, i64), b: (i64, i64), p: (i64, i64)) -> bool {
    orient(a, b, p) == 0
        && p.0 >= a.0.min(b.0)
        && p.0 <= a.0.max(b.0)
        && p.1 >= a.1.min(b.1)
        && p.1 <= a.1.max(b.1)
}

fn segments_meet(a: (i64, i64), b: (i64, i64), c: (i64, i64), d: (i64, i64)) -> bool {
    let (d1, d2) = (orient(c, d, a), orient(c, d, b));
    let (d3, d4) = (orient(a, b, c), orient(a, b, d));
    if ((d1 > 0 && d2 < 0) || (d1 < 0 && d2 > 0)) && ((d3 > 0 && d4 < 0) || (d3 < 0 && d4 > 0)) {
        return true;
    }
    on_segment(c, d, a) || on_segment(c, d, b) || on_segment(a, b, c) || on_segment(a, b, d)
}

fn in_closed_triangle(v: [(i64, i64); 3], p: (i64, i64)) -> bool {
    let s = orient(v[0], v[1], v[2]).signum();
    s != 0 && (0..3).all(|i| orient(v[i], v[(i + 1) % 3], p) * s >= 0)
}

/// Independent oracle of the conservative rule: closed square and closed triangle meet when a
/// vertex is in the square, a corner in the triangle, or an edge crosses a side.
fn meets_oracle(v: [(i64, i64); 3], x: i64, y: i64) -> bool {
    let (x0, y0, x1, y1) = (x * SUBPIXEL, y * SUBPIXEL, (x + 1) * SUBPIXEL, (y + 1) * SUBPIXEL);
    let corners = [(x0, y0), (x1, y0), (x1, y1), (x0, y1)];
    if v.iter().any(|p| p.0 >= x0 && p.0 <= x1 && p.1 >= y0 && p.1 <= y1) {
        return true;
    }
    if corners.iter().any(|&c| in_closed_triangle(v, c)) {
        return true;
    }
    (0..3).any(|i| {
        (0..4).any(|k| segments_meet(v[i], v[(i + 1) % 3], corners[k], corners[(k + 1) % 4]))
    })
}

/// Sutherland–Hodgman clipping of a polygon to `f ≥ 0`, in f64.
fn clip_f64(poly: &[DVec3], f: impl Fn(DVec3) -> f64) -> Vec<DVec3> {
    let mut out = Vec::new();
    for i in 0..poly.len() {
        let (a, b) = (poly[i], poly[(i + 1) % poly.len()]);
        let (fa, fb) = (f(a), f(b));
        if fa >= 0.0 {
            out.push(a);
        }
        if (fa >= 0.0) != (fb >= 0.0) {
            out.push(a + (b - a) * (fa / (fa - fb)));
        }
    }
    out
}

fn coverage(t: &SliceTriangle, n: u32) -> Vec<(u32, u32)> {
    let mut out = Vec::new();
    for_each_covered(t, n, n, |x, y| out.push((x, y)));
    out
}

/// Vertex coordinates on a coarse sub-lattice (multiples of `step` sub-pixel units) inside
/// `[-1, n + 1]` pixels, so that centres, edges and corners tie often.
fn lattice_tri(n: i64, step: i64) -> impl Strategy<Value = [(i64, i64); 3]> {
    let c = (-SUBPIXEL / step)..=((n + 1) * SUBPIXEL / step);
    proptest::array::uniform3((c.clone(), c))
        .prop_map(move |v| v.map(|(x, y)| (x * step, y * step)))
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 300, ..ProptestConfig::default() })]

    #[test]
    fn standard_coverage_matches_the_oracle(v in lattice_tri(6, 64)) {
        let t = tri(v, [0.0; 3]);
        let got = coverage(&t, 6);
        for y in 0..6 {
            for x in 0..6 {
                prop_assert_eq!(got.contains(&(x, y)), covers_oracle(v, x as i64, y as i64),
                    "pixel ({}, {}) of {:?}", x, y, v);
            }
        }
        // Each pixel once.
        let mut sorted = got.clone();
        sorted.sort();
        sorted.dedup();
        prop_assert_eq!(sorted.len(), got.len());
    }

    #[test]
    fn triangles_sharing_an_edge_cover_its_centres_once(
        v in lattice_tri(6, 128), d in ((-1i64..=7), (-1i64..=7))
    ) {
        // Triangles (a, b, c) and (b, a, d) with c and d on opposite sides of ab.
        let d = (d.0 * SUBPIXEL, d.1 * SUBPIXEL);
        let (a, b, c) = (v[0], v[1], v[2]);
        prop_assume!(orient(a, b, c) != 0 && orient(a, b, d) != 0);
        prop_assume!((orient(a, b, c) > 0) != (orient(a, b, d) > 0));
        let one = coverage(&tri([a, b, c], [0.0; 3]), 8);
        let two = coverage(&tri([b, a, d], [0.0; 3]), 8);
        for p in &one {
            prop_assert!(!two.contains(p), "{:?} covered twice", p);
        }
        // Centres on the open shared edge: covered by exactly one.
        for y in 0..8i64 {
            for x in 0..8i64 {
                let p = (x * SUBPIXEL + 128, y * SUBPIXEL + 128);
                if on_segment(a, b, p) && p != a && p != b {
                    let n = one.contains(&(x as u32, y as u32)) as u32
                        + two.contains(&(x as u32, y as u32)) as u32;
                    prop_assert_eq!(n, 1, "centre {:?} on the shared edge", p);
                }
            }
        }
    }

    #[test]
    fn conservative_coverage_matches_the_oracle(v in lattice_tri(5, 64)) {
        let t = tri(v, [1.0, 2.0, 3.0]);
        let mut got = Vec::new();
        for_each_conservative(&t, 5, 5, |x, y, lo, hi| got.push((x, y, lo, hi)));
        for y in 0..5 {
            for x in 0..5 {
                let hit = got.iter().any(|g| (g.0, g.1) == (x, y));
                prop_assert_eq!(hit, meets_oracle(v, x as i64, y as i64),
                    "pixel ({}, {}) of {:?}", x, y, v);
            }
        }
        // Standard ⊆ conservative.
        for p in coverage(&t, 5) {
            prop_assert!(got.iter().any(|g| (g.0, g.1) == p));
        }
        // Depth ranges within the triangle's.
        for g in got {
            prop_assert!(g.2 >= 1.0 && g.3 <= 3.0 && g.2 <= g.3, "{:?}", g);
        }
    }

    #[test]
    fn conservative_depth_range_is_the_range_over_the_square(
        v in lattice_tri(4, 16), q in proptest::array::uniform3(0.5f32..4.0)
    ) {
        let t = tri(v, q);
        let poly: Vec<DVec3> = (0..3)
            .map(|i| DVec3::new(v[i].0 as f64 / 256.0, v[i].1 as f64 / 256.0, q[i] as f64))
            .collect();
        for_each_conservative(&t, 4, 4, |x, y, lo, hi| {
            // Oracle: the (x, y, q) triangle clipped to the closed square in f64.
            let (x, y) = (x as f64, y as f64);
            let mut p = poly.clone();
            for (axis, bound, sign) in [(0, x, 1.0), (0, x + 1.0, -1.0), (1, y, 1.0), (1, y + 1.0, -1.0)] {
                p = clip_f64(&p, |v: DVec3| sign * (v[axis] - bound));
            }
            let qmin = p.iter().map(|v| v.z).fold(f64::INFINITY, f64::min);
            let qmax = p.iter().map(|v| v.z).fold(f64::NEG_INFINITY, f64::max);
            if p.is_empty() {
                // Touching in a point or along a side: the clip may lose it in f64; skip.
                return;
            }
            assert!((lo as f64 - qmin).abs() < 1e-5 && (hi as f64 - qmax).abs() < 1e-5,
                "range [{lo}, {hi}] vs exact [{qmin}, {qmax}] at ({x}, {y})");
        });
    }

    #[test]
    fn words_count_below_any_slice(words in proptest::collection::vec(any::<u32>(), 1..=16),
                                   s in 0u32..=512) {
        let s = s.min(words.len() as u32 * 32);
        let naive = (0..s).filter(|&j| words[(j / 32) as usize] >> (j % 32) & 1 == 1).count();
        prop_assert_eq!(count_below(&words, s), naive as u32);
    }

    #[test]
    fn unambiguous_intervals_count_their_length(
        cuts in proptest::collection::btree_set(0u32..96, 0..10), local in any::<bool>()
    ) {
        // Alternating front/back voxels at distinct slices: inner = Σ (back − front), plus the
        // rest of the column after an unmatched front.
        let cuts: Vec<u32> = cuts.into_iter().collect();
        let (mut front, mut back) = ([0u32; 3], [0u32; 3]);
        let mut expected = 0;
        for (i, &s) in cuts.iter().enumerate() {
            if i % 2 == 0 {
                front[(s / 32) as usize] |= 1 << (s % 32);
                expected += cuts.get(i + 1).map_or(96 - s, |&b| b - s);
            } else {
                back[(s / 32) as usize] |= 1 << (s % 32);
                if local && s == 95 {
                    expected += 1;
                }
            }
        }
        prop_assert_eq!(inner_voxels(&front, &back, 96, local), expected);
    }
}

fn bits(slices: &[u32]) -> [u32; 1] {
    [slices.iter().fold(0, |w, &s| w | 1 << s)]
}

#[test]
fn ambiguous_voxels_follow_the_papers_rules() {
    let n = 32;
    // Ambiguous at 5, empties 6..9, back at 10: empties were inside (4), ambiguous counts 1.
    assert_eq!(inner_voxels(&bits(&[5]), &bits(&[5, 10]), n, false), 5);
    // Ambiguous at 5, empties, front at 10 (then back at 12): empties were outside.
    assert_eq!(inner_voxels(&bits(&[5, 10]), &bits(&[5, 12]), n, false), 1 + 2);
    // Two ambiguous voxels: the empties between are not counted.
    assert_eq!(inner_voxels(&bits(&[5, 10]), &bits(&[5, 10]), n, false), 2);
    // Front 2, ambiguous 6 (empties 3..5 inside, counted), back 9 (empties 7, 8 inside).
    assert_eq!(inner_voxels(&bits(&[2, 6]), &bits(&[6, 9]), n, false), 1 + 3 + 1 + 2);
    // A back voxel while outside changes nothing; a front without a back runs to the end.
    assert_eq!(inner_voxels(&bits(&[]), &bits(&[4]), n, false), 0);
    assert_eq!(inner_voxels(&bits(&[30]), &bits(&[]), n, false), 2);
    // Local: the back voxel in the last slice ends at the column's far end.
    assert_eq!(inner_voxels(&bits(&[0]), &bits(&[31]), n, true), 32);
    assert_eq!(inner_voxels(&bits(&[0]), &bits(&[31]), n, false), 31);
}

#[test]
fn a_slice_is_defined_by_eye_space_z_not_distance() {
    // A wide perspective map and a triangle parallel to the image plane at z = 2: its points
    // are between 2 and 2/cos(60°) = 4 from the eye, but one eye-space z, so one slice.
    let camera = SliceCamera {
        eye: DVec3::ZERO,
        forward: DVec3::NEG_Z,
        up: DVec3::Y,
        projection: Projection::Perspective { fov_y_deg: 120.0 },
        width: 64,
        height: 64,
        near: 1.0,
        far: 5.0,
    };
    let g = geometry(&[[
        Vec3::new(-3.0, -3.0, -2.0),
        Vec3::new(3.0, -3.0, -2.0),
        Vec3::new(0.0, 3.0, -2.0),
    ]]);
    let map = build(&g, &camera, &opts(8)).unwrap();
    // z = 2 is 1/4 of the way from near to far: slice 2 of 8.
    let mut set = [0u64; 8];
    for y in 0..64 {
        for x in 0..64 {
            for s in 0..8 {
                set[s as usize] += map.get(0, x, y, s) as u64;
            }
        }
    }
    assert!(set[2] > 1000, "{set:?}");
    assert_eq!(set.iter().sum::<u64>(), set[2], "every fragment in slice 2: {set:?}");
    // Distance would have spread it: at pixel (50, 55) the triangle is 3.8 from the eye,
    // which is in slice 5 by distance.
    let frame = camera.frame();
    let (_, dir) = frame.ray(DVec2::new(50.5, 55.5));
    let hit_distance = 2.0 / dir.dot(frame.forward);
    assert!(hit_distance > 3.7, "{hit_distance}");
    assert!(map.get(0, 50, 55, 2));
}

#[test]
fn aligned_camera_maps_grid_coordinates() {
    let grid = GridSpec::new(DVec3::new(-1.0, 2.0, 0.5), 0.25, UVec3::new(8, 12, 16)).unwrap();
    for axis in 0..3 {
        let cam = SliceCamera::aligned(&grid, axis).unwrap();
        let frame = cam.frame();
        let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
        assert_eq!((cam.width, cam.height), (grid.dims[u], grid.dims[v]));
        let g = DVec3::new(3.3, 7.7, 11.1);
        let p = grid.origin + g * grid.voxel_size;
        let (w, z) = frame.project(p).unwrap();
        assert!((w.x - g[u]).abs() < 1e-12 && (w.y - g[v]).abs() < 1e-12, "{axis}: {w}");
        assert!((z - g[axis] * grid.voxel_size).abs() < 1e-12);
    }
    assert!(SliceCamera::aligned(&grid, 3).is_err());
}

#[test]
fn perspective_camera_projects_like_the_scene_camera() {
    let c = voxlod_scene::Camera::look_at(
        Vec3::new(1.0, 2.0, 5.0),
        Vec3::new(0.0, 0.5, 0.0),
        Vec3::Y,
        50.0,
    );
    let cam = SliceCamera::from_camera(&c, 80, 60, 0.1, 20.0);
    let frame = cam.frame();
    let scene = c.frame(80, 60);
    let p = Vec3::new(0.3, 0.2, -0.4);
    let (w, z) = frame.project(p.as_dvec3()).unwrap();
    let (ws, zs) = scene.project(p).unwrap();
    assert!((w.x - ws.x as f64).abs() < 1e-3 && (w.y - ws.y as f64).abs() < 1e-3);
    assert!((z - zs as f64).abs() < 1e-5);
    // The pixel-centre ray inverts the projection.
    let (o, d) = frame.ray(w);
    let back = o + d * (z / d.dot(frame.forward));
    assert!((back - p.as_dvec3()).length() < 1e-5);
}

#[test]
fn bad_cameras_and_options_are_named() {
    let good = ortho(8, 0.0, 20.0);
    good.validate().unwrap();
    let cases: Vec<(SliceCamera, &str)> = vec![
        (SliceCamera { width: 0, ..good }, "width"),
        (SliceCamera { height: 5000, ..good }, "height"),
        (SliceCamera { near: 5.0, far: 5.0, ..good }, "depth range"),
        (SliceCamera { far: f64::NAN, ..good }, "depth range"),
        (SliceCamera { forward: DVec3::ZERO, ..good }, "forward"),
        (SliceCamera { up: DVec3::NEG_Z, ..good }, "up"),
        (SliceCamera { eye: DVec3::INFINITY, ..good }, "finite"),
        (
            SliceCamera {
                projection: Projection::Orthographic { half_width: 0.0, half_height: 1.0 },
                ..good
            },
            "extent",
        ),
        (SliceCamera { projection: Projection::Perspective { fov_y_deg: 180.0 }, ..good }, "fov"),
        (
            SliceCamera {
                projection: Projection::Perspective { fov_y_deg: 60.0 },
                near: 0.0,
                ..good
            },
            "near",
        ),
    ];
    for (cam, word) in cases {
        let err = cam.validate().unwrap_err().to_string();
        assert!(err.contains(word), "{word}: {err}");
    }
    for slices in [0, 513] {
        let err = opts(slices).validate(&good).unwrap_err().to_string();
        assert!(err.contains("slices"), "{err}");
    }
    let tiny = Options { memory_limit_bytes: 100, ..opts(32) };
    assert!(matches!(tiny.validate(&good), Err(Error::OutOfMemory { .. })));
    // Bad geometry names the vertex or the triangle.
    let mut g = geometry(&[[Vec3::ZERO, Vec3::X, Vec3::Y]]);
    g.positions[1].y = f32::NAN;
    let err = build(&g, &good, &opts(32)).unwrap_err().to_string();
    assert!(err.contains("vertex 1"), "{err}");
    g.positions[1].y = 0.0;
    g.indices[0][2] = 9;
    let err = build(&g, &good, &opts(32)).unwrap_err().to_string();
    assert!(err.contains("triangle 0") && err.contains("vertex 9"), "{err}");
}

#[test]
fn a_triangle_seen_edge_on_is_missed_unless_conservative() {
    // The plane x = 3.5 seen along −z: zero area in the window.
    let g =
        geometry(&[[Vec3::new(3.5, 1.0, 9.0), Vec3::new(3.5, 6.0, 9.0), Vec3::new(3.5, 1.0, 2.0)]]);
    let cam = ortho(8, 0.0, 8.0);
    let prepared = prepare(&g, &cam).unwrap();
    assert_eq!(prepared.triangles.len(), 1);
    assert_eq!(prepared.triangles[0].area2(), 0);
    let standard = build(&g, &cam, &opts(8)).unwrap();
    assert_eq!(standard.occupied(), 0, "edge-on: no fragment");
    let cons = build(&g, &cam, &Options { coverage: Coverage::Conservative, ..opts(8) }).unwrap();
    // Columns x = 3 and x = 4 touch the line x = 3.5? Only x = 3 (its square is [3, 4]);
    // rows y from 8 − 6 = 2 to 8 − 1 = 7 (closed squares: rows 1..=7).
    for y in 0..8 {
        for x in 0..8 {
            let expect = x == 3 && (1..=7).contains(&y);
            let column = cons.column(0, x, y)[0];
            assert_eq!(column != 0, expect, "column ({x}, {y}): {column:#b}");
        }
    }
    // Window row 7 holds the vertices at world y = 1, depths 1 and 8 (slices 1..=7); row 1
    // only touches the vertex at world y = 6, depth 1 (slice 1).
    assert_eq!(cons.column(0, 3, 7)[0], 0b1111_1110);
    assert_eq!(cons.column(0, 3, 1)[0], 0b10);
}

#[test]
fn zero_area_triangles_cover_nothing_or_what_they_touch() {
    // A point inside pixel (2, 5) and a segment along y = 3.25 from x = 1.5 to x = 4.5.
    let point = tri([(600, 1400); 3], [2.0; 3]);
    assert!(coverage(&point, 8).is_empty());
    let mut got = Vec::new();
    for_each_conservative(&point, 8, 8, |x, y, lo, hi| got.push((x, y, lo, hi)));
    assert_eq!(got, vec![(2, 5, 2.0, 2.0)]);
    let seg = tri([(384, 832), (1152, 832), (768, 832)], [1.0, 4.0, 2.0]);
    assert!(coverage(&seg, 8).is_empty());
    got.clear();
    for_each_conservative(&seg, 8, 8, |x, y, lo, hi| got.push((x, y, lo, hi)));
    let pixels: Vec<_> = got.iter().map(|g| (g.0, g.1)).collect();
    assert_eq!(pixels, vec![(1, 3), (2, 3), (3, 3), (4, 3)]);
    // In (x, q) the segment is the triangle (1.5, 1), (4.5, 4), (3, 2): over x in [1.5, 2]
    // q runs from 1 to 1.5, over [4, 4.5] from 2 + 2·(2/3) to 4.
    assert_eq!((got[0].2, got[0].3), (1.0, 1.5));
    assert!((got[3].2 - 10.0 / 3.0).abs() < 1e-6 && got[3].3 == 4.0, "{:?}", got[3]);
}

#[test]
fn front_and_back_layers_split_a_closed_cube() {
    let g = crate::voxelize::tests::cube(Vec3::new(2.25, 2.25, 3.25), 3.5, &[]);
    let cam = ortho(8, 0.0, 8.0);
    let o = Options { faces: Faces::Split, slicing: Slicing::Local, ..opts(32) };
    let map = build(&g, &cam, &o).unwrap();
    // Column (4, 4) looks through the cube: front face at world z = 6.75 (depth 3.25), back
    // at z = 3.25 (depth 6.75); local slicing puts them in slices 0 and 31.
    assert_eq!(map.range(4, 4), Some((3.25, 6.75)));
    assert_eq!(map.column(0, 4, 4)[0], 1, "front layer");
    assert_eq!(map.column(1, 4, 4)[0], 1 << 31, "back layer");
    assert_eq!(map.inner_voxels(4, 4), Some(32));
    assert!((map.thickness(4, 4).unwrap() - 3.5).abs() < 1e-6);
    // Outside the cube: empty, no range.
    assert_eq!(map.range(0, 0), None);
    assert_eq!(map.thickness(0, 0), Some(0.0));
    // The one-layer map has no thickness.
    assert_eq!(build(&g, &cam, &opts(32)).unwrap().thickness(4, 4), None);
}

#[test]
fn local_columns_start_and_end_with_their_extreme_fragments() {
    let g = vox::tests::blob(6, 0.3);
    let cam = SliceCamera::from_camera(
        &voxlod_scene::Camera::look_at(Vec3::new(0.3, 0.5, 4.0), Vec3::ZERO, Vec3::Y, 40.0),
        48,
        40,
        1.0,
        8.0,
    );
    let map = build(&g, &cam, &Options { slicing: Slicing::Local, ..opts(96) }).unwrap();
    let mut columns = 0;
    for y in 0..40 {
        for x in 0..48 {
            match map.range(x, y) {
                None => assert!(map.column(0, x, y).iter().all(|&w| w == 0)),
                Some((lo, hi)) if hi > lo => {
                    columns += 1;
                    assert!(map.get(0, x, y, 0) && map.get(0, x, y, 95), "({x}, {y})");
                }
                Some(_) => assert_eq!(map.column(0, x, y), &[1, 0, 0]),
            }
        }
    }
    assert!(columns > 300, "{columns}");
    // Uniform slicing of the same scene: fewer distinct slices per column (coarser cells).
    let uniform = build(&g, &cam, &opts(96)).unwrap();
    assert!(uniform.occupied() < map.occupied());
}

/// A perspective map of 512 slices between 0.01 and 100, and planes parallel to the image 5 %
/// of a slice from either boundary of (every seventh and the last) slices.
#[test]
fn perspective_512_slices_place_the_far_slices_exactly() {
    let (near, far, n) = (0.01f64, 100.0f64, 512u32);
    let cam = SliceCamera {
        eye: DVec3::ZERO,
        forward: DVec3::NEG_Z,
        up: DVec3::Y,
        projection: Projection::Perspective { fov_y_deg: 10.0 },
        width: 4,
        height: 4,
        near,
        far,
    };
    let width = (far - near) / n as f64;
    for k in (0..n).step_by(7).chain([n - 3, n - 2, n - 1]) {
        for frac in [0.5, 0.05, 0.95] {
            let z = near + (k as f64 + frac) * width;
            let r = z * 0.5;
            let g = geometry(&[[
                Vec3::new(-r as f32, -r as f32, -z as f32),
                Vec3::new(r as f32, -r as f32, -z as f32),
                Vec3::new(0.0, r as f32, -z as f32),
            ]]);
            let map = build(&g, &cam, &opts(n)).unwrap();
            let w = map.column(0, 1, 2);
            let set: Vec<u32> =
                (0..n).filter(|&s| w[(s / 32) as usize] >> (s % 32) & 1 == 1).collect();
            assert_eq!(set, vec![k], "plane at z = {z} ({frac} into slice {k})");
        }
    }
    // The hardware's normalized depth (z_ndc = (f/(f−n))·(1 − n/z)) rounded to f32 would put
    // the last slices' planes in the wrong slice: the reason slices use eye-space z.
    let ndc = |z: f64| ((far / (far - near)) * (1.0 - near / z)) as f32;
    let z_of = |d: f32| near / (1.0 - d as f64 * (far - near) / far);
    let wrong = (n - 64..n)
        .filter(|&k| {
            let z = near + (k as f64 + 0.05) * width;
            ((z_of(ndc(z)) - near) / width).floor() as u32 != k
        })
        .count();
    assert!(wrong > 10, "f32 NDC depth misplaces {wrong} of the last 64 slices' planes");
    assert_eq!(
        slice_of(normalized((far as f32) - near as f32, 0.0, far as f32 - near as f32), n),
        n - 1
    );
}

#[test]
fn a_column_with_every_bit_set() {
    // 512 planes, one per slice, in an orthographic map: every bit of the column.
    let n = 512u32;
    let cam = ortho(2, 0.0, 512.0);
    let tris: Vec<[Vec3; 3]> = (0..n)
        .map(|k| {
            let z = 10.0 - (k as f32 + 0.5);
            [Vec3::new(-1.0, -1.0, z), Vec3::new(4.0, -1.0, z), Vec3::new(-1.0, 4.0, z)]
        })
        .collect();
    let map = build(&geometry(&tris), &cam, &opts(n)).unwrap();
    assert_eq!(map.column(0, 0, 0), &[u32::MAX; 16]);
    assert_eq!(map.count_nearer(0, 0, 0, 600.0), 512);
    assert_eq!(map.count_nearer(0, 0, 0, 511.0), 511);
    assert_eq!(map.count_nearer(0, 0, 0, 0.2), 0);
    // Everything ambiguous in a split map with the same bits in both layers: each voxel inner.
    let full = [u32::MAX; 16];
    assert_eq!(inner_voxels(&full, &full, n, false), 512);
    assert_eq!(inner_voxels(&full, &[0; 16], n, false), 512);
    assert_eq!(inner_voxels(&[0; 16], &full, n, true), 0);
}

#[test]
fn a_light_inside_the_volume_sees_what_is_in_front_and_nothing_behind() {
    // A closed cube [0, 4]³ around a "light" at its centre looking +z: the far wall (z = 4)
    // is in front, the near wall (z = 0) behind the eye, the side walls cross the near plane.
    let g = crate::voxelize::tests::cube(Vec3::ZERO, 4.0, &[]);
    let cam = SliceCamera {
        eye: DVec3::splat(2.0),
        forward: DVec3::Z,
        up: DVec3::Y,
        projection: Projection::Perspective { fov_y_deg: 120.0 },
        width: 32,
        height: 32,
        near: 0.05,
        far: 3.0,
    };
    let prepared = prepare(&g, &cam).unwrap();
    assert!(prepared.clipped > 0, "side walls are clipped at the near plane");
    let map = build(&g, &cam, &opts(64)).unwrap();
    let frame = cam.frame();
    // A point beyond the far wall, straight ahead: one wall in front of it.
    assert_eq!(map.occluders(0, DVec3::new(2.1, 2.2, 4.5)), Some(1));
    // A point between the light and the wall: nothing in front.
    assert_eq!(map.occluders(0, DVec3::new(2.1, 2.2, 3.0)), Some(0));
    // Behind the light: outside the map.
    assert_eq!(map.occluders(0, DVec3::new(2.0, 2.0, 1.0)), None);
    assert!(frame.project(DVec3::new(2.0, 2.0, 1.0)).is_none());
    // Every column sees a wall (the 120° view of the inside of a cube): all covered.
    assert_eq!(map.covered_columns(), 32 * 32);
}

#[test]
fn a_scene_larger_than_the_depth_range_keeps_only_what_is_inside() {
    // A huge tilted plane from far in front of near to far beyond far, with vertices far
    // outside the window: clipped on the host, fragments only between near and far.
    let cam = ortho(16, 2.0, 6.0);
    let g = geometry(&[[
        Vec3::new(-1e5, -1e5, 10.0 + 1e5),
        Vec3::new(1e5, -1e5, 10.0 - 1e5),
        Vec3::new(0.0, 1e5, 10.0),
    ]]);
    let prepared = prepare(&g, &cam).unwrap();
    assert_eq!(prepared.clipped, 1);
    let map = build(&g, &cam, &opts(32)).unwrap();
    // Depth along the plane is 10 − z = x (world), so columns x in [2, 6) hold it.
    for x in 0..16 {
        let any = (0..16).any(|y| map.column(0, x, y)[0] != 0);
        assert_eq!(any, (2..6).contains(&x), "column x = {x}");
    }
    // Triangles wholly outside the range are culled.
    let behind = geometry(&[[Vec3::new(1.0, 1.0, 20.0), Vec3::X * 5.0, Vec3::Y * 5.0]]);
    let behind =
        geometry(&[[behind.positions[0], Vec3::new(5.0, 1.0, 20.0), Vec3::new(1.0, 5.0, 20.0)]]);
    assert_eq!(prepare(&behind, &cam).unwrap().culled, 1);
}

#[test]
fn occluder_counts_exclude_the_points_own_slice() {
    let cam = ortho(4, 0.0, 8.0);
    let tris: Vec<[Vec3; 3]> = [1.5f32, 3.5, 5.5]
        .iter()
        .map(|&d| {
            let z = 10.0 - d;
            [Vec3::new(-1.0, -1.0, z), Vec3::new(9.0, -1.0, z), Vec3::new(-1.0, 9.0, z)]
        })
        .collect();
    let map = build(&geometry(&tris), &cam, &opts(8)).unwrap();
    let at = |d: f64| map.occluders(0, DVec3::new(1.5, 1.5, 10.0 - d)).unwrap();
    assert_eq!(
        [at(0.5), at(1.5), at(1.9), at(2.1), at(3.5), at(5.6), at(7.9)],
        [0, 0, 0, 1, 1, 2, 3]
    );
    // Local slicing: in front of the first occluder, nothing; beyond the last, all.
    let local =
        build(&geometry(&tris), &cam, &Options { slicing: Slicing::Local, ..opts(8) }).unwrap();
    let at = |d: f64| local.occluders(0, DVec3::new(1.5, 1.5, 10.0 - d)).unwrap();
    assert_eq!([at(1.0), at(1.5), at(3.0), at(5.5), at(6.0)], [0, 0, 1, 2, 3]);
}

#[test]
fn aligned_maps_against_the_exact_voxelizers() {
    let grid = GridSpec::new(DVec3::splat(-1.07), 2.14 / 24.0, UVec3::splat(24)).unwrap();
    let g = vox::tests::blob(10, 0.25);
    let exact = |mode| {
        let o = vox::Options { mode, triangle_lists: false, ..Default::default() };
        DenseBits::from_voxelization(&vox::voxelize(&g, &grid, &o).unwrap())
    };
    let (conservative, thin) = (exact(Mode::Conservative), exact(Mode::Thin));
    // The conservative map along z reproduces the conservative voxelizer, except where the
    // triangle passes within rounding of a voxel face along z (the voxelizer snaps z to 1/256
    // voxel, the map interpolates it) or touches it exactly (slices are half-open in depth).
    let cons_map = aligned_voxels(&g, &grid, 2, Coverage::Conservative).unwrap();
    let a = Agreement::of(&cons_map, &conservative);
    assert!(a.missed + a.extra <= a.reference / 200, "{a:?}");
    // The standard map is a subset of the conservative voxelization with holes.
    let std_map = aligned_voxels(&g, &grid, 2, Coverage::Standard).unwrap();
    let s = Agreement::of(&std_map, &conservative);
    assert!(s.extra <= s.reference / 1000, "{s:?}");
    assert!(s.missed > s.reference / 10, "the blob's sides are steep along z: {s:?}");
    // It misses thin voxels too, and merging three axes fills most holes.
    let t = Agreement::of(&std_map, &thin);
    assert!(t.missed > 0, "{t:?}");
    let merged = merged_voxels(&g, &grid, Coverage::Standard).unwrap();
    let m = Agreement::of(&merged, &thin);
    assert!(m.missed * 2 < t.missed, "three axes: {m:?} vs one: {t:?}");
}

#[test]
fn conservative_in_ranges_gives_the_exact_cells_of_a_local_map() {
    let g = vox::tests::blob(8, 0.2);
    let cam = SliceCamera::from_camera(
        &voxlod_scene::Camera::look_at(Vec3::new(0.5, 0.8, 3.5), Vec3::ZERO, Vec3::Y, 45.0),
        40,
        40,
        0.5,
        8.0,
    );
    let o = Options { slicing: Slicing::Local, ..opts(64) };
    let map = build(&g, &cam, &o).unwrap();
    let prepared = prepare(&g, &cam).unwrap();
    let ranges = map.ranges.clone().unwrap();
    let exact = build_in_ranges(
        &prepared.triangles,
        &cam,
        &Options { coverage: Coverage::Conservative, ..o },
        &ranges,
    )
    .unwrap();
    let a = compare::cell_agreement(&map, &exact).unwrap();
    assert_eq!(a.extra, 0, "{a:?}");
    assert!(a.missed > 0 && a.missed < a.reference, "{a:?}");
    // Mismatched ranges are refused.
    assert!(build_in_ranges(&prepared.triangles, &cam, &o, &ranges[1..]).is_err());
}

#[test]
fn word_masks_cover_ranges_across_words() {
    assert_eq!(word_mask(0, 31, 0), u32::MAX);
    assert_eq!(word_mask(3, 5, 0), 0b111000);
    assert_eq!(word_mask(30, 33, 0), 0b11 << 30);
    assert_eq!(word_mask(30, 33, 1), 0b11);
    assert_eq!(word_mask(30, 33, 2), 0);
    assert_eq!(word_mask(64, 64, 2), 1);
    assert_eq!(slice_of(1.0, 32), 31);
    assert_eq!(slice_of(0.0, 32), 0);
    assert_eq!(normalized(5.0, 5.0, 5.0), 0.0);
}

#[test]
fn front_facing_follows_the_world_normal() {
    let cam = ortho(8, 0.0, 20.0);
    // Counter-clockwise seen from the eye above (+z): normal +z, toward the eye.
    let up = [Vec3::new(1.0, 1.0, 5.0), Vec3::new(6.0, 1.0, 5.0), Vec3::new(1.0, 6.0, 5.0)];
    let down = [up[0], up[2], up[1]];
    let p = prepare(&geometry(&[up, down]), &cam).unwrap();
    assert_eq!(p.triangles[0].flags & FRONT_FACING, FRONT_FACING);
    assert_eq!(p.triangles[1].flags & FRONT_FACING, 0);
    assert_eq!(p.triangles[1].id, 1);
}
