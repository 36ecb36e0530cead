//! Tests of the per-voxel overlap tests: explicit tie and degenerate cases, and proptests
//! against point sampling, explicit separating-axis certificates and an independent `f64`
//! polygon clipper.

use glam::{DVec3, I64Vec3, IVec3};
use proptest::prelude::*;

use super::*;

const V: i32 = VOXEL;
const H: i32 = HALF_VOXEL;

fn p(x: i32, y: i32, z: i32) -> IVec3 {
    IVec3::new(x, y, z)
}

/// Every voxel in `[-r, r + 4)³` that `test` accepts.
fn hits(tri: &[IVec3; 3], r: i32, test: fn(&[IVec3; 3], IVec3) -> bool) -> Vec<IVec3> {
    let mut out = Vec::new();
    for z in -r..r + 4 {
        for y in -r..r + 4 {
            for x in -r..r + 4 {
                if test(tri, p(x, y, z)) {
                    out.push(p(x, y, z));
                }
            }
        }
    }
    out
}

#[test]
fn points_touch_every_voxel_sharing_them() {
    // Corner, edge, face, interior: 8, 4, 2, 1 voxels.
    for (point, count) in [
        (p(2 * V, V, 3 * V), 8),
        (p(2 * V, V, 3 * V + 5), 4),
        (p(2 * V, V + 9, 3 * V + 5), 2),
        (p(2 * V + 1, V + 9, 3 * V + 5), 1),
    ] {
        assert_eq!(hits(&[point; 3], 2, box_overlap).len(), count, "{point}");
    }
}

#[test]
fn segments_touch_exactly_the_voxels_along_them() {
    // Through voxel centres along x, from the centre of voxel 0 to that of voxel 3.
    let (a, b) = (p(H, H, H), p(3 * V + H, H, H));
    let expected: Vec<IVec3> = (0..4).map(|x| p(x, 0, 0)).collect();
    assert_eq!(hits(&[a, b, b], 2, box_overlap), expected);
    // Along a voxel edge line (y = z = V): the four voxels around it at each x.
    let (a, b) = (p(H, V, V), p(V + H, V, V));
    assert_eq!(hits(&[a, a, b], 2, box_overlap).len(), 2 * 4);
    // A diagonal needle from corner to corner of a 3-voxel cube passes through 3 voxels and
    // touches their shared corners: every voxel sharing a corner on the diagonal.
    let (a, b) = (p(0, 0, 0), p(3 * V, 3 * V, 3 * V));
    let got = hits(&[a, b, b], 2, box_overlap);
    for c in &got {
        assert!((c.x - c.y).abs() <= 1 && (c.y - c.z).abs() <= 1 && (c.x - c.z).abs() <= 1);
    }
    // Collinear triangle (a, midpoint, b) equals the segment.
    let m = p(3 * V / 2, 3 * V / 2, 3 * V / 2);
    assert_eq!(hits(&[a, m, b], 2, box_overlap), got);
}

#[test]
fn a_plane_on_a_voxel_boundary_touches_both_layers() {
    // Regression: faces exactly on voxel boundaries must not lose voxels. Under the closed-box
    // tie rule the plane z = 2·V overlaps the layers z = 1 and z = 2.
    let tri = [p(0, 0, 2 * V), p(4 * V, 0, 2 * V), p(0, 4 * V, 2 * V)];
    let got = hits(&tri, 1, box_overlap);
    assert!(got.iter().all(|c| c.z == 1 || c.z == 2));
    let layer = |z| got.iter().filter(|c| c.z == z).count();
    // The triangle covers the lower-left half of a 4×4 square including the diagonal: the
    // closed voxels touched are those with x + y ≤ 4 (and x, y ≥ −1).
    let expected =
        (-1..=4).flat_map(|x| (-1..=4).map(move |y| (x, y))).filter(|&(x, y)| x + y <= 4);
    assert_eq!(layer(1), expected.clone().count());
    assert_eq!(layer(2), layer(1));
    // Thin mode: the plane through the diamonds' tips still touches both layers (ties count),
    // but a plane through the voxel centres touches only its own layer.
    let thin = hits(&tri, 1, diamond_overlap);
    assert!(thin.iter().any(|c| c.z == 1) && thin.iter().any(|c| c.z == 2));
    let mid = tri.map(|v| v + p(0, 0, H));
    assert!(hits(&mid, 1, diamond_overlap).iter().all(|c| c.z == 2));
    assert!(hits(&mid, 1, box_overlap).iter().all(|c| c.z == 2));
}

/// Whether `axis` strictly separates the triangle from the convex hull of `corners`, by
/// explicit projection of every point (no support formula).
fn separates(axis: I64Vec3, tri: &[IVec3; 3], corners: &[I64Vec3]) -> bool {
    let dot = |q: I64Vec3| {
        axis.x as i128 * q.x as i128 + axis.y as i128 * q.y as i128 + axis.z as i128 * q.z as i128
    };
    let t: Vec<i128> = tri.iter().map(|v| dot(v.as_i64vec3())).collect();
    let b: Vec<i128> = corners.iter().map(|&q| dot(q)).collect();
    let (tmin, tmax) = (*t.iter().min().unwrap(), *t.iter().max().unwrap());
    let (bmin, bmax) = (*b.iter().min().unwrap(), *b.iter().max().unwrap());
    tmax < bmin || bmax < tmin
}

fn box_corners(voxel: IVec3) -> Vec<I64Vec3> {
    let o = voxel.as_i64vec3() * V as i64;
    (0..8).map(|i| o + I64Vec3::new(i & 1, (i >> 1) & 1, i >> 2) * V as i64).collect()
}

fn diamond_corners(voxel: IVec3) -> Vec<I64Vec3> {
    let c = voxel.as_i64vec3() * V as i64 + H as i64;
    let u = [I64Vec3::X, I64Vec3::Y, I64Vec3::Z];
    u.iter().flat_map(|&a| [c + a * H as i64, c - a * H as i64]).collect()
}

/// The separating axes each test is defined by, computed independently of the code under test.
fn candidate_axes(tri: &[IVec3; 3], diamond: bool) -> Vec<I64Vec3> {
    let v = tri.map(|x| x.as_i64vec3());
    let units = [I64Vec3::X, I64Vec3::Y, I64Vec3::Z];
    let mut axes = units.to_vec();
    axes.push((v[1] - v[0]).cross(v[2] - v[0]));
    for i in 0..3 {
        for u in units {
            axes.push((v[(i + 1) % 3] - v[i]).cross(u));
        }
    }
    if diamond {
        for k in 0..3 {
            let (a, b) = (units[(k + 1) % 3], units[(k + 2) % 3]);
            axes.extend([a + b, a - b]);
        }
    }
    axes
}

/// A sample point of the triangle (weights summing to `S`) lies in the closed box / diamond.
fn sampled_inside(tri: &[IVec3; 3], voxel: IVec3, diamond: bool) -> bool {
    const S: i64 = 12;
    let v = tri.map(|x| x.as_i64vec3());
    let lo = voxel.as_i64vec3() * V as i64;
    let centre2 = (lo * 2 + V as i64) * S; // 2·S·centre
    (0..=S).any(|a| {
        (0..=S - a).any(|b| {
            let q = v[0] * a + v[1] * b + v[2] * (S - a - b); // S·point
            if diamond {
                let d = (q * 2 - centre2).abs();
                d.x + d.y + d.z <= H as i64 * 2 * S
            } else {
                (q.cmpge(lo * S) & q.cmple((lo + V as i64) * S)).all()
            }
        })
    })
}

fn coord(tie_prone: bool) -> BoxedStrategy<i32> {
    if tie_prone { (-6..14i32).prop_map(|k| k * H).boxed() } else { (-3 * V..6 * V).boxed() }
}

fn vertex(tie_prone: bool) -> impl Strategy<Value = IVec3> {
    (coord(tie_prone), coord(tie_prone), coord(tie_prone)).prop_map(|(x, y, z)| p(x, y, z))
}

/// Random triangles: general, tie-prone (half-voxel steps), and degenerate (collinear, point).
fn triangle() -> impl Strategy<Value = [IVec3; 3]> {
    (any::<bool>(), 0..4u8).prop_flat_map(|(ties, shape)| {
        (vertex(ties), vertex(ties), vertex(ties)).prop_map(move |(a, b, c)| match shape {
            0 => [a, b, b * 2 - a],
            1 => [a, a, a],
            _ => [a, b, c],
        })
    })
}

/// Sutherland–Hodgman clip of a polygon by the box `[lo, hi]` in `f64`; true if anything is left.
fn clip_nonempty(poly: &[DVec3], lo: DVec3, hi: DVec3) -> bool {
    let mut poly = poly.to_vec();
    for k in 0..3 {
        for (sign, bound) in [(1.0, lo[k]), (-1.0, hi[k])] {
            let inside = |q: DVec3| sign * (q[k] - bound) >= 0.0;
            let mut out = Vec::new();
            for i in 0..poly.len() {
                let (a, b) = (poly[i], poly[(i + 1) % poly.len()]);
                if inside(a) {
                    out.push(a);
                }
                if inside(a) != inside(b) {
                    let t = (bound - a[k]) / (b[k] - a[k]);
                    out.push(a + (b - a) * t);
                }
            }
            if out.is_empty() {
                return false;
            }
            poly = out;
        }
    }
    true
}

proptest! {
    #[test]
    fn box_test_is_the_13_axis_theorem_and_agrees_with_sampling(tri in triangle()) {
        let axes = candidate_axes(&tri, false);
        for voxel in hits(&[p(0, 0, 0); 3], 3, |_, _| true) {
            let got = box_overlap(&tri, voxel);
            let corners = box_corners(voxel);
            let certificate = axes.iter().find(|&&a| separates(a, &tri, &corners));
            prop_assert_eq!(got, certificate.is_none(), "voxel {} certificate {:?}", voxel, certificate);
            if sampled_inside(&tri, voxel, false) {
                prop_assert!(got, "a sample point of the triangle lies in voxel {}", voxel);
            }
        }
    }

    #[test]
    fn diamond_test_is_its_axis_set_and_agrees_with_sampling(tri in triangle()) {
        let axes = candidate_axes(&tri, true);
        for voxel in hits(&[p(0, 0, 0); 3], 3, |_, _| true) {
            let got = diamond_overlap(&tri, voxel);
            let corners = diamond_corners(voxel);
            let certificate = axes.iter().find(|&&a| separates(a, &tri, &corners));
            prop_assert_eq!(got, certificate.is_none(), "voxel {} certificate {:?}", voxel, certificate);
            if sampled_inside(&tri, voxel, true) {
                prop_assert!(got, "a sample point of the triangle lies in the diamond of {}", voxel);
            }
            // Thin is a subset of conservative.
            prop_assert!(!got || box_overlap(&tri, voxel));
        }
    }

    #[test]
    fn box_test_agrees_with_f64_clipping_away_from_ties(
        a in vertex(false), b in vertex(false), c in vertex(false)
    ) {
        let tri = [a, b, c];
        let poly: Vec<DVec3> = tri.iter().map(|v| v.as_dvec3()).collect();
        let eps = 1e-3;
        for voxel in hits(&[p(0, 0, 0); 3], 3, |_, _| true) {
            let lo = voxel.as_dvec3() * V as f64;
            let hi = lo + V as f64;
            let grown = clip_nonempty(&poly, lo - eps, hi + eps);
            let shrunk = clip_nonempty(&poly, lo + eps, hi - eps);
            if grown == shrunk {
                prop_assert_eq!(box_overlap(&tri, voxel), grown, "voxel {}", voxel);
            }
        }
    }
}

#[test]
fn extreme_coordinates_do_not_overflow() {
    use crate::voxelize::lattice::COORD_LIMIT as L;
    // A huge triangle spanning the whole lattice band, and voxels at the corners of the largest
    // grid: the i64/i128 widths documented in the module must hold.
    let tri = [p(-L, -L, -L), p(L, -L, L), p(-L, L, L)];
    let far = (1 << 20) - 1;
    for voxel in [p(0, 0, 0), p(far, far, far), p(far, 0, far), p(0, far, 0)] {
        let expected = {
            let axes = candidate_axes(&tri, false);
            !axes.iter().any(|&a| separates(a, &tri, &box_corners(voxel)))
        };
        assert_eq!(box_overlap(&tri, voxel), expected, "{voxel}");
        let expected = {
            let axes = candidate_axes(&tri, true);
            !axes.iter().any(|&a| separates(a, &tri, &diamond_corners(voxel)))
        };
        assert_eq!(diamond_overlap(&tri, voxel), expected, "{voxel}");
    }
}
