//! Tests of the `dynamic` module.

use std::mem::offset_of;

use super::*;
use crate::cone::GpuConeParams;
use crate::layout::assert_mirrors;

#[test]
fn dynamic_types_mirror_their_wgsl() {
    for (_, src) in KERNELS {
        assert_mirrors(
            src,
            "Params",
            size_of::<GpuDynamicParams>(),
            &[
                ("n", offset_of!(GpuDynamicParams, n)),
                ("filter_mode", offset_of!(GpuDynamicParams, filter_mode)),
                ("brick_log2", offset_of!(GpuDynamicParams, brick_log2)),
                ("extra", offset_of!(GpuDynamicParams, extra)),
                ("dims", offset_of!(GpuDynamicParams, dims)),
                ("min_weight", offset_of!(GpuDynamicParams, min_weight)),
            ],
        );
        assert_mirrors(
            src,
            "Placed",
            size_of::<Placed>(),
            &[
                ("cell", offset_of!(Placed, cell)),
                ("frac", offset_of!(Placed, frac)),
                ("normal", offset_of!(Placed, normal)),
                ("status", offset_of!(Placed, status)),
            ],
        );
    }
    let (_, t) = KERNELS[TRANSFORM];
    assert_mirrors(
        t,
        "Object",
        size_of::<GpuObject>(),
        &[
            ("anchor", offset_of!(GpuObject, anchor)),
            ("first_matrix", offset_of!(GpuObject, first_matrix)),
            ("skinned", offset_of!(GpuObject, skinned)),
            ("outside", offset_of!(GpuObject, outside)),
            ("pad", offset_of!(GpuObject, pad)),
        ],
    );
    assert_mirrors(t, "Affine", size_of::<voxlod_octree::dynamic::Affine>(), &[("m", 0)]);
    let inject = inject_source();
    assert!(
        inject.contains("fn march(") && !inject.contains("fn main(@builtin(global_invocation_id)")
    );
    assert_mirrors(
        &inject,
        "InjectParams",
        size_of::<GpuInjectParams>(),
        &[
            ("light_a", offset_of!(GpuInjectParams, light_a)),
            ("light_b", offset_of!(GpuInjectParams, light_b)),
            ("shadow", offset_of!(GpuInjectParams, shadow)),
            ("counts", offset_of!(GpuInjectParams, counts)),
        ],
    );
    type C = GpuConeParams;
    assert_mirrors(
        &inject,
        "Params",
        size_of::<C>(),
        &[
            ("grid", offset_of!(C, grid)),
            ("size", offset_of!(C, size)),
            ("tree", offset_of!(C, tree)),
            ("march", offset_of!(C, march)),
            ("limits", offset_of!(C, limits)),
            ("extra", offset_of!(C, extra)),
        ],
    );
}
