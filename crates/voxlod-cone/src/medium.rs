//! What a cone reads from the octree: the [`RadiancePayload`] that light injection stores, and
//! the [`ConeMedium`] trait through which the tracer reads opacity (isotropic or directional)
//! and radiance from any payload.
//!
//! Radiance is stored **premultiplied by opacity**, like every voxlod-octree payload, so the
//! octree's linear pre-filter (mean of eight children) gives a parent the opacity-weighted mean
//! radiance of its children and their mean opacity (coverage).

use glam::Vec3;
use voxlod_octree::{AveragePayload, Directional, Payload};

/// Opacity-weighted outgoing radiance (linear RGB) and opacity of a node. 16 bytes, `f32` only.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[repr(C)]
pub struct RadiancePayload {
    /// Radiance × opacity.
    pub radiance_alpha: [f32; 3],
    /// Opacity (coverage) in \[0, 1\].
    pub opacity: f32,
}

impl RadiancePayload {
    /// A leaf from its radiance and opacity.
    pub fn new(radiance: Vec3, opacity: f32) -> Self {
        Self { radiance_alpha: (radiance * opacity).to_array(), opacity }
    }
    /// Opacity-weighted mean radiance (zero where the opacity is zero).
    pub fn radiance(&self) -> Vec3 {
        if self.opacity > 0.0 { Vec3::from(self.radiance_alpha) / self.opacity } else { Vec3::ZERO }
    }
}

impl Payload for RadiancePayload {
    #[inline]
    fn empty() -> Self {
        Self::default()
    }
    #[inline]
    fn add_scaled(&mut self, o: &Self, w: f32) {
        for i in 0..3 {
            self.radiance_alpha[i] += w * o.radiance_alpha[i];
        }
        self.opacity += w * o.opacity;
    }
    fn opacity(&self) -> f32 {
        self.opacity
    }
    fn check(&self) -> Option<&'static str> {
        if !(self.radiance_alpha.iter().all(|x| x.is_finite()) && self.opacity.is_finite()) {
            return Some("a component is NaN or infinite");
        }
        if !(0.0..=1.0).contains(&self.opacity) {
            return Some("opacity outside [0, 1]");
        }
        if self.radiance_alpha.iter().any(|&x| x < 0.0) {
            return Some("negative radiance");
        }
        None
    }
    fn max_abs_diff(&self, o: &Self) -> f32 {
        let d = (Vec3::from(self.radiance_alpha) - Vec3::from(o.radiance_alpha)).abs();
        d.max_element().max((self.opacity - o.opacity).abs())
    }
}

/// A payload a cone can march through: opacity seen along a direction, and the radiance the
/// node sends back along it (not premultiplied).
pub trait ConeMedium: Payload {
    /// Opacity of crossing the node along unit direction `dir` (isotropic payloads ignore it).
    fn opacity_toward(&self, dir: Vec3) -> f32;
    /// Opacity-weighted mean radiance (zero for payloads without radiance, which serve AO only).
    fn radiance(&self) -> Vec3;
}

impl ConeMedium for RadiancePayload {
    #[inline]
    fn opacity_toward(&self, _dir: Vec3) -> f32 {
        self.opacity
    }
    #[inline]
    fn radiance(&self) -> Vec3 {
        RadiancePayload::radiance(self)
    }
}

impl ConeMedium for AveragePayload {
    #[inline]
    fn opacity_toward(&self, _dir: Vec3) -> f32 {
        self.opacity
    }
    #[inline]
    fn radiance(&self) -> Vec3 {
        Vec3::ZERO
    }
}

impl<P: ConeMedium> ConeMedium for Directional<P> {
    /// The six directional opacities blended by `dir²` ([`Directional::opacity_along`]).
    #[inline]
    fn opacity_toward(&self, dir: Vec3) -> f32 {
        self.opacity_along(dir).clamp(0.0, 1.0)
    }
    #[inline]
    fn radiance(&self) -> Vec3 {
        self.inner.radiance()
    }
}

/// How a leaf of the radiance octree is made from injected radiance and opacity: plain
/// ([`RadiancePayload`]) or with six directional opacities (`Directional<RadiancePayload>`,
/// isotropic at the leaves, anisotropic above by the octree's pre-filter).
pub trait RadianceLeaf: ConeMedium {
    /// The leaf payload.
    fn leaf(radiance: Vec3, opacity: f32) -> Self;
}

impl RadianceLeaf for RadiancePayload {
    fn leaf(radiance: Vec3, opacity: f32) -> Self {
        RadiancePayload::new(radiance, opacity)
    }
}

impl RadianceLeaf for Directional<RadiancePayload> {
    fn leaf(radiance: Vec3, opacity: f32) -> Self {
        Directional::isotropic(RadiancePayload::new(radiance, opacity))
    }
}
