//! Watertight ray/triangle intersection (Woop, Benthin and Wald, "Watertight Ray/Triangle
//! Intersection", JCGT 2013), on triangles stored three vertices at a time in SIMD lanes.
//!
//! Why it is watertight: every vertex is translated to the ray origin and sheared into ray space
//! by the same operations wherever it appears, so two triangles sharing an edge compute the edge
//! function of that edge from bit-identical inputs; `a·b − c·d` and `c·d − a·b` round to exact
//! negatives (Rust never contracts them into an FMA), and an edge function of 0 counts as inside.
//! A ray through a shared edge or vertex therefore hits at least one of the triangles around it:
//! no cracks, whatever the mesh's scale. The paper's double-precision fallback for edge
//! functions that round to 0 is not needed for that property and is omitted (WGSL has no `f64`
//! either; a WGSL port must keep the two products unfused to stay watertight).

use glam::{Vec3, Vec4, Vec4Swizzles};

/// A triangle laid out for intersection: lane `i` of `x`, `y`, `z` holds vertex `i` (lane 3 is
/// zero, so it never produces NaN).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[repr(C)]
pub(crate) struct SoaTriangle {
    x: Vec4,
    y: Vec4,
    z: Vec4,
}

impl SoaTriangle {
    /// Packs three vertices.
    pub(crate) fn new([a, b, c]: [Vec3; 3]) -> Self {
        Self {
            x: Vec4::new(a.x, b.x, c.x, 0.0),
            y: Vec4::new(a.y, b.y, c.y, 0.0),
            z: Vec4::new(a.z, b.z, c.z, 0.0),
        }
    }
}

/// Per-ray constants of the watertight test: the dominant axis and the shear.
///
/// The permuted axes are `kx = kz + 1`, `ky = kz + 2` (mod 3), without the paper's swap for
/// negative `d[kz]`: the swap only fixes the sign of the determinant, which flips the signs of
/// all three edge functions together and leaves the barycentrics and `t` unchanged. The
/// intersection routine is instantiated once per dominant axis ([`ShearedRay::intersect`]'s
/// `KZ`), so the permutation costs nothing per triangle.
#[derive(Clone, Copy, Debug)]
pub(crate) struct ShearedRay {
    origin: Vec3,
    /// The dominant axis of the direction.
    pub kz: usize,
    /// Shear constants `(d[kx]/d[kz], d[ky]/d[kz], 1/d[kz])`.
    s: Vec3,
}

/// Barycentrics and distance of a ray/triangle hit. `u` and `v` weight vertices 1 and 2 (vertex
/// 0 gets `1 − u − v`), the convention of `Geometry::interpolate`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct TriangleHit {
    pub t: f32,
    pub u: f32,
    pub v: f32,
}

impl ShearedRay {
    /// Precomputes the ray. `dir` must be finite and non-zero (the caller checks).
    #[inline]
    pub(crate) fn new(origin: Vec3, dir: Vec3) -> Self {
        let a = dir.abs();
        let kz = if a.x >= a.y && a.x >= a.z {
            0
        } else if a.y >= a.z {
            1
        } else {
            2
        };
        let (kx, ky) = ((kz + 1) % 3, (kz + 2) % 3);
        let s = Vec3::new(dir[kx] / dir[kz], dir[ky] / dir[kz], 1.0 / dir[kz]);
        Self { origin, kz, s }
    }

    /// Intersects `tri`, accepting `t` in `[t_min, t_max]`. Edges and vertices count as inside;
    /// both faces are hit; a degenerate (zero-area in ray space) triangle is never hit. `KZ`
    /// must be the ray's [`ShearedRay::kz`].
    #[inline(always)]
    pub(crate) fn intersect<const KZ: usize>(
        &self,
        tri: &SoaTriangle,
        t_min: f32,
        t_max: f32,
    ) -> Option<TriangleHit> {
        debug_assert_eq!(KZ, self.kz);
        let x = tri.x - Vec4::splat(self.origin.x);
        let y = tri.y - Vec4::splat(self.origin.y);
        let z = tri.z - Vec4::splat(self.origin.z);
        let (px, py, pz) = match KZ {
            0 => (y, z, x),
            1 => (z, x, y),
            _ => (x, y, z),
        };
        // Lanes: vertices A, B, C in sheared ray space.
        let ax = px - Vec4::splat(self.s.x) * pz;
        let ay = py - Vec4::splat(self.s.y) * pz;
        // Edge functions, lane 0 = U (weight of A), 1 = V (B), 2 = W (C):
        // U = Cx·By − Cy·Bx, V = Ax·Cy − Ay·Cx, W = Bx·Ay − By·Ax.
        let x1 = ax.yzxw();
        let x2 = ax.zxyw();
        let y1 = ay.yzxw();
        let y2 = ay.zxyw();
        let uvw = x2 * y1 - y2 * x1;
        let negative = uvw.cmplt(Vec4::ZERO).bitmask() & 7;
        let positive = uvw.cmpgt(Vec4::ZERO).bitmask() & 7;
        if negative != 0 && positive != 0 {
            return None;
        }
        let det = uvw.x + uvw.y + uvw.z;
        if det == 0.0 {
            return None;
        }
        let az = Vec4::splat(self.s.z) * pz;
        let big_t = uvw.x * az.x + uvw.y * az.y + uvw.z * az.z;
        let inv_det = 1.0 / det;
        let t = big_t * inv_det;
        // NaN (never expected for finite input) fails both comparisons and misses.
        if !(t >= t_min && t <= t_max) {
            return None;
        }
        Some(TriangleHit { t, u: uvw.y * inv_det, v: uvw.z * inv_det })
    }
}

impl ShearedRay {
    /// [`ShearedRay::intersect`] with the dominant axis dispatched at run time (references
    /// and tests).
    #[cfg(test)]
    pub(crate) fn test(&self, tri: &SoaTriangle, t_min: f32, t_max: f32) -> Option<TriangleHit> {
        match self.kz {
            0 => self.intersect::<0>(tri, t_min, t_max),
            1 => self.intersect::<1>(tri, t_min, t_max),
            _ => self.intersect::<2>(tri, t_min, t_max),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn hit(o: Vec3, d: Vec3, tri: [Vec3; 3]) -> Option<TriangleHit> {
        ShearedRay::new(o, d).test(&SoaTriangle::new(tri), 0.0, f32::INFINITY)
    }

    const TRI: [Vec3; 3] = [Vec3::ZERO, Vec3::X, Vec3::Y];

    #[test]
    fn barycentrics_follow_the_geometry_convention() {
        let h = hit(Vec3::new(0.25, 0.5, 2.0), Vec3::NEG_Z, TRI).unwrap();
        assert!((h.t - 2.0).abs() < 1e-6, "{h:?}");
        assert!((h.u - 0.25).abs() < 1e-6 && (h.v - 0.5).abs() < 1e-6, "{h:?}");
        // From behind, along every dominant axis and sign.
        let h = hit(Vec3::new(0.25, 0.5, -3.0), Vec3::Z, TRI).unwrap();
        assert!((h.t - 3.0).abs() < 1e-6 && (h.u - 0.25).abs() < 1e-6, "{h:?}");
        let tilted =
            [Vec3::new(0.0, -1.0, -1.0), Vec3::new(0.0, 1.0, -1.0), Vec3::new(0.0, 0.0, 1.0)];
        for d in [Vec3::X, Vec3::NEG_X] {
            let h = hit(Vec3::new(-d.x * 5.0, 0.0, 0.0), d, tilted).unwrap();
            assert!((h.t - 5.0).abs() < 1e-5, "{h:?}");
            assert!((h.u - 0.25).abs() < 1e-6 && (h.v - 0.5).abs() < 1e-6, "{h:?}");
        }
    }

    #[test]
    fn misses_outside_range_and_degenerate() {
        assert!(hit(Vec3::new(0.8, 0.8, 1.0), Vec3::NEG_Z, TRI).is_none());
        assert!(hit(Vec3::new(0.2, 0.2, -1.0), Vec3::NEG_Z, TRI).is_none(), "behind the origin");
        let r = ShearedRay::new(Vec3::new(0.2, 0.2, 1.0), Vec3::NEG_Z);
        assert!(r.test(&SoaTriangle::new(TRI), 0.0, 0.5).is_none());
        assert!(r.test(&SoaTriangle::new(TRI), 1.5, 9.0).is_none());
        // Edge-on and zero-area triangles.
        assert!(hit(Vec3::new(0.2, 0.2, 0.0), Vec3::X, TRI).is_none());
        assert!(
            hit(Vec3::new(0.2, 0.2, 1.0), Vec3::NEG_Z, [Vec3::ZERO, Vec3::X, Vec3::X * 2.0])
                .is_none()
        );
    }

    #[test]
    fn shared_edges_and_vertices_are_hit() {
        // A fan of 6 triangles around the origin: rays exactly through the shared centre vertex
        // and exactly along the shared spokes hit at least one triangle.
        let ring: Vec<Vec3> = (0..6)
            .map(|i| {
                let a = i as f32 * std::f32::consts::TAU / 6.0;
                Vec3::new(a.cos(), a.sin(), 0.0) * 1.7
            })
            .collect();
        let tris: Vec<[Vec3; 3]> =
            (0..6).map(|i| [Vec3::ZERO, ring[i], ring[(i + 1) % 6]]).collect();
        let targets = ring.iter().map(|&p| p * 0.5).chain([Vec3::ZERO]);
        for target in targets {
            for eye in [Vec3::new(0.3, -0.2, 2.0), Vec3::new(-1.0, 4.0, -3.0)] {
                let d = (target - eye).normalize();
                let hits = tris.iter().filter(|&&t| hit(eye, d, t).is_some()).count();
                assert!(hits >= 1, "a ray through {target} leaked through the fan");
            }
        }
    }
}
