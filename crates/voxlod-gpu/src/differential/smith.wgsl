// Smith's model in f32, a line-by-line port of voxlod-octree's microsurface::special
// (`erfc_f32`, `cf_tail_f32`) and microsurface::smith (`lambda_cs_f32`, `attribute_factor_f32`,
// `light_visibility_f32`): the same term counts, splits and clamps, operations in the same
// order, no infinity ever produced (WGSL leaves them undefined).

const SQRT_PI_F32: f32 = 1.7724539;
const FRAC_2_SQRT_PI_F32: f32 = 1.1283792;
const SQRT_2_F32: f32 = 1.4142135;
const SPLIT_F32: f32 = 1.5;
const CF_TERMS_F32: u32 = 30u;
const SERIES_TERMS_F32: u32 = 24u;
const LAMBDA_MAX_F32: f32 = 1e30;

// Laplace's continued fraction K(x) = (1/2)/(x + 1/(x + (3/2)/(x + …))), backwards.
fn cf_tail(x: f32) -> f32 {
    var t = 0.0;
    for (var k = CF_TERMS_F32; k > 0u; k -= 1u) {
        t = (0.5 * f32(k)) / (x + t);
    }
    return t;
}

// erf on 0 ≤ x < 1.5 by the positive-term series (A&S 7.1.6).
fn erf_series(x: f32) -> f32 {
    let two_x2 = 2.0 * x * x;
    var term = x;
    var sum = x;
    for (var n = 1u; n < SERIES_TERMS_F32; n += 1u) {
        term *= two_x2 / f32(2u * n + 1u);
        sum += term;
    }
    return FRAC_2_SQRT_PI_F32 * exp(-x * x) * sum;
}

fn erfc_f32(x: f32) -> f32 {
    let a = abs(x);
    var r: f32;
    if a < SPLIT_F32 {
        r = 1.0 - erf_series(a);
    } else if a > 9.5 {
        r = 0.0;
    } else {
        r = exp(-a * a) / (SQRT_PI_F32 * (a + cf_tail(a)));
    }
    if x < 0.0 {
        return 2.0 - r;
    }
    return r;
}

// Λ from cos θ, sin θ ≥ 0 and the slope deviation σ ≥ 0 (cos θ ≤ 0: below the horizon).
fn lambda_cs(cos_t: f32, sin_t: f32, sigma: f32) -> f32 {
    if cos_t <= 0.0 {
        return LAMBDA_MAX_F32;
    }
    let denom = SQRT_2_F32 * sigma * max(sin_t, 0.0);
    if denom <= cos_t * (1.0 / 9.5) {
        return 0.0;
    }
    if cos_t <= denom * 1e-30 {
        return LAMBDA_MAX_F32;
    }
    let a = cos_t / denom;
    var l: f32;
    if a < SPLIT_F32 {
        l = 0.5 * (exp(-a * a) / (a * SQRT_PI_F32) - erfc_f32(a));
    } else {
        let k = cf_tail(a);
        l = exp(-a * a) * k / (2.0 * SQRT_PI_F32 * a * (a + k));
    }
    return clamp(l, 0.0, LAMBDA_MAX_F32);
}

// Eq. 17's factor S/(S + 2), S = Λv + Λl.
fn attribute_factor(lv: f32, ll: f32) -> f32 {
    let s = lv + ll;
    return s / (s + 2.0);
}

// V̄(l) = (1 + Λv)/(1 + Λv + Λl).
fn light_visibility(lv: f32, ll: f32) -> f32 {
    return (1.0 + lv) / (1.0 + lv + ll);
}
