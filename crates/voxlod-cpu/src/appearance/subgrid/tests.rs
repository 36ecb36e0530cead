//! Tests of the subgrid build and of both directional-opacity rules (design note §1, §6).

use glam::Vec3;
use proptest::prelude::*;

use super::*;
use crate::appearance::line_sampler::sample_line;
use crate::appearance::voxel_samples::{RaySample, SurfaceSample};

const RULES: [DirectionalRule; 2] = [DirectionalRule::Lines, DirectionalRule::Circles];

/// `n` spherical-Fibonacci directions.
fn fibonacci(n: usize) -> Vec<Vec3> {
    let golden = std::f32::consts::PI * (3.0 - 5f32.sqrt());
    (0..n)
        .map(|i| {
            let z = 1.0 - (2 * i + 1) as f32 / n as f32;
            let r = (1.0 - z * z).sqrt();
            let (s, c) = (golden * i as f32).sin_cos();
            Vec3::new(r * c, r * s, z)
        })
        .collect()
}

/// 200 Fibonacci directions plus the ±axes and the face and body diagonals (all signs).
fn test_directions() -> Vec<Vec3> {
    let mut dirs = fibonacci(200);
    for x in -1..=1 {
        for y in -1..=1 {
            for z in -1..=1 {
                if (x, y, z) != (0, 0, 0) {
                    dirs.push(Vec3::new(x as f32, y as f32, z as f32).normalize());
                }
            }
        }
    }
    dirs
}

/// The subgrid whose cells satisfy `f(x, y, z)` are opaque, the others empty.
fn pattern(f: impl Fn(usize, usize, usize) -> bool) -> [u8; 27] {
    std::array::from_fn(|c| if f(c % 3, c / 3 % 3, c / 9) { 255 } else { 0 })
}

#[test]
fn solid_is_opaque_and_empty_transparent_from_every_direction() {
    let solid = [255u8; 27];
    let empty = [0u8; 27];
    for rule in RULES {
        for d in test_directions() {
            let o = directional_opacity(&solid, d, rule);
            assert!(o >= 0.999, "{rule:?} solid along {d}: {o}");
            assert_eq!(directional_opacity(&empty, d, rule), 0.0, "{rule:?} along {d}");
        }
    }
}

#[test]
fn thin_plane_is_opaque_face_on_and_near_the_third_floor_edge_on() {
    for axis in 0..3 {
        let plane = pattern(|x, y, z| [x, y, z][axis] == 1);
        let normal = Vec3::AXES[axis];
        for rule in RULES {
            for d in [normal, -normal] {
                let o = directional_opacity(&plane, d, rule);
                assert!(o >= 0.99, "{rule:?}, layer ⟂ {axis}, face-on {d}: {o}");
            }
        }
        // Edge-on: every direction in the plane, including exact axes and diagonals.
        let (a, b) = (Vec3::AXES[(axis + 1) % 3], Vec3::AXES[(axis + 2) % 3]);
        for i in 0..16 {
            let (s, c) = (i as f32 * std::f32::consts::PI / 8.0).sin_cos();
            let d = a * c + b * s;
            let lines = directional_opacity(&plane, d, DirectionalRule::Lines);
            assert!(lines <= 0.40, "lines, layer ⟂ {axis}, edge-on {d}: {lines}");
            assert!(
                (lines - 1.0 / 3.0).abs() <= 0.05,
                "lines, layer ⟂ {axis}, edge-on {d}: {lines} is not within 0.05 of 1/3"
            );
            let circles = directional_opacity(&plane, d, DirectionalRule::Circles);
            assert!(circles <= 0.55, "circles, layer ⟂ {axis}, edge-on {d}: {circles}");
        }
    }
}

/// Views exactly along an axis (exactly ⟂ two faces, lines parallel to four) of patterns
/// whose exact opacity is known: the centre column 1/9, one slab of columns 1/3. Lines are
/// within 0.05 of it (32 lines resolve 1/32; the column measures 2/32); Circles, whose discs spill over neighbouring pixels (the paper's
/// "tendency of extending opacities"), within 0.12 (the column measures 0.22).
#[test]
fn exact_axis_views_match_exact_footprints() {
    for axis in 0..3 {
        let (p, q) = ((axis + 1) % 3, (axis + 2) % 3);
        let column = pattern(|x, y, z| [x, y, z][p] == 1 && [x, y, z][q] == 1);
        let slab = pattern(|x, y, z| [x, y, z][p] == 0);
        for d in [Vec3::AXES[axis], -Vec3::AXES[axis]] {
            for (rule, tolerance) in
                [(DirectionalRule::Lines, 0.05), (DirectionalRule::Circles, 0.12)]
            {
                let c = directional_opacity(&column, d, rule);
                assert!((c - 1.0 / 9.0).abs() <= tolerance, "{rule:?} column along {d}: {c}");
                let s = directional_opacity(&slab, d, rule);
                assert!((s - 1.0 / 3.0).abs() <= tolerance, "{rule:?} slab along {d}: {s}");
            }
        }
    }
}

#[test]
fn zero_and_non_finite_directions_read_as_z() {
    let plane = pattern(|_, _, z| z == 1);
    for rule in RULES {
        let z = directional_opacity(&plane, Vec3::Z, rule);
        for d in [Vec3::ZERO, Vec3::NAN, Vec3::new(f32::INFINITY, 0.0, 0.0)] {
            assert_eq!(directional_opacity(&plane, d, rule), z, "{rule:?} along {d}");
        }
    }
}

#[test]
fn lines_through_subcell_edges_skip_the_cells_they_touch() {
    // Through the sub-cell edge at (1/3, 2/3): from cell (0,1,1) straight into (1,2,1).
    let d = Vec3::new(1.0, 1.0, 0.0).normalize();
    let entry = Vec3::new(0.0, 1.0 / 3.0, 0.5);
    let mut cells = Vec::new();
    for_each_subcell(entry, d, chord(entry, d), |c| {
        cells.push(c);
        true
    });
    assert_eq!(cells, [3 + 9, 1 + 6 + 9]);
    // Along an axis, on the boundary between two columns: booked in the column above.
    let entry = Vec3::new(1.0 / 3.0, 0.5, 0.0);
    let mut cells = Vec::new();
    for_each_subcell(entry, Vec3::Z, chord(entry, Vec3::Z), |c| {
        cells.push(c);
        true
    });
    assert_eq!(cells, [4, 4 + 9, 4 + 18]);
}

#[test]
fn subcell_of_marks_one_cell_also_on_shared_faces() {
    assert_eq!(subcell_of(Vec3::new(1.0 / 3.0, 0.5, 0.5)), 1 + 3 + 9);
    assert_eq!(subcell_of(Vec3::new(2.0 / 3.0, 2.0 / 3.0, 2.0 / 3.0)), 2 + 6 + 18);
    assert_eq!(subcell_of(Vec3::ZERO), 0);
    assert_eq!(subcell_of(Vec3::ONE), 26);
    assert_eq!(subcell_of(Vec3::new(-0.1, 1.2, 0.5)), 6 + 9);
}

fn ray(entry: Vec3, dir: Vec3, occluded: bool, hit: Option<Vec3>) -> RaySample {
    RaySample {
        dir,
        entry,
        chord: chord(entry, dir),
        occluded,
        surface: hit.map(|point| SurfaceSample {
            point,
            normal: -dir,
            albedo: Vec3::ONE,
            specular: 0.0,
            shininess: 0.0,
        }),
    }
}

/// A hit exactly on the face between sub-cells x = 0 and x = 1 marks one of them, although
/// occluded lines cross both.
#[test]
fn a_hit_on_a_subcell_face_marks_one_cell() {
    let mut samples = VoxelSamples::default();
    for y in [0.4f32, 0.5, 0.6] {
        // Along +x through the middle row: crosses cells x = 0, 1, 2 of row (y=1, z=1).
        samples.rays.push(ray(Vec3::new(0.0, y, 0.5), Vec3::X, true, None));
    }
    samples.rays.push(ray(
        Vec3::new(0.0, 0.5, 0.5),
        Vec3::X,
        true,
        Some(Vec3::new(1.0 / 3.0, 0.5, 0.5)),
    ));
    let alpha = build(&samples);
    let nonzero: Vec<usize> = (0..27).filter(|&c| alpha[c] != 0).collect();
    assert_eq!(nonzero, [1 + 3 + 9]);
    assert_eq!(alpha[13], 255);
}

/// α = occluded / rays on marked cells, over whole chords (also behind the hit); cells without
/// a front hit are cleared even where every line through them is occluded.
#[test]
fn build_books_whole_chords_and_clears_unmarked_cells() {
    let mut samples = VoxelSamples::default();
    let e = |y: f32| Vec3::new(0.5, y, 0.0);
    // Four lines up the middle column, one front hit in the bottom cell; three occluded.
    samples.rays.push(ray(e(0.5), Vec3::Z, true, Some(Vec3::new(0.5, 0.5, 0.1))));
    samples.rays.push(ray(e(0.45), Vec3::Z, true, None));
    samples.rays.push(ray(e(0.55), Vec3::Z, true, None));
    samples.rays.push(ray(e(0.6), Vec3::Z, false, None));
    // A hit in the top cell of the column.
    samples.rays[2].surface = ray(e(0.55), Vec3::Z, true, Some(Vec3::new(0.5, 0.55, 0.9))).surface;
    let alpha = build(&samples);
    assert_eq!(alpha[4], unorm8(0.75));
    assert_eq!(alpha[4 + 18], unorm8(0.75));
    assert_eq!(alpha[4 + 9], 0, "the middle cell has no front hit");
    assert_eq!(alpha.iter().filter(|&&a| a != 0).count(), 2);
    assert_eq!(build(&VoxelSamples::default()), [0; 27]);
}

/// [`build`] books only marked cells; the literal rule books every crossed cell, then clears
/// the unmarked ones. Both give the same bytes, exactly, on random voxels of 150 lines.
#[test]
fn build_equals_booking_every_cell_then_clearing() {
    for v in 0..300u32 {
        let mut samples = VoxelSamples::default();
        for i in 0..150 {
            let (d, entry, len) = sample_line(v, i, 3);
            let r = |k| crate::random::rand_u32(v, i, k);
            let occluded = r(0) % 3 != 0;
            // Hits at random points along the chord, on about a third of the lines.
            let hit = (r(1) % 3 == 0).then(|| entry + d * len * (r(2) as f32 / u32::MAX as f32));
            samples.rays.push(RaySample { chord: len, ..ray(entry, d, occluded, hit) });
        }
        let (mut rays, mut occ, mut marked) = ([0u32; 27], [0u32; 27], [false; 27]);
        for r in &samples.rays {
            for_each_subcell(r.entry, r.dir, r.chord, |c| {
                rays[c] += 1;
                occ[c] += r.occluded as u32;
                true
            });
            if let Some(s) = &r.surface {
                marked[subcell_of(s.point)] = true;
            }
        }
        let literal: [u8; 27] = std::array::from_fn(|c| {
            if marked[c] && rays[c] > 0 { unorm8(occ[c] as f32 / rays[c] as f32) } else { 0 }
        });
        assert_eq!(build(&samples), literal, "voxel {v}");
    }
}

/// The crossed cells against brute force: every cell whose closed box the segment crosses over
/// more than 10⁻⁵ is visited, none it crosses over less than 10⁻⁷, each once, in index order.
#[test]
fn crossed_cells_are_the_ones_a_brute_force_slab_test_finds() {
    for i in 0..20_000 {
        let (d, entry, len) = sample_line(17, i, 0);
        let mut visited = Vec::new();
        for_each_subcell(entry, d, len, |c| {
            visited.push(c);
            true
        });
        let mut expected = Vec::new();
        for c in 0..27usize {
            let lo = Vec3::new((c % 3) as f32, (c / 3 % 3) as f32, (c / 9) as f32) / 3.0;
            let hi = lo + 1.0 / 3.0;
            let (mut t0, mut t1) = (0.0f32, len);
            for j in 0..3 {
                if d[j] == 0.0 {
                    if entry[j] < lo[j] || entry[j] > hi[j] {
                        t1 = -1.0;
                    }
                } else {
                    let (a, b) = ((lo[j] - entry[j]) / d[j], (hi[j] - entry[j]) / d[j]);
                    t0 = t0.max(a.min(b));
                    t1 = t1.min(a.max(b));
                }
            }
            expected.push((c, t0, t1 - t0));
        }
        for &(c, _, length) in &expected {
            if length > 1e-5 {
                assert!(visited.contains(&c), "line {i}: cell {c} crossed over {length}");
            }
            if length < 1e-7 {
                assert!(!visited.contains(&c), "line {i}: cell {c} only touched ({length})");
            }
        }
        assert!(visited.windows(2).all(|w| w[0] < w[1]), "line {i}: order {visited:?}");
        assert!(visited.len() <= 7);
    }
}

proptest! {
    #[test]
    fn opacity_is_in_the_unit_interval(
        alpha in proptest::array::uniform27(any::<u8>()),
        x in -1.0f32..1.0, y in -1.0f32..1.0, z in -1.0f32..1.0,
    ) {
        for rule in RULES {
            let o = directional_opacity(&alpha, Vec3::new(x, y, z), rule);
            prop_assert!((0.0..=1.0).contains(&o), "{rule:?}: {o}");
            // Never above the largest sub-cell opacity, never below the smallest.
            let (lo, hi) = (*alpha.iter().min().unwrap(), *alpha.iter().max().unwrap());
            prop_assert!(o <= hi as f32 / 255.0 + 1e-5 && o + 1e-5 >= lo as f32 / 255.0, "{rule:?}: {o}");
        }
    }
}

// The authors' rule (`DirectionalRule::Authors`), against values worked out by hand from
// their `computeOcclusion` / `projectionKernel` / `circleIntersection`. Throughout, lengths are
// in units of the window's pixel width `s = step_u`: the sub-cell circle has radius R = √2,
// the pixel circle r = ½, so a pixel whose centre is within R − r = 0.914 of a projected
// sub-cell centre is covered fully, one beyond R + r = 1.914 not at all, and in between the
// lens area is A = ½r²(β − sin β) + ½R²(α − sin α) with α = 2 acos((R² + d² − r²)/(2Rd)) and
// β = 2 acos((r² + d² − R²)/(2rd)); coverage = A/(πr²) = A/0.785398.

fn one_cell(x: usize, y: usize, z: usize) -> [u8; 27] {
    pattern(|a, b, c| (a, b, c) == (x, y, z))
}

/// The centre sub-cell (1,1,1) seen along ±x. The voxel projects to a unit square, so
/// s = ¼ and the pixels are (i + ½)/4 from the window's corner; the centre projects to the
/// window's middle, (2, 2) in pixels: exactly on a pixel corner, and the truncation puts it in
/// pixel (2, 2), whose 3×3 neighbourhood is pixels 1..=3 on both axes.
/// - Pixels (1,1), (1,2), (2,1), (2,2): d = √(½² + ½²) = 0.707 < 0.914, coverage 1.
/// - Pixels (1,3), (2,3), (3,1), (3,2): d = √(½² + 1½²) = √2.5 = 1.5811; cos α = (2 + 2.5 −
///   0.25)/(2·√2·1.5811) = 0.950329, α = 0.633011; cos β = (0.25 + 2.5 − 2)/(2·½·1.5811) =
///   0.474342, β = 2.153161; A = 0.125(2.153161 − 0.835202) + 1.0(0.633011 − 0.591575) =
///   0.164749 + 0.041436 = 0.206185; coverage 0.262523.
/// - Pixel (3,3): d = √(2·1.5²) = 2.121 > 1.914, nothing; the 7 pixels of row or column 0
///   are outside the 3×3 neighbourhood (pixel (0, 1) would be reached at d = 1.58, it is not
///   visited).
///
/// Opacity = (4·1 + 4·0.262523)/16 = 0.315631, from either side (the mirror image puts the
/// centre in the same pixel, and the neighbourhood's partial pixels are the same four).
#[test]
fn authors_rule_one_centre_cell_along_an_axis() {
    let alpha = one_cell(1, 1, 1);
    for dir in [Vec3::X, Vec3::NEG_X, Vec3::Y, Vec3::Z] {
        let got = directional_opacity(&alpha, dir, DirectionalRule::Authors);
        assert!((got - 0.315_631).abs() < 2e-5, "{dir}: {got}");
    }
    // Not normalized and a larger circle: more than the paper's normalized circles give.
    let circles = directional_opacity(&alpha, Vec3::X, DirectionalRule::Circles);
    assert!(circles < 0.25, "circles {circles}");
}

/// The corner sub-cell (0,0,0) seen along +z (the authors' ray travels along −z): with
/// r = (0,0,−1) the Hughes–Möller basis is u = (−1,0,0), v = (0,1,0); relative to the voxel
/// centre the cell's centre (−⅓, −⅓) in (x, y) projects to (u, v) = (⅓, −⅓), the window is
/// [−½, ½]², s = ¼, so in pixels it sits at (3.333, 0.667): pixel (3, 0), neighbourhood
/// columns 2..=3, rows 0..=1.
/// - (3,0): offsets (0.167, 0.167), d = 0.236, coverage 1.
/// - (2,0) and (3,1): offsets (0.833, 0.167), d = 0.850 < 0.914, coverage 1.
/// - (2,1): offsets (0.833, 0.833), d = 1.1785; cos α = (2 + 1.388889 − 0.25)/(2·√2·1.1785) =
///   0.941667, α = 0.686495; cos β = (0.25 + 1.388889 − 2)/(2·½·1.1785) = −0.306413,
///   β = 3.764437; A = 0.125(3.764437 + 0.583659) + (0.686495 − 0.633830) = 0.543473 +
///   0.052665 = 0.596138; coverage 0.759027.
///
/// Opacity = (3 + 0.759027)/16 = 0.234939.
#[test]
fn authors_rule_one_corner_cell_along_an_axis() {
    let got = directional_opacity(&one_cell(0, 0, 0), Vec3::Z, DirectionalRule::Authors);
    assert!((got - 0.234_939).abs() < 2e-5, "{got}");
    // At half opacity every covered pixel keeps half: not normalized, linear in α.
    let half = pattern(|x, y, z| (x, y, z) == (0, 0, 0)).map(|a| a / 2);
    let got = directional_opacity(&half, Vec3::Z, DirectionalRule::Authors);
    assert!((got - 0.234_939 * 127.0 / 255.0).abs() < 2e-5, "{got}");
}

/// The sub-cell (0,2,0) seen along the body diagonal d = (1,1,1)/√3 (ray r = −d). The basis
/// of r: |r_x| = |r_z|, so v = normalize(0, −r_z, r_y) = (0, 1, −1)/√2 and u = v × r =
/// (−2, 1, 1)/√6. The corners project to a hexagon whose bounding window is
/// u ∈ ±2/√6 = ±0.816497, v ∈ ±1/√2 = ±0.707107: a rectangle, s = step_u = 0.408248,
/// step_v = 0.353553 = 0.866 s; R = √2·s = 0.577350, r = s/2 = 0.204124. The cell centre,
/// (−⅓, ⅓, −⅓) from the voxel centre, projects to u = (⅔ + ⅓ − ⅓)/√6 = 0.272166,
/// v = (⅓ + ⅓)/√2 = 0.471405; in window pixels ((0.272166 + 0.816497)/s,
/// (0.471405 + 0.707107)/step_v) = (2.667, 3.333): pixel (2, 3), neighbourhood columns 1..=3,
/// rows 2..=3. Offsets from the pixel centres in units of s (rows are 0.866 s apart):
/// - (2,3): offsets (0.167, −0.167·0.866), d = 0.2205, coverage 1;
/// - (2,2): (0.167, 0.833·0.866), d = 0.7407, coverage 1; (3,3): (−0.833, −0.144), d =
///   0.8457, coverage 1;
/// - (1,2): (1.167, 0.722), d = 1.3718; cos α = 0.936032, α = 0.719231; cos β = 0.096181,
///   β = 2.948934; A = 0.344683 + 0.060425 = 0.405108; coverage 0.515799;
/// - (1,3): (1.167, −0.144), d = 1.1756; α = 0.684862, β = 3.778481; A = 0.546647 +
///   0.052296 = 0.598943; coverage 0.762598;
/// - (3,2): (−0.833, 0.722), d = 1.1024; α = 0.628655, β = 4.154443; A = 0.625349 +
///   0.040597 = 0.665946; coverage 0.847909.
///
/// Opacity = (3 + 0.515799 + 0.762598 + 0.847909)/16 = 0.320394, the same for the opposite
/// diagonal (the mirror image, no centre on a pixel boundary).
#[test]
fn authors_rule_one_cell_along_a_diagonal() {
    let alpha = one_cell(0, 2, 0);
    for dir in [Vec3::ONE, Vec3::NEG_ONE] {
        let got = directional_opacity(&alpha, dir, DirectionalRule::Authors);
        assert!((got - 0.320_394).abs() < 2e-5, "{dir}: {got}");
    }
}

/// No normalization: a uniform subgrid of opacity α gives α itself where every pixel is
/// covered fully, which the large sub-cell circles achieve from every test direction; an
/// empty one gives 0.
#[test]
fn authors_rule_is_alpha_on_uniform_subgrids() {
    for dir in test_directions() {
        for a in [255u8, 128, 1] {
            let got = directional_opacity(&[a; 27], dir, DirectionalRule::Authors);
            let want = a as f32 / 255.0;
            assert!((got - want).abs() < 1e-6, "{dir}, α {a}: {got}");
        }
        assert_eq!(directional_opacity(&[0; 27], dir, DirectionalRule::Authors), 0.0);
    }
}
