//! From an object's matrices for one frame to the `f32` maps the transform applies
//! ([`place`]; rules in the [module docs](super)).

use glam::{DMat4, DVec3, UVec3};
use voxlod_format::GridSpec;

use super::cache::VoxelCache;
use crate::{Error, Result};

/// Where an object is in one frame: its object-to-world matrices.
#[derive(Clone, Debug, PartialEq)]
pub enum Placement {
    /// A rigid object's matrix.
    Rigid(DMat4),
    /// A skinned object's joint matrices, one per joint of its skin: bind space to world (the
    /// joint's world matrix times its inverse bind matrix).
    Skinned(Vec<DMat4>),
}

/// An affine map in `f32`: columns x, y, z and the translation, 3 floats each (the WGSL mirror
/// is `array<f32, 12>`). 48 bytes.
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
pub struct Affine {
    /// `m[0..3]` x column, `m[3..6]` y column, `m[6..9]` z column, `m[9..12]` translation.
    pub m: [f32; 12],
}

/// An object's frame as the transform reads it: the integer anchor and one map per matrix from
/// a cached voxel's integer position to world-grid coordinates relative to the anchor.
#[derive(Clone, Debug, PartialEq)]
pub struct ObjectFrame {
    /// World-grid cell of the object's reference point.
    pub anchor: [i32; 3],
    /// One map per matrix of the [`Placement`] (one for a rigid object, one per joint).
    pub matrices: Vec<Affine>,
    /// The anchor is beyond ±2³⁰ voxels: every voxel is outside the grid (the maps are zero).
    pub outside: bool,
}

/// Largest anchor coordinate (voxels) for which the object is transformed at all.
pub const MAX_ANCHOR: f64 = (1u64 << 30) as f64;

/// Checks `placement` against `cache` and the world grid and composes the frame's maps (module
/// docs): the cache's voxel must be the world's (relative `tolerance`), every matrix finite,
/// affine and rigid at the cache's scale within `tolerance`, and a skinned cache needs one
/// matrix per joint.
pub fn place(
    cache: &VoxelCache,
    placement: &Placement,
    world: &GridSpec,
    tolerance: f64,
) -> Result<ObjectFrame> {
    world.validate()?;
    if !(tolerance.is_finite() && tolerance >= 0.0) {
        return Err(Error::InvalidParameter {
            name: "rigidity_tolerance",
            value: tolerance.to_string(),
            reason: "finite and >= 0",
        });
    }
    let object = || cache.name.clone();
    let bad = |reason: String| Error::InvalidPlacement { object: object(), reason };
    let cache_voxel = cache.grid.voxel_size * cache.scale;
    if (cache_voxel - world.voxel_size).abs() > tolerance.max(1e-9) * world.voxel_size {
        return Err(Error::CacheResolution {
            object: object(),
            cache_voxel,
            world_voxel: world.voxel_size,
        });
    }
    let matrices: &[DMat4] = match (placement, &cache.skin) {
        (Placement::Rigid(m), None) => std::slice::from_ref(m),
        (Placement::Skinned(m), Some(s)) if m.len() == s.joint_count as usize => m,
        (Placement::Skinned(m), Some(s)) => {
            return Err(bad(format!(
                "{} joint matrices for a skin of {} joints",
                m.len(),
                s.joint_count
            )));
        }
        (Placement::Rigid(_), Some(_)) => {
            return Err(bad("a skinned cache needs joint matrices, not one rigid matrix".into()));
        }
        (Placement::Skinned(_), None) => {
            return Err(bad("a rigid cache needs one matrix, not joint matrices".into()));
        }
    };
    for (k, m) in matrices.iter().enumerate() {
        if !m.is_finite() {
            return Err(bad(format!("matrix {k} has a NaN or infinite entry")));
        }
        if m.row(3) != glam::DVec4::new(0.0, 0.0, 0.0, 1.0) {
            return Err(bad(format!("matrix {k} is projective (last row {})", m.row(3))));
        }
        check_rigid(cache, k, m, tolerance)?;
    }
    // Index → grid units: r(i) = L·i + t with L = M_lin·Δo/Δw and
    // t = (M·(origin + ½Δo) − origin_w)/Δw.
    let (dxo, dxw) = (cache.grid.voxel_size, world.voxel_size);
    let first_centre = cache.grid.origin + DVec3::splat(0.5 * dxo);
    let maps: Vec<(DMat4, DVec3)> = matrices
        .iter()
        .map(|m| {
            let lin = DMat4::from_cols(m.x_axis, m.y_axis, m.z_axis, glam::DVec4::W);
            let l = lin * (dxo / dxw);
            let t = (m.transform_point3(first_centre) - world.origin) / dxw;
            (l, t)
        })
        .collect();
    // The reference map: the rigid matrix, or the joint most voxels depend on most.
    let reference = match &cache.skin {
        None => 0,
        Some(s) => {
            let mut count = vec![0u64; matrices.len()];
            for v in &s.voxels {
                count[v.joints[0] as usize] += 1;
            }
            (0..count.len()).max_by_key(|&k| (count[k], std::cmp::Reverse(k))).unwrap_or(0)
        }
    };
    let centre = (cache.grid.dims.min(UVec3::splat(super::MAX_CACHE_DIM)).as_dvec3()) * 0.5;
    let (l, t) = &maps[reference];
    let anchor = (l.transform_vector3(centre) + *t).floor();
    if anchor.abs().max_element() > MAX_ANCHOR {
        return Ok(ObjectFrame {
            anchor: [0; 3],
            matrices: vec![Affine::default(); maps.len()],
            outside: true,
        });
    }
    let matrices = maps
        .iter()
        .map(|(l, t)| {
            let t = *t - anchor;
            let c = |v: DVec3| [v.x as f32, v.y as f32, v.z as f32];
            let [a, b, d, e] =
                [c(l.x_axis.truncate()), c(l.y_axis.truncate()), c(l.z_axis.truncate()), c(t)];
            Affine { m: [a[0], a[1], a[2], b[0], b[1], b[2], d[0], d[1], d[2], e[0], e[1], e[2]] }
        })
        .collect();
    Ok(ObjectFrame {
        anchor: [anchor.x as i32, anchor.y as i32, anchor.z as i32],
        matrices,
        outside: false,
    })
}

/// [`Error::NotRigid`] unless `m`'s linear columns have length `cache.scale` and are pairwise
/// orthogonal, within relative `tolerance`.
fn check_rigid(cache: &VoxelCache, k: usize, m: &DMat4, tolerance: f64) -> Result<()> {
    let cols = [m.x_axis.truncate(), m.y_axis.truncate(), m.z_axis.truncate()];
    let scales = cols.map(|c| c.length());
    let mut shear = 0.0f64;
    for (i, j) in [(0, 1), (0, 2), (1, 2)] {
        let d = scales[i] * scales[j];
        let cos = if d > 0.0 { cols[i].dot(cols[j]).abs() / d } else { 1.0 };
        shear = shear.max(cos);
    }
    let scale_ok = scales.iter().all(|s| (s / cache.scale - 1.0).abs() <= tolerance);
    if scale_ok && shear <= tolerance {
        return Ok(());
    }
    Err(Error::NotRigid {
        object: cache.name.clone(),
        matrix: k,
        scales,
        shear,
        expected_scale: cache.scale,
        tolerance,
    })
}
