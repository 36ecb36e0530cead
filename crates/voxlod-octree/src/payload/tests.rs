//! The pre-filtering rules of the module docs, one test each.

use glam::{Mat3, Vec3};
use voxlod_format::records::{AverageRecord, SggxRecord};

use super::*;

fn avg(color: Vec3, normal: Vec3, opacity: f32) -> AveragePayload {
    AveragePayload::new(color, normal, opacity)
}

#[test]
fn averages_weight_colour_and_normal_by_opacity() {
    let mut c = [AveragePayload::empty(); 8];
    c[0] = avg(Vec3::new(1.0, 0.0, 0.0), Vec3::X, 0.75);
    c[5] = avg(Vec3::new(0.0, 0.0, 1.0), Vec3::Y, 0.25);
    let p = AveragePayload::prefilter(&c);
    assert!((p.opacity - 0.125).abs() < 1e-7, "mean coverage: {}", p.opacity);
    assert!((p.color() - Vec3::new(0.75, 0.0, 0.25)).length() < 1e-6, "{}", p.color());
    assert!((p.normal() - Vec3::new(3.0, 1.0, 0.0).normalize()).length() < 1e-6);
    assert_eq!(AveragePayload::prefilter(&[AveragePayload::empty(); 8]), AveragePayload::empty());
    assert_eq!(AveragePayload::empty().color(), Vec3::ZERO);
}

#[test]
fn averages_decode_records() {
    let r = AverageRecord::new(Vec3::new(0.2, 0.4, 0.6), Vec3::Z, 0.5);
    let p = AveragePayload::from_record(&r);
    assert!((p.color() - r.color()).length() < 1e-6 && (p.normal() - Vec3::Z).length() < 1e-6);
    assert_eq!(p.opacity, r.opacity());
}

#[test]
fn sggx_matrices_average_linearly_weighted_by_opacity() {
    let (a, b) = (
        Mat3::from_diagonal(Vec3::new(1.0, 0.1, 0.1)),
        Mat3::from_diagonal(Vec3::new(0.1, 0.1, 1.0)),
    );
    let off = Mat3::from_cols(
        Vec3::new(0.5, 0.2, 0.0),
        Vec3::new(0.2, 0.5, 0.0),
        Vec3::new(0.0, 0.0, 0.5),
    );
    let mut c = [SggxPayload::empty(); 8];
    c[1] = SggxPayload::new(a, Vec3::ONE, 1.0);
    c[2] = SggxPayload::new(b, Vec3::ZERO, 0.5);
    c[7] = SggxPayload::new(off, Vec3::ONE, 0.5);
    let p = SggxPayload::prefilter(&c);
    let want = (a * 1.0 + b * 0.5 + off * 0.5) * 0.5;
    assert!((p.matrix() - want).abs_diff_eq(Mat3::ZERO, 1e-6), "{} vs {want}", p.matrix());
    assert!((p.color() - Vec3::splat(0.75)).length() < 1e-6);
    assert!((p.opacity - 0.25).abs() < 1e-7);
    let r = SggxRecord::new(a, Vec3::splat(0.5), 2.0, 1.0);
    let q = SggxPayload::from_record(&r);
    assert!((q.opacity - (1.0 - (-r.sigma_t()).exp())).abs() < 1e-6);
    assert!((q.matrix() - r.matrix()).abs_diff_eq(Mat3::ZERO, 1e-6));
}

/// A wall: the lower-x half of a node opaque, the upper half empty. Crossing the node along ±x
/// always meets the wall (opacity 1); its coverage is 1/2; along y and z half the columns are
/// opaque.
#[test]
fn directional_opacity_composites_columns_front_to_back() {
    let wall = Directional::isotropic(avg(Vec3::ONE, Vec3::X, 1.0));
    let empty = Directional::<AveragePayload>::empty();
    let c: [_; 8] = std::array::from_fn(|k| if k & 1 == 0 { wall } else { empty });
    let p = Directional::prefilter(&c);
    assert_eq!(p.opacity, [1.0, 1.0, 0.5, 0.5, 0.5, 0.5]);
    assert_eq!(p.inner.opacity, 0.5);
    assert!((p.opacity_along(Vec3::X) - 1.0).abs() < 1e-7);
    assert!((p.opacity_along(Vec3::new(1.0, 1.0, 0.0).normalize()) - 0.75).abs() < 1e-6);
    // Two half-opaque layers along z: 1 − (1 − ½)² = ¾ along ±z, ½ coverage elsewhere.
    let half = Directional::isotropic(avg(Vec3::ONE, Vec3::Z, 0.5));
    let p = Directional::prefilter(&[half; 8]);
    assert_eq!(p.opacity, [0.75; 6]);
    // Front and back differ: front 1 and back ½ give 1 along +z; along −z ½ + ½·1 = 1 too, but
    // front ½ over an empty back gives ½ from either side.
    let c: [_; 8] = std::array::from_fn(|k| if k & 4 == 0 { half } else { empty });
    assert_eq!(Directional::prefilter(&c).opacity[4..], [0.5, 0.5]);
}

#[test]
fn directional_leaves_reject_bad_opacities() {
    let mut d = Directional::isotropic(avg(Vec3::ONE, Vec3::X, 0.5));
    assert_eq!(d.check(), None);
    d.opacity[3] = 1.5;
    assert!(d.check().unwrap().contains("directional"));
    d.opacity[3] = f32::NAN;
    assert!(d.check().unwrap().contains("NaN"));
}
