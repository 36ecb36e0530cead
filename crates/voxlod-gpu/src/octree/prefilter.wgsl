// Averages pre-filter of `level`: one invocation per node takes its eight children (its child
// tile, or on a dense level above the finest dense one the 8 Morton-consecutive nodes below)
// and writes their mean, summed in octant order from zero and then scaled by 1/8: the CPU's
// operations in the CPU's order. A node without children keeps the zeroed (empty) payload.

@group(0) @binding(0) var<storage, read> params: Params;
@group(0) @binding(1) var<storage, read> levels: array<GpuLevel>;
@group(0) @binding(2) var<storage, read> nodes: array<GpuNode>;
@group(0) @binding(3) var<storage, read_write> payload: array<Average>;

@compute @workgroup_size(64)
fn main(
    @builtin(workgroup_id) wg: vec3<u32>,
    @builtin(num_workgroups) nwg: vec3<u32>,
    @builtin(local_invocation_index) li: u32,
) {
    let i = flat_index(wg, nwg, li);
    let l = params.level;
    let lv = levels[l];
    if i >= lv.count {
        return;
    }
    var first = NONE;
    if l > params.first_dense {
        first = levels[l - 1u].first + 8u * i;
    } else {
        first = nodes[lv.first + i].child;
    }
    if first == NONE {
        return;
    }
    var ca = vec3<f32>(0.0);
    var na = vec3<f32>(0.0);
    var op = 0.0;
    for (var k = 0u; k < 8u; k = k + 1u) {
        let c = payload[first + k];
        ca = ca + vec3<f32>(c.color_alpha[0], c.color_alpha[1], c.color_alpha[2]);
        na = na + vec3<f32>(c.normal_alpha[0], c.normal_alpha[1], c.normal_alpha[2]);
        op = op + c.opacity;
    }
    ca = ca * 0.125;
    na = na * 0.125;
    payload[lv.first + i] = Average(
        array<f32, 3>(ca.x, ca.y, ca.z),
        array<f32, 3>(na.x, na.y, na.z),
        op * 0.125,
    );
}
