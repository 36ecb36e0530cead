// The directional node payload (voxlod-octree's Directional<RadiancePayload>, or
// Directional<AveragePayload> for AO): the isotropic payload and six opacities, +x +y +z in
// `plus`, −x −y −z in `minus` (the CPU's [+x, −x, +y, −y, +z, −z] regrouped; the pads keep
// each vec3 on 16 bytes). Mirrors `GpuDirectionalRadiance`.
struct Payload {
    radiance_alpha: vec3<f32>,
    opacity: f32,
    plus: vec3<f32>,
    pad0: f32,
    minus: vec3<f32>,
    pad1: f32,
}

fn payload_zero() -> Payload {
    return Payload(vec3<f32>(0.0), 0.0, vec3<f32>(0.0), 0.0, vec3<f32>(0.0), 0.0);
}

// `acc += w·o`: the inner payload, then the six opacities (Directional::add_scaled).
fn payload_add(acc: Payload, o: Payload, w: f32) -> Payload {
    return Payload(
        acc.radiance_alpha + w * o.radiance_alpha,
        acc.opacity + w * o.opacity,
        acc.plus + w * o.plus,
        0.0,
        acc.minus + w * o.minus,
        0.0,
    );
}

// Directional::opacity_along, clamped (ConeMedium::opacity_toward): the six opacities blended
// by dir² per axis, the + one where the component is >= 0 (so −0 reads +), summed x, y, z.
fn payload_opacity_toward(s: Payload, dir: vec3<f32>) -> f32 {
    let w = dir * dir;
    let px = select(s.minus.x, s.plus.x, dir.x >= 0.0);
    let py = select(s.minus.y, s.plus.y, dir.y >= 0.0);
    let pz = select(s.minus.z, s.plus.z, dir.z >= 0.0);
    return clamp(w.x * px + w.y * py + w.z * pz, 0.0, 1.0);
}
