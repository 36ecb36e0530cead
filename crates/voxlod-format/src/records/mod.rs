//! Per-voxel appearance records of the filtered representations (Brito, Poulin and Teichrieb, HPG 2023),
//! frozen `#[repr(C)]` `Pod` layouts that the GPU mirrors field for field. All fields are bytes,
//! one `u32` or `f32`s, so a record has no padding the compiler chooses and no alignment above 4.
//!
//! | record | bytes | content |
//! |---|---|---|
//! | [`AverageRecord`] | 8 (7 + 1 pad) | mean colour (sRGB8), opacity (unorm8), mean normal (snorm8×3) |
//! | [`SggxRecord`] | 12 (11 + 1 pad) | SGGX matrix (σ unorm8×3, r snorm8×3), colour (sRGB8), extinction σ (log byte), blend γ (unorm8) |
//! | [`VirtualMeshRecord`] | 136 | eigenframe (snorm8×3×3), semi-axes (log byte×3), 8 face colours (sRGB8), 24 extremal normals (snorm8×3), distribution mask, 27 sub-cell opacities (unorm8) |
//! | [`SpecularRecord`] | 2 | mean specular level (unorm8) and exponent (log byte); stored beside any of the above only for scenes with specular materials |
//! | [`AdaptiveRef`] | 4 | which representation a voxel uses (2 bits) and its index in that representation's array (30 bits) |
//! | [`VoxelSkin`] | 8 | linear-blend-skinning influences of a voxel of an object-space cache: 4 joint indices (u8), 4 weights (unorm8 summing to 255) |
//! | [`SkinnedRecord`] | 16 | a skinned object's cached voxel: [`AverageRecord`] + [`VoxelSkin`] |
//! | [`MicrosurfaceRecord`] | 84 | Heitz and Neyret (2012) Gaussian micro-surface statistics of a leaf, `f32` (not quantized: the octree pre-filters them) |
//!
//! Decoders return linear floats; quantizers are in [`quant`].

pub mod quant;
mod skin;

pub use skin::{SkinnedRecord, VoxelSkin};

use glam::{Mat3, Vec3};

use crate::vxl::VxlRecord;
use quant::{
    LogByte, decode_dir, decode_srgb8, encode_dir, encode_srgb8, from_snorm8, from_unorm8, snorm8,
    unorm8,
};

/// Range of the \[VJK21\] extinction σ, per voxel size: codes 1..=255 span 2⁻⁶ … 2⁸.
pub const SIGMA_RANGE: LogByte = LogByte { lo: -6.0, hi: 8.0 };
/// Range of the virtual mesh's semi-axes, in voxel units: 2⁻⁵ … 2¹.
pub const SCALE_RANGE: LogByte = LogByte { lo: -5.0, hi: 1.0 };
/// Range of the Blinn-Phong exponent: 2⁰ … 2¹².
pub const EXPONENT_RANGE: LogByte = LogByte { lo: 0.0, hi: 12.0 };

/// Averages: one mean colour, one mean normal, one opacity (the paper's 7 bytes, plus one pad
/// byte so records are 4-byte aligned on the GPU).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
pub struct AverageRecord {
    /// Mean albedo, sRGB8.
    pub color: [u8; 3],
    /// Opacity = occluded rays / rays, unorm8.
    pub opacity: u8,
    /// Mean shading normal, snorm8×3 (renormalized on decode; zero = none).
    pub normal: [i8; 3],
    /// Zero.
    pub _pad: u8,
}

impl AverageRecord {
    /// Encodes linear colour, unit normal and opacity.
    pub fn new(color: Vec3, normal: Vec3, opacity: f32) -> Self {
        Self {
            color: encode_srgb8(color),
            opacity: unorm8(opacity),
            normal: encode_dir(normal),
            _pad: 0,
        }
    }
    /// Linear colour.
    pub fn color(&self) -> Vec3 {
        decode_srgb8(self.color)
    }
    /// Unit normal (zero if none).
    pub fn normal(&self) -> Vec3 {
        decode_dir(self.normal)
    }
    /// Opacity in [0, 1].
    pub fn opacity(&self) -> f32 {
        from_unorm8(self.opacity)
    }

    /// The exponential extinction coefficient of this voxel's opacity, per world unit:
    /// [`extinction_from_opacity`]`(self.opacity(), voxel_size)`.
    pub fn extinction(&self, voxel_size: f64) -> f32 {
        extinction_from_opacity(self.opacity(), voxel_size)
    }
}

/// Largest optical depth across one voxel that a unorm8 opacity stands for: code 255 covers
/// opacities from 254.5/255 up, so its transmittance is at most 0.5/255 and its optical depth at
/// least `ln 510` ≈ 6.23. Opacity 1 maps to this depth rather than to an infinite extinction.
pub const MAX_VOXEL_OPTICAL_DEPTH: f32 = 6.234_411;

/// Extinction σ (per world unit) of a homogeneous voxel of edge `voxel_size` whose opacity along
/// one voxel edge is `opacity`, under exponential (Beer–Lambert) transmittance:
/// `σ = −ln(1 − α) / voxel_size`, the optical depth `−ln(1 − α)` capped at
/// [`MAX_VOXEL_OPTICAL_DEPTH`]. This is what volume formats (OpenVDB, NanoVDB, Mitsuba) call
/// density. The opacity of an Averages record is a fraction of occluded rays over all
/// directions, not along one edge, and \[VJK21\]'s non-exponential transmittance (the SGGX
/// record's γ) has no counterpart in these formats: both are approximations this conversion
/// makes. Opacity outside `[0, 1]` is clamped; NaN gives 0.
///
/// ```
/// use voxlod_format::records::extinction_from_opacity;
/// // Half the light through a voxel of 0.5 world units: σ = ln 2 / 0.5.
/// assert!((extinction_from_opacity(0.5, 0.5) - 2.0 * std::f32::consts::LN_2).abs() < 1e-6);
/// assert_eq!(extinction_from_opacity(0.0, 0.5), 0.0);
/// ```
pub fn extinction_from_opacity(opacity: f32, voxel_size: f64) -> f32 {
    let a = if opacity.is_nan() { 0.0 } else { opacity.clamp(0.0, 1.0) };
    let depth = (-(1.0 - a as f64).ln()).min(MAX_VOXEL_OPTICAL_DEPTH as f64);
    (depth / voxel_size) as f32
}

/// \[VJK21\]: an SGGX distribution of normals (Heitz et al. 2015), the mean colour, and the
/// non-exponential transmittance parameters σ (extinction per voxel size) and γ (blend between
/// exponential, γ = 1, and linear, γ = 0). The paper's 11 bytes, plus one pad byte.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
pub struct SggxRecord {
    /// `√S_xx, √S_yy, √S_zz`, scaled so the largest is 1, unorm8.
    pub sigma: [u8; 3],
    /// Correlations `S_xy/√(S_xx S_yy)`, `S_xz/…`, `S_yz/…`, snorm8.
    pub corr: [i8; 3],
    /// Mean albedo, sRGB8.
    pub color: [u8; 3],
    /// Extinction σ in [`SIGMA_RANGE`] (log byte; 0 = none).
    pub density: u8,
    /// Blend γ, unorm8.
    pub gamma: u8,
    /// Zero.
    pub _pad: u8,
}

impl SggxRecord {
    /// Encodes a symmetric positive semi-definite matrix `s` (any scale) with colour, σ and γ.
    pub fn new(s: Mat3, color: Vec3, sigma: f32, gamma: f32) -> Self {
        let d = Vec3::new(s.x_axis.x, s.y_axis.y, s.z_axis.z).max(Vec3::ZERO);
        let sd = Vec3::new(d.x.sqrt(), d.y.sqrt(), d.z.sqrt());
        let m = sd.max_element();
        let r = |a: f32, b: f32, off: f32| if a * b > 0.0 { snorm8(off / (a * b)) } else { 0 };
        Self {
            sigma: if m > 0.0 { [sd.x / m, sd.y / m, sd.z / m].map(unorm8) } else { [255; 3] },
            corr: [r(sd.x, sd.y, s.y_axis.x), r(sd.x, sd.z, s.z_axis.x), r(sd.y, sd.z, s.z_axis.y)],
            color: encode_srgb8(color),
            density: SIGMA_RANGE.encode(sigma),
            gamma: unorm8(gamma),
            _pad: 0,
        }
    }

    /// The SGGX matrix, repaired to be positive definite: if `det S ≤ 10⁻⁶·(tr S/3)³`, then
    /// `10⁻³·tr S·I` is added (a rank-deficient fit, all normals equal, stays finite).
    pub fn matrix(&self) -> Mat3 {
        let s = Vec3::from_array(self.sigma.map(from_unorm8));
        let [rxy, rxz, ryz] = self.corr.map(from_snorm8);
        let (xy, xz, yz) = (rxy * s.x * s.y, rxz * s.x * s.z, ryz * s.y * s.z);
        let m = Mat3::from_cols(
            Vec3::new(s.x * s.x, xy, xz),
            Vec3::new(xy, s.y * s.y, yz),
            Vec3::new(xz, yz, s.z * s.z),
        );
        let tr = s.length_squared().max(1e-12);
        if m.determinant() <= 1e-6 * (tr / 3.0).powi(3) {
            m + Mat3::from_diagonal(Vec3::splat(1e-3 * tr))
        } else {
            m
        }
    }
    /// Linear colour.
    pub fn color(&self) -> Vec3 {
        decode_srgb8(self.color)
    }
    /// Extinction σ per voxel size.
    pub fn sigma_t(&self) -> f32 {
        SIGMA_RANGE.decode(self.density)
    }
    /// Blend γ.
    pub fn gamma(&self) -> f32 {
        from_unorm8(self.gamma)
    }
}

/// The virtual mesh (an octahedron in the SGGX eigenframe; per face one colour and three
/// extremal normals) with the 3×3×3 opacity subgrid: the paper's ~143 bytes as 136.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
pub struct VirtualMeshRecord {
    /// Eigenframe axes `e0, e1, e2` (right-handed), snorm8×3 each.
    pub axes: [[i8; 3]; 3],
    /// Semi-axes along `e0, e1, e2` in voxel units, [`SCALE_RANGE`] log bytes.
    pub scales: [u8; 3],
    /// One colour per octahedron face, sRGB8.
    pub colors: [[u8; 3]; 8],
    /// Three extremal normals per face, snorm8×3; `(0,0,0)` = absent.
    pub normals: [[[i8; 3]; 3]; 8],
    /// Bit `f` set: face `f` holds a distribution (sample by barycentric interpolation);
    /// clear: its present normals are a fixed set of one to three.
    pub distribution: u8,
    /// Sub-cell opacities, unorm8, index `x + 3y + 9z`.
    pub opacity: [u8; 27],
}

impl Default for VirtualMeshRecord {
    fn default() -> Self {
        bytemuck::Zeroable::zeroed()
    }
}

impl VirtualMeshRecord {
    /// Axis `k` of the eigenframe (unit).
    pub fn axis(&self, k: usize) -> Vec3 {
        decode_dir(self.axes[k])
    }
    /// Semi-axis `k` in voxel units.
    pub fn scale(&self, k: usize) -> f32 {
        SCALE_RANGE.decode(self.scales[k])
    }
    /// Colour of face `f`, linear.
    pub fn face_color(&self, f: usize) -> Vec3 {
        decode_srgb8(self.colors[f])
    }
    /// Extremal normal `i` of face `f` (zero if absent).
    pub fn normal(&self, f: usize, i: usize) -> Vec3 {
        decode_dir(self.normals[f][i])
    }
    /// Whether face `f` holds a distribution.
    pub fn is_distribution(&self, f: usize) -> bool {
        self.distribution >> f & 1 == 1
    }
    /// Opacity of sub-cell `(x, y, z)`, each in 0..3.
    pub fn subcell_opacity(&self, x: usize, y: usize, z: usize) -> f32 {
        from_unorm8(self.opacity[x + 3 * y + 9 * z])
    }
}

/// Specular appearance beside a record, for scenes whose materials have a specular lobe.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
pub struct SpecularRecord {
    /// Mean specular level (grey), unorm8.
    pub level: u8,
    /// Mean Blinn-Phong exponent, [`EXPONENT_RANGE`] log byte.
    pub exponent: u8,
}

impl SpecularRecord {
    /// Encodes a specular level and exponent.
    pub fn new(level: f32, exponent: f32) -> Self {
        Self { level: unorm8(level), exponent: EXPONENT_RANGE.encode(exponent) }
    }
    /// Specular level.
    pub fn level(&self) -> f32 {
        from_unorm8(self.level)
    }
    /// Blinn-Phong exponent.
    pub fn exponent(&self) -> f32 {
        EXPONENT_RANGE.decode(self.exponent)
    }
}

/// Which representation a voxel of an adaptive grid uses.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Kind {
    /// [`AverageRecord`].
    Average = 0,
    /// [`SggxRecord`].
    Sggx = 1,
    /// [`VirtualMeshRecord`].
    VirtualMesh = 2,
}

/// A voxel of an adaptive grid: its [`Kind`] in the top 2 bits and its index into that kind's
/// record array in the low 30 bits.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
pub struct AdaptiveRef(pub u32);

impl AdaptiveRef {
    /// Largest index: 2³⁰ − 1.
    pub const MAX_INDEX: u32 = (1 << 30) - 1;

    /// A reference; `None` if `index` exceeds [`AdaptiveRef::MAX_INDEX`].
    pub fn new(kind: Kind, index: u32) -> Option<Self> {
        (index <= Self::MAX_INDEX).then_some(Self((kind as u32) << 30 | index))
    }
    /// The kind.
    pub fn kind(self) -> Kind {
        match self.0 >> 30 {
            0 => Kind::Average,
            1 => Kind::Sggx,
            _ => Kind::VirtualMesh,
        }
    }
    /// The index into the kind's array.
    pub fn index(self) -> u32 {
        self.0 & Self::MAX_INDEX
    }
}

/// The Gaussian micro-surface of one voxel (Heitz and Neyret 2012 §5.2), as fitted to its
/// surface samples: the leaf record of voxlod-octree's `MicrosurfacePayload`. Lengths are in
/// voxel units; every field is `f32` (the statistics are pre-filtered up the octree, so they
/// are kept at full precision here).
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
pub struct MicrosurfaceRecord {
    /// Centroid of the surface in the voxel, voxel-local (in \[0, 1\]³ for surface samples).
    pub centroid: [f32; 3],
    /// The normal of the macro-surface plane through the centroid: the mean of the samples'
    /// unit normals (length ≤ 1: it shrinks as the normals spread), or a unit principal axis
    /// where the normals cancel (a thin two-sided sheet).
    pub plane_normal: [f32; 3],
    /// Second moments of the samples' unit normals `E[n nᵀ]`: `xx, yy, zz, xy, xz, yz`.
    pub normal_moments: [f32; 6],
    /// Variance of the samples' heights about the plane, voxels².
    pub height_variance: f32,
    /// Mean linear albedo `ā`.
    pub albedo: [f32; 3],
    /// Projection `aₛ` of the albedo on the height profile `s(h) = erf(h/(√2·σh))`.
    pub albedo_slope: [f32; 3],
    /// Mean specular level (0 for diffuse materials).
    pub specular: f32,
    /// Mean slope variance of the materials' own micro-facets (Blinn-Phong exponent `e` as
    /// `1/(e + 2)`, the Beckmann equivalent).
    pub roughness: f32,
}

macro_rules! byte_records {
    ($($t:ty => $tag:literal, $size:literal;)*) => {$(
        impl VxlRecord for $t {
            const TAG: [u8; 4] = *$tag;
            const FIELD_WIDTHS: &'static [u8] = &[1];
        }
        const _: () = assert!(size_of::<$t>() == $size);
    )*};
}

byte_records! {
    AverageRecord => b"AVG1", 8;
    SggxRecord => b"SGX1", 12;
    VirtualMeshRecord => b"VMS1", 136;
    SpecularRecord => b"SPC1", 2;
}

impl VxlRecord for AdaptiveRef {
    const TAG: [u8; 4] = *b"ADR1";
    const FIELD_WIDTHS: &'static [u8] = &[4];
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sggx_round_trip_keeps_a_positive_definite_matrix() {
        // Surface-like: n = z, roughness 0.1.
        let n = Vec3::new(0.0, 0.6, 0.8);
        let s = Mat3::from_cols(n * n.x, n * n.y, n * n.z) * 0.99
            + Mat3::from_diagonal(Vec3::splat(0.01));
        let rec = SggxRecord::new(s, Vec3::splat(0.5), 3.0, 0.25);
        let d = rec.matrix();
        assert!(d.determinant() > 0.0, "{d}");
        // Same shape up to scale: the projected-area ratio along n vs a tangent is preserved.
        let pa = |m: Mat3, w: Vec3| w.dot(m * w).sqrt();
        let t = Vec3::X;
        let (before, after) = (pa(s, n) / pa(s, t), pa(d, n) / pa(d, t));
        assert!((before - after).abs() / before < 0.05, "{before} vs {after}");
        assert!((rec.sigma_t() - 3.0).abs() < 0.06 && (rec.gamma() - 0.25).abs() < 0.003);
        // Rank-deficient (all normals equal) and zero matrices stay finite and PD.
        for m in [Mat3::from_cols(Vec3::Z * 0.0, Vec3::Z * 0.0, Vec3::Z), Mat3::ZERO] {
            let d = SggxRecord::new(m, Vec3::ONE, 0.0, 1.0).matrix();
            assert!(d.is_finite() && d.determinant() > 0.0, "{d}");
        }
    }

    #[test]
    fn adaptive_refs_pack_kind_and_index() {
        for kind in [Kind::Average, Kind::Sggx, Kind::VirtualMesh] {
            let r = AdaptiveRef::new(kind, AdaptiveRef::MAX_INDEX).unwrap();
            assert_eq!((r.kind(), r.index()), (kind, AdaptiveRef::MAX_INDEX));
        }
        assert!(AdaptiveRef::new(Kind::Sggx, 1 << 30).is_none());
    }

    #[test]
    fn records_decode_what_they_encode() {
        let a = AverageRecord::new(Vec3::new(0.2, 0.5, 0.9), Vec3::new(0.0, 1.0, 0.0), 0.75);
        assert!((a.color() - Vec3::new(0.2, 0.5, 0.9)).abs().max_element() < 0.01);
        assert!((a.normal() - Vec3::Y).length() < 1e-6);
        assert!((a.opacity() - 0.75).abs() <= 0.5 / 255.0);
        let s = SpecularRecord::new(0.3, 64.0);
        assert!((s.exponent() - 64.0).abs() / 64.0 < 0.02);
    }
}
