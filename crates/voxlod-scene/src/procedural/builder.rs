//! [`MeshBuilder`]: appends vertices and triangles to one [`Mesh`], with the shapes the
//! generators share: quads, oriented boxes and tapered, slightly bent tubes (trunks, branches).
//! Winding is counter-clockwise seen from the front (outside), as [`Mesh`] requires.

use glam::{Vec2, Vec3};

use super::rng::sin_cos_turns;
use crate::Mesh;

/// Accumulates one mesh.
#[derive(Debug, Default)]
pub(crate) struct MeshBuilder {
    positions: Vec<Vec3>,
    normals: Vec<Vec3>,
    uvs: Vec<Vec2>,
    indices: Vec<[u32; 3]>,
    with_uvs: bool,
}

/// A tapered tube along a quadratic curve from `start` to `end`: the axis point at `t` is the
/// straight line plus `bend · 4t(1 − t)`, so the ends stay put and the middle bows by `bend`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Tube {
    /// Centre of the first ring.
    pub start: Vec3,
    /// Centre of the last ring.
    pub end: Vec3,
    /// Radius at `start`.
    pub r0: f32,
    /// Radius at `end`.
    pub r1: f32,
    /// Bow of the axis at its middle (perpendicular to it, ideally).
    pub bend: Vec3,
}

impl Tube {
    /// The axis point at `t` in [0, 1].
    #[inline]
    pub fn point(&self, t: f32) -> Vec3 {
        self.start + (self.end - self.start) * t + self.bend * (4.0 * t * (1.0 - t))
    }

    /// The radius at `t`.
    #[inline]
    pub fn radius(&self, t: f32) -> f32 {
        self.r0 + (self.r1 - self.r0) * t
    }

    /// The unit axis direction of the chord, start to end (+y for a zero-length tube).
    #[inline]
    pub fn direction(&self) -> Vec3 {
        (self.end - self.start).try_normalize().unwrap_or(Vec3::Y)
    }

    /// Chord length.
    #[inline]
    pub fn length(&self) -> f32 {
        (self.end - self.start).length()
    }

    /// Triangles [`MeshBuilder::tube`] emits for `sides` and `segments`.
    pub const fn triangle_count(sides: u32, segments: u32) -> u64 {
        2 * sides as u64 * segments as u64 + (sides as u64 - 2)
    }

    /// Vertices [`MeshBuilder::tube`] emits for `sides` and `segments`.
    pub const fn vertex_count(sides: u32, segments: u32) -> u64 {
        sides as u64 * (segments as u64 + 2)
    }
}

impl MeshBuilder {
    /// An empty builder with room for `vertices` and `triangles`; `with_uvs` decides whether the
    /// mesh carries texture coordinates.
    pub fn with_capacity(vertices: usize, triangles: usize, with_uvs: bool) -> Self {
        Self {
            positions: Vec::with_capacity(vertices),
            normals: Vec::with_capacity(vertices),
            uvs: Vec::with_capacity(if with_uvs { vertices } else { 0 }),
            indices: Vec::with_capacity(triangles),
            with_uvs,
        }
    }

    /// Appends a vertex and returns its index (`uv` ignored without UVs).
    #[inline]
    pub fn vertex(&mut self, p: Vec3, n: Vec3, uv: Vec2) -> u32 {
        let i = self.positions.len() as u32;
        self.positions.push(p);
        self.normals.push(n);
        if self.with_uvs {
            self.uvs.push(uv);
        }
        i
    }

    /// Appends a triangle.
    #[inline]
    pub fn triangle(&mut self, a: u32, b: u32, c: u32) {
        self.indices.push([a, b, c]);
    }

    /// Appends the quad `a b c d` (counter-clockwise) as triangles `a b c` and `a c d`.
    #[inline]
    pub fn quad(&mut self, a: u32, b: u32, c: u32, d: u32) {
        self.indices.push([a, b, c]);
        self.indices.push([a, c, d]);
    }

    /// Appends a flat quad with corners `corner`, `+ u`, `+ u + v`, `+ v`, facing `u × v`, with
    /// UVs (0,1), (1,1), (1,0), (0,0) (v of the texture runs against `v`).
    pub fn flat_quad(&mut self, corner: Vec3, u: Vec3, v: Vec3) {
        let n = u.cross(v).try_normalize().unwrap_or(Vec3::Y);
        let a = self.vertex(corner, n, Vec2::new(0.0, 1.0));
        let b = self.vertex(corner + u, n, Vec2::new(1.0, 1.0));
        let c = self.vertex(corner + u + v, n, Vec2::new(1.0, 0.0));
        let d = self.vertex(corner + v, n, Vec2::new(0.0, 0.0));
        self.quad(a, b, c, d);
    }

    /// Appends a flat grid of `n × n` quads over the parallelogram `corner + [0,1]·u + [0,1]·v`,
    /// facing `u × v`, with shared vertices and UVs spanning [0, 1]².
    pub fn grid(&mut self, corner: Vec3, u: Vec3, v: Vec3, n: u32) {
        let normal = u.cross(v).try_normalize().unwrap_or(Vec3::Y);
        let base = self.positions.len() as u32;
        for j in 0..=n {
            for i in 0..=n {
                let (s, t) = (i as f32 / n as f32, j as f32 / n as f32);
                self.vertex(corner + u * s + v * t, normal, Vec2::new(s, 1.0 - t));
            }
        }
        let at = |i: u32, j: u32| base + j * (n + 1) + i;
        for j in 0..n {
            for i in 0..n {
                self.quad(at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1));
            }
        }
    }

    /// Appends the faces of the box `center ± axes[k] · half[k]` (the axes orthonormal and
    /// right-handed) selected by `faces`: bit `2k` is the `+axes[k]` face, bit `2k + 1` the
    /// `−axes[k]` face. Each face has its own four vertices with the flat outward normal; the
    /// eight corners are computed once, so faces meet at bit-identical positions.
    pub fn oriented_box(&mut self, center: Vec3, axes: [Vec3; 3], half: Vec3, faces: u8) {
        let corner = |s: [f32; 3]| {
            center
                + axes[0] * (half.x * s[0])
                + axes[1] * (half.y * s[1])
                + axes[2] * (half.z * s[2])
        };
        let uvs = [Vec2::new(0.0, 1.0), Vec2::new(1.0, 1.0), Vec2::new(1.0, 0.0), Vec2::ZERO];
        for k in 0..3 {
            for (side, sign) in [(0, 1.0f32), (1, -1.0)] {
                if faces & (1 << (2 * k + side)) == 0 {
                    continue;
                }
                // Around n = sign·axes[k], the edges u = sign·axes[k+1] and v = axes[k+2]
                // satisfy u × v = n: corners −u−v, +u−v, +u+v, −u+v are counter-clockwise.
                let n = axes[k] * sign;
                let mut ids = [0u32; 4];
                for (c, (su, sv)) in
                    [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)].into_iter().enumerate()
                {
                    let mut s = [0.0f32; 3];
                    s[k] = sign;
                    s[(k + 1) % 3] = su * sign;
                    s[(k + 2) % 3] = sv;
                    ids[c] = self.vertex(corner(s), n, uvs[c]);
                }
                self.quad(ids[0], ids[1], ids[2], ids[3]);
            }
        }
    }

    /// Appends a tapered tube of `sides ≥ 3` around its axis and `segments ≥ 1` rings along it,
    /// open at `start` and closed by a flat fan of `sides − 2` triangles at `end`: exactly
    /// [`Tube::triangle_count`] triangles. Normals are those of the cone (radial, tilted by the
    /// taper). The ring frame is derived from the chord, so the tube is a pure function of `tube`.
    pub fn tube(&mut self, tube: &Tube, sides: u32, segments: u32) {
        let dir = tube.direction();
        let (e1, e2) = dir.any_orthonormal_pair();
        let len = tube.length().max(f32::MIN_POSITIVE);
        let ring: Vec<(Vec3, f32)> = (0..sides)
            .map(|k| {
                let (s, c) = sin_cos_turns(k as f32 / sides as f32);
                (e1 * c + e2 * s, k as f32 / sides as f32)
            })
            .collect();
        let base = self.positions.len() as u32;
        for j in 0..=segments {
            let t = j as f32 / segments as f32;
            let (center, r) = (tube.point(t), tube.radius(t));
            for &(radial, u) in &ring {
                let n = (radial * len + dir * (tube.r0 - tube.r1)).normalize();
                self.vertex(center + radial * r, n, Vec2::new(u, t));
            }
        }
        let at = |k: u32, j: u32| base + j * sides + k % sides;
        for j in 0..segments {
            for k in 0..sides {
                self.quad(at(k, j), at(k + 1, j), at(k + 1, j + 1), at(k, j + 1));
            }
        }
        // End cap: the last ring again, with the axis as normal, fanned.
        let cap = self.positions.len() as u32;
        let (end, r_end) = (tube.point(1.0), tube.radius(1.0));
        for &(radial, u) in &ring {
            self.vertex(end + radial * r_end, dir, Vec2::new(u, 1.0));
        }
        for k in 1..sides - 1 {
            self.triangle(cap, cap + k, cap + k + 1);
        }
    }

    /// The finished mesh.
    pub fn finish(self, name: &str, material: usize) -> Mesh {
        Mesh {
            name: name.into(),
            positions: self.positions,
            normals: self.normals,
            uvs: self.uvs,
            indices: self.indices,
            material,
            skin: None,
            node: None,
        }
    }
}
