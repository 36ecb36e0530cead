//! [`Mesh`]: an indexed triangle mesh in its scene's coordinates with per-vertex normals and
//! optional UVs.

use glam::{Vec2, Vec3};

use crate::{Error, Result};

/// Per-vertex skinning data, kept for the dynamic-scene pipeline (not used by static renders).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SkinBinding {
    /// Index into [`crate::Scene::skins`].
    pub skin: usize,
    /// Up to four joint indices per vertex (indices into the skin's joint list).
    pub joints: Vec<[u16; 4]>,
    /// The matching weights (non-negative, summing to 1).
    pub weights: Vec<[f32; 4]>,
    /// Vertex positions in the skin's bind space, before skinning (morph targets at their
    /// default weights applied): the joint matrices ([`crate::Skin::joint_matrices`]) blended
    /// by the weights map them to world space. Empty when unknown.
    pub bind_positions: Vec<Vec3>,
    /// Unit vertex normals in bind space, one per bind position (empty when unknown).
    pub bind_normals: Vec<Vec3>,
}

/// An indexed triangle mesh, already transformed to its scene's coordinates (world space less
/// [`crate::Scene::origin`]).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Mesh {
    /// Name, used in error messages.
    pub name: String,
    /// Vertex positions.
    pub positions: Vec<Vec3>,
    /// Unit vertex normals, one per position (loaders compute area-weighted normals when the
    /// file has none).
    pub normals: Vec<Vec3>,
    /// Texture coordinates, one per position, or empty when the mesh has none.
    pub uvs: Vec<Vec2>,
    /// Triangles as vertex-index triples, counter-clockwise seen from the front.
    pub indices: Vec<[u32; 3]>,
    /// Index into [`crate::Scene::materials`].
    pub material: usize,
    /// Skinning data, if the mesh is skinned.
    pub skin: Option<SkinBinding>,
    /// The scene node ([`crate::Scene::nodes`]) whose transform placed this mesh, if it came
    /// from a node hierarchy: an animation of that node moves the mesh rigidly (a skinned mesh
    /// moves with its skin's joints instead).
    pub node: Option<usize>,
}

impl Mesh {
    /// Number of triangles.
    pub fn triangle_count(&self) -> usize {
        self.indices.len()
    }

    /// The three positions of triangle `t`.
    #[inline]
    pub fn triangle(&self, t: usize) -> [Vec3; 3] {
        self.indices[t].map(|i| self.positions[i as usize])
    }

    /// Replaces the normals with area-weighted vertex normals: each triangle adds its
    /// unnormalized cross product (twice its area times its unit normal) to its three vertices.
    /// A vertex touched only by degenerate triangles gets +z.
    pub fn compute_normals(&mut self) {
        let mut acc = vec![Vec3::ZERO; self.positions.len()];
        for tri in &self.indices {
            let [a, b, c] = tri.map(|i| self.positions[i as usize]);
            let n = (b - a).cross(c - a);
            for &i in tri {
                acc[i as usize] += n;
            }
        }
        self.normals = acc.into_iter().map(|n| n.try_normalize().unwrap_or(Vec3::Z)).collect();
    }

    /// Checks attribute lengths, index ranges and that every attribute is finite, naming the
    /// offending vertex or triangle.
    pub fn validate(&self) -> Result<()> {
        let n = self.positions.len();
        let length = |attribute, found| Error::AttributeLength {
            mesh: self.name.clone(),
            attribute,
            found,
            expected: n,
        };
        if self.normals.len() != n {
            return Err(length("normals", self.normals.len()));
        }
        if !self.uvs.is_empty() && self.uvs.len() != n {
            return Err(length("uvs", self.uvs.len()));
        }
        if let Some(skin) = &self.skin {
            if skin.joints.len() != n || skin.weights.len() != n {
                return Err(length("joints/weights", skin.joints.len().min(skin.weights.len())));
            }
            if !skin.bind_positions.is_empty() && skin.bind_positions.len() != n {
                return Err(length("bind positions", skin.bind_positions.len()));
            }
            if skin.bind_normals.len() != skin.bind_positions.len() {
                return Err(length("bind normals", skin.bind_normals.len()));
            }
        }
        let non_finite = |attribute, vertex, value| Error::NonFinite {
            mesh: self.name.clone(),
            attribute,
            vertex,
            value,
        };
        for (i, p) in self.positions.iter().enumerate() {
            if !p.is_finite() {
                return Err(non_finite("position", i, p.to_array()));
            }
        }
        for (i, v) in self.normals.iter().enumerate() {
            if !v.is_finite() {
                return Err(non_finite("normal", i, v.to_array()));
            }
        }
        if let Some(skin) = &self.skin {
            for (i, p) in skin.bind_positions.iter().enumerate() {
                if !p.is_finite() {
                    return Err(non_finite("bind position", i, p.to_array()));
                }
            }
            for (i, w) in skin.weights.iter().enumerate() {
                let sum: f32 = w.iter().sum();
                if !(sum > 0.0 && sum.is_finite()) || w.iter().any(|x| *x < 0.0) {
                    return Err(Error::InvalidParameter {
                        name: format!("mesh '{}': skin weights of vertex {i}", self.name),
                        value: format!("{w:?}"),
                        reason: "weights must be finite, non-negative, with a positive sum".into(),
                    });
                }
            }
        }
        for (i, uv) in self.uvs.iter().enumerate() {
            if !uv.is_finite() {
                return Err(non_finite("uv", i, [uv.x, uv.y, 0.0]));
            }
        }
        for (t, tri) in self.indices.iter().enumerate() {
            if let Some(&index) = tri.iter().find(|&&i| i as usize >= n) {
                return Err(Error::IndexOutOfRange {
                    mesh: self.name.clone(),
                    triangle: t,
                    index,
                    vertex_count: n,
                });
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn quad() -> Mesh {
        Mesh {
            name: "quad".into(),
            positions: vec![Vec3::ZERO, Vec3::X, Vec3::new(1.0, 1.0, 0.0), Vec3::Y],
            indices: vec![[0, 1, 2], [0, 2, 3]],
            ..Default::default()
        }
    }

    #[test]
    fn computed_normals_are_area_weighted() {
        // A big triangle in z=0 and a tiny one tilted: the shared vertex leans toward +z.
        let mut m = Mesh {
            name: "m".into(),
            positions: vec![
                Vec3::ZERO,
                Vec3::new(10.0, 0.0, 0.0),
                Vec3::new(0.0, 10.0, 0.0),
                Vec3::new(0.0, 0.0, 0.1),
            ],
            indices: vec![[0, 1, 2], [0, 3, 1]],
            ..Default::default()
        };
        m.compute_normals();
        let n0 = m.normals[0];
        assert!((n0.length() - 1.0).abs() < 1e-6);
        // Areas: 50 (normal +z) and 0.5 (normal +y): weights 100:1.
        let expected = Vec3::new(0.0, 1.0, 100.0).normalize();
        assert!((n0 - expected).length() < 1e-5, "{n0} vs {expected}");
        assert_eq!(m.normals[2], Vec3::Z);
    }

    #[test]
    fn validate_names_the_bad_vertex_and_triangle() {
        let mut m = quad();
        m.compute_normals();
        m.validate().unwrap();
        m.positions[2].y = f32::NAN;
        let err = m.validate().unwrap_err().to_string();
        assert!(err.contains("vertex 2") && err.contains("quad"), "{err}");
        let mut m = quad();
        m.compute_normals();
        m.indices[1][2] = 9;
        let err = m.validate().unwrap_err().to_string();
        assert!(err.contains("triangle 1") && err.contains("vertex 9"), "{err}");
    }
}
