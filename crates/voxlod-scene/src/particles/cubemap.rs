//! [`DisplacementMap`]: a cube map of 3D fractal noise sampled on the unit sphere (McNabb 2015,
//! Figure 5.8), so that a fill reads one bilinear texel look-up per voxel instead of evaluating
//! 3D noise.
//!
//! Face layout: face `2a + (sign < 0)` for major axis `a ∈ {x, y, z}`; on that face the texel
//! coordinates are `(p[(a+1)%3], p[(a+2)%3]) / |p[a]|` in [−1, 1]², texel centres at
//! `(i + 0.5) / N · 2 − 1`. Building and sampling use the same mapping; a bilinear look-up is
//! clamped at a face's edge (no filtering across faces).

use glam::{BVec4A, IVec4, Vec3, Vec4};

use crate::procedural::noise::fbm3;
use crate::{Error, Result};

/// Largest face edge accepted (6 · 1024² floats = 24 MiB).
pub const MAX_FACE_SIZE: u32 = 1024;

/// A cube map of displacements in [0, 1].
#[derive(Clone, Debug, PartialEq)]
pub struct DisplacementMap {
    face_size: u32,
    /// `6 · face_size²` texels, face-major, then row-major.
    texels: Vec<f32>,
    /// The texels again, each face `(face_size + 1)²` with its last column and row repeated
    /// (the bilinear clamp built in): texel `(x0, y0)` and its three neighbours are two pairs
    /// of adjacent floats, one row apart, at any `x0, y0 < face_size`
    /// ([`DisplacementMap::sample4`]).
    padded: Vec<f32>,
    /// Smallest and largest texel.
    range: [f32; 2],
}

impl DisplacementMap {
    /// `0.5 + 0.5 · fbm3(seed, direction · frequency, octaves)`, clamped to [0, 1], sampled at
    /// every texel's direction. Errors on `face_size` outside `1..=MAX_FACE_SIZE`, a non-finite
    /// or non-positive frequency, or more than 16 octaves.
    pub fn noise(seed: u64, face_size: u32, frequency: f32, octaves: u32) -> Result<Self> {
        let bad = |name: &str, value: String, reason: String| {
            Err(Error::InvalidParameter { name: name.into(), value, reason })
        };
        if !(1..=MAX_FACE_SIZE).contains(&face_size) {
            return bad(
                "cube map face size",
                face_size.to_string(),
                format!("1..={MAX_FACE_SIZE}"),
            );
        }
        if !(frequency.is_finite() && frequency > 0.0) {
            return bad("noise frequency", frequency.to_string(), "finite and > 0".into());
        }
        if octaves > 16 {
            return bad("noise octaves", octaves.to_string(), "at most 16".into());
        }
        let n = face_size as usize;
        let mut texels = Vec::with_capacity(6 * n * n);
        for face in 0..6 {
            let (a, sign) = (face / 2, if face % 2 == 0 { 1.0 } else { -1.0 });
            for j in 0..n {
                for i in 0..n {
                    let u = (i as f32 + 0.5) / n as f32 * 2.0 - 1.0;
                    let v = (j as f32 + 0.5) / n as f32 * 2.0 - 1.0;
                    let mut p = [0.0f32; 3];
                    p[a] = sign;
                    p[(a + 1) % 3] = u;
                    p[(a + 2) % 3] = v;
                    let dir = Vec3::from_array(p).normalize();
                    let value = 0.5 + 0.5 * fbm3(seed, dir * frequency, octaves);
                    texels.push(value.clamp(0.0, 1.0));
                }
            }
        }
        Ok(Self::from_texels(face_size, texels))
    }

    /// The map of `texels` (`6 · face_size²`, in [0, 1]) with its padded copy and range.
    fn from_texels(face_size: u32, texels: Vec<f32>) -> Self {
        let n = face_size as usize;
        let mut padded = Vec::with_capacity(6 * (n + 1) * (n + 1));
        for face in texels.chunks_exact(n * n) {
            for y in 0..=n {
                let row = &face[y.min(n - 1) * n..][..n];
                padded.extend_from_slice(row);
                padded.push(row[n - 1]);
            }
        }
        let range = texels
            .iter()
            .fold([f32::INFINITY, f32::NEG_INFINITY], |[lo, hi], &t| [lo.min(t), hi.max(t)]);
        Self { face_size, texels, padded, range }
    }

    /// A map of one value (clamped to [0, 1]): `0` gives plain spheres of the inner radius,
    /// `1` of the outer radius.
    pub fn constant(value: f32) -> Self {
        let v = if value.is_nan() { 0.0 } else { value.clamp(0.0, 1.0) };
        Self::from_texels(1, vec![v; 6])
    }

    /// Texels per face edge.
    pub fn face_size(&self) -> u32 {
        self.face_size
    }

    /// Heap bytes of the texels (and of their padded copy).
    pub fn bytes(&self) -> usize {
        (self.texels.len() + self.padded.len()) * std::mem::size_of::<f32>()
    }

    /// Bounds `[lo, hi]` on every value [`DisplacementMap::sample`] and
    /// [`DisplacementMap::sample4`] return for finite directions: the smallest and largest
    /// texel, widened by a relative 2⁻²⁰ for the rounding of the bilinear lerps (each lerp of
    /// values in `[m, M]` lies in `[m(1 − u)³, M(1 + u)³]`, `u = 2⁻²⁴`; two levels of lerp). A
    /// fill rejects a voxel beyond `inner + amplitude · hi` and accepts one within
    /// `inner + amplitude · lo` without reading the map.
    pub fn bounds(&self) -> [f32; 2] {
        const WIDEN: f32 = 1.0 / (1 << 20) as f32;
        [self.range[0] * (1.0 - WIDEN), self.range[1] * (1.0 + WIDEN)]
    }

    /// The texels, `6 · face_size²`, face-major then row-major (for a GPU upload).
    pub fn texels(&self) -> &[f32] {
        &self.texels
    }

    /// The displacement in direction `dir` (any length; the zero vector reads face +x's
    /// centre), bilinear within the face, in [0, 1].
    ///
    /// Written without arrays indexed by the major axis (which kept the vector on the stack)
    /// and with one face slice: the same operations in the same order as the plain mapping of
    /// the module docs, so the same bits. Always inlined: the fill calls it once per voxel, and
    /// a call passes the direction through memory.
    #[inline(always)]
    pub fn sample(&self, dir: Vec3) -> f32 {
        let abs = dir.abs();
        // (face, |major|, first and second minor coordinates): axes (a+1)%3 and (a+2)%3.
        let (face, major, pu, pv) = if abs.x >= abs.y && abs.x >= abs.z {
            (usize::from(dir.x < 0.0), abs.x, dir.y, dir.z)
        } else if abs.y >= abs.z {
            (2 + usize::from(dir.y < 0.0), abs.y, dir.z, dir.x)
        } else {
            (4 + usize::from(dir.z < 0.0), abs.z, dir.x, dir.y)
        };
        let (u, v) = if major > 0.0 { (pu / major, pv / major) } else { (0.0, 0.0) };
        let n = self.face_size as usize;
        let nf = n as f32;
        let last = (n - 1) as f32;
        let x = ((u + 1.0) * 0.5 * nf - 0.5).clamp(0.0, last);
        let y = ((v + 1.0) * 0.5 * nf - 0.5).clamp(0.0, last);
        let (x0, y0) = (x as usize, y as usize);
        let (x1, y1) = ((x0 + 1).min(n - 1), (y0 + 1).min(n - 1));
        let (fx, fy) = (x - x0 as f32, y - y0 as f32);
        let t = &self.texels[face * n * n..(face + 1) * n * n];
        let (r0, r1) = (&t[y0 * n..y0 * n + n], &t[y1 * n..y1 * n + n]);
        let (a0, b0, a1, b1) = (r0[x0], r0[x1], r1[x0], r1[x1]);
        let (r0, r1) = (a0 + (b0 - a0) * fx, a1 + (b1 - a1) * fx);
        r0 + (r1 - r0) * fy
    }

    /// Four look-ups at once: lane `i` is [`DisplacementMap::sample`] of `(x[i], y[i], z[i])`,
    /// **the same bits** for finite directions (every step is the scalar one, lane-wise: face
    /// selection by selects, the two divisions, the clamp as two compares, the truncation, the
    /// same bilinear lerps, the four texels read from the padded copy, whose indices are formed
    /// in `f32`, exact below 2²⁴).
    /// Non-finite lanes give some value in [0, 1] or NaN, never a panic. For the fill, which
    /// reads the map once per covered voxel, four voxels of a row at a time.
    #[inline(always)]
    pub fn sample4(&self, x: Vec4, y: Vec4, z: Vec4) -> Vec4 {
        let zero = Vec4::ZERO;
        let (ax, ay, az) = (x.abs(), y.abs(), z.abs());
        let xm = ax.cmpge(ay) & ax.cmpge(az);
        let ym = !xm & ay.cmpge(az);
        let pick = |m: BVec4A, a: Vec4, b: Vec4| Vec4::select(m, a, b);
        let neg = |d: Vec4| pick(d.cmplt(zero), Vec4::ONE, zero);
        let face = pick(xm, neg(x), pick(ym, neg(y) + 2.0, neg(z) + 4.0));
        let major = pick(xm, ax, pick(ym, ay, az));
        let (pu, pv) = (pick(xm, y, pick(ym, z, x)), pick(xm, z, pick(ym, x, y)));
        let positive = major.cmpgt(zero);
        let (u, v) = (pick(positive, pu / major, zero), pick(positive, pv / major, zero));
        let n = self.face_size as usize;
        let nf = Vec4::splat(n as f32);
        let last = Vec4::splat((n - 1) as f32);
        // `f32::clamp(0, last)`: the same two compares (a NaN stays NaN).
        let clamp = |t: Vec4| {
            let t = pick(t.cmplt(zero), zero, t);
            pick(t.cmpgt(last), last, t)
        };
        let tx = clamp((u + 1.0) * 0.5 * nf - 0.5);
        let ty = clamp((v + 1.0) * 0.5 * nf - 0.5);
        // The scalar `as usize` truncates (here x ≥ 0) and takes NaN to 0: `max` takes NaN to
        // 0 (SSE's max returns its second operand) and leaves the rest alone.
        let (x0, y0) = (trunc4(tx.max(zero)).as_vec4(), trunc4(ty.max(zero)).as_vec4());
        let (fx, fy) = (tx - x0, ty - y0);
        // The texels at (x0, y0), (x1, y0), (x0, y1), (x1, y1), `x1 = min(x0 + 1, n − 1)`:
        // in the padded copy, two adjacent pairs one padded row apart.
        let stride = n + 1;
        let sf = Vec4::splat(stride as f32);
        let [c0, c1, c2, c3] = trunc4(face * (sf * sf) + y0 * sf + x0).to_array();
        // One bounds check per lane; written out (an array `map` here was not inlined into
        // the AVX2 build of the fill, and passed the texels through memory).
        let p = &self.padded;
        let q0 = &p[c0 as usize..][..stride + 2];
        let q1 = &p[c1 as usize..][..stride + 2];
        let q2 = &p[c2 as usize..][..stride + 2];
        let q3 = &p[c3 as usize..][..stride + 2];
        let a0 = Vec4::new(q0[0], q1[0], q2[0], q3[0]);
        let b0 = Vec4::new(q0[1], q1[1], q2[1], q3[1]);
        let a1 = Vec4::new(q0[stride], q1[stride], q2[stride], q3[stride]);
        let t = stride + 1;
        let b1 = Vec4::new(q0[t], q1[t], q2[t], q3[t]);
        let (r0, r1) = (a0 + (b0 - a0) * fx, a1 + (b1 - a1) * fx);
        r0 + (r1 - r0) * fy
    }

    /// The plain look-up [`DisplacementMap::sample`] is checked against (major axis by index).
    #[cfg(test)]
    pub(crate) fn sample_plain(&self, dir: Vec3) -> f32 {
        let abs = dir.abs();
        let a = if abs.x >= abs.y && abs.x >= abs.z {
            0
        } else if abs.y >= abs.z {
            1
        } else {
            2
        };
        let p = dir.to_array();
        let major = abs.to_array()[a];
        let face = 2 * a + usize::from(p[a] < 0.0);
        let (u, v) =
            if major > 0.0 { (p[(a + 1) % 3] / major, p[(a + 2) % 3] / major) } else { (0.0, 0.0) };
        let n = self.face_size as usize;
        let last = (n - 1) as f32;
        let x = ((u + 1.0) * 0.5 * n as f32 - 0.5).clamp(0.0, last);
        let y = ((v + 1.0) * 0.5 * n as f32 - 0.5).clamp(0.0, last);
        let (x0, y0) = (x as usize, y as usize);
        let (x1, y1) = ((x0 + 1).min(n - 1), (y0 + 1).min(n - 1));
        let (fx, fy) = (x - x0 as f32, y - y0 as f32);
        let t = &self.texels[face * n * n..(face + 1) * n * n];
        let row = |y: usize| t[y * n + x0] + (t[y * n + x1] - t[y * n + x0]) * fx;
        let (r0, r1) = (row(y0), row(y1));
        r0 + (r1 - r0) * fy
    }
}

/// Lane-wise truncation toward zero of values in `i32` range (`cvttps2dq` on x86: glam's
/// `as_ivec4` converts lane by lane with Rust's saturating `as`, four scalar conversions and
/// their range checks).
#[inline(always)]
fn trunc4(v: Vec4) -> IVec4 {
    #[cfg(all(any(target_arch = "x86", target_arch = "x86_64"), target_feature = "sse2"))]
    {
        #[cfg(target_arch = "x86")]
        use std::arch::x86::_mm_cvttps_epi32;
        #[cfg(target_arch = "x86_64")]
        use std::arch::x86_64::_mm_cvttps_epi32;
        // SAFETY: SSE2 is enabled at compile time (the `cfg` above); no memory is touched.
        let lanes: [i32; 4] = bytemuck::cast(unsafe { _mm_cvttps_epi32(v.into()) });
        IVec4::from_array(lanes)
    }
    #[cfg(not(all(any(target_arch = "x86", target_arch = "x86_64"), target_feature = "sse2")))]
    {
        v.as_ivec4()
    }
}
