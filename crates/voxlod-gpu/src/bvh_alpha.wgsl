// The alpha-tested BVH traversal (voxlod-cpu's Bvh::intersect_filtered and
// Bvh::occluded_filtered), appended to bvh.wgsl: the same CWBVH walk as `trace`, where each
// candidate hit is offered to the includer's
//   fn accepts_hit(triangle: u32, u: f32, v: f32, ray: AlphaRay) -> bool
// (the material's alpha test at the hit's UV), as the CPU offers it to its filter:
// - closest hit: a candidate closer than the best so far (ties: the lower triangle id) and
//   accepted becomes the best and shrinks the search;
// - any hit (shadow rays): a candidate with 0 < t < t_max that is accepted ends the walk
//   (the CPU's open range, so a blocker exactly at the light does not shadow).
// The node walk below the primitive loop is `trace`'s, line for line (a unit test checks it).

// Which random numbers a blend test draws: rand_f32(pixel, sample, key ^ triangle).
struct AlphaRay {
    pixel: u32,
    sample: u32,
    key: u32,
}

fn trace_alpha(o: vec3<f32>, d: vec3<f32>, t_min: f32, t_max_in: f32, any_hit: bool, alpha: AlphaRay) -> Hit {
    var best: Hit;
    best.t = 0.0;
    best.triangle = MISS;
    best.u = 0.0;
    best.v = 0.0;
    var t_max = t_max_in;
    if t_min > t_max || arrayLength(&nodes) == 0u || (any_hit && !(t_max > 0.0)) {
        return best;
    }
    let ray = box_ray(o, d);
    let a = abs(d);
    var kz = 2u;
    if a.x >= a.y && a.x >= a.z {
        kz = 0u;
    } else if a.y >= a.z {
        kz = 1u;
    }
    let kx = (kz + 1u) % 3u;
    let ky = (kz + 2u) % 3u;
    let s = vec3<f32>(d[kx] / d[kz], d[ky] / d[kz], 1.0 / d[kz]);

    var stack: array<vec2<u32>, 32>;
    var sp = 0u;
    var current = vec2<u32>(0u, 0x80000000u);
    var prims = vec2<u32>(0u, 0u);
    loop {
        while prims.y != 0u {
            let local_bit = firstLeadingBit(prims.y);
            prims.y &= ~(1u << local_bit);
            let slot = prims.x + local_bit;
            let h = intersect_tri(slot, o, kz, s, t_min, t_max);
            if !h.ok {
                continue;
            }
            let id = bitcast<u32>(tris[slot].v0.w);
            // One call site of the alpha test (the driver inlines each).
            var candidate = best.triangle == MISS || h.t < best.t || (h.t == best.t && id < best.triangle);
            if any_hit {
                candidate = h.t > 0.0 && h.t < t_max_in;
            }
            if candidate && accepts_hit(id, h.u, h.v, alpha) {
                best.t = h.t;
                best.triangle = id;
                best.u = h.u;
                best.v = h.v;
                if any_hit {
                    return best;
                }
                t_max = h.t;
            }
        }
        if (current.y & 0xff000000u) != 0u {
            let hits_mask = current.y;
            let offset = firstLeadingBit(hits_mask);
            current.y &= ~(1u << offset);
            if (current.y & 0xff000000u) != 0u {
                stack[sp] = current;
                sp = min(sp + 1u, STACK_SIZE - 1u);
            }
            let slot = (offset - 24u) ^ (ray.oct_inv4 & 0xffu);
            let relative = countOneBits(hits_mask & ~(0xffffffffu << slot));
            let n = current.x + relative;
            let hit_mask = intersect_node(n, ray, t_min, t_max);
            current = vec2<u32>(nodes[n].child_base, (hit_mask & 0xff000000u) | nodes[n].imask);
            prims = vec2<u32>(nodes[n].primitive_base, hit_mask & 0x00ffffffu);
        } else {
            current = vec2<u32>(0u, 0u);
        }
        if prims.y == 0u && (current.y & 0xff000000u) == 0u {
            if sp == 0u {
                break;
            }
            sp -= 1u;
            current = stack[sp];
        }
    }
    return best;
}
