//! Differential cone tracing on analytic surfaces: opaque walls at every level, silhouettes
//! that keep their coverage under masks and thicken under alpha blending (the paper's Fig. 4),
//! depth of field, the level read, view-dependent colour, bad input and extremes.

use std::sync::Mutex;

use glam::{DVec3, UVec3, Vec3};
use voxlod_format::GridSpec;
use voxlod_format::records::MicrosurfaceRecord;
use voxlod_octree::{BuildOptions, MicrosurfacePayload, Octree};

use super::*;

const LIGHT: Light = Light::Directional { to_light: Vec3::NEG_Z, irradiance: Vec3::ONE };

/// Leaves of the surface `sdf = 0` (positive outside) in a 64³ grid of unit voxels: every
/// voxel whose centre is within √3/2 of it, with its closest-point plane, no micro-spread.
fn sdf_tree(
    sdf: impl Fn(Vec3) -> f32,
    grad: impl Fn(Vec3) -> Vec3,
    leaf: impl Fn(Vec3, Vec3, Vec3) -> MicrosurfaceRecord,
) -> Octree<MicrosurfacePayload> {
    sdf_tree_in(GridSpec::new(DVec3::ZERO, 1.0, UVec3::splat(64)).unwrap(), sdf, grad, leaf)
}

/// [`sdf_tree`] in another placement of the same 64³ grid (the surface in grid coordinates).
fn sdf_tree_in(
    grid: GridSpec,
    sdf: impl Fn(Vec3) -> f32,
    grad: impl Fn(Vec3) -> Vec3,
    leaf: impl Fn(Vec3, Vec3, Vec3) -> MicrosurfaceRecord,
) -> Octree<MicrosurfacePayload> {
    let mut voxels = Vec::new();
    for z in 0..64u32 {
        for y in 0..64u32 {
            for x in 0..64u32 {
                let c = Vec3::new(x as f32, y as f32, z as f32) + 0.5;
                let d = sdf(c);
                if d.abs() <= 0.87 {
                    let n = grad(c).normalize();
                    let local = c - d * n - (c - 0.5);
                    let r = leaf(local, n, c - d * n);
                    voxels.push((UVec3::new(x, y, z), MicrosurfacePayload::from_record(&r)));
                }
            }
        }
    }
    Octree::build(grid, voxels, &BuildOptions { depth: None, dense_log2: 3 }).unwrap()
}

fn grey(local: Vec3, n: Vec3, _: Vec3) -> MicrosurfaceRecord {
    MicrosurfaceRecord {
        centroid: local.to_array(),
        plane_normal: n.to_array(),
        normal_moments: [n.x * n.x, n.y * n.y, n.z * n.z, n.x * n.y, n.x * n.z, n.y * n.z],
        height_variance: 0.0,
        albedo: [0.5; 3],
        albedo_slope: [0.0; 3],
        specular: 0.0,
        roughness: 0.5,
    }
}

/// The box `[32, 64) × [0, 64) × [24, 56)` (its left face x = 32, its front face z = 24).
fn box_tree() -> Octree<MicrosurfacePayload> {
    box_tree_in(GridSpec::new(DVec3::ZERO, 1.0, UVec3::splat(64)).unwrap())
}

fn box_tree_in(grid: GridSpec) -> Octree<MicrosurfacePayload> {
    let (lo, hi) = (Vec3::new(32.0, -8.0, 24.0), Vec3::new(72.0, 72.0, 56.0));
    let sdf = move |p: Vec3| {
        let q = (lo - p).max(p - hi);
        q.max(Vec3::ZERO).length() + q.max_element().min(0.0)
    };
    let grad = move |p: Vec3| {
        let e = 1e-2;
        Vec3::new(
            sdf(p + Vec3::X * e) - sdf(p - Vec3::X * e),
            sdf(p + Vec3::Y * e) - sdf(p - Vec3::Y * e),
            sdf(p + Vec3::Z * e) - sdf(p - Vec3::Z * e),
        )
    };
    sdf_tree_in(grid, sdf, grad, grey)
}

fn camera(eye: Vec3, target: Vec3, fov: f32, w: u32, h: u32) -> PinholeCamera {
    PinholeCamera { eye, target, up: Vec3::Y, fov_y_deg: fov, width: w, height: h }
}

fn albedo_only(s: &SurfaceShadeInput) -> Vec3 {
    s.illumination.albedo
}

fn opts(bias: f32, compositing: Compositing) -> DifferentialOptions {
    DifferentialOptions {
        lod_bias: bias,
        compositing,
        shadows: false,
        background: Vec3::new(0.1, 0.2, 0.3),
        ..Default::default()
    }
}

#[test]
fn a_wall_seen_face_on_is_opaque_at_every_level() {
    let tree = sdf_tree(|p| 40.0 - p.z, |_| Vec3::NEG_Z, grey);
    let cam = camera(Vec3::new(32.0, 32.0, 0.0), Vec3::new(32.0, 32.0, 40.0), 30.0, 8, 8);
    for bias in [0.0, 1.0, 8.0, 32.0] {
        let r =
            DifferentialRenderer::new(&tree, cam, LIGHT, opts(bias, Compositing::CoverageMasks))
                .unwrap();
        let img = r.render(&albedo_only);
        for p in &img.pixels {
            assert_eq!(p.w, 1.0, "bias {bias}");
            assert!((p.truncate() - Vec3::splat(0.5)).length() < 1e-5, "bias {bias}: {p}");
        }
        assert!(img.shaded >= 64 && img.elements > img.shaded, "bias {bias}");
    }
}

/// A pixel whose cone is cut in half by the box's left face (x = 32, parallel to the axis):
/// every element along the face sees half the footprint. Masks keep it at one half at every
/// footprint; alpha blending composites the halves as if uncorrelated and saturates (Fig. 4).
#[test]
fn silhouettes_keep_their_coverage_under_masks_and_thicken_under_alpha_blending() {
    let tree = box_tree();
    // 15 × 15 pixels (1.5 voxels wide at the front face); the middle column, 7, is centred on
    // the edge; the box fills the image's left half (image right is world −x). Row 7.
    let cam = camera(Vec3::new(32.0, 32.0, -40.0), Vec3::new(32.0, 32.0, 0.0), 20.0, 15, 15);
    for bias in [1.0, 4.0, 8.0] {
        let render = |c| {
            DifferentialRenderer::new(&tree, cam, LIGHT, opts(bias, c))
                .unwrap()
                .render(&albedo_only)
        };
        let (masks, blend) =
            (render(Compositing::CoverageMasks), render(Compositing::AlphaBlending));
        let centre = |img: &DifferentialImage| img.pixels[7 * 15 + 7].w;
        let (m, b) = (centre(&masks), centre(&blend));
        // Not exactly ½: at coarse levels the trilinear mix of the front and side faces' planes
        // rounds the 90° edge (the model's locally planar surface, H6).
        assert!((m - 0.5).abs() < 0.15, "bias {bias}: masks cover {m}");
        assert!(b > m + 0.2, "bias {bias}: blending {b} vs masks {m}");
        // Silhouette thickness: the row's total coverage. The box covers 7.5 columns; the
        // cones of the columns next to the edge overlap it by (bias − 1)/2 pixels when wide.
        let row = |img: &DifferentialImage| img.pixels[105..120].iter().map(|p| p.w).sum::<f32>();
        let (rm, rb) = (row(&masks), row(&blend));
        assert!((rm - 7.5).abs() < 0.2 + 0.15 * bias, "bias {bias}: masks row {rm}");
        assert!(rb > rm + 0.2, "bias {bias}: blending row {rb} vs masks {rm}");
    }
}

#[test]
fn the_level_read_follows_the_footprint() {
    let tree = sdf_tree(|p| 40.0 - p.z, |_| Vec3::NEG_Z, grey);
    for k in 0..4u32 {
        let probe = DifferentialRenderer::new(
            &tree,
            camera(Vec3::ZERO, Vec3::Z, 20.0, 63, 63),
            LIGHT,
            opts(1.0, Compositing::CoverageMasks),
        )
        .unwrap();
        // The footprint is linear in the distance: find where it spans 2^k voxels.
        let d = (1u32 << k) as f32 / probe.footprint_voxels(1.0);
        let eye = Vec3::new(32.0, 32.0, 40.0 - d);
        let cam = camera(eye, eye + Vec3::Z, 20.0, 63, 63);
        let r = DifferentialRenderer::new(&tree, cam, LIGHT, opts(1.0, Compositing::CoverageMasks))
            .unwrap();
        let seen = Mutex::new(Vec::new());
        let px = r.pixel(31, 31, &|s: &SurfaceShadeInput| {
            seen.lock().unwrap().push((s.distance_voxels, s.level, s.diameter));
            albedo_only(s)
        });
        assert_eq!(px.rgba.w, 1.0, "k = {k}");
        let seen = seen.into_inner().unwrap();
        let &(t, level, diameter) = seen.first().expect("a shaded element");
        assert!((t - d).abs() <= 1.5 * diameter.max(1.0), "k = {k}: t = {t}, d = {d}");
        assert!((level - k as f32).abs() < 0.3, "k = {k}: level {level}");
    }
}

/// An edge in focus stays sharp; out of focus it spreads over several pixels, and with masks
/// the row's total coverage is conserved (the blur moves coverage, it does not add any).
#[test]
fn depth_of_field_blurs_out_of_focus_edges_and_conserves_coverage() {
    let tree = box_tree();
    let cam = camera(Vec3::new(32.0, 32.0, -40.0), Vec3::new(32.0, 32.0, 0.0), 20.0, 15, 15);
    let row = |dof: Option<DepthOfField>| {
        let o =
            DifferentialOptions { depth_of_field: dof, ..opts(1.0, Compositing::CoverageMasks) };
        let r = DifferentialRenderer::new(&tree, cam, LIGHT, o).unwrap();
        (0..15).map(|x| r.pixel(x, 7, &albedo_only).rgba.w).collect::<Vec<f32>>()
    };
    let sharp = row(None);
    // Circle of confusion at the face (64 voxels away): 0 in focus, 2·0.5·56/8 = 7 voxels
    // (about 5 pixels) focused at 8.
    let focused = row(Some(DepthOfField { lens_radius: 0.5, focus_distance: 64.0 }));
    let blurred = row(Some(DepthOfField { lens_radius: 0.5, focus_distance: 8.0 }));
    let partial = |r: &[f32]| r.iter().filter(|&&a| a > 0.02 && a < 0.98).count();
    assert!(partial(&sharp) <= 1 && partial(&focused) <= 3, "{sharp:?} {focused:?}");
    assert!(partial(&blurred) >= 4, "{blurred:?}");
    let sum = |r: &[f32]| r.iter().sum::<f32>();
    assert!((sum(&blurred) - sum(&sharp)).abs() < 0.6, "{blurred:?} vs {sharp:?}");
    // Wider cones read coarser levels: fewer elements than the pinhole.
    let count = |dof| {
        let o =
            DifferentialOptions { depth_of_field: dof, ..opts(1.0, Compositing::CoverageMasks) };
        let r = DifferentialRenderer::new(&tree, cam, LIGHT, o).unwrap();
        (0..15).map(|x| r.pixel(x, 7, &albedo_only).elements).sum::<u32>()
    };
    let lens = Some(DepthOfField { lens_radius: 0.5, focus_distance: 8.0 });
    assert!(count(lens) < count(None), "{} vs {}", count(lens), count(None));
}

/// A surface whose colour rises with height (red up, green down) and whose normals spread:
/// seen at a grazing angle, the visible colour moves toward the tops, as Eq. 17 says.
#[test]
fn grazing_views_see_the_colour_of_the_tops() {
    let rough = |local: Vec3, n: Vec3, _: Vec3| {
        let t = 0.05; // tangential second moment per axis (slope variance ≈ 0.055)
        MicrosurfaceRecord {
            centroid: local.to_array(),
            plane_normal: (n * (1.0 - t)).to_array(),
            normal_moments: [t, 1.0 - 2.0 * t, t, 0.0, 0.0, 0.0],
            height_variance: 0.01,
            albedo: [0.5, 0.5, 0.5],
            albedo_slope: [0.3, -0.3, 0.0],
            specular: 0.0,
            roughness: 0.5,
        }
    };
    let tree = sdf_tree(|p| p.y - 20.0, |_| Vec3::Y, rough);
    // The light straight above (Λl = 0): only the view matters.
    let light = Light::Directional { to_light: Vec3::Y, irradiance: Vec3::ONE };
    let colour = |eye: Vec3| {
        let cam = camera(eye, Vec3::new(32.0, 20.0, 32.0), 0.5, 3, 3);
        let r = DifferentialRenderer::new(&tree, cam, light, opts(1.0, Compositing::CoverageMasks))
            .unwrap();
        r.pixel(1, 1, &albedo_only).rgba
    };
    let above = colour(Vec3::new(32.0, 60.0, 32.0001));
    let grazing = colour(Vec3::new(32.0, 21.5, -20.0));
    assert!(above.w == 1.0 && grazing.w == 1.0, "{above} {grazing}");
    // Eq. 17 at 1.65° above the plane: σ² ≈ 0.0556, μ = 0.0288, Λv ≈ 2.7: ā + aₛ·Λv/(Λv + 2).
    assert!((grazing.x - 0.67).abs() < 0.02, "{grazing}");
    assert!((above.x - 0.5).abs() < 0.02, "{above}");
    assert!(grazing.x > above.x + 0.1 && grazing.y < above.y - 0.1, "{grazing} vs {above}");
}

/// Tiny and huge scenes, far from the origin: the march runs in grid coordinates, so the image
/// of the same scene placed at another scale and offset is the same up to rounding (shadows,
/// a directional light and depth of field included).
#[test]
fn the_image_does_not_depend_on_the_scene_scale() {
    let render = |origin: DVec3, voxel: f64| {
        let grid = GridSpec::new(origin, voxel, UVec3::splat(64)).unwrap();
        let tree = box_tree_in(grid);
        let w = |p: Vec3| (origin + p.as_dvec3() * voxel).as_vec3();
        let cam =
            camera(w(Vec3::new(20.0, 45.0, -30.0)), w(Vec3::new(34.0, 30.0, 30.0)), 40.0, 12, 12);
        let dof =
            DepthOfField { lens_radius: 0.5 * voxel as f32, focus_distance: 50.0 * voxel as f32 };
        let o = DifferentialOptions {
            shadows: true,
            depth_of_field: Some(dof),
            ..opts(1.0, Compositing::CoverageMasks)
        };
        let light =
            Light::Directional { to_light: Vec3::new(-0.4, 1.0, -0.7), irradiance: Vec3::ONE };
        DifferentialRenderer::new(&tree, cam, light, o).unwrap().render(&albedo_only)
    };
    let unit = render(DVec3::ZERO, 1.0);
    assert!(unit.pixels.iter().any(|p| p.w == 1.0) && unit.pixels.iter().any(|p| p.w == 0.0));
    for (origin, voxel) in [(DVec3::splat(-3.0e-2), 1e-4), (DVec3::new(1e3, -2e3, 5e2), 1e4)] {
        let other = render(origin, voxel);
        let worst = unit
            .pixels
            .iter()
            .zip(&other.pixels)
            .map(|(a, b)| (*a - *b).abs().max_element())
            .fold(0.0f32, f32::max);
        // Measured: 6e-8 at 1e-4, 0 at 1e4; the same elements.
        assert!(worst < 1e-5, "voxel {voxel}: worst {worst}");
        assert_eq!(other.elements, unit.elements, "voxel {voxel}");
    }
}

#[test]
fn empty_space_bad_options_and_extreme_cameras() {
    let grid = GridSpec::new(DVec3::ZERO, 1.0, UVec3::splat(16)).unwrap();
    let empty: Octree<MicrosurfacePayload> =
        Octree::build(grid, Vec::new(), &BuildOptions::default()).unwrap();
    let cam = camera(Vec3::new(8.0, 8.0, -5.0), Vec3::new(8.0, 8.0, 0.0), 60.0, 4, 4);
    let o = opts(1.0, Compositing::CoverageMasks);
    let img = DifferentialRenderer::new(&empty, cam, LIGHT, o).unwrap().render(&albedo_only);
    assert!(img.pixels.iter().all(|&p| p == o.background.extend(0.0)));
    assert_eq!(img.shaded, 0);
    let err = |o: DifferentialOptions| {
        DifferentialRenderer::new(&empty, cam, LIGHT, o).unwrap_err().to_string()
    };
    assert!(err(DifferentialOptions { lod_bias: -1.0, ..o }).contains("lod_bias"));
    assert!(err(DifferentialOptions { element_factor: 0.0, ..o }).contains("element_factor"));
    assert!(err(DifferentialOptions { max_distance: 0.0, ..o }).contains("max_distance"));
    let dof = |r, f| Some(DepthOfField { lens_radius: r, focus_distance: f });
    assert!(err(DifferentialOptions { depth_of_field: dof(-1.0, 5.0), ..o }).contains("lens"));
    assert!(err(DifferentialOptions { depth_of_field: dof(1.0, 0.0), ..o }).contains("focus"));
    assert!(err(DifferentialOptions { background: Vec3::NAN, ..o }).contains("background"));
    // Extremes stay finite: tiny and near-180° fields of view, a camera inside the box, a huge
    // lens, with shadows on.
    let tree = box_tree();
    let shadows = DifferentialOptions { shadows: true, ..o };
    for (cam, o) in [
        (camera(Vec3::new(32.0, 32.0, -10.0), Vec3::new(33.0, 32.0, 0.0), 1e-3, 4, 4), shadows),
        (camera(Vec3::new(32.0, 32.0, -10.0), Vec3::new(33.0, 32.0, 0.0), 179.9, 4, 4), shadows),
        (camera(Vec3::new(40.0, 32.0, 40.0), Vec3::new(41.0, 32.0, 40.0), 60.0, 4, 4), shadows),
        (
            camera(Vec3::new(32.0, 32.0, -1e5), Vec3::new(32.0, 32.0, 0.0), 1.0, 4, 4),
            DifferentialOptions { depth_of_field: dof(1e4, 1.0), ..shadows },
        ),
    ] {
        let img = DifferentialRenderer::new(&tree, cam, LIGHT, o).unwrap().render(&albedo_only);
        for p in &img.pixels {
            assert!(p.is_finite() && (0.0..=1.0).contains(&p.w), "{cam:?}: {p}");
        }
    }
}
