// Slicemap queries: occupied slices in front of points (transmittance shadow maps) and inner
// voxels per column from front and back layers (traversed volume). Mirrors
// voxlod_cpu::voxelize::slicemap::query: shifts, countOneBits and firstTrailingBit on the
// column's words, integer results.

struct QueryParams {
    width: u32,
    height: u32,
    slices: u32,
    words: u32,
    // bit 0: local slicing (ranges bound), bit 1: the far end of local columns is known
    mode: u32,
    count: u32,
    span: f32,
    pad: u32,
}

// A located point: its column (y·width + x, or 0xffffffff outside the map) and depth d.
struct Query {
    column: u32,
    d: f32,
}

@group(0) @binding(0) var<storage, read> params: QueryParams;
@group(0) @binding(1) var<storage, read> bits: array<u32>;
@group(0) @binding(2) var<storage, read> ranges: array<vec2<f32>>;
@group(0) @binding(3) var<storage, read> queries: array<Query>;
@group(0) @binding(4) var<storage, read_write> out: array<u32>;

fn flat_index(gid: vec3<u32>, nwg: vec3<u32>) -> u32 {
    return gid.x + gid.y * nwg.x * 64u;
}

fn normalized(d: f32, lo: f32, hi: f32) -> f32 {
    let r = hi - lo;
    if r > 0.0 {
        return clamp((d - lo) / r, 0.0, 1.0);
    }
    return 0.0;
}

fn slice_of(z: f32) -> u32 {
    return min(u32(z * f32(params.slices)), params.slices - 1u);
}

@compute @workgroup_size(64)
fn occluders(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let i = flat_index(gid, nwg);
    if i >= params.count {
        return;
    }
    let q = queries[i];
    if q.column == 0xffffffffu {
        out[i] = 0xffffffffu;
        return;
    }
    var lo = 0.0;
    var hi = params.span;
    if (params.mode & 1u) != 0u {
        let r = ranges[q.column];
        lo = r.x;
        hi = r.y;
        if !(lo <= hi) {
            out[i] = 0u;
            return;
        }
    }
    let base = q.column * params.words;
    if !(q.d >= lo) {
        out[i] = 0u;
        return;
    }
    var n = 0u;
    if q.d > hi {
        for (var w = 0u; w < params.words; w++) {
            n += countOneBits(bits[base + w]);
        }
        out[i] = n;
        return;
    }
    let s = slice_of(normalized(q.d, lo, hi));
    for (var w = 0u; w < params.words; w++) {
        let b = w * 32u;
        if b + 32u <= s {
            n += countOneBits(bits[base + w]);
        } else if b < s {
            n += countOneBits(bits[base + w] & ((1u << (s - b)) - 1u));
        }
    }
    out[i] = n;
}

@compute @workgroup_size(64)
fn inner_voxels(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let c = flat_index(gid, nwg);
    let columns = params.width * params.height;
    if c >= columns {
        return;
    }
    let far_end = (params.mode & 2u) != 0u;
    let front = c * params.words;
    let back = (columns + c) * params.words;
    // 0 outside, 1 inside, 2 unresolved (after an ambiguous voxel)
    var state = 0u;
    var count = 0u;
    var pending = 0u;
    var last = -1;
    for (var w = 0u; w < params.words; w++) {
        let f = bits[front + w];
        let b = bits[back + w];
        var events = f | b;
        while events != 0u {
            let i = firstTrailingBit(events);
            events &= events - 1u;
            let s = i32(w * 32u + i);
            let gap = u32(s - last - 1);
            if state == 1u {
                count += gap;
            } else if state == 2u {
                pending += gap;
            }
            let is_f = ((f >> i) & 1u) == 1u;
            let is_b = ((b >> i) & 1u) == 1u;
            if is_f && is_b {
                count += 1u;
                pending = 0u;
                state = 2u;
            } else if is_f {
                count += 1u;
                state = 1u;
            } else {
                if state == 2u {
                    count += pending;
                }
                if far_end && s == i32(params.slices) - 1 && state != 0u {
                    count += 1u;
                }
                state = 0u;
            }
            last = s;
        }
    }
    if state == 1u {
        count += u32(i32(params.slices) - 1 - last);
    }
    out[c] = count;
}
