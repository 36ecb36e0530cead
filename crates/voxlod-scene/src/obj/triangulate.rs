//! Triangulation of OBJ polygons by ear clipping, on the polygon projected to its dominant
//! plane (the plane whose axis is the largest component of the Newell normal).
//!
//! tobj's own `triangulate` option makes a fan from the first corner, which covers area outside
//! a concave polygon. Ear clipping handles concave and weakly simple polygons (a "keyhole" ring
//! whose bridge edge is traversed twice, as in assimp's `concave_polygon.obj`); for input that
//! is not simple it degrades gracefully (drops collinear corners, then clips convex corners,
//! then any corner) so it always terminates with at most n − 2 triangles.

use glam::{DVec2, DVec3, Vec3};

/// The result of triangulating one polygon.
#[derive(Debug, Default, PartialEq)]
pub(super) struct Triangulation {
    /// Triangles as corner indices into the polygon, with the polygon's winding.
    pub triangles: Vec<[usize; 3]>,
    /// Corners dropped because they were collinear with their neighbours (or on a spike).
    pub dropped_corners: usize,
}

/// Newell's normal of a (possibly non-planar) polygon: twice its vector area.
pub(super) fn newell_normal(points: &[DVec3]) -> DVec3 {
    let mut n = DVec3::ZERO;
    for (i, a) in points.iter().enumerate() {
        let b = points[(i + 1) % points.len()];
        n += DVec3::new(
            (a.y - b.y) * (a.z + b.z),
            (a.z - b.z) * (a.x + b.x),
            (a.x - b.x) * (a.y + b.y),
        );
    }
    n
}

/// Projects 3D points to the dominant plane of their Newell normal; the returned sign is
/// positive when the projected polygon is counter-clockwise. `None` for a polygon without area.
pub(super) fn project(points: &[DVec3]) -> Option<(Vec<DVec2>, f64)> {
    let n = newell_normal(points);
    let a = n.abs();
    let k = if a.x >= a.y && a.x >= a.z {
        0
    } else if a.y >= a.z {
        1
    } else {
        2
    };
    if a[k].is_nan() || a[k] <= 0.0 {
        return None;
    }
    let (u, v) = ((k + 1) % 3, (k + 2) % 3);
    Some((points.iter().map(|p| DVec2::new(p[u], p[v])).collect(), n[k].signum()))
}

fn cross(o: DVec2, a: DVec2, b: DVec2) -> f64 {
    (a - o).perp_dot(b - o)
}

/// Triangulates the polygon with corners `points` (in order). A polygon without area (all
/// corners collinear or coincident) gives a fan of degenerate triangles, so that its corners
/// stay referenced.
pub(super) fn triangulate(points: &[Vec3]) -> Triangulation {
    let n = points.len();
    let fan = || Triangulation {
        triangles: (1..n.saturating_sub(1)).map(|i| [0, i, i + 1]).collect(),
        dropped_corners: 0,
    };
    if n <= 3 {
        return fan();
    }
    let p3: Vec<DVec3> = points.iter().map(|p| p.as_dvec3()).collect();
    let Some((p, sign)) = project(&p3) else { return fan() };
    let (lo, hi) = p.iter().fold((p[0], p[0]), |(lo, hi), &q| (lo.min(q), hi.max(q)));
    let eps = 1e-12 * (hi - lo).length_squared();
    // Signed doubled area of corner b, positive when convex.
    let turn = |a: usize, b: usize, c: usize| sign * cross(p[a], p[b], p[c]);
    let mut next: Vec<usize> = (1..=n).map(|i| i % n).collect();
    let mut prev: Vec<usize> = (0..n).map(|i| (i + n - 1) % n).collect();
    let mut out = Triangulation::default();
    let (mut left, mut cur, mut misses, mut stage) = (n, 0usize, 0usize, 0u8);
    while left > 3 {
        let (a, c) = (prev[cur], next[cur]);
        let t = turn(a, cur, c);
        let clip = match stage {
            0 => t > eps && is_ear(&p, &next, a, cur, c, sign, eps),
            1 => t.abs() <= eps,
            2 => t > eps,
            _ => true,
        };
        if clip {
            if t.abs() > eps || stage == 3 {
                out.triangles.push([a, cur, c]);
            } else {
                out.dropped_corners += 1;
            }
            next[a] = c;
            prev[c] = a;
            left -= 1;
            cur = a;
            misses = 0;
            stage = 0;
        } else {
            cur = c;
            misses += 1;
            if misses >= left {
                misses = 0;
                stage += 1;
            }
        }
    }
    let (a, c) = (prev[cur], next[cur]);
    if turn(a, cur, c).abs() > eps || out.triangles.is_empty() {
        out.triangles.push([a, cur, c]);
    } else {
        out.dropped_corners += 1;
    }
    out
}

/// Whether no other remaining corner lies inside or on the triangle (a, b, c). Corners at the
/// same position as a, b or c (the two ends of a keyhole bridge) do not count.
fn is_ear(p: &[DVec2], next: &[usize], a: usize, b: usize, c: usize, sign: f64, eps: f64) -> bool {
    let (pa, pb, pc) = (p[a], p[b], p[c]);
    let mut i = next[c];
    while i != a {
        let q = p[i];
        if q != pa
            && q != pb
            && q != pc
            && sign * cross(pa, pb, q) >= -eps
            && sign * cross(pb, pc, q) >= -eps
            && sign * cross(pc, pa, q) >= -eps
        {
            return false;
        }
        i = next[i];
    }
    true
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::{Quat, Vec2};
    use proptest::prelude::*;

    fn shoelace(p: &[Vec2]) -> f64 {
        let n = p.len();
        (0..n).map(|i| p[i].as_dvec2().perp_dot(p[(i + 1) % n].as_dvec2())).sum::<f64>() * 0.5
    }

    /// Even-odd point-in-polygon test.
    fn inside(poly: &[DVec2], q: DVec2) -> bool {
        let mut odd = false;
        for i in 0..poly.len() {
            let (a, b) = (poly[i], poly[(i + 1) % poly.len()]);
            if (a.y > q.y) != (b.y > q.y) && q.x < a.x + (q.y - a.y) / (b.y - a.y) * (b.x - a.x) {
                odd = !odd;
            }
        }
        odd
    }

    fn dist_to_segment(q: DVec2, a: DVec2, b: DVec2) -> f64 {
        let t = ((q - a).dot(b - a) / (b - a).length_squared().max(1e-300)).clamp(0.0, 1.0);
        (a + (b - a) * t - q).length()
    }

    /// The oracle: the triangles (all with the polygon's orientation) cover every sample point
    /// strictly inside the polygon exactly once and no point outside it; their areas sum to the
    /// polygon's area. Samples within `margin` of any edge are skipped as ambiguous.
    fn check_cover(points3: &[Vec3], tri: &Triangulation) -> Result<(), String> {
        let p3: Vec<DVec3> = points3.iter().map(|p| p.as_dvec3()).collect();
        let normal = newell_normal(&p3);
        let (p, sign) = project(&p3).ok_or("no area")?;
        let area: f64 = tri
            .triangles
            .iter()
            .map(|&[a, b, c]| (p3[b] - p3[a]).cross(p3[c] - p3[a]).length() * 0.5)
            .sum();
        let want = normal.length() * 0.5;
        if (area - want).abs() > 1e-4 * want {
            return Err(format!("area {area} != polygon area {want}"));
        }
        for &[a, b, c] in &tri.triangles {
            if (p3[b] - p3[a]).cross(p3[c] - p3[a]).dot(normal) < -1e-9 * want {
                return Err(format!("triangle {a},{b},{c} is flipped"));
            }
        }
        let (lo, hi) = p.iter().fold((p[0], p[0]), |(l, h), &q| (l.min(q), h.max(q)));
        let margin = 1e-6 * (hi - lo).length();
        let mut edges: Vec<(DVec2, DVec2)> =
            (0..p.len()).map(|i| (p[i], p[(i + 1) % p.len()])).collect();
        for &[a, b, c] in &tri.triangles {
            edges.extend([(p[a], p[b]), (p[b], p[c]), (p[c], p[a])]);
        }
        for i in 0..=24 {
            for j in 0..=24 {
                let q = lo + (hi - lo) * DVec2::new(i as f64 + 0.37, j as f64 + 0.61) / 25.0;
                if edges.iter().any(|&(a, b)| dist_to_segment(q, a, b) < margin) {
                    continue;
                }
                let covered = tri
                    .triangles
                    .iter()
                    .filter(|&&[a, b, c]| {
                        [(a, b), (b, c), (c, a)]
                            .iter()
                            .all(|&(u, v)| sign * cross(p[u], p[v], q) > 0.0)
                    })
                    .count();
                let expected = usize::from(inside(&p, q));
                if covered != expected {
                    return Err(format!("sample {q} covered {covered}×, expected {expected}×"));
                }
            }
        }
        Ok(())
    }

    fn flat(points: &[[f32; 2]]) -> Vec<Vec3> {
        points.iter().map(|&[x, y]| Vec3::new(x, y, 0.0)).collect()
    }

    #[test]
    fn l_shape() {
        let l = flat(&[[0.0, 0.0], [2.0, 0.0], [2.0, 1.0], [1.0, 1.0], [1.0, 2.0], [0.0, 2.0]]);
        let t = triangulate(&l);
        assert_eq!(t.triangles.len(), 4);
        check_cover(&l, &t).unwrap();
        // A fan from the corner (1, 2) covers the notch x > 1, y > 1. Same polygon, rotated so
        // that it starts there.
        let rotated: Vec<Vec3> = (0..6).map(|i| l[(i + 4) % 6]).collect();
        check_cover(&rotated, &triangulate(&rotated)).unwrap();
        let fan = Triangulation {
            triangles: (1..5).map(|i| [0, i, i + 1]).collect(),
            dropped_corners: 0,
        };
        assert!(check_cover(&rotated, &fan).is_err(), "the oracle must reject a fan");
    }

    #[test]
    fn star_both_windings_and_tilted_planes() {
        let star: Vec<[f32; 2]> = (0..10)
            .map(|i| {
                let (r, a) =
                    (if i % 2 == 0 { 1.0 } else { 0.38 }, i as f32 * 0.2 * std::f32::consts::PI);
                [r * a.cos(), r * a.sin()]
            })
            .collect();
        let area = shoelace(&star.iter().map(|&[x, y]| Vec2::new(x, y)).collect::<Vec<_>>());
        assert!(area > 0.0);
        for reverse in [false, true] {
            for q in [
                Quat::IDENTITY,
                Quat::from_rotation_x(1.9),
                Quat::from_euler(glam::EulerRot::XYZ, 0.3, -2.2, 1.1),
            ] {
                let mut s: Vec<Vec3> = flat(&star).into_iter().map(|p| q * p).collect();
                if reverse {
                    s.reverse();
                }
                let t = triangulate(&s);
                assert_eq!(t.triangles.len(), 8);
                check_cover(&s, &t).unwrap();
            }
        }
    }

    #[test]
    fn keyhole_ring_with_a_doubled_bridge() {
        // An annulus cut open along a bridge: outer ring counter-clockwise, then the bridge,
        // the inner ring clockwise, and back along the bridge (corners 0/9 and 1/8 coincide).
        let mut ring = vec![[1.0f32, 0.0]];
        for i in 1..8 {
            let a = i as f32 * std::f32::consts::TAU / 8.0;
            ring.push([a.cos(), a.sin()]);
        }
        ring.push([1.0, 0.0]);
        ring.push([0.5, 0.0]);
        for i in (1..8).rev() {
            let a = i as f32 * std::f32::consts::TAU / 8.0;
            ring.push([0.5 * a.cos(), 0.5 * a.sin()]);
        }
        ring.push([0.5, 0.0]);
        let pts = flat(&ring);
        let t = triangulate(&pts);
        check_cover(&pts, &t).unwrap();
        // Exactly the annulus of two octagons: 0.75 of the outer octagon's area.
        let outer = 8.0 * 0.5 * (std::f64::consts::TAU / 8.0).sin();
        let got: f64 = t
            .triangles
            .iter()
            .map(|&[a, b, c]| (pts[b] - pts[a]).cross(pts[c] - pts[a]).length() as f64 * 0.5)
            .sum();
        assert!((got - 0.75 * outer).abs() < 1e-5, "{got} vs {}", 0.75 * outer);
    }

    #[test]
    fn collinear_corners_and_degenerate_polygons() {
        // A square with a midpoint on every edge: corners stay referenced, area preserved.
        let sq = flat(&[
            [0.0, 0.0],
            [1.0, 0.0],
            [2.0, 0.0],
            [2.0, 1.0],
            [2.0, 2.0],
            [1.0, 2.0],
            [0.0, 2.0],
            [0.0, 1.0],
        ]);
        let t = triangulate(&sq);
        check_cover(&sq, &t).unwrap();
        // All corners on one line: a fan of degenerate triangles, never a panic.
        let line = flat(&[[0.0, 0.0], [1.0, 0.0], [2.0, 0.0], [3.0, 0.0]]);
        assert_eq!(triangulate(&line).triangles.len(), 2);
        let same = vec![Vec3::ONE; 5];
        assert_eq!(triangulate(&same).triangles.len(), 3);
    }

    #[test]
    fn self_intersecting_input_terminates() {
        // A bow-tie and a pentagram: not simple, but the clipper must finish with ≤ n−2
        // triangles and only valid corner indices.
        let bowtie = flat(&[[0.0, 0.0], [1.0, 1.0], [1.0, 0.0], [0.0, 1.0]]);
        let pentagram: Vec<[f32; 2]> = (0..5)
            .map(|i| {
                let a = (i * 2 % 5) as f32 * std::f32::consts::TAU / 5.0;
                [a.cos(), a.sin()]
            })
            .collect();
        for poly in [bowtie, flat(&pentagram)] {
            let t = triangulate(&poly);
            assert!(t.triangles.len() <= poly.len() - 2);
            assert!(t.triangles.iter().flatten().all(|&i| i < poly.len()));
        }
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(64))]
        /// Random star-shaped (generally concave) polygons in random planes, either winding.
        #[test]
        fn random_star_polygons_are_covered_exactly(
            radii in prop::collection::vec(0.05f32..1.0, 4..40),
            jitter in prop::collection::vec(0.0f32..0.9, 40),
            axis in (-1.0f32..1.0, -1.0f32..1.0, -1.0f32..1.0),
            angle in 0.0f32..6.3,
            reverse in any::<bool>(),
            scale in prop::sample::select(vec![1e-3f32, 1.0, 1e3]),
        ) {
            let n = radii.len();
            let q = Vec3::new(axis.0, axis.1, axis.2)
                .try_normalize()
                .map_or(Quat::IDENTITY, |a| Quat::from_axis_angle(a, angle));
            let mut poly: Vec<Vec3> = (0..n)
                .map(|i| {
                    let a = (i as f32 + jitter[i]) * std::f32::consts::TAU / n as f32;
                    q * (Vec3::new(a.cos(), a.sin(), 0.0) * radii[i] * scale)
                })
                .collect();
            if reverse {
                poly.reverse();
            }
            let t = triangulate(&poly);
            prop_assert!(t.triangles.len() + t.dropped_corners == n - 2);
            if let Err(e) = check_cover(&poly, &t) {
                prop_assert!(false, "{}", e);
            }
        }
    }
}
