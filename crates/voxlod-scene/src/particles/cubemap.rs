//! [`DisplacementMap`]: a cube map of 3D fractal noise sampled on the unit sphere (seed 001,
//! Figure 5.8), so that a fill reads one bilinear texel look-up per voxel instead of evaluating
//! 3D noise.
//!
//! Face layout: face `2a + (sign < 0)` for major axis `a ∈ {x, y, z}`; on that face the texel
//! coordinates are `(p[(a+1)%3], p[(a+2)%3]) / |p[a]|` in [−1, 1]², texel centres at
//! `(i + 0.5) / N · 2 − 1`. Building and sampling use the same mapping; a bilinear look-up is
//! clamped at a face's edge (no filtering across faces).

use glam::Vec3;

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
        Ok(Self { face_size, texels })
    }

    /// A map of one value (clamped to [0, 1]): `0` gives plain spheres of the inner radius,
    /// `1` of the outer radius.
    pub fn constant(value: f32) -> Self {
        let v = if value.is_nan() { 0.0 } else { value.clamp(0.0, 1.0) };
        Self { face_size: 1, texels: vec![v; 6] }
    }

    /// Texels per face edge.
    pub fn face_size(&self) -> u32 {
        self.face_size
    }

    /// Heap bytes of the texels.
    pub fn bytes(&self) -> usize {
        self.texels.len() * std::mem::size_of::<f32>()
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
