//! Subdivision: counts, watertightness, the midpoint split keeping the surface and its
//! attributes, Loop's stencils, its convergence to the limit positions, creases and non-manifold
//! edges, and the errors.

use std::collections::BTreeMap;

use glam::{Vec2, Vec3};

use super::*;
use crate::Material;
use crate::mesh::SkinBinding;
use crate::procedural::primitives::{cube, icosphere, scene_with};

/// Every directed edge (by position bits) used once and its reverse once.
fn closed(mesh: &Mesh) -> bool {
    let key = |i: u32| weld_key(mesh.positions[i as usize]);
    let mut edges = BTreeMap::new();
    for t in &mesh.indices {
        for e in 0..3 {
            *edges.entry((key(t[e]), key(t[(e + 1) % 3]))).or_insert(0u32) += 1;
        }
    }
    edges.iter().all(|(&(a, b), &n)| n == 1 && edges.get(&(b, a)) == Some(&1))
}

fn area(mesh: &Mesh) -> f64 {
    (0..mesh.triangle_count())
        .map(|t| {
            let [a, b, c] = mesh.triangle(t).map(|p| p.as_dvec3());
            0.5 * (b - a).cross(c - a).length()
        })
        .sum()
}

fn volume(mesh: &Mesh) -> f64 {
    (0..mesh.triangle_count())
        .map(|t| {
            let [a, b, c] = mesh.triangle(t).map(|p| p.as_dvec3());
            a.dot(b.cross(c)) / 6.0
        })
        .sum()
}

/// A flat regular triangulated grid in z = 0 (`n × n` quads split along one diagonal, so every
/// interior vertex has valence 6), with UVs = (x, y) / n.
fn regular_grid(n: u32) -> Mesh {
    let mut m = Mesh { name: "grid".into(), ..Default::default() };
    for j in 0..=n {
        for i in 0..=n {
            m.positions.push(Vec3::new(i as f32, j as f32, 0.0));
            m.uvs.push(Vec2::new(i as f32, j as f32) / n as f32);
        }
    }
    let at = |i: u32, j: u32| j * (n + 1) + i;
    for j in 0..n {
        for i in 0..n {
            m.indices.push([at(i, j), at(i + 1, j), at(i + 1, j + 1)]);
            m.indices.push([at(i, j), at(i + 1, j + 1), at(i, j + 1)]);
        }
    }
    m.compute_normals();
    m
}

#[test]
fn counts_are_four_to_the_n_and_closed_meshes_stay_closed() {
    let c = cube(Vec3::splat(-1.0), Vec3::splat(1.0));
    assert!(closed(&c));
    for scheme in [Scheme::Midpoint, Scheme::Loop] {
        for levels in 0..=3 {
            let m = subdivide_mesh(&c, scheme, levels).unwrap();
            assert_eq!(m.triangle_count(), 12 * 4usize.pow(levels), "{scheme:?} {levels}");
            m.validate().unwrap();
            assert!(closed(&m), "{scheme:?} level {levels} opened the cube");
            assert!(volume(&m) > 0.0, "{scheme:?} {levels}: orientation flipped");
        }
    }
    let s = icosphere(Vec3::ZERO, 1.0, 1);
    let m = loop_(&s).unwrap();
    assert!(closed(&m));
    // An icosphere shares its vertices: V' = V + E, E = 3T/2.
    assert_eq!(m.positions.len(), s.positions.len() + 3 * s.triangle_count() / 2);
}

#[test]
fn midpoint_keeps_the_surface_and_interpolates_attributes() {
    let mut g = regular_grid(3);
    // Tilt it out of plane so the check is not trivially z = 0.
    for p in &mut g.positions {
        p.z = 0.25 * p.x - 0.5 * p.y;
    }
    g.compute_normals();
    let m = midpoint(&g).unwrap();
    // Original vertices first, unchanged.
    assert_eq!(&m.positions[..g.positions.len()], &g.positions[..]);
    assert_eq!(&m.uvs[..g.uvs.len()], &g.uvs[..]);
    // Every new vertex is on the plane, and its UV is the linear map of its position.
    for (p, uv) in m.positions.iter().zip(&m.uvs) {
        assert!((p.z - (0.25 * p.x - 0.5 * p.y)).abs() < 1e-6, "{p}");
        assert!((*uv - Vec2::new(p.x, p.y) / 3.0).length() < 1e-6, "{p} {uv}");
    }
    assert!((area(&m) - area(&g)).abs() < 1e-9 * area(&g));
    assert!(m.normals.iter().all(|n| (n.length() - 1.0).abs() < 1e-5));
    // Each original triangle's four children cover it: same total area per parent.
    for t in 0..g.triangle_count() {
        let parent = Mesh { indices: vec![g.indices[t]], ..g.clone() };
        let kids = Mesh { indices: m.indices[4 * t..4 * t + 4].to_vec(), ..m.clone() };
        assert!((area(&kids) - area(&parent)).abs() < 1e-9);
    }
}

#[test]
fn seams_stay_watertight_with_their_own_attributes() {
    // Two triangles sharing an edge by position but not by vertex (a UV seam).
    let mesh = Mesh {
        name: "seam".into(),
        positions: vec![Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::X, Vec3::Y, Vec3::new(1.0, 1.0, 0.0)],
        normals: vec![Vec3::Z; 6],
        uvs: vec![
            Vec2::ZERO,
            Vec2::X,
            Vec2::Y,
            Vec2::new(0.5, 0.5),
            Vec2::new(0.5, 0.5),
            Vec2::ONE,
        ],
        indices: vec![[0, 1, 2], [3, 5, 4]],
        ..Default::default()
    };
    for scheme in [Scheme::Midpoint, Scheme::Loop] {
        let m = subdivide_mesh(&mesh, scheme, 2).unwrap();
        // Positions along the shared diagonal x + y = 1 appear in pairs (one per side), at
        // bit-identical positions, with each side's UVs.
        let on_seam: Vec<(Vec3, Vec2)> = m
            .positions
            .iter()
            .zip(&m.uvs)
            .filter(|(p, _)| (p.x + p.y - 1.0).abs() < 1e-6 && p.z == 0.0)
            .map(|(p, uv)| (*p, *uv))
            .collect();
        for &(p, _) in &on_seam {
            let copies: Vec<Vec2> =
                on_seam.iter().filter(|(q, _)| weld_key(*q) == weld_key(p)).map(|q| q.1).collect();
            assert_eq!(copies.len(), 2, "{scheme:?}: {p} has {} copies", copies.len());
        }
        // The seam's far side keeps its constant UV (0.5, 0.5) along the edge.
        assert!(on_seam.iter().any(|(_, uv)| *uv == Vec2::new(0.5, 0.5)), "{scheme:?}");
        // Welded, the two halves still meet: every interior edge has both directions.
        let welded_edges = |m: &Mesh| {
            let mut boundary = 0;
            let key = |i: u32| weld_key(m.positions[i as usize]);
            let mut set = BTreeMap::new();
            for t in &m.indices {
                for e in 0..3 {
                    set.insert((key(t[e]), key(t[(e + 1) % 3])), ());
                }
            }
            for &(a, b) in set.keys() {
                if !set.contains_key(&(b, a)) {
                    boundary += 1;
                }
            }
            boundary
        };
        // The square's boundary is 4 sides × 4 segments after two levels: nothing else.
        assert_eq!(welded_edges(&m), 16, "{scheme:?}");
    }
}

#[test]
fn loop_regular_vertex_follows_the_one_sixteenth_stencil() {
    assert_eq!(loop_beta(6), 1.0 / 16.0);
    assert_eq!(warren_beta(6), 1.0 / 16.0);
    assert_eq!(warren_beta(3), 3.0 / 16.0);
    assert!((loop_beta(3) - 0.1875).abs() < 1e-7); // 5/8 − (3/8 − 1/8)² = 9/16, / 3
    assert!((loop_beta(4) - 0.1210938).abs() < 1e-6); // (5/8 − 9/64) / 4 = 31/256
    // A unit bump at the centre of a flat valence-6 patch.
    let mut g = regular_grid(4);
    let centre = 2 * 5 + 2;
    g.positions[centre].z = 1.0;
    let m = loop_(&g).unwrap();
    // Vertex rule: 1 − 6/16 = 10/16 of itself, 1/16 of each (flat) neighbour.
    assert!((m.positions[centre].z - 0.625).abs() < 1e-7, "{}", m.positions[centre]);
    assert!((m.positions[centre].x - 2.0).abs() < 1e-6);
    // Edge rule: an edge from the bump gets 3/8 of it; an edge opposite it (the bump is one of
    // its two opposite vertices) 1/8; edges two rings out nothing.
    let mut zs: Vec<f32> = m.positions[g.positions.len()..].iter().map(|p| p.z).collect();
    zs.sort_by(f32::total_cmp);
    let count = |z: f32| zs.iter().filter(|&&v| (v - z).abs() < 1e-7).count();
    assert_eq!(count(0.375), 6, "{zs:?}");
    assert_eq!(count(0.125), 6, "{zs:?}");
    // Neighbours of the bump: 1/16 each.
    let neighbour = 2 * 5 + 3;
    assert!((m.positions[neighbour].z - 0.0625).abs() < 1e-7);
}

#[test]
fn loop_converges_to_its_limit_positions() {
    // A closed cube (welded, its corners have valence 3 to 6) approaches the limit surface: the limit of each original vertex is the same whichever level it is
    // computed from, and each level roughly halves (or better) the distance to it.
    let c = cube(Vec3::splat(-1.0), Vec3::splat(1.0));
    let limit0 = loop_limit_positions(&c);
    let mut m = c.clone();
    let mut last = f32::INFINITY;
    for level in 1..=4 {
        m = loop_(&m).unwrap();
        let limit = loop_limit_positions(&m);
        let mut worst = 0.0f32;
        for (i, l0) in limit0.iter().enumerate() {
            assert!((limit[i] - *l0).length() < 2e-5, "level {level} vertex {i}");
            worst = worst.max((m.positions[i] - *l0).length());
        }
        assert!(worst < 0.5 * last, "level {level}: {worst} after {last}");
        last = worst;
        // The surface stays inside the cube (Loop's weights are convex), its corners strictly.
        assert!(m.positions.iter().all(|p| p.abs().max_element() <= 1.0));
        assert!(m.positions[..c.positions.len()].iter().all(|p| p.abs().max_element() < 0.9));
    }
    assert!(last < 0.02, "{last}");
    // An icosphere's limit is near its sphere and its vertices stay symmetric.
    let s = icosphere(Vec3::ZERO, 1.0, 1);
    let radii: Vec<f32> = loop_limit_positions(&s).iter().map(|p| p.length()).collect();
    let (lo, hi) = radii.iter().fold((f32::MAX, 0.0f32), |(a, b), &r| (a.min(r), b.max(r)));
    assert!(hi - lo < 0.03 && lo > 0.85, "{lo}..{hi}");
}

#[test]
fn boundaries_and_non_manifold_edges_are_creases() {
    // A flat open grid: its boundary follows the crease rules, so the grid stays in its plane
    // and inside its square (the square's corners lie on two crease edges and are rounded off
    // like any crease vertex).
    let mut g = regular_grid(3);
    for p in &mut g.positions {
        p.z = 0.0;
    }
    let m = subdivide_mesh(&g, Scheme::Loop, 2).unwrap();
    for p in &m.positions {
        assert!(p.z == 0.0 && p.x >= 0.0 && p.x <= 3.0 && p.y >= 0.0 && p.y <= 3.0, "{p}");
    }
    // A boundary vertex in the middle of the side y = 0 stays on y = 0.
    assert_eq!(m.positions[1].y, 0.0);
    // Crease vertex rule: 3/4 v + 1/8 (a + b) along the side — a straight line keeps x.
    assert!((m.positions[1].x - 1.0).abs() < 1e-6);

    // Three triangles on one edge (a non-manifold fin): Loop treats the edge as a crease.
    let fin = Mesh {
        name: "fin".into(),
        positions: vec![
            Vec3::ZERO,
            Vec3::new(2.0, 0.0, 0.0),
            Vec3::new(1.0, 1.0, 0.0),
            Vec3::new(1.0, -1.0, 0.0),
            Vec3::new(1.0, 0.0, 1.0),
        ],
        normals: vec![Vec3::Z; 5],
        indices: vec![[0, 1, 2], [1, 0, 3], [0, 1, 4]],
        ..Default::default()
    };
    let m = loop_(&fin).unwrap();
    m.validate().unwrap();
    assert_eq!(m.triangle_count(), 12);
    // The shared edge's new vertex is its midpoint, not pulled towards the three wings.
    let mid = Vec3::new(1.0, 0.0, 0.0);
    assert!(m.positions.contains(&mid), "{:?}", m.positions);
    // Its end points lie on four crease edges each (the fin edge and three wing boundaries):
    // corners, which stay put.
    assert_eq!(m.positions[0], Vec3::ZERO);
    assert_eq!(m.positions[1], Vec3::new(2.0, 0.0, 0.0));
}

#[test]
fn spec_parameters_and_errors() {
    let mut pairs = vec![("trees", "2"), ("subdivide", "2"), ("subdivision", "loop")];
    let s = Subdivision::take_from_pairs("forest", &mut pairs).unwrap().unwrap();
    assert_eq!(s, Subdivision { levels: 2, scheme: Scheme::Loop });
    assert_eq!(pairs, vec![("trees", "2")]);
    let mut pairs = vec![("subdivide", "1")];
    let s = Subdivision::take_from_pairs("x", &mut pairs).unwrap().unwrap();
    assert_eq!(s.scheme, Scheme::Midpoint);
    assert_eq!(Subdivision::take_from_pairs("x", &mut vec![("seed", "1")]).unwrap(), None);
    let err = |pairs: &[(&str, &str)]| {
        Subdivision::take_from_pairs("bunny", &mut pairs.to_vec()).unwrap_err().to_string()
    };
    let e = err(&[("subdivide", "9")]);
    assert!(e.contains("bunny.subdivide") && e.contains("0..=8"), "{e}");
    let e = err(&[("subdivide", "two")]);
    assert!(e.contains("bunny.subdivide"), "{e}");
    let e = err(&[("subdivide", "1"), ("subdivision", "catmull-clark")]);
    assert!(e.contains("bunny.subdivision") && e.contains("midpoint or loop"), "{e}");
    let e = err(&[("subdivision", "loop")]);
    assert!(e.contains("needs subdivide"), "{e}");
    let e = err(&[("subdivide", "1"), ("subdivide", "2")]);
    assert!(e.contains("more than once"), "{e}");
}

#[test]
fn too_many_triangles_and_skinned_meshes_are_refused() {
    let scene = scene_with("ball", icosphere(Vec3::ZERO, 1.0, 3), Material::default());
    // 1 280 · 4^8 = 83 886 080 > the limit: refused before any work, naming scene, N, count.
    let e = Subdivision { levels: 8, scheme: Scheme::Loop }.apply(scene.clone()).unwrap_err();
    let e = e.to_string();
    assert!(e.contains("'ball'") && e.contains("= 8") && e.contains("83886080"), "{e}");
    let s = Subdivision { levels: 1, scheme: Scheme::Midpoint }.apply(scene).unwrap();
    assert_eq!(s.triangle_count(), 5_120);
    s.validate().unwrap();

    let mut skinned = cube(Vec3::ZERO, Vec3::ONE);
    skinned.skin = Some(SkinBinding {
        joints: vec![[0; 4]; 24],
        weights: vec![[1.0, 0.0, 0.0, 0.0]; 24],
        ..Default::default()
    });
    let e = midpoint(&skinned).unwrap_err().to_string();
    assert!(e.contains("skinned") && e.contains("'box'"), "{e}");
    assert!(loop_(&skinned).is_err());
}
