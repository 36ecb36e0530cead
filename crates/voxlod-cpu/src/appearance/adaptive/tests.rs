use super::heldout::nearest_bin;
use super::*;
use crate::appearance::voxel_samples::{RaySample, SurfaceSample};
use bytemuck::Zeroable;
use voxlod_format::brickmap::BrickHeader;

#[test]
fn the_cheapest_kind_under_the_threshold_wins_else_the_least_error() {
    assert_eq!(Candidates::choose([0.05, 0.01, 0.0], 0.1), Kind::Average);
    assert_eq!(Candidates::choose([0.2, 0.05, 0.0], 0.1), Kind::Sggx);
    assert_eq!(Candidates::choose([0.2, 0.15, 0.1], 0.1), Kind::VirtualMesh);
    assert_eq!(Candidates::choose([0.3, 0.2, 0.25], 0.1), Kind::Sggx);
    // Ties without any kind under the threshold go to the cheaper kind.
    assert_eq!(Candidates::choose([0.3, 0.3, 0.3], 0.1), Kind::Average);
}

/// Held-out lines in every bin not parallel to the plane z = ½, all hitting its white
/// two-sided surface (normal ±z toward the line).
fn opaque_plane(count: usize) -> VoxelSamples {
    let bins: Vec<Vec3> = BINS.iter().copied().filter(|b| b.z != 0.0).collect();
    let rays = (0..count)
        .map(|i| {
            let dir = bins[i % bins.len()];
            let normal = if dir.z < 0.0 { Vec3::Z } else { -Vec3::Z };
            RaySample {
                dir,
                entry: Vec3::splat(0.5),
                chord: 1.0,
                occluded: true,
                surface: Some(SurfaceSample {
                    point: Vec3::splat(0.5),
                    normal,
                    albedo: Vec3::ONE,
                    specular: 0.0,
                    shininess: 1.0,
                }),
            }
        })
        .collect();
    VoxelSamples { rays }
}

#[test]
fn a_matching_record_scores_lower_than_a_wrong_one() {
    let held = opaque_plane(10 * 8);
    let good = AverageRecord::new(Vec3::ONE, Vec3::Z, 1.0);
    let transparent = AverageRecord::new(Vec3::ONE, Vec3::Z, 0.0);
    let dark = AverageRecord::new(Vec3::splat(0.2), Vec3::Z, 1.0);
    let e_good = directional_error(&good, (), None, &held);
    let e_transparent = directional_error(&transparent, (), None, &held);
    let e_dark = directional_error(&dark, (), None, &held);
    // The opacity term vanishes for the opaque record; the Averages normal is flipped
    // toward each viewer like the samples', so shading matches up to quantization.
    assert!(e_good < 0.02, "{e_good}");
    assert!((e_transparent - e_good - 1.0).abs() < 0.02, "{e_transparent} vs {e_good}");
    assert!(e_dark > e_good + 0.1, "{e_dark} vs {e_good}");
    for e in [e_good, e_transparent, e_dark] {
        assert!(e.is_finite() && e >= 0.0);
    }
}

#[test]
fn every_held_out_line_falls_in_its_nearest_bin() {
    for (i, b) in BINS.iter().enumerate() {
        assert_eq!(nearest_bin(*b), i);
        assert_eq!(nearest_bin(*b * 3.0 + Vec3::splat(1e-3)), i);
    }
    for l in LIGHTS {
        assert!((l.length() - 1.0).abs() < 1e-6);
    }
}

/// Candidates for voxels at `coords` (any order) with distinct records, without errors.
fn hand_candidates(dims: UVec3, coords: &[UVec3], specular: bool) -> Candidates {
    let mut codes: Vec<u64> = coords.iter().map(|&c| morton::encode(c)).collect();
    codes.sort_unstable();
    let voxels = codes
        .iter()
        .enumerate()
        .map(|(i, &code)| Candidate {
            code,
            average: AverageRecord::new(Vec3::splat(i as f32 / 16.0), Vec3::Z, 0.5),
            sggx: SggxRecord::zeroed(),
            vmesh: VirtualMeshRecord::zeroed(),
            specular: specular.then(|| SpecularRecord::new(0.5, 16.0)),
            errors: [0.0; 3],
            image_errors: [0.0; 3],
        })
        .collect();
    let grid = GridSpec::new(glam::DVec3::ZERO, 1.0, dims).unwrap();
    Candidates {
        grid,
        rule: VirtualMeshParams::default(),
        selector: Selector::HeldOut,
        voxels,
        specular,
    }
}

#[test]
fn bytes_are_the_packed_records_plus_the_index_exactly() {
    // 10 voxels in 2 bricks, with a specular side record each.
    let coords: Vec<UVec3> = (0..8)
        .map(|i| UVec3::new(i % 2, i / 2, 0))
        .chain([UVec3::splat(9), UVec3::splat(15)])
        .collect();
    let c = hand_candidates(UVec3::splat(16), &coords, true);
    let kinds = [
        Kind::Average,
        Kind::VirtualMesh,
        Kind::Sggx,
        Kind::Average,
        Kind::Average,
        Kind::VirtualMesh,
        Kind::Sggx,
        Kind::Average,
        Kind::Average,
        Kind::Sggx,
    ];
    let g = c.select_kinds(&kinds).unwrap();
    assert_eq!(g.refs().bricks().len(), 2);
    let index = 2 * (size_of::<BrickHeader>() + 12) + 10 * size_of::<AdaptiveRef>();
    let records = 5 * size_of::<AverageRecord>()
        + 3 * size_of::<SggxRecord>()
        + 2 * size_of::<VirtualMeshRecord>()
        + 10 * size_of::<SpecularRecord>();
    assert_eq!((size_of::<BrickHeader>(), index, records), (80, 224, 40 + 36 + 272 + 20));
    assert_eq!(g.memory_bytes(), index + records);
    // Bytes per voxel = the record bytes per voxel + the bricks' share, exactly.
    let per_voxel = g.memory_bytes() as f64 / 10.0;
    assert!((per_voxel - (g.record_bytes() + 2.0 * 92.0 / 10.0)).abs() < 1e-9, "{per_voxel}");
    // No growth slack behind the packed size.
    assert_eq!(g.averages.capacity(), 5);
    assert_eq!(g.sggx.capacity(), 3);
    assert_eq!(g.vmesh.capacity(), 2);
    assert_eq!(g.specular.as_ref().unwrap().capacity(), 10);
    // The records land where the tags say.
    for (i, &k) in kinds.iter().enumerate() {
        assert_eq!(g.tag(i).kind(), k);
    }
    assert_eq!(g.average_records()[1], c.voxels[3].average);
    assert!(c.select_kinds(&kinds[..9]).is_err());
}

#[test]
fn selectors_parse_by_name_and_the_default_is_held_out() {
    assert_eq!(AdaptiveOptions::default().selector, Selector::HeldOut);
    for s in [Selector::HeldOut, Selector::Image] {
        assert_eq!(s.name().parse::<Selector>().unwrap(), s);
    }
    assert!("images".parse::<Selector>().is_err());
}
