// The one shading function of voxlod (voxlod-cpu's shading.rs `shade`), for every GPU renderer.
//
// albedo/π · E · max(n·l, 0) · visibility
// + specular · (s+8)/(8π) · max(n·h, 0)^s · E · max(n·l, 0) · visibility   (where specular > 0)
// + albedo · ambient
//
// Rust's powf(0, 0) = 1 and powf(0, s > 0) = 0, where WGSL's pow(0, y) is undefined: spelled out.

const PI: f32 = 3.14159265358979323846;

struct MaterialSample {
    albedo: vec3<f32>,
    specular: vec3<f32>,
    shininess: f32,
}

struct LightSample {
    to_light: vec3<f32>,
    irradiance: vec3<f32>,
}

fn pow_rust(x: f32, y: f32) -> f32 {
    if x <= 0.0 {
        return select(0.0, 1.0, y == 0.0);
    }
    return pow(x, y);
}

const F32_MAX: f32 = 3.40282347e38;

// glam's try_normalize: v · (1/|v|) where that reciprocal is finite and positive; else zero
// (callers test for zero: a unit vector is never zero).
fn normalize_or_zero(v: vec3<f32>) -> vec3<f32> {
    let rcp = 1.0 / length(v);
    if rcp > 0.0 && rcp <= F32_MAX {
        return v * rcp;
    }
    return vec3<f32>(0.0);
}

fn shade(
    m: MaterialSample,
    n: vec3<f32>,
    v: vec3<f32>,
    light: LightSample,
    visibility: f32,
    ambient: vec3<f32>,
) -> vec3<f32> {
    let l = light.to_light;
    let ndl = max(dot(n, l), 0.0);
    let direct = light.irradiance * (ndl * visibility);
    var radiance = m.albedo * (1.0 / PI) * direct + m.albedo * ambient;
    if max(max(m.specular.x, m.specular.y), m.specular.z) > 0.0 && ndl > 0.0 {
        let h = normalize_or_zero(l + v);
        let ndh = max(dot(n, h), 0.0);
        let norm = (m.shininess + 8.0) / (8.0 * PI);
        radiance += m.specular * (norm * pow_rust(ndh, m.shininess)) * direct;
    }
    return radiance;
}
