//! [`MicrosurfacePayload`], its pre-filter (module docs of [`crate::microsurface`]) and the
//! statistics a renderer reads from a sample ([`Microsurface`]).

use glam::{DVec3, Mat3, Vec3};
use voxlod_format::records::MicrosurfaceRecord;

use super::special::erf_approx;
use crate::payload::Payload;

/// Gauss–Hermite nodes and weights for `E[f(Z)]`, `Z ~ N(0, 1)`, 8 points (exact for
/// polynomials up to degree 15).
const GAUSS_HERMITE: [(f64, f64); 8] = [
    (-4.144_547_186_125_894, 0.000_112_614_538_375_367_77),
    (-2.802_485_861_287_541_7, 0.009_635_220_120_788_267),
    (-1.636_519_042_435_108, 0.117_239_907_661_759_02),
    (-0.539_079_811_351_375_1, 0.373_012_257_679_077_35),
    (0.539_079_811_351_375_1, 0.373_012_257_679_077_35),
    (1.636_519_042_435_108, 0.117_239_907_661_759_02),
    (2.802_485_861_287_541_7, 0.009_635_220_120_788_267),
    (4.144_547_186_125_894, 0.000_112_614_538_375_367_77),
];

/// `erf(z/√2)` at the [`GAUSS_HERMITE`] nodes: a child's own colour profile `s(ε)` at
/// `ε = σ·z`.
const PROFILE: [f64; 8] = [
    -0.999_965_951_415_681_6,
    -0.994_928_956_087_327_6,
    -0.898_268_996_346_759_4,
    -0.410_168_214_744_767_95,
    0.410_168_214_744_767_95,
    0.898_268_996_346_759_4,
    0.994_928_956_087_327_6,
    0.999_965_951_415_681_6,
];

/// In-plane spread `E|u|²` of the surface in a node, node units²: a node-sized square
/// (`2·(1/12)`), used for the tilt of a child's plane across its extent.
const SPREAD: f64 = 1.0 / 6.0;

/// A node of the Gaussian micro-surface (Heitz and Neyret 2012 §5.2), premultiplied by
/// coverage (module docs of [`crate::microsurface`]). 88 bytes, `f32` only, `#[repr(C)]`.
///
/// A **stored** node holds its centroid relative to its centre in node units; a **sampled**
/// payload ([`crate::Octree::sample`]) holds it relative to the sample point in voxels.
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
pub struct MicrosurfacePayload {
    /// Coverage `c` in \[0, 1\]: the fraction of the node's leaves that hold surface.
    pub coverage: f32,
    /// `c·ȳ`: the surface's centroid, relative to the node's centre (or the sample point). The
    /// macro-surface is the plane through it perpendicular to `n̄`.
    pub centroid: [f32; 3],
    /// `c·n̄`, the mean unit normal (not renormalized).
    pub normal: [f32; 3],
    /// `c·E[n nᵀ]`: `xx, yy, zz, xy, xz, yz`.
    pub normal_moments: [f32; 6],
    /// `c·σh²`, the height variance about the plane.
    pub height_variance: f32,
    /// `c·ā`, the mean linear albedo.
    pub albedo: [f32; 3],
    /// `c·aₛ`, the albedo's projection on the height profile (H5bis).
    pub albedo_slope: [f32; 3],
    /// `c·` the mean specular level.
    pub specular: f32,
    /// `c·σₚ²`, the materials' own micro-facet slope variance.
    pub roughness: f32,
}

/// What a renderer reads from a sampled [`MicrosurfacePayload`] ([`MicrosurfacePayload::
/// decode`]): the statistics divided by coverage, lengths in voxels at the sample point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Microsurface {
    /// Coverage weight of the sample (the trilinear mix of the corners' coverages).
    pub coverage: f32,
    /// Signed distance from the sample point to the macro-surface plane along `normal`,
    /// voxels (positive outside).
    pub distance: f32,
    /// Unit macro-normal.
    pub normal: Vec3,
    /// `|n̄|` in \[0, 1\]: 1 when every micro-normal is the macro-normal.
    pub normal_length: f32,
    /// `E[n nᵀ]` of the micro-normals.
    pub normal_moments: Mat3,
    /// `σh²`, voxels².
    pub height_variance: f32,
    /// `ā`.
    pub albedo: Vec3,
    /// `aₛ`.
    pub albedo_slope: Vec3,
    /// Mean specular level.
    pub specular: f32,
    /// Material micro-facet slope variance `σₚ²`.
    pub roughness: f32,
}

fn sym(m: [f32; 6]) -> Mat3 {
    let [xx, yy, zz, xy, xz, yz] = m;
    Mat3::from_cols(Vec3::new(xx, xy, xz), Vec3::new(xy, yy, yz), Vec3::new(xz, yz, zz))
}

impl Microsurface {
    /// Variance of the micro-slopes along unit tangent direction `t` (perpendicular to
    /// [`Microsurface::normal`]): `tᵀ E[n nᵀ] t / nᵀ E[n nᵀ] n` (tangential over normal
    /// second moment, the slope's second moment for moderate slopes). `+∞` when no
    /// micro-normal has a component along the macro-normal.
    pub fn slope_variance_along(&self, t: Vec3) -> f32 {
        let along = self.normal.dot(self.normal_moments * self.normal);
        let across = t.dot(self.normal_moments * t).max(0.0);
        if along > 0.0 { across / along } else { f32::INFINITY }
    }
    /// Isotropic slope variance per axis: the mean over tangent directions,
    /// `(tr E[n nᵀ] − nᵀ E[n nᵀ] n) / (2·nᵀ E[n nᵀ] n)`.
    pub fn slope_variance(&self) -> f32 {
        let m = self.normal_moments;
        let along = self.normal.dot(m * self.normal);
        let trace = m.x_axis.x + m.y_axis.y + m.z_axis.z;
        if along > 0.0 { (trace - along).max(0.0) / (2.0 * along) } else { f32::INFINITY }
    }
}

impl MicrosurfacePayload {
    /// The leaf of a voxel's record (coverage 1; a voxel is one node unit wide).
    pub fn from_record(r: &MicrosurfaceRecord) -> Self {
        Self {
            coverage: 1.0,
            centroid: (Vec3::from(r.centroid) - 0.5).to_array(),
            normal: r.plane_normal,
            normal_moments: r.normal_moments,
            height_variance: r.height_variance,
            albedo: r.albedo,
            albedo_slope: r.albedo_slope,
            specular: r.specular,
            roughness: r.roughness,
        }
    }

    /// The statistics divided by coverage (lengths in the payload's units: voxels at the
    /// sample point for a sampled payload). `None` where there is no surface: zero coverage,
    /// or a zero mean normal (no plane).
    pub fn decode(&self) -> Option<Microsurface> {
        let c = self.coverage;
        let g = Vec3::from(self.normal);
        let len = g.length();
        if !(c > 0.0 && len > 0.0 && len.is_finite()) {
            return None;
        }
        let inv = 1.0 / c;
        let normal = g / len;
        Some(Microsurface {
            coverage: c,
            // The sample point relative to the centroid is −centroid.
            distance: -normal.dot(Vec3::from(self.centroid) * inv),
            normal,
            normal_length: (len * inv).min(1.0),
            normal_moments: sym(self.normal_moments) * inv,
            height_variance: (self.height_variance * inv).max(0.0),
            albedo: Vec3::from(self.albedo) * inv,
            albedo_slope: Vec3::from(self.albedo_slope) * inv,
            specular: self.specular * inv,
            roughness: self.roughness * inv,
        })
    }

    fn fields(&self) -> [f32; 22] {
        bytemuck::cast(*self)
    }

    fn fields_mut(&mut self) -> &mut [f32; 22] {
        bytemuck::cast_mut(self)
    }
}

impl Payload for MicrosurfacePayload {
    #[inline]
    fn empty() -> Self {
        Self::default()
    }

    fn prefilter(children: &[Self; 8]) -> Self {
        prefilter(children)
    }

    #[inline]
    fn add_scaled(&mut self, o: &Self, w: f32) {
        let src = o.fields();
        for (d, s) in self.fields_mut().iter_mut().zip(src) {
            *d += w * s;
        }
    }

    /// Moves `o` to the sample point (module docs of [`crate::microsurface`]): the centroid
    /// becomes `ȳ·size − offset` voxels from the point, the height variance `σh²·size²`.
    #[inline]
    fn add_scaled_at(&mut self, o: &Self, w: f32, offset: Vec3, size: f32) {
        let mut moved = *o;
        let c = Vec3::from(o.centroid) * size - offset * o.coverage;
        moved.centroid = c.to_array();
        moved.height_variance = o.height_variance * (size * size);
        self.add_scaled(&moved, w);
    }

    fn opacity(&self) -> f32 {
        self.coverage
    }

    fn check(&self) -> Option<&'static str> {
        let f = self.fields();
        if !f.iter().all(|x| x.is_finite()) {
            return Some("a component is NaN or infinite");
        }
        if !(0.0..=1.0).contains(&self.coverage) {
            return Some("coverage outside [0, 1]");
        }
        if self.height_variance < 0.0 || self.roughness < 0.0 {
            return Some("a variance is negative");
        }
        let m = &self.normal_moments;
        if m[0] < 0.0 || m[1] < 0.0 || m[2] < 0.0 {
            return Some("a normal second moment is negative");
        }
        None
    }

    fn max_abs_diff(&self, o: &Self) -> f32 {
        let (a, b) = (self.fields(), o.fields());
        a.iter().zip(&b).map(|(x, y)| (x - y).abs()).fold(0.0, f32::max)
    }
}

/// One child as the parent's pre-filter sees it, parent units, relative to the parent's centre.
#[derive(Clone, Copy, Default)]
struct Child {
    c: f64,
    /// Offset of the child's centroid from the parent's plane.
    delta: f64,
    /// Variance of the child's heights on the parent's plane (own heights tilted, plus tilt).
    var: f64,
    /// The child's own height standard deviation (parent units) and its heights' factor on
    /// the parent's axis (`cos φ`), for the colour profile.
    sigma: f64,
    cos: f64,
    /// Variance added by the tilt alone.
    tilt_var: f64,
    albedo: DVec3,
    slope: DVec3,
}

/// The parent of eight children (module docs of [`crate::microsurface`]).
fn prefilter(children: &[MicrosurfacePayload; 8]) -> MicrosurfacePayload {
    // The linear part: the mean of the eight children, each centroid moved into the parent's
    // frame first (child frame → parent frame: + (o − ½), then halved); the variance and aₛ
    // are replaced below.
    let mut p = MicrosurfacePayload::empty();
    let mut centroid = Vec3::ZERO;
    for (k, child) in children.iter().enumerate() {
        let o = Vec3::new((k & 1) as f32, (k >> 1 & 1) as f32, (k >> 2 & 1) as f32);
        p.add_scaled(child, 0.125);
        centroid += (Vec3::from(child.centroid) + (o - 0.5) * child.coverage) * 0.0625;
    }
    p.centroid = centroid.to_array();
    let total = p.coverage as f64;
    if total <= 0.0 {
        return MicrosurfacePayload::empty();
    }
    let g = Vec3::from(p.normal).as_dvec3() / total;
    let glen = g.length();
    let n_p = if glen > 0.0 { g / glen } else { DVec3::ZERO };
    let centroid_p = Vec3::from(p.centroid).as_dvec3() / total;
    let albedo_p = Vec3::from(p.albedo).as_dvec3() / total;
    let mut slots = [Child::default(); 8];
    let mut count = 0;
    for (k, ch) in children.iter().enumerate() {
        let c = ch.coverage as f64;
        if c <= 0.0 {
            continue;
        }
        let o = DVec3::new((k & 1) as f64, (k >> 1 & 1) as f64, (k >> 2 & 1) as f64);
        let y = (Vec3::from(ch.centroid).as_dvec3() / c + o - 0.5) * 0.5;
        let n = Vec3::from(ch.normal).as_dvec3() / c;
        let nlen = n.length();
        let n_hat = if nlen > 0.0 { n / nlen } else { n_p };
        let (delta, cos) =
            if glen > 0.0 { (n_p.dot(y - centroid_p), n_p.dot(n_hat)) } else { (0.0, 1.0) };
        let sin2 = (1.0 - cos * cos).max(0.0);
        let own = (ch.height_variance as f64 / c).max(0.0) * 0.25;
        let tilt_var = sin2 * SPREAD * 0.25 * 0.5;
        slots[count] = Child {
            c,
            delta,
            var: own * cos * cos + tilt_var,
            sigma: own.sqrt(),
            cos,
            tilt_var,
            albedo: Vec3::from(ch.albedo).as_dvec3() / c,
            slope: Vec3::from(ch.albedo_slope).as_dvec3() / c,
        };
        count += 1;
    }
    let kids = &slots[..count];
    let weight: f64 = kids.iter().map(|k| k.c).sum();
    let var_p = kids.iter().map(|k| k.c * (k.var + k.delta * k.delta)).sum::<f64>() / weight;
    p.height_variance = (total * var_p) as f32;
    let slope = albedo_slope(kids, var_p, albedo_p);
    p.albedo_slope = (slope * total).as_vec3().to_array();
    p
}

/// `aₛ` of the parent: `Σ c·E[s(h)·(a − ā)] / Σ c·E[s(h)²]` over the children's heights on the
/// parent's plane, `s` with the parent's `σh` (module docs of [`crate::microsurface`]).
fn albedo_slope(kids: &[Child], var_p: f64, albedo_p: DVec3) -> DVec3 {
    if var_p <= 0.0 {
        return DVec3::ZERO;
    }
    let s = |h: f64, var: f64| erf_approx(h / (2.0 * var).sqrt());
    let (mut num, mut den) = (DVec3::ZERO, 0.0);
    for k in kids {
        // E[s], closed form: a Gaussian blur of an erf is an erf.
        let mean_s = s(k.delta, var_p + k.var);
        // E[s²] over the child's total height N(δ, var).
        let mut s2 = 0.0;
        // E[s(h)·s_child(ε)], ε the child's own height: the tilt part of h blurs s in closed form.
        let mut cross = 0.0;
        for (i, &(z, w)) in GAUSS_HERMITE.iter().enumerate() {
            let v = s(k.delta + k.var.sqrt() * z, var_p);
            s2 += w * v * v;
            if k.sigma > 0.0 {
                let own = k.sigma * z;
                cross += w * s(k.delta + own * k.cos, var_p + k.tilt_var) * PROFILE[i];
            }
        }
        num += k.c * ((k.albedo - albedo_p) * mean_s + k.slope * cross);
        den += k.c * s2;
    }
    if den > 1e-12 { num / den } else { DVec3::ZERO }
}

#[cfg(test)]
mod tests;

const _: () = assert!(size_of::<MicrosurfacePayload>() == 88);
