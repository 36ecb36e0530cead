//! Checking that the `#[repr(C)]` Rust types the host uploads match their WGSL mirrors: the
//! WGSL is parsed with naga (wgpu's own front end, re-exported as `wgpu::naga`) and each
//! struct's size and member offsets are compared with the Rust type's.

use wgpu::naga;

/// Size and `(member name, offset)` list of struct `name` in WGSL `source`, as naga lays it out
/// (the layout the GPU will use); `None` if there is no such struct.
///
/// Panics if `source` does not parse (the kernels' sources are constants of this crate).
pub fn wgsl_struct(source: &str, name: &str) -> Option<(u32, Vec<(String, u32)>)> {
    let module = naga::front::wgsl::parse_str(source)
        .unwrap_or_else(|e| panic!("WGSL does not parse: {}", e.emit_to_string(source)));
    module.types.iter().find_map(|(_, ty)| match (&ty.name, &ty.inner) {
        (Some(n), naga::TypeInner::Struct { members, span }) if n == name => Some((
            *span,
            members.iter().map(|m| (m.name.clone().unwrap_or_default(), m.offset)).collect(),
        )),
        _ => None,
    })
}

/// Asserts that WGSL struct `name` has size `size` and exactly the members `offsets` (name,
/// byte offset) in order: the Rust side passes `size_of::<T>()` and `offset_of!` values.
pub fn assert_mirrors(source: &str, name: &str, size: usize, offsets: &[(&str, usize)]) {
    let (span, members) =
        wgsl_struct(source, name).unwrap_or_else(|| panic!("no WGSL struct {name}"));
    assert_eq!(span as usize, size, "size of WGSL struct {name} vs its Rust mirror");
    let members: Vec<(&str, usize)> =
        members.iter().map(|(n, o)| (n.as_str(), *o as usize)).collect();
    assert_eq!(members, offsets, "members and offsets of WGSL struct {name} vs its Rust mirror");
}

/// Asserts that voxlod-octree's flat-layout types match their WGSL mirrors in `source`, named
/// `[level, node, tile]` there (`GpuLevel`, `GpuNode`, `GpuTile` in Rust): the octree-build
/// kernels and the cone kernel read the same arrays.
#[cfg(test)]
pub(crate) fn assert_flat_octree_mirrors(source: &str, [level, node, tile]: [&str; 3]) {
    use std::mem::offset_of;

    use voxlod_octree::{GpuLevel, GpuNode, GpuTile};
    assert_mirrors(
        source,
        level,
        size_of::<GpuLevel>(),
        &[
            ("first", offset_of!(GpuLevel, first)),
            ("count", offset_of!(GpuLevel, count)),
            ("res_log2", offset_of!(GpuLevel, res_log2)),
            ("dense", offset_of!(GpuLevel, dense)),
            ("first_tile", offset_of!(GpuLevel, first_tile)),
        ],
    );
    assert_mirrors(
        source,
        node,
        size_of::<GpuNode>(),
        &[("child", offset_of!(GpuNode, child)), ("mask", offset_of!(GpuNode, mask))],
    );
    assert_mirrors(source, tile, size_of::<GpuTile>(), &[("links", offset_of!(GpuTile, links))]);
}

#[cfg(test)]
mod tests {
    use std::mem::offset_of;

    use super::*;
    use crate::voxelize::{GpuTriangle, GpuVoxelizeParams};

    #[test]
    fn voxelize_types_mirror_their_wgsl() {
        let src = crate::voxelize::WGSL;
        assert_mirrors(
            src,
            "Tri",
            size_of::<GpuTriangle>(),
            &[
                ("a", offset_of!(GpuTriangle, a)),
                ("b", offset_of!(GpuTriangle, b)),
                ("c", offset_of!(GpuTriangle, c)),
                ("lo", offset_of!(GpuTriangle, lo)),
                ("hi", offset_of!(GpuTriangle, hi)),
                ("plane", offset_of!(GpuTriangle, plane)),
            ],
        );
        assert_mirrors(
            src,
            "Params",
            size_of::<GpuVoxelizeParams>(),
            &[
                ("dims", offset_of!(GpuVoxelizeParams, dims)),
                ("batch", offset_of!(GpuVoxelizeParams, batch)),
            ],
        );
    }

    #[test]
    fn a_mismatch_is_caught() {
        let src = "struct S { a: vec3<f32>, b: f32, c: vec4<u32> }";
        assert_eq!(
            wgsl_struct(src, "S").unwrap(),
            (32, vec![("a".into(), 0), ("b".into(), 12), ("c".into(), 16)])
        );
        let wrong = std::panic::catch_unwind(|| assert_mirrors(src, "S", 32, &[("a", 0)]));
        assert!(wrong.is_err());
    }
}
