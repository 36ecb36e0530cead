// Exclusive prefix sum, pass 1: each workgroup of 256 invocations scans a block of 512
// values in place (two per invocation, a Hillis–Steele scan of the pair sums in workgroup
// memory) and writes the block's total to `sums[block]`.

@group(0) @binding(0) var<storage, read> params: Params;
@group(0) @binding(3) var<storage, read_write> data: array<u32>;
@group(0) @binding(4) var<storage, read_write> sums: array<u32>;

const SCAN_WG: u32 = 256u;
const BLOCK: u32 = 512u;

var<workgroup> shared_sums: array<u32, 256>;

@compute @workgroup_size(256)
fn main(
    @builtin(workgroup_id) wg: vec3<u32>,
    @builtin(num_workgroups) nwg: vec3<u32>,
    @builtin(local_invocation_index) li: u32,
) {
    let block = wg.y * nwg.x + wg.x;
    let blocks = (params.n + BLOCK - 1u) / BLOCK;
    // Workgroup-uniform: the whole workgroup leaves together, the barriers below stay uniform.
    if block >= blocks {
        return;
    }
    let base = block * BLOCK + 2u * li;
    var a = 0u;
    var b = 0u;
    if base < params.n {
        a = data[base];
    }
    if base + 1u < params.n {
        b = data[base + 1u];
    }
    shared_sums[li] = a + b;
    workgroupBarrier();
    for (var off = 1u; off < SCAN_WG; off = off * 2u) {
        var v = shared_sums[li];
        if li >= off {
            v = v + shared_sums[li - off];
        }
        workgroupBarrier();
        shared_sums[li] = v;
        workgroupBarrier();
    }
    let inclusive = shared_sums[li];
    let exclusive = inclusive - a - b;
    if base < params.n {
        data[base] = exclusive;
    }
    if base + 1u < params.n {
        data[base + 1u] = exclusive + a;
    }
    if li == SCAN_WG - 1u {
        sums[block] = inclusive;
    }
}
