//! Ray-casting tests: the BVH against a brute-force loop over all triangles, on every obvhs
//! build preset (exact per ray, plus obvhs-style order-independent aggregates), watertightness,
//! scale invariance, the shadow-origin rule and bad input.

use glam::Vec3;
use obvhs::BvhBuildParams;
use proptest::prelude::*;
use voxlod_scene::Geometry;

use super::triangle::{ShearedRay, SoaTriangle};
use super::*;
use crate::render::test_scenes::{geometry, icosphere, quad, soup};

const PRESETS: [(&str, BvhBuildParams); 6] = [
    ("fastest", BvhBuildParams::fastest_build()),
    ("very_fast", BvhBuildParams::very_fast_build()),
    ("fast", BvhBuildParams::fast_build()),
    ("medium", BvhBuildParams::medium_build()),
    ("slow", BvhBuildParams::slow_build()),
    ("very_slow", BvhBuildParams::very_slow_build()),
];

/// The reference: every triangle, same intersection routine, same tie rule, same filter.
fn brute_closest(
    g: &Geometry,
    o: Vec3,
    d: Vec3,
    t_min: f32,
    t_max: f32,
    accept: impl Fn(&Hit) -> bool,
) -> Option<Hit> {
    let ray = ShearedRay::new(o, d);
    let mut best: Option<Hit> = None;
    for t in 0..g.triangle_count() {
        if let Some(h) = ray.test(&SoaTriangle::new(g.triangle(t)), t_min, t_max) {
            let hit = Hit { t: h.t, triangle: t as u32, u: h.u, v: h.v };
            let closer =
                best.is_none_or(|b| h.t < b.t || (h.t == b.t && hit.triangle < b.triangle));
            if closer && accept(&hit) {
                best = Some(hit);
            }
        }
    }
    best
}

fn random_soup(seed: u32, n: usize) -> Geometry {
    let r = |i: usize, k: u32| crate::random::rand_f32(seed, i as u32, k) * 2.0 - 1.0;
    let tris: Vec<[Vec3; 3]> = (0..n)
        .map(|i| {
            let c = Vec3::new(r(i, 0), r(i, 1), r(i, 2));
            let size = 0.05 + 0.3 * (r(i, 3) * 0.5 + 0.5);
            [0, 1, 2]
                .map(|v| c + Vec3::new(r(i, 4 + 3 * v), r(i, 5 + 3 * v), r(i, 6 + 3 * v)) * size)
        })
        .collect();
    geometry(soup("soup", &tris, 0))
}

fn random_ray(seed: u32, i: u32) -> (Vec3, Vec3) {
    let r = |k: u32| crate::random::rand_f32(seed ^ 0xabcd, i, k) * 2.0 - 1.0;
    let o = Vec3::new(r(0), r(1), r(2)) * 1.5;
    let target = Vec3::new(r(3), r(4), r(5)) * 0.8;
    (o, (target - o).normalize_or(Vec3::X))
}

#[test]
fn every_preset_matches_brute_force_exactly_and_in_aggregate() {
    for (name, params) in PRESETS {
        for (seed, n) in [(1, 1), (2, 7), (3, 300)] {
            let g = random_soup(seed, n);
            let bvh = Bvh::with_params(&g, params).unwrap();
            let (mut count, mut sum, mut ref_count, mut ref_sum) = (0u32, 0u32, 0u32, 0u32);
            for i in 0..400 {
                let (o, d) = random_ray(seed, i);
                let got = bvh.intersect(o, d, 0.0, f32::INFINITY);
                let want = brute_closest(&g, o, d, 0.0, f32::INFINITY, |_| true);
                assert_eq!(got, want, "preset {name}, soup {seed}, ray {i}");
                if let Some(h) = got {
                    count += 1;
                    sum = sum.wrapping_add(h.triangle);
                }
                if let Some(h) = want {
                    ref_count += 1;
                    ref_sum = ref_sum.wrapping_add(h.triangle);
                }
                // Any hit agrees with the closest hit on the open range.
                let t_max = 1.0 + i as f32 / 200.0;
                let closest = brute_closest(&g, o, d, 0.0, t_max, |_| true);
                let expected = closest.is_some_and(|h| h.t > 0.0 && h.t < t_max);
                assert_eq!(bvh.occluded(o, d, t_max), expected, "preset {name}, ray {i}");
            }
            assert_eq!((count, sum), (ref_count, ref_sum), "preset {name}");
            if n == 300 {
                assert!(count > 100, "the test rays should mostly hit: {count}");
            }
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(24))]
    #[test]
    fn random_soups_and_rays_match_brute_force(seed in any::<u32>(), n in 1usize..120) {
        let g = random_soup(seed, n);
        let bvh = Bvh::new(&g).unwrap();
        // A filter that drops odd triangles, as an alpha mask would.
        let even = |h: &Hit| h.triangle.is_multiple_of(2);
        for i in 0..64 {
            let (o, d) = random_ray(seed, i);
            let t_min = (i % 4) as f32 * 0.3;
            let want = brute_closest(&g, o, d, t_min, 4.0, |_| true);
            prop_assert_eq!(bvh.intersect(o, d, t_min, 4.0), want);
            let want = brute_closest(&g, o, d, t_min, 4.0, even);
            prop_assert_eq!(bvh.intersect_filtered(o, d, t_min, 4.0, even), want);
            let any_even = brute_closest(&g, o, d, 0.0, 4.0, even).is_some_and(|h| h.t > 0.0);
            prop_assert_eq!(bvh.occluded_filtered(o, d, 4.0, even), any_even);
        }
    }
}

#[test]
fn packets_equal_single_rays_bit_for_bit() {
    for (seed, n) in [(11, 5), (12, 400)] {
        let g = random_soup(seed, n);
        let bvh = Bvh::new(&g).unwrap();
        let odd = |h: &Hit| h.triangle % 3 != 1;
        let mut hits = 0;
        for i in 0..300u32 {
            let r = |k| crate::random::rand_f32(seed, i, k) * 2.0 - 1.0;
            let origin = Vec3::new(r(0), r(1), r(2)) * 1.5;
            // Coherent packets (a small cone), and every fifth one scattered (the fallback).
            let axis = (Vec3::new(r(3), r(4), r(5)) * 0.5 - origin).normalize_or(Vec3::X);
            let spread = if i % 5 == 0 { 2.0 } else { 0.05 };
            let dirs: [Vec3; 4] = std::array::from_fn(|l| {
                let j = |k| crate::random::rand_f32(seed, i, 10 + 3 * l as u32 + k) - 0.5;
                (axis + Vec3::new(j(0), j(1), j(2)) * spread).normalize_or(Vec3::Y)
            });
            let t_min = (i % 3) as f32 * 0.2;
            let packet = bvh.intersect_packet(origin, &dirs, t_min, 5.0);
            let filtered = bvh.intersect_packet_filtered(origin, &dirs, t_min, 5.0, |_, h| odd(h));
            for l in 0..4 {
                assert_eq!(packet[l], bvh.intersect(origin, dirs[l], t_min, 5.0), "ray {i}.{l}");
                let single = bvh.intersect_filtered(origin, dirs[l], t_min, 5.0, odd);
                assert_eq!(filtered[l], single, "filtered ray {i}.{l}");
                hits += packet[l].is_some() as u32;
            }
        }
        assert!(n < 100 || hits > 300, "{hits}");
    }
    // Invalid lanes fall back to single rays and hit nothing.
    let g = random_soup(3, 50);
    let bvh = Bvh::new(&g).unwrap();
    let dirs = [Vec3::ZERO, Vec3::X, Vec3::NAN, Vec3::NEG_Y];
    let p = bvh.intersect_packet(Vec3::splat(-2.0), &dirs, 0.0, f32::INFINITY);
    assert!(p[0].is_none() && p[2].is_none());
    assert_eq!(p[1], bvh.intersect(Vec3::splat(-2.0), Vec3::X, 0.0, f32::INFINITY));
}

#[test]
fn t_matches_an_independent_moller_trumbore() {
    let g = random_soup(9, 200);
    let bvh = Bvh::new(&g).unwrap();
    let mut checked = 0;
    for i in 0..500 {
        let (o, d) = random_ray(9, i);
        if let Some(h) = bvh.intersect(o, d, 0.0, f32::INFINITY) {
            let [a, b, c] = g.triangle(h.triangle as usize).map(glam::Vec3A::from);
            let tri = obvhs::triangle::Triangle { v0: a, v1: b, v2: c };
            let t = tri.intersect(&obvhs::ray::Ray::new_inf(o.into(), d.into()));
            if t.is_finite() {
                assert!((t - h.t).abs() <= 1e-5 * h.t.max(1.0), "ray {i}: {t} vs {}", h.t);
                let p = o + d * h.t;
                let q = a * (1.0 - h.u - h.v) + b * h.u + c * h.v;
                assert!((p - Vec3::from(q)).length() < 1e-5, "ray {i}: {p} vs {q}");
                checked += 1;
            }
        }
    }
    assert!(checked > 100, "{checked}");
}

#[test]
fn closed_mesh_is_watertight_from_inside() {
    // Rays from the centre toward every vertex and edge midpoint (exactly where triangles meet)
    // and in random directions: none may escape.
    let m = icosphere("s", 3, Vec3::new(0.3, -0.2, 0.1), 2.0);
    let g = geometry(m.clone());
    let bvh = Bvh::new(&g).unwrap();
    let c = Vec3::new(0.3, -0.2, 0.1);
    let mut targets: Vec<Vec3> = m.positions.clone();
    for t in &m.indices {
        for e in 0..3 {
            targets.push((m.positions[t[e] as usize] + m.positions[t[(e + 1) % 3] as usize]) * 0.5);
        }
    }
    for i in 0..2000u32 {
        let r = |k| crate::random::rand_f32(77, i, k) * 2.0 - 1.0;
        targets.push(c + Vec3::new(r(0), r(1), r(2)));
    }
    for (i, &p) in targets.iter().enumerate() {
        let d = p - c;
        assert!(bvh.intersect(c, d, 0.0, f32::INFINITY).is_some(), "ray {i} toward {p} escaped");
    }
}

#[test]
fn scaled_scenes_hit_the_same_triangles() {
    let g = random_soup(5, 150);
    for scale in [1e-4f32, 1e5] {
        let mut s = g.clone();
        s.positions.iter_mut().for_each(|p| *p *= scale);
        let (a, b) = (Bvh::new(&g).unwrap(), Bvh::new(&s).unwrap());
        let mut hits = 0;
        for i in 0..300 {
            let (o, d) = random_ray(5, i);
            let h1 = a.intersect(o, d, 0.0, f32::INFINITY);
            let h2 = b.intersect(o * scale, d, 0.0, f32::INFINITY);
            assert_eq!(h1.map(|h| h.triangle), h2.map(|h| h.triangle), "scale {scale}, ray {i}");
            if let (Some(h1), Some(h2)) = (h1, h2) {
                assert!((h1.t * scale - h2.t).abs() <= 1e-4 * h2.t, "{} vs {}", h1.t * scale, h2.t);
                hits += 1;
            }
        }
        assert!(hits > 50);
    }
}

#[test]
fn axis_aligned_and_signed_zero_directions_hit() {
    let g = geometry(quad("q", Vec3::new(-1.0, -1.0, 0.0), Vec3::X * 2.0, Vec3::Y * 2.0, 0));
    let bvh = Bvh::new(&g).unwrap();
    for d in
        [Vec3::new(0.0, 0.0, -1.0), Vec3::new(-0.0, -0.0, -1.0), Vec3::new(1e-30, -1e-39, -1.0)]
    {
        let h = bvh.intersect(Vec3::new(0.25, 0.5, 3.0), d, 0.0, f32::INFINITY);
        assert_eq!(h.map(|h| h.t), Some(3.0), "direction {d:?}");
    }
    // A ray inside the quad's plane, and a ray starting on it, pointing away.
    assert!(bvh.intersect(Vec3::new(-3.0, 0.0, 0.0), Vec3::X, 0.0, f32::INFINITY).is_none());
    assert!(!bvh.occluded(Vec3::new(0.2, 0.1, 0.0), Vec3::Z, f32::INFINITY));
    // Degenerate rays hit nothing instead of panicking.
    for (o, d) in [(Vec3::ZERO, Vec3::ZERO), (Vec3::NAN, Vec3::Z), (Vec3::ZERO, Vec3::INFINITY)] {
        assert!(bvh.intersect(o, d, 0.0, f32::INFINITY).is_none());
        assert!(!bvh.occluded(o, d, f32::INFINITY));
    }
}

#[test]
fn offset_origins_never_self_intersect_at_any_scale() {
    let base = icosphere("s", 3, Vec3::new(0.5, 0.25, -0.5), 1.0);
    for scale in [1e-4f32, 1.0, 3e4] {
        let mut m = base.clone();
        m.positions.iter_mut().for_each(|p| *p *= scale);
        let g = geometry(m);
        let bvh = Bvh::new(&g).unwrap();
        let mut lit = 0;
        for i in 0..3000u32 {
            // A primary ray from outside onto the sphere, then a shadow ray along the outward
            // normal's hemisphere: nothing but the sphere itself could block it, and the
            // sphere is convex.
            let r = |k| crate::random::rand_f32(i, 3, k) * 2.0 - 1.0;
            let eye = Vec3::new(r(0), r(1), r(2)).normalize_or(Vec3::Y) * 4.0 * scale;
            let Some(h) = bvh.intersect(eye, -eye, 0.0, f32::INFINITY) else { continue };
            let p = eye - eye * h.t;
            let [a, b, c] = g.triangle(h.triangle as usize);
            let n = (b - a).cross(c - a).normalize();
            let l = (n + Vec3::new(r(3), r(4), r(5)) * 0.9).normalize();
            if l.dot(n) <= 0.05 {
                continue;
            }
            let o = offset_origin(&g, h.triangle, p, l, eye - p);
            assert!(!bvh.occluded(o, l, f32::INFINITY), "scale {scale}, ray {i}");
            lit += 1;
        }
        assert!(lit > 1000, "{lit}");
    }
}

#[test]
fn bad_geometry_is_an_error_and_empty_geometry_hits_nothing() {
    let mut g = geometry(quad("q", Vec3::ZERO, Vec3::X, Vec3::Y, 0));
    g.positions[2].y = f32::NAN;
    let err = Bvh::new(&g).unwrap_err().to_string();
    assert!(err.contains("vertex 2"), "{err}");
    let mut g = geometry(quad("q", Vec3::ZERO, Vec3::X, Vec3::Y, 0));
    g.indices[1][2] = 99;
    assert!(Bvh::new(&g).unwrap_err().to_string().contains("99"));
    // Positions are all the BVH needs.
    let mut g = geometry(quad("q", Vec3::ZERO, Vec3::X, Vec3::Y, 0));
    g.uvs.clear();
    g.normals.clear();
    assert_eq!(Bvh::new(&g).unwrap().triangle_count(), 2);
    let empty = Bvh::new(&Geometry::default()).unwrap();
    assert_eq!(empty.triangle_count(), 0);
    assert!(empty.intersect(Vec3::ZERO, Vec3::X, 0.0, f32::INFINITY).is_none());
    assert!(!empty.occluded(Vec3::ZERO, Vec3::X, f32::INFINITY));
}

proptest! {
    /// A camera ray lands on the shared edge of two faces that meet at a concave angle (a
    /// room's floor and wall): the secondary rays from that point must see the two faces as a
    /// point just inside the wedge would. A ray that leaves toward the other face's front hits
    /// it at a small `t`; one that leaves away from it hits nothing (the scene is the two
    /// triangles). Before the origin moved toward the viewer, rays leaving away from the
    /// adjacent face hit it at `t ≈ 0` for a share of directions that depended on rounding.
    #[test]
    fn secondary_rays_from_a_shared_edge_see_it_from_the_viewer_side(
        angle_deg in 25.0f32..155.0,
        (yaw, pitch, roll) in (0.0f32..std::f32::consts::TAU, -1.5f32..1.5, 0.0f32..std::f32::consts::TAU),
        log_scale in -3.0f32..4.0,
        offset in prop::array::uniform3(-100.0f32..100.0),
        u in 0.3f32..0.7,
        (eye_a, eye_r) in (0.2f32..0.8, 0.1f32..0.9),
        seed in any::<u32>(),
    ) {
        let scale = 10f32.powf(log_scale);
        let rot = glam::Quat::from_euler(glam::EulerRot::YXZ, yaw, pitch, roll);
        let place = |p: Vec3| rot * (p * scale) + Vec3::from(offset) * scale;
        // Face A in the plane y = 0 (x ≥ 0), face B at `angle` from it about the z axis; the
        // wedge between them (the "room") is where the viewer is.
        let (s, c) = angle_deg.to_radians().sin_cos();
        let b_dir = Vec3::new(c, s, 0.0);
        let (e0, e1) = (Vec3::new(0.0, 0.0, -1.0), Vec3::new(0.0, 0.0, 1.0));
        let tris = [
            [place(e0), place(e1), place(Vec3::new(4.0, 0.0, 0.0))],
            [place(e0), place(e1), place(b_dir * 4.0)],
        ];
        let g = geometry(soup("wedge", &tris, 0));
        let bvh = Bvh::new(&g).unwrap();
        let (n_a, n_b) = (rot * Vec3::Y, rot * Vec3::new(s, -c, 0.0));
        // The viewer: inside the wedge, looking at the edge point.
        let half = Vec3::X * (1.0 - eye_a) + b_dir * eye_a;
        let target = place(Vec3::new(0.0, 0.0, 2.0 * u - 1.0));
        let eye = place(half * (0.5 + eye_r) + Vec3::new(0.0, 0.0, 2.0 * u - 1.0));
        let d = (target - eye).normalize();
        let Some(h) = bvh.intersect(eye, d, 0.0, f32::INFINITY) else {
            return Err(TestCaseError::reject("the camera ray missed the edge"));
        };
        let p = eye + d * h.t;
        let (n_own, n_other) = if h.triangle == 0 { (n_a, n_b) } else { (n_b, n_a) };
        let other = 1 - h.triangle;
        let mut checked = 0;
        for k in 0..64u32 {
            let r = |dim| crate::random::rand_f32(seed, k, dim) * 2.0 - 1.0;
            let l = Vec3::new(r(0), r(1), r(2)).normalize_or(n_own);
            let (own, towards) = (l.dot(n_own), l.dot(n_other));
            // Grazing directions (within ~3° of either plane) are left out: their answer is
            // decided by the offset's size, not by its side.
            if own < 0.05 || towards.abs() < 0.05 {
                continue;
            }
            let o = offset_origin(&g, h.triangle, p, l, eye - p);
            let hit = bvh.intersect(o, l, 0.0, f32::INFINITY);
            if towards < 0.0 {
                let hit = hit.expect("a ray into the adjacent face hits it");
                prop_assert_eq!(hit.triangle, other);
                let size = p.abs().max_element().max(4.0 * scale);
                prop_assert!(hit.t < 1e-2 * size, "t {} at size {}", hit.t, size);
            } else {
                prop_assert!(hit.is_none(), "a ray leaving the wedge hit {:?} (own {own}, towards {towards})", hit);
            }
            checked += 1;
        }
        prop_assert!(checked > 10, "{checked}");
    }
}
