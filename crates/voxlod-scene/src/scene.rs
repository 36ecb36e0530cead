//! [`Scene`]: meshes, materials, textures, camera, lights and background; and [`Geometry`], the
//! flattened triangle arrays that voxelizers and ray casters consume.

use std::path::Path;

use glam::{DVec3, Vec2, Vec3};

use crate::{
    Animation, Camera, Error, Light, Material, MaterialSample, Mesh, Node, Result, Skin, Texture,
};

/// A scene: meshes, materials, camera and lights in `f32` coordinates local to an `f64`
/// [`origin`](Scene::origin) (`world = local + origin`).
///
/// The loaders read coordinates in `f64` and re-centre every file they load
/// ([`voxlod_format::origin::recentring_origin`]): a model that reaches near the world origin
/// keeps origin 0 and its world coordinates; a model far from it (geo-referenced CAD and GIS
/// exports at 10⁶–10⁷) is stored around zero, so that it keeps the `f32` precision of its own
/// scale and voxelizes and renders as it would at the world origin. Everything in a scene —
/// positions, normals, camera, lights, node transforms — is local; world coordinates meet it only
/// at its edges: convert them with [`Scene::to_local`] and [`Scene::to_world`] (camera and light
/// specifications given by a user, exported grid origins, reports).
#[derive(Clone, Debug, PartialEq)]
pub struct Scene {
    /// Name, for messages and reports.
    pub name: String,
    /// World position of the local origin, in `f64`: `world = local + origin`. Zero for
    /// procedural scenes and for files that reach near the world origin.
    pub origin: DVec3,
    /// Meshes, in local coordinates.
    pub meshes: Vec<Mesh>,
    /// Materials; every mesh refers to one.
    pub materials: Vec<Material>,
    /// Textures; materials refer to them.
    pub textures: Vec<Texture>,
    /// The scene's own camera, if it has one.
    pub camera: Option<Camera>,
    /// Lights (renderers use the first; a scene without lights gets [`Light::default`]).
    pub lights: Vec<Light>,
    /// Linear RGB background colour.
    pub background: Vec3,
    /// Node hierarchy (glTF), kept for animation.
    pub nodes: Vec<Node>,
    /// Skins (glTF), kept for animation.
    pub skins: Vec<Skin>,
    /// Animations (glTF), kept for animation.
    pub animations: Vec<Animation>,
}

impl Default for Scene {
    fn default() -> Self {
        Self {
            name: "scene".into(),
            origin: DVec3::ZERO,
            meshes: Vec::new(),
            materials: Vec::new(),
            textures: Vec::new(),
            camera: None,
            lights: Vec::new(),
            background: Vec3::new(0.05, 0.07, 0.12),
            nodes: Vec::new(),
            skins: Vec::new(),
            animations: Vec::new(),
        }
    }
}

/// All triangles of a scene in flat arrays. Triangle `t` has vertices `indices[t]` into the
/// vertex arrays and material `materials[t]`. Meshes without UVs get (0, 0).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Geometry {
    /// Vertex positions.
    pub positions: Vec<Vec3>,
    /// Unit vertex normals.
    pub normals: Vec<Vec3>,
    /// Vertex texture coordinates.
    pub uvs: Vec<Vec2>,
    /// Triangles.
    pub indices: Vec<[u32; 3]>,
    /// Material index per triangle.
    pub materials: Vec<u32>,
}

impl Geometry {
    /// Number of triangles.
    pub fn triangle_count(&self) -> usize {
        self.indices.len()
    }

    /// The three positions of triangle `t`.
    #[inline]
    pub fn triangle(&self, t: usize) -> [Vec3; 3] {
        self.indices[t].map(|i| self.positions[i as usize])
    }

    /// Axis-aligned bounds of all vertices referenced by a triangle, or `None` without
    /// triangles.
    pub fn bounds(&self) -> Option<(Vec3, Vec3)> {
        self.indices.iter().flatten().map(|&i| self.positions[i as usize]).fold(None, |acc, p| {
            Some(match acc {
                None => (p, p),
                Some((lo, hi)) => (lo.min(p), hi.max(p)),
            })
        })
    }

    /// Interpolates the shading normal (normalized) and UV of triangle `t` at barycentrics
    /// `(u, v)` (weights `1-u-v, u, v` of vertices 0, 1, 2).
    #[inline]
    pub fn interpolate(&self, t: usize, u: f32, v: f32) -> (Vec3, Vec2) {
        let [a, b, c] = self.indices[t].map(|i| i as usize);
        let w = 1.0 - u - v;
        let n = self.normals[a] * w + self.normals[b] * u + self.normals[c] * v;
        let n = n.try_normalize().unwrap_or_else(|| {
            let [p0, p1, p2] = self.triangle(t);
            (p1 - p0).cross(p2 - p0).try_normalize().unwrap_or(Vec3::Z)
        });
        (n, self.uvs[a] * w + self.uvs[b] * u + self.uvs[c] * v)
    }
}

impl Scene {
    /// Loads an `.obj`, `.gltf` or `.glb` file, validates it and returns the scene.
    pub fn load(path: &Path) -> Result<Self> {
        let ext = path.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase);
        let scene = match ext.as_deref() {
            Some("obj") => crate::obj::load(path)?,
            Some("gltf" | "glb") => crate::gltf::load(path)?,
            _ => return Err(Error::UnsupportedFormat { path: path.to_owned() }),
        };
        scene.validate()?;
        Ok(scene)
    }

    /// A world position in this scene's local coordinates: `world − origin`, subtracted in `f64`
    /// and rounded to `f32` once.
    ///
    /// ```
    /// use glam::{DVec3, Vec3};
    /// let scene = voxlod_scene::Scene { origin: DVec3::splat(1e7), ..Default::default() };
    /// let world = DVec3::new(1e7 + 0.25, 1e7 - 2.0, 1e7);
    /// assert_eq!(scene.to_local(world), Vec3::new(0.25, -2.0, 0.0));
    /// assert_eq!(scene.to_world(Vec3::new(0.25, -2.0, 0.0)), world);
    /// ```
    pub fn to_local(&self, world: DVec3) -> Vec3 {
        (world - self.origin).as_vec3()
    }

    /// A local position in world coordinates: `local + origin`, in `f64`.
    pub fn to_world(&self, local: Vec3) -> DVec3 {
        local.as_dvec3() + self.origin
    }

    /// Bounds of all triangles in world coordinates ([`Scene::bounds`] + [`Scene::origin`], in
    /// `f64`), or an [`Error::EmptyScene`].
    pub fn world_bounds(&self) -> Result<(DVec3, DVec3)> {
        let (lo, hi) = self.bounds()?;
        Ok((self.to_world(lo), self.to_world(hi)))
    }

    /// Total triangle count.
    pub fn triangle_count(&self) -> usize {
        self.meshes.iter().map(Mesh::triangle_count).sum()
    }

    /// The light renderers use: the first light, or [`Light::default`].
    pub fn light(&self) -> Light {
        self.lights.first().copied().unwrap_or_default()
    }

    /// Checks every mesh (finite attributes, indices in range) and every material and texture
    /// reference.
    pub fn validate(&self) -> Result<()> {
        for mesh in &self.meshes {
            mesh.validate()?;
            if mesh.material >= self.materials.len() {
                return Err(Error::DanglingReference {
                    what: "material",
                    index: mesh.material,
                    count: self.materials.len(),
                    by: format!("mesh '{}'", mesh.name),
                });
            }
        }
        for m in &self.materials {
            if let Some(r) = m.base_color_texture
                && r.texture >= self.textures.len()
            {
                return Err(Error::DanglingReference {
                    what: "texture",
                    index: r.texture,
                    count: self.textures.len(),
                    by: format!("material '{}'", m.name),
                });
            }
        }
        for t in &self.textures {
            if t.width == 0
                || t.height == 0
                || t.texels.len() != t.width as usize * t.height as usize
            {
                return Err(Error::InvalidParameter {
                    name: format!("texture '{}'", t.name),
                    value: format!("{}×{} with {} texels", t.width, t.height, t.texels.len()),
                    reason: "size and texel count disagree".into(),
                });
            }
        }
        if let Some(c) = &self.camera {
            c.validate()?;
        }
        for l in &self.lights {
            l.validated()?;
        }
        Ok(())
    }

    /// Flattens all meshes into one [`Geometry`].
    pub fn geometry(&self) -> Geometry {
        let mut g = Geometry::default();
        let vertices = self.meshes.iter().map(|m| m.positions.len()).sum();
        g.positions.reserve(vertices);
        g.normals.reserve(vertices);
        g.uvs.reserve(vertices);
        g.indices.reserve(self.triangle_count());
        g.materials.reserve(self.triangle_count());
        for m in &self.meshes {
            let base = g.positions.len() as u32;
            g.positions.extend_from_slice(&m.positions);
            g.normals.extend_from_slice(&m.normals);
            if m.uvs.is_empty() {
                g.uvs.extend(std::iter::repeat_n(Vec2::ZERO, m.positions.len()));
            } else {
                g.uvs.extend_from_slice(&m.uvs);
            }
            g.indices.extend(m.indices.iter().map(|t| t.map(|i| i + base)));
            g.materials.extend(std::iter::repeat_n(m.material as u32, m.indices.len()));
        }
        g
    }

    /// Bounds of all triangles in local coordinates, or an [`Error::EmptyScene`] if there are
    /// none.
    pub fn bounds(&self) -> Result<(Vec3, Vec3)> {
        let mut b: Option<(Vec3, Vec3)> = None;
        for m in &self.meshes {
            for &i in m.indices.iter().flatten() {
                let p = m.positions[i as usize];
                b = Some(b.map_or((p, p), |(lo, hi)| (lo.min(p), hi.max(p))));
            }
        }
        b.ok_or_else(|| Error::EmptyScene {
            scene: self.name.clone(),
            reason: "it has no triangles".into(),
        })
    }

    /// Evaluates triangle `t`'s material (from `geometry.materials`) at `uv`.
    #[inline]
    pub fn material_sample(&self, material: u32, uv: Vec2) -> MaterialSample {
        self.materials[material as usize].sample(&self.textures, uv)
    }

    /// A camera for this scene: its own, or one framing its bounds from the front-right-top.
    pub fn default_camera(&self) -> Result<Camera> {
        if let Some(c) = self.camera {
            return Ok(c);
        }
        let (lo, hi) = self.bounds()?;
        let center = (lo + hi) * 0.5;
        let radius = ((hi - lo).length() * 0.5).max(1e-6);
        Ok(Camera::framing(Vec3::new(0.45, 0.35, 1.0), center, radius, 40.0))
    }
}
