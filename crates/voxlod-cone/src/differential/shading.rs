//! The local illumination of a cone element (Heitz and Neyret 2012 §5.5, Eq. 13): what the
//! micro-surface statistics of a sample do to its shading, in the `f32` arithmetic the GPU
//! kernel mirrors.
//!
//! For a sample with macro-normal `N` (turned toward the viewer: surfaces are shaded
//! two-sided, as voxlod's other voxel renderers do), seen from `v` and lit from `l`:
//! - **Smith's Λ** per direction `d ∈ {v, l}` (Eq. 6): `μ = cot θ` from `cos θ = N·d` and
//!   `sin θ = |N × d|`, and the slope deviation along `d`'s projection on the tangent plane
//!   from the normals' second moments ([`Microsurface::slope_variance_along`]: the
//!   anisotropic form). A direction at or below the macro-surface has Λ = ∞ (clamped to
//!   `LAMBDA_MAX_F32`).
//! - **Visible colour** (Eq. 17): `ā(v, l) = ā + aₛ·S/(S + 2)`, `S = Λv + Λl`, for the light's
//!   direct term; `ā(v) = ā + aₛ·Λv/(Λv + 2)` (no light term, as the paper does for
//!   view-dependency alone) for the ambient term, which comes from every direction. Clamped to
//!   \[0, 1\].
//! - **Light visibility of the visible micro-surface** `V̄(l) = (1 + Λv)/(1 + Λv + Λl)`
//!   (Smith's masking-shadowing with correlated heights), multiplied into the shadow.
//! - **BRDF convolved with the normal distribution** (§5.5): Gaussian slope variances add, so
//!   the Blinn-Phong lobe of the materials (slope variance `σₚ² = 1/(e + 2)`) widens to
//!   `σ² = σn² + σₚ²` and is shaded with the exponent `e′ = 1/σ² − 2` (≥ 0). `σn² = 0` (a
//!   flat node) gives back the material's own exponent: the unfiltered result.

use glam::Vec3;
use voxlod_octree::Microsurface;
use voxlod_octree::microsurface::smith::{
    attribute_factor_f32, lambda_cs_f32, light_visibility_f32,
};

/// Largest slope variance used (a finite stand-in for "no micro-normal along the macro-normal",
/// which makes Λ = ∞ anyway); keeps every quantity finite for the GPU.
pub const MAX_SLOPE_VARIANCE: f32 = 1e30;

/// Smallest total slope variance of the convolved lobe (exponent at most 10⁶).
pub const MIN_LOBE_VARIANCE: f32 = 1e-6;

/// What the micro-surface does to a sample's shading (module docs).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LocalIllumination {
    /// Unit shading normal: the macro-normal turned toward the viewer.
    pub normal: Vec3,
    /// Λ toward the viewer.
    pub lambda_view: f32,
    /// Λ toward the light (0 without a light direction).
    pub lambda_light: f32,
    /// `ā(v, l)`, the colour the direct light sees (Eq. 17).
    pub albedo: Vec3,
    /// `ā(v)`, the colour the ambient term sees.
    pub ambient_albedo: Vec3,
    /// `ā`, the mean colour (what separate filtering of the colour gives, whatever the view).
    pub mean_albedo: Vec3,
    /// `V̄(l)` in \[0, 1\].
    pub light_visibility: f32,
    /// Specular level.
    pub specular: f32,
    /// Blinn-Phong exponent of the convolved lobe.
    pub exponent: f32,
}

/// Λ of direction `d` (unit) over a surface with unit normal `n` (module docs).
pub fn lambda_toward(s: &Microsurface, n: Vec3, d: Vec3) -> f32 {
    let cos = n.dot(d);
    let cross = n.cross(d);
    let sin = cross.length();
    if sin <= 0.0 || cos <= 0.0 {
        // Normal incidence (Λ = 0) or at / below the horizon (Λ = max).
        return lambda_cs_f32(cos, sin.max(0.0), 0.0);
    }
    let t = (d - n * cos) * (1.0 / sin);
    let var = s.slope_variance_along(t).min(MAX_SLOPE_VARIANCE);
    lambda_cs_f32(cos, sin, var.sqrt())
}

/// The local illumination of sample `s` seen along unit `to_viewer`, lit from unit `to_light`
/// (`None`: no direct light reaches it, e.g. a point light at the sample).
pub fn local_illumination(
    s: &Microsurface,
    to_viewer: Vec3,
    to_light: Option<Vec3>,
) -> LocalIllumination {
    let n = if s.normal.dot(to_viewer) < 0.0 { -s.normal } else { s.normal };
    let lambda_view = lambda_toward(s, n, to_viewer);
    let lambda_light = to_light.map_or(0.0, |l| lambda_toward(s, n, l));
    let visible = |factor: f32| (s.albedo + s.albedo_slope * factor).clamp(Vec3::ZERO, Vec3::ONE);
    let lobe = (s.slope_variance().min(MAX_SLOPE_VARIANCE) + s.roughness).max(MIN_LOBE_VARIANCE);
    LocalIllumination {
        normal: n,
        lambda_view,
        lambda_light,
        albedo: visible(attribute_factor_f32(lambda_view, lambda_light)),
        ambient_albedo: visible(attribute_factor_f32(lambda_view, 0.0)),
        mean_albedo: s.albedo.clamp(Vec3::ZERO, Vec3::ONE),
        light_visibility: if to_light.is_some() {
            light_visibility_f32(lambda_view, lambda_light)
        } else {
            0.0
        },
        specular: s.specular,
        exponent: (1.0 / lobe - 2.0).max(0.0),
    }
}

#[cfg(test)]
mod tests {
    use glam::Mat3;
    use voxlod_octree::microsurface::smith::LAMBDA_MAX_F32;

    use super::*;

    fn surface(slope_var: f32) -> Microsurface {
        // Normals spread isotropically about z: E[n nᵀ] with tangential share per axis.
        let t = slope_var / (1.0 + 2.0 * slope_var);
        Microsurface {
            coverage: 1.0,
            distance: 0.0,
            normal: Vec3::Z,
            normal_length: 1.0,
            normal_moments: Mat3::from_diagonal(Vec3::new(t, t, 1.0 - 2.0 * t)),
            height_variance: 0.01,
            albedo: Vec3::splat(0.5),
            albedo_slope: Vec3::new(0.3, -0.3, 0.0),
            specular: 0.5,
            roughness: 1.0 / 66.0,
        }
    }

    #[test]
    fn a_smooth_node_gives_the_unfiltered_result() {
        let s = surface(0.0);
        let v = Vec3::new(0.0, 0.6, 0.8);
        let l = Vec3::new(0.8, 0.0, 0.6);
        let li = local_illumination(&s, v, Some(l));
        assert_eq!((li.lambda_view, li.lambda_light), (0.0, 0.0));
        assert_eq!(li.albedo, s.albedo);
        assert_eq!(li.ambient_albedo, s.albedo);
        assert_eq!(li.light_visibility, 1.0);
        assert!((li.exponent - 64.0).abs() < 1e-3, "{}", li.exponent);
    }

    #[test]
    fn grazing_views_see_the_tops_and_grazing_light_lights_nothing_below() {
        let s = surface(0.1);
        let near_normal = local_illumination(&s, Vec3::Z, Some(Vec3::Z));
        let grazing = local_illumination(&s, Vec3::new(0.0, 0.999, 0.0447), Some(Vec3::Z));
        // The red channel rises with height: grazing views see more of it.
        assert!(grazing.albedo.x > near_normal.albedo.x + 0.1, "{grazing:?}");
        // Light below the horizon: Λl = max, no light; exactly grazing view sees the tops only.
        let below = local_illumination(&s, Vec3::Z, Some(Vec3::new(0.6, 0.0, -0.8)));
        assert_eq!(below.lambda_light, LAMBDA_MAX_F32);
        assert!(below.light_visibility < 1e-20);
        let edge = local_illumination(&s, Vec3::X, Some(Vec3::Z));
        assert_eq!(edge.lambda_view, LAMBDA_MAX_F32);
        assert!((edge.albedo - Vec3::new(0.8, 0.2, 0.5)).length() < 1e-5);
        assert_eq!(edge.light_visibility, 1.0);
        // A viewer behind the macro-normal shades the flipped side (two-sided).
        let back = local_illumination(&s, -Vec3::Z, Some(-Vec3::Z));
        assert_eq!(back.normal, -Vec3::Z);
        assert_eq!(back.lambda_view, 0.0);
        // Rough nodes widen the lobe: a lower exponent.
        assert!(local_illumination(&s, Vec3::Z, None).exponent < near_normal.exponent + 1e-3);
        assert!(local_illumination(&surface(0.1), Vec3::Z, None).exponent < 10.0);
        assert_eq!(local_illumination(&s, Vec3::Z, None).light_visibility, 0.0);
    }

    #[test]
    fn degenerate_moments_stay_finite() {
        let mut s = surface(0.0);
        s.normal_moments = Mat3::from_diagonal(Vec3::new(0.5, 0.5, 0.0));
        let li = local_illumination(&s, Vec3::new(0.0, 0.6, 0.8), Some(Vec3::Z));
        assert!(li.lambda_view > 1e14, "{}", li.lambda_view);
        assert!(
            li.albedo.is_finite() && li.exponent.is_finite() && li.light_visibility.is_finite()
        );
    }
}
