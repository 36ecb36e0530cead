//! What an octree node stores and how eight children combine into their parent: the
//! [`Payload`] trait, and its implementations for Averages ([`AveragePayload`]), SGGX
//! ([`SggxPayload`]) and six directional opacities around either ([`Directional`]).
//!
//! # Rules
//! - **Premultiplied, so that pre-filtering is linear.** Colour, normal and SGGX matrix are
//!   stored multiplied by opacity. The parent of eight children is then their plain mean, every
//!   missing child counting as [`Payload::empty`] (zero): the parent's colour is the
//!   opacity-weighted mean colour of its children, its opacity their mean opacity (coverage),
//!   its SGGX matrix the opacity-weighted mean matrix (SGGX matrices average linearly, Heitz et
//!   al. 2015 §5). Trilinear interpolation of premultiplied values is the same linear map, so
//!   sampling at a coarse level equals sampling the box-filtered leaf grid (tested).
//! - **Directional opacities** ([`Directional`], the standard anisotropic VCT scheme): for each
//!   of ±x, ±y, ±z the parent's opacity is the mean over the 4 child columns along that axis of
//!   the two children composited front to back, `α = α_front + (1 − α_front)·α_back`, where
//!   the front child is the one a ray travelling in that direction enters first (lower
//!   coordinate for +x). It is the opacity of crossing the whole parent node along that axis,
//!   which the isotropic mean opacity (coverage) underestimates for a thin wall seen face-on.
//!   It is not linear, so only the isotropic part obeys the dense-grid equality above. It also
//!   assumes the coverage of the two composited children uncorrelated: partial coverage that is
//!   aligned across layers (a wall seen edge-on) is over-estimated — a one-voxel wall across an
//!   8³ grid seen along its plane gets 0.305 at the root instead of its true 1/8 (tested).
//! - **Virtual-mesh records** (Brito et al. 2023) are not supported: merging them across levels is open
//!   research (Brito et al. 2023, §6) and out of scope.

use glam::{Mat3, Vec3};
use voxlod_format::records::{AverageRecord, SggxRecord};

/// A node record that can be pre-filtered (eight children → parent) and interpolated.
///
/// Laws every implementation keeps (the octree's sampling and [`crate::Octree::validate`]
/// rely on them): [`Payload::empty`] is the additive zero of [`Payload::add_scaled`] and the
/// prefilter of eight empties is empty; `add_scaled` is linear.
pub trait Payload: Copy + Send + Sync + std::fmt::Debug + 'static {
    /// Empty space: the payload of nodes without content, and the value sampling returns there.
    fn empty() -> Self;
    /// The parent of eight children, indexed by octant `x + 2y + 4z` (0 or 1 per axis; the
    /// child at the lower coordinate has bit 0). Missing children are [`Payload::empty`].
    /// The default is the plain mean: [`Payload::empty`] plus `⅛·child` for each child, in
    /// octant order, through [`Payload::add_scaled`].
    fn prefilter(children: &[Self; 8]) -> Self {
        let mut parent = Self::empty();
        for child in children {
            parent.add_scaled(child, 0.125);
        }
        parent
    }
    /// `self += w·other`, used by trilinear and inter-level interpolation.
    fn add_scaled(&mut self, other: &Self, w: f32);
    /// `self += w·other` where `other` is the stored payload of a node `size` voxels wide whose
    /// centre lies `offset` voxels from the sample point (sample point − centre): what the
    /// sampler calls for each corner of a trilinear interpolation. Payloads whose statistics
    /// do not depend on where they are read (every payload above) keep the default,
    /// [`Payload::add_scaled`]. A payload stored relative to its node (a distance from the
    /// node's centre in node units, as [`crate::MicrosurfacePayload`]) re-expresses `other` at
    /// the sample point in voxel units first, so that every sample, of any level, is in the
    /// same frame. Must be linear in `other`, and equal [`Payload::add_scaled`] for
    /// `offset = 0`, `size = 1`.
    #[inline]
    fn add_scaled_at(&mut self, other: &Self, w: f32, offset: Vec3, size: f32) {
        let _ = (offset, size);
        self.add_scaled(other, w);
    }
    /// Mean (isotropic) opacity in \[0, 1\].
    fn opacity(&self) -> f32;
    /// Why this payload cannot be stored in a leaf (non-finite value, opacity outside
    /// \[0, 1\]), or `None` if it can.
    fn check(&self) -> Option<&'static str>;
    /// Largest absolute difference between corresponding components, for tolerance checks.
    fn max_abs_diff(&self, other: &Self) -> f32;
}

fn opacity_problem(a: f32) -> Option<&'static str> {
    if !(0.0..=1.0).contains(&a) { Some("opacity outside [0, 1]") } else { None }
}

fn max_diff(a: &[f32], b: &[f32]) -> f32 {
    a.iter().zip(b).map(|(x, y)| (x - y).abs()).fold(0.0, f32::max)
}

fn mean8<T: Copy>(children: &[T; 8], get: impl Fn(&T) -> Vec3) -> Vec3 {
    children.iter().map(get).sum::<Vec3>() * 0.125
}

/// Averages (colour, normal, opacity), premultiplied by opacity (module rules). 28 bytes,
/// `#[repr(C)]`, `f32` only, so the GPU can read it as `array<f32, 7>`.
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
pub struct AveragePayload {
    /// Colour × opacity (linear RGB).
    pub color_alpha: [f32; 3],
    /// Unit normal × opacity (the sum of children's weighted normals, not renormalized).
    pub normal_alpha: [f32; 3],
    /// Opacity (coverage) in \[0, 1\].
    pub opacity: f32,
}

impl AveragePayload {
    /// A leaf payload from linear colour, normal (normalized here; zero allowed) and opacity.
    pub fn new(color: Vec3, normal: Vec3, opacity: f32) -> Self {
        let n = normal.normalize_or_zero();
        Self {
            color_alpha: (color * opacity).to_array(),
            normal_alpha: (n * opacity).to_array(),
            opacity,
        }
    }
    /// The leaf payload of an Averages record (decoded colour, normal and opacity).
    pub fn from_record(r: &AverageRecord) -> Self {
        Self::new(r.color(), r.normal(), r.opacity())
    }
    /// Opacity-weighted mean colour (zero where the opacity is zero).
    pub fn color(&self) -> Vec3 {
        if self.opacity > 0.0 { Vec3::from(self.color_alpha) / self.opacity } else { Vec3::ZERO }
    }
    /// Unit mean normal (zero if the weighted normals cancel or the node is empty).
    pub fn normal(&self) -> Vec3 {
        Vec3::from(self.normal_alpha).normalize_or_zero()
    }
    fn fields(&self) -> [f32; 7] {
        bytemuck::cast(*self)
    }
}

impl Payload for AveragePayload {
    #[inline]
    fn empty() -> Self {
        Self::default()
    }
    fn prefilter(c: &[Self; 8]) -> Self {
        Self {
            color_alpha: mean8(c, |p| Vec3::from(p.color_alpha)).to_array(),
            normal_alpha: mean8(c, |p| Vec3::from(p.normal_alpha)).to_array(),
            opacity: c.iter().map(|p| p.opacity).sum::<f32>() * 0.125,
        }
    }
    #[inline]
    fn add_scaled(&mut self, o: &Self, w: f32) {
        for i in 0..3 {
            self.color_alpha[i] += w * o.color_alpha[i];
            self.normal_alpha[i] += w * o.normal_alpha[i];
        }
        self.opacity += w * o.opacity;
    }
    fn opacity(&self) -> f32 {
        self.opacity
    }
    fn check(&self) -> Option<&'static str> {
        if !self.fields().iter().all(|x| x.is_finite()) {
            return Some("a component is NaN or infinite");
        }
        opacity_problem(self.opacity)
    }
    fn max_abs_diff(&self, o: &Self) -> f32 {
        max_diff(&self.fields(), &o.fields())
    }
}

/// SGGX (Heitz et al. 2015) with colour and opacity, premultiplied by opacity (module rules):
/// the parent's matrix is the opacity-weighted mean of its children's. 40 bytes, `f32` only.
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
pub struct SggxPayload {
    /// Symmetric SGGX matrix × opacity: `S_xx, S_yy, S_zz, S_xy, S_xz, S_yz`.
    pub matrix_alpha: [f32; 6],
    /// Colour × opacity (linear RGB).
    pub color_alpha: [f32; 3],
    /// Opacity (coverage) in \[0, 1\].
    pub opacity: f32,
}

impl SggxPayload {
    /// A leaf payload from an SGGX matrix (its scale is kept as given), colour and opacity.
    pub fn new(s: Mat3, color: Vec3, opacity: f32) -> Self {
        let m = [s.x_axis.x, s.y_axis.y, s.z_axis.z, s.y_axis.x, s.z_axis.x, s.z_axis.y];
        Self {
            matrix_alpha: m.map(|x| x * opacity),
            color_alpha: (color * opacity).to_array(),
            opacity,
        }
    }
    /// The leaf payload of an \[VJK21\] SGGX record: its decoded matrix and colour, and the
    /// opacity `1 − exp(−σ)` of crossing one voxel edge with the record's extinction σ. This
    /// is the exponential transmittance: the record's non-exponential blend γ is not kept
    /// (callers with a better opacity use [`SggxPayload::new`]).
    pub fn from_record(r: &SggxRecord) -> Self {
        Self::new(r.matrix(), r.color(), 1.0 - (-r.sigma_t()).exp())
    }
    /// The opacity-weighted mean SGGX matrix (zero where the opacity is zero).
    pub fn matrix(&self) -> Mat3 {
        if self.opacity <= 0.0 {
            return Mat3::ZERO;
        }
        let [xx, yy, zz, xy, xz, yz] = self.matrix_alpha.map(|x| x / self.opacity);
        Mat3::from_cols(Vec3::new(xx, xy, xz), Vec3::new(xy, yy, yz), Vec3::new(xz, yz, zz))
    }
    /// Opacity-weighted mean colour (zero where the opacity is zero).
    pub fn color(&self) -> Vec3 {
        if self.opacity > 0.0 { Vec3::from(self.color_alpha) / self.opacity } else { Vec3::ZERO }
    }
    fn fields(&self) -> [f32; 10] {
        bytemuck::cast(*self)
    }
}

impl Payload for SggxPayload {
    #[inline]
    fn empty() -> Self {
        Self::default()
    }
    #[inline]
    fn add_scaled(&mut self, o: &Self, w: f32) {
        for i in 0..6 {
            self.matrix_alpha[i] += w * o.matrix_alpha[i];
        }
        for i in 0..3 {
            self.color_alpha[i] += w * o.color_alpha[i];
        }
        self.opacity += w * o.opacity;
    }
    fn opacity(&self) -> f32 {
        self.opacity
    }
    fn check(&self) -> Option<&'static str> {
        if !self.fields().iter().all(|x| x.is_finite()) {
            return Some("a component is NaN or infinite");
        }
        opacity_problem(self.opacity)
    }
    fn max_abs_diff(&self, o: &Self) -> f32 {
        max_diff(&self.fields(), &o.fields())
    }
}

/// Direction indices of [`Directional::opacity`]: a ray travelling along +x, −x, +y, −y, +z, −z.
pub const DIRECTIONS: [Vec3; 6] =
    [Vec3::X, Vec3::NEG_X, Vec3::Y, Vec3::NEG_Y, Vec3::Z, Vec3::NEG_Z];

/// A payload with six directional opacities (module rules): `opacity[d]` is the opacity a ray
/// travelling along [`DIRECTIONS`]`[d]` meets crossing the node.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[repr(C)]
pub struct Directional<P> {
    /// The isotropic payload, pre-filtered by its own rule.
    pub inner: P,
    /// Opacity along +x, −x, +y, −y, +z, −z.
    pub opacity: [f32; 6],
}

// SAFETY: every field is `Zeroable` (`P` by the bound, `[f32; 6]`), so all-zero bytes are a
// valid value. (`Pod` is not implemented: for a generic `P` the layout may contain padding.)
unsafe impl<P: bytemuck::Zeroable> bytemuck::Zeroable for Directional<P> {}

impl<P: Payload> Directional<P> {
    /// A leaf whose six directional opacities all equal the payload's isotropic opacity.
    pub fn isotropic(inner: P) -> Self {
        Self { inner, opacity: [inner.opacity(); 6] }
    }
    /// Opacity seen along unit direction `dir`: the six values blended by `dir²` per axis
    /// (the standard VCT weighting; the weights sum to 1 for a unit vector).
    pub fn opacity_along(&self, dir: Vec3) -> f32 {
        let w = dir * dir;
        let pick = |axis: usize, comp: f32| {
            if comp >= 0.0 { self.opacity[2 * axis] } else { self.opacity[2 * axis + 1] }
        };
        w.x * pick(0, dir.x) + w.y * pick(1, dir.y) + w.z * pick(2, dir.z)
    }
}

impl<P: Payload> Payload for Directional<P> {
    #[inline]
    fn empty() -> Self {
        Self { inner: P::empty(), opacity: [0.0; 6] }
    }
    fn prefilter(c: &[Self; 8]) -> Self {
        let inner = P::prefilter(&c.map(|x| x.inner));
        let mut opacity = [0.0; 6];
        for axis in 0..3 {
            let bit = 1 << axis;
            for (sign, slot) in [(0, 2 * axis), (1, 2 * axis + 1)] {
                let mut sum = 0.0;
                for k in (0..8).filter(|k| k & bit == 0) {
                    let (lo, hi) = (c[k].opacity[slot], c[k | bit].opacity[slot]);
                    // +axis: the lower child is in front; −axis: the upper one.
                    let (front, back) = if sign == 0 { (lo, hi) } else { (hi, lo) };
                    sum += front + (1.0 - front) * back;
                }
                opacity[slot] = sum * 0.25;
            }
        }
        Self { inner, opacity }
    }
    #[inline]
    fn add_scaled(&mut self, o: &Self, w: f32) {
        self.inner.add_scaled(&o.inner, w);
        for i in 0..6 {
            self.opacity[i] += w * o.opacity[i];
        }
    }
    fn opacity(&self) -> f32 {
        self.inner.opacity()
    }
    fn check(&self) -> Option<&'static str> {
        if let Some(p) = self.inner.check() {
            return Some(p);
        }
        if !self.opacity.iter().all(|a| a.is_finite()) {
            return Some("a directional opacity is NaN or infinite");
        }
        if !self.opacity.iter().all(|a| (0.0..=1.0).contains(a)) {
            return Some("a directional opacity is outside [0, 1]");
        }
        None
    }
    fn max_abs_diff(&self, o: &Self) -> f32 {
        self.inner.max_abs_diff(&o.inner).max(max_diff(&self.opacity, &o.opacity))
    }
}

#[cfg(test)]
mod tests;
