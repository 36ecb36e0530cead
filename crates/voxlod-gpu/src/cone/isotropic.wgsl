// The isotropic node payload (voxlod-cone's RadiancePayload, or an AveragePayload's opacity
// for AO): radiance premultiplied by opacity, and the opacity. Mirrors `GpuRadiance`.
struct Payload {
    radiance_alpha: vec3<f32>,
    opacity: f32,
}

fn payload_zero() -> Payload {
    return Payload(vec3<f32>(0.0), 0.0);
}

// `acc += w·o` (voxlod-octree's Payload::add_scaled), field by field.
fn payload_add(acc: Payload, o: Payload, w: f32) -> Payload {
    return Payload(acc.radiance_alpha + w * o.radiance_alpha, acc.opacity + w * o.opacity);
}

// ConeMedium::opacity_toward: isotropic payloads ignore the direction.
fn payload_opacity_toward(s: Payload, dir: vec3<f32>) -> f32 {
    return s.opacity;
}
