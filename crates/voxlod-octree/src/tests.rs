//! Octree tests: sampling against a dense-grid oracle (proptest), every invariant of
//! `validate` broken on purpose, and the extremes (empty, one voxel, max corner, depth 16,
//! bad input).

mod extremes;
mod fast_build;
mod fast_sample;
mod invariants;
mod oracle;

use glam::{DVec3, UVec3, Vec3};
use voxlod_format::GridSpec;

use crate::{AveragePayload, BuildOptions, Octree};

pub(crate) fn grid(dims: UVec3) -> GridSpec {
    GridSpec::new(DVec3::ZERO, 1.0, dims).expect("a valid grid")
}

/// A deterministic payload for voxel `c` (distinct colours, normals and opacities).
pub(crate) fn payload_of(c: UVec3) -> AveragePayload {
    let h = |k: u32| {
        let x = (c.x.wrapping_mul(73_856_093) ^ c.y.wrapping_mul(19_349_663))
            ^ c.z.wrapping_mul(83_492_791)
            ^ k.wrapping_mul(2_654_435_761);
        (x % 1000) as f32 / 999.0
    };
    let n = Vec3::new(h(1) - 0.5, h(2) - 0.5, h(3) + 0.1);
    AveragePayload::new(Vec3::new(h(4), h(5), h(6)), n, 0.05 + 0.95 * h(7))
}

fn build(dims: UVec3, coords: &[UVec3], dense_log2: u32) -> Octree<AveragePayload> {
    let voxels = coords.iter().map(|&c| (c, payload_of(c)));
    Octree::build(grid(dims), voxels, &BuildOptions { depth: None, dense_log2 }).expect("built")
}

/// Asserts two payloads agree within `eps`, printing both and the difference.
#[track_caller]
fn assert_close(a: &AveragePayload, b: &AveragePayload, eps: f32, what: &str) {
    use crate::Payload;
    let d = a.max_abs_diff(b);
    assert!(d <= eps, "{what}: differ by {d} > {eps}\n  {a:?}\n  {b:?}");
}
