//! The payload's laws (as every payload's), the coverage-weighted distance next to empty nodes
//! (the trap of the module docs, with the unweighted reading as a control that fails), and the
//! pre-filter's statistics against cases with a closed form.

use glam::{DVec3, UVec3, Vec3};
use voxlod_format::GridSpec;
use voxlod_format::records::MicrosurfaceRecord;

use super::*;
use crate::microsurface::special::erf_f64;
use crate::{BuildOptions, Octree};

/// A leaf whose surface is the plane through `point` (voxel-local) with unit normal `n`.
fn plane_leaf(point: Vec3, n: Vec3, albedo: Vec3) -> MicrosurfacePayload {
    let n = n.normalize();
    let m = [n.x * n.x, n.y * n.y, n.z * n.z, n.x * n.y, n.x * n.z, n.y * n.z];
    MicrosurfacePayload::from_record(&MicrosurfaceRecord {
        centroid: point.to_array(),
        plane_normal: n.to_array(),
        normal_moments: m,
        height_variance: 0.0,
        albedo: albedo.to_array(),
        albedo_slope: [0.0; 3],
        specular: 0.0,
        roughness: 0.5,
    })
}

fn leaf(k: u32) -> MicrosurfacePayload {
    let r =
        |i: u32| ((k.wrapping_mul(2_654_435_761) ^ i.wrapping_mul(40_503)) % 1000) as f32 / 999.0;
    let mut p = plane_leaf(
        Vec3::new(r(1), r(2), r(3)),
        Vec3::new(r(4) - 0.5, r(5) - 0.5, 1.0),
        Vec3::new(r(6), r(7), r(8)),
    );
    p.height_variance = 0.01 * r(9);
    p.albedo_slope = [0.1 * r(10), -0.1 * r(11), 0.0];
    p
}

#[test]
fn laws_empty_is_the_additive_zero_and_accumulation_is_linear() {
    let e = MicrosurfacePayload::empty();
    assert_eq!(MicrosurfacePayload::prefilter(&[e; 8]), e);
    let (a, b) = (leaf(1), leaf(2));
    let mut x = a;
    x.add_scaled(&e, 0.7);
    assert_eq!(x, a);
    let mut y = e;
    y.add_scaled(&a, 1.0);
    assert_eq!(y, a);
    // Linear: (a + 0.5 b) + 0.25 b = a + 0.75 b.
    let mut s = a;
    s.add_scaled(&b, 0.5);
    s.add_scaled(&b, 0.25);
    let mut t = a;
    t.add_scaled(&b, 0.75);
    assert!(s.max_abs_diff(&t) < 1e-6);
    // add_scaled_at: add_scaled at offset 0, size 1; linear in `other` for any offset.
    let mut u = a;
    u.add_scaled_at(&b, 0.3, Vec3::ZERO, 1.0);
    let mut v = a;
    v.add_scaled(&b, 0.3);
    assert_eq!(u, v);
    let (off, size) = (Vec3::new(0.3, -1.2, 2.0), 4.0);
    let mut lhs = e;
    let mut both = a;
    both.add_scaled(&b, 2.0);
    lhs.add_scaled_at(&both, 0.5, off, size);
    let mut rhs = e;
    rhs.add_scaled_at(&a, 0.5, off, size);
    rhs.add_scaled_at(&b, 1.0, off, size);
    assert!(lhs.max_abs_diff(&rhs) < 1e-5, "{lhs:?} vs {rhs:?}");
    let mut z = e;
    z.add_scaled_at(&e, 1.0, off, size);
    assert_eq!(z, e);
    assert_eq!(e.decode(), None);
    assert_eq!(a.check(), None);
}

#[test]
fn bad_leaves_are_rejected() {
    let good = leaf(3);
    for (bad, needle) in [
        (MicrosurfacePayload { coverage: 1.5, ..good }, "coverage"),
        (MicrosurfacePayload { centroid: [0.0, f32::NAN, 0.0], ..good }, "NaN"),
        (MicrosurfacePayload { height_variance: -1.0, ..good }, "variance"),
        (MicrosurfacePayload { normal_moments: [-0.1, 0.0, 1.0, 0.0, 0.0, 0.0], ..good }, "moment"),
    ] {
        assert!(bad.check().unwrap().contains(needle), "{needle}");
    }
}

/// The plane `n·x = n·x0` (grid units) crossing a 16³ grid, one leaf per voxel it crosses,
/// each with its exact distance.
fn plane_tree(n: Vec3, x0: Vec3) -> Octree<MicrosurfacePayload> {
    let n = n.normalize();
    let grid = GridSpec::new(DVec3::ZERO, 1.0, UVec3::splat(16)).unwrap();
    let mut voxels = Vec::new();
    for z in 0..16 {
        for y in 0..16 {
            for x in 0..16 {
                let c = Vec3::new(x as f32, y as f32, z as f32) + 0.5;
                // The plane crosses the voxel when the centre is within its support radius.
                let support = 0.5 * (n.x.abs() + n.y.abs() + n.z.abs());
                let d = n.dot(c - x0);
                if d.abs() <= support {
                    let local = (c - d * n) - (c - 0.5); // the closest plane point, voxel-local
                    voxels.push((UVec3::new(x, y, z), plane_leaf(local, n, Vec3::splat(0.5))));
                }
            }
        }
    }
    Octree::build(grid, voxels, &BuildOptions { depth: None, dense_log2: 1 }).unwrap()
}

/// The trap: next to empty nodes the plane must stay where the surface is. Sampled along lines
/// crossing the surface layer into empty space on both sides, on every level, the distance is
/// the true distance wherever any corner has coverage, and there is no surface where none has.
#[test]
fn no_false_surface_appears_next_to_empty_nodes() {
    for n in [Vec3::Z, Vec3::new(0.3, 0.5, 0.81)] {
        let x0 = Vec3::new(8.0, 8.0, 7.3);
        let tree = plane_tree(n, x0);
        let n = n.normalize();
        let mut seen = [0usize; 2];
        for level in 0..=3u32 {
            for i in 0..=200 {
                // Around the middle of the grid (the plane's tiles end at the grid's faces).
                let p = Vec3::new(7.6, 8.2, 0.0) + Vec3::Z * (i as f32 * 0.08);
                let want = n.dot(p - x0);
                match tree.sample_level(p, level).decode() {
                    Some(s) => {
                        seen[0] += 1;
                        let err = (s.distance - want).abs();
                        assert!(err < 2e-4, "level {level}, p {p}: {} vs {want}", s.distance);
                        assert!((s.normal - n).length() < 1e-5);
                    }
                    None => {
                        seen[1] += 1;
                        // No data anywhere near: far from the surface layer (≥ one node away).
                        assert!(want.abs() > 0.5 * (1u32 << level) as f32, "level {level}, {p}");
                    }
                }
            }
        }
        assert!(seen[0] > 300 && seen[1] > 100, "{seen:?}");
    }
}

/// The control: read unweighted and unmoved (the plain trilinear mean of the distances at the
/// nodes' centres, empty corners as 0, the way every other payload is read), the same plane
/// grows a false surface in the empty space next to it.
#[test]
fn the_unweighted_reading_would_put_a_surface_in_empty_space() {
    let x0 = Vec3::new(8.0, 8.0, 7.3);
    let tree = plane_tree(Vec3::Z, x0);
    let p = Vec3::new(8.0, 8.0, 8.1); // 0.8 voxels above the surface, 0.1 above the layer
    let level = tree.level(0);
    // Corners: centres at z = 7.5 (occupied, h = 0.2) and 8.5 (empty), trilinear weight 0.6 on
    // the upper (empty) layer (x and y on a centre: one column).
    let codes = tree.node_codes(0);
    let h_at = |c: UVec3| {
        codes
            .binary_search(&voxlod_format::morton::encode(c))
            .ok()
            .map_or(0.0, |i| -Vec3::from(level.payload[i].centroid).z)
    };
    let p = Vec3::new(8.5, 8.5, p.z);
    let naive = 0.6 * h_at(UVec3::new(8, 8, 8)) + 0.4 * h_at(UVec3::new(8, 8, 7));
    let right = tree.sample_level(p, 0).decode().unwrap().distance;
    assert!((right - 0.8).abs() < 1e-4, "{right}");
    assert!(naive < 0.1, "the unweighted mean puts the surface at p: {naive}");
}

#[test]
fn a_plane_stays_flat_and_keeps_its_colour_at_every_level() {
    let tree = plane_tree(Vec3::new(0.3, 0.5, 0.81), Vec3::new(8.0, 8.0, 7.3));
    for l in 1..=tree.depth() {
        for p in tree.level(l).payload.iter().filter(|p| p.coverage > 0.0) {
            let s = p.decode().unwrap();
            assert!(s.height_variance < 1e-6, "level {l}: σh² {}", s.height_variance);
            assert!((s.albedo - Vec3::splat(0.5)).length() < 1e-6);
            assert!(Vec3::from(p.albedo_slope).length() < 1e-6);
            assert!(s.slope_variance() < 1e-5, "level {l}: {}", s.slope_variance());
        }
    }
}

/// Two children, planes ±δ about the parent's plane, red above and green below (σ = 0 each):
/// σh² = δ², and aₛ fits the model a(h) = ā + aₛ·erf(h/(√2σh)) exactly at both heights.
#[test]
fn height_correlated_colour_is_projected_on_the_profile() {
    let up = Vec3::new(0.9, 0.1, 0.1);
    let down = Vec3::new(0.1, 0.9, 0.1);
    // Children 0 and 1 (side by side along x): a step of the surface between them, heights
    // +0.2 and −0.2 child units (±0.1 parent units) about the parent's plane.
    let step = |dz: f32, a| plane_leaf(Vec3::new(0.5, 0.5, 0.5 + dz), Vec3::Z, a);
    let mut kids = [MicrosurfacePayload::empty(); 8];
    kids[0] = step(0.2, up);
    kids[1] = step(-0.2, down);
    let p = MicrosurfacePayload::prefilter(&kids);
    let s = p.decode().unwrap();
    assert!((p.coverage - 0.25).abs() < 1e-7);
    assert!((s.height_variance - 0.01).abs() < 1e-6, "σh² {}", s.height_variance);
    assert!((s.distance - 0.25).abs() < 1e-6, "the plane halfway between: {}", s.distance);
    assert!((s.albedo - (up + down) * 0.5).length() < 1e-6);
    let prof = erf_f64(1.0 / 2f64.sqrt()) as f32; // s(δ) with σh = δ
    let fit_up = s.albedo + s.albedo_slope * prof;
    let fit_down = s.albedo - s.albedo_slope * prof;
    assert!((fit_up - up).length() < 1e-4 && (fit_down - down).length() < 1e-4, "{s:?}");
    assert!(s.albedo_slope.x > 0.0 && s.albedo_slope.y < 0.0);
    // Both at the same height: no spread, no slope.
    kids[1] = step(0.2, down);
    let q = MicrosurfacePayload::prefilter(&kids).decode().unwrap();
    assert!(q.height_variance < 1e-12 && q.albedo_slope.length() < 1e-9, "{q:?}");
}

/// One child under a parent: the parent is that child at the parent's scale (plane moved,
/// variance in parent units, the same colour profile), whatever the seven empty ones.
#[test]
fn a_single_child_is_its_parent_at_the_parent_scale() {
    for k in 0..8 {
        let mut c = leaf(7);
        c.height_variance = 0.04;
        c.albedo_slope = [0.2, -0.1, 0.05];
        let mut kids = [MicrosurfacePayload::empty(); 8];
        kids[k] = c;
        let p = MicrosurfacePayload::prefilter(&kids);
        let (cs, ps) = (c.decode().unwrap(), p.decode().unwrap());
        assert!((p.coverage - 0.125).abs() < 1e-7);
        assert!((ps.height_variance - 0.01).abs() < 1e-6, "octant {k}: {}", ps.height_variance);
        assert!((ps.albedo_slope - cs.albedo_slope).length() < 1e-5, "octant {k}: {ps:?}");
        assert!((ps.normal - cs.normal).length() < 1e-6);
        // The child's plane read at the parent's centre, in parent units.
        let o = Vec3::new((k & 1) as f32, (k >> 1 & 1) as f32, (k >> 2 & 1) as f32);
        let want = (cs.distance + cs.normal.dot(Vec3::splat(0.5) - o)) * 0.5;
        assert!((ps.distance - want).abs() < 1e-6, "octant {k}");
    }
}

#[test]
fn slope_variances_follow_the_normal_moments() {
    // Normals at ±φ about z in the xz plane: slope variance tan²φ along x, 0 along y.
    let phi = 0.3f32;
    let (s, c) = phi.sin_cos();
    let mut a = plane_leaf(Vec3::splat(0.5), Vec3::new(s, 0.0, c), Vec3::ONE);
    let b = plane_leaf(Vec3::splat(0.5), Vec3::new(-s, 0.0, c), Vec3::ONE);
    a.add_scaled(&b, 1.0);
    a.add_scaled(&MicrosurfacePayload::empty(), 0.0);
    let mut m = MicrosurfacePayload::empty();
    m.add_scaled(&a, 0.5);
    let d = m.decode().unwrap();
    assert!((d.normal - Vec3::Z).length() < 1e-6);
    assert!((d.normal_length - c).abs() < 1e-6);
    let tan2 = (s / c).powi(2);
    assert!((d.slope_variance_along(Vec3::X) - tan2).abs() < 1e-5);
    assert!(d.slope_variance_along(Vec3::Y) < 1e-7);
    assert!((d.slope_variance() - tan2 / 2.0).abs() < 1e-5);
}

/// A corrugated surface `z = z0 + A·sin(2πx/λ)` (λ = 8 voxels, A = 0.3) with its colour
/// rising with height, one tangent-plane leaf per voxel it crosses. At level 3 a node spans a
/// period: its statistics must approach those of the heights it covers, `σh² = A²/2`, and the
/// colour profile's projection computed directly from the heights. (Between nodes the
/// variances interpolate linearly, without the spread of the nodes' planes, as in the paper;
/// the renderer reads `σh²` nowhere but through `aₛ`.)
#[test]
fn a_corrugated_surface_prefilters_to_its_height_statistics() {
    let (z0, amp, lambda) = (11.6f32, 0.3f32, 8.0f32);
    let k = std::f32::consts::TAU / lambda;
    let colour = |h: f32| Vec3::new(0.5 + h, 0.5 - h, 0.5);
    let grid = GridSpec::new(DVec3::ZERO, 1.0, UVec3::splat(16)).unwrap();
    let mut voxels = Vec::new();
    for x in 0..16u32 {
        let xc = x as f32 + 0.5;
        let h = amp * (k * xc).sin();
        let n = Vec3::new(-amp * k * (k * xc).cos(), 0.0, 1.0).normalize();
        for y in 0..16u32 {
            for z in 0..16u32 {
                let c = Vec3::new(xc, y as f32 + 0.5, z as f32 + 0.5);
                let surface = Vec3::new(xc, c.y, z0 + h);
                let d = n.dot(c - surface);
                if d.abs() <= 0.5 * (n.x.abs() + n.z.abs()) {
                    let local = c - d * n - (c - 0.5);
                    voxels.push((UVec3::new(x, y, z), plane_leaf(local, n, colour(h))));
                }
            }
        }
    }
    let tree = Octree::build(grid, voxels, &BuildOptions { depth: None, dense_log2: 1 }).unwrap();
    // The level-3 node x ∈ [0, 8), y ∈ [0, 8), z ∈ [8, 16), read at its centre.
    let s = tree.sample_level(Vec3::new(4.0, 4.0, 12.0), 3).decode().unwrap();
    let var = s.height_variance;
    let want = amp * amp / 2.0;
    assert!((var - want).abs() < 0.25 * want, "σh² {var} vs {want}");
    assert!((s.normal - Vec3::Z).length() < 0.05, "{}", s.normal);
    // aₛ from the heights directly: E[s(h)(a − ā)] / E[s(h)²] over a period, s with σh = A/√2.
    let sigma = (want as f64).sqrt();
    let (mut num, mut den) = (0.0, 0.0);
    for i in 0..1000 {
        let h = amp as f64 * (std::f64::consts::TAU * (i as f64 + 0.5) / 1000.0).sin();
        let prof = erf_f64(h / (2f64.sqrt() * sigma));
        num += prof * h;
        den += prof * prof;
    }
    let slope = (num / den) as f32; // for the red channel, a − ā = h
    assert!((s.albedo_slope.x - slope).abs() < 0.2 * slope, "aₛ {} vs {slope}", s.albedo_slope.x);
    assert!((s.albedo_slope.y + slope).abs() < 0.2 * slope && s.albedo_slope.z.abs() < 1e-4);
    assert!((s.albedo - Vec3::splat(0.5)).length() < 0.02, "{}", s.albedo);
}

mod planes {
    use proptest::prelude::*;

    use super::*;

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(24))]
        /// Any plane, any sample point and level: wherever a sample has coverage its distance
        /// and normal are the plane's (the octree reads like the plane's distance field), and
        /// a sample without coverage is at least one node from the surface.
        #[test]
        fn every_sample_of_a_plane_reads_the_plane(
            nx in -1.0f32..1.0, ny in -1.0f32..1.0, nz in 0.2f32..1.0,
            (ox, oy, oz) in (6.0f32..10.0, 6.0f32..10.0, 6.0f32..10.0),
            points in proptest::collection::vec((4.0f32..12.0, 4.0f32..12.0, 0.0f32..16.0, 0u32..4), 40),
        ) {
            let n = Vec3::new(nx, ny, nz).normalize();
            let x0 = Vec3::new(ox, oy, oz);
            let tree = plane_tree(n, x0);
            for (x, y, z, level) in points {
                let p = Vec3::new(x, y, z);
                let want = n.dot(p - x0);
                match tree.sample_level(p, level).decode() {
                    Some(s) => {
                        prop_assert!((s.distance - want).abs() < 5e-4, "{p} level {level}: {} vs {want}", s.distance);
                        prop_assert!((s.normal - n).length() < 1e-4);
                    }
                    None => prop_assert!(want.abs() > 0.5 * (1u32 << level) as f32 - 1e-3),
                }
            }
        }
    }
}

#[test]
fn the_profile_table_is_erf_at_the_nodes() {
    for (i, &(z, _)) in GAUSS_HERMITE.iter().enumerate() {
        assert!((PROFILE[i] - erf_f64(z / 2f64.sqrt())).abs() < 1e-15, "{i}");
    }
}
